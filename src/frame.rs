//! Frame: the tracer's linear, unclamped f32 RGB (+ optional depth and coverage), row-major
//! from the top left, and its conversions to the integer pixels files and streams carry.

use crate::transfer::{Curve, Encoding};

#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// 3 floats per pixel, row-major, top row first.
    pub rgb: Vec<f32>,
    /// Planar depth of each pixel centre's first hit (`Z`, see `tracer::rows::depth`), when
    /// asked for.
    pub depth: Option<Vec<f32>>,
    /// Coverage (alpha) when asked for: then `rgb` is premultiplied, eye rays that miss
    /// having added nothing.
    pub(crate) alpha: Option<Vec<f32>>,
    /// Compositing passes (`render.aov`), when asked for; `tracer::aov` fills them in.
    pub aov: Option<Passes>,
    /// How integer values encode the colour.
    pub(crate) encoding: Encoding,
    /// Colour values the tracer produced as NaN or beyond f32 and that were replaced before
    /// storing; the test suite asserts this stays 0 on every extreme scene.
    pub non_finite: u64,
    /// Eye-ray samples traced for the colour (the cost measure of sampling strategies).
    pub samples: u64,
    /// All rays cast for the colour: eye, shadow and reflection rays.
    pub rays: u64,
    /// `to_rgb8`'s bytes when the tracer made them band by band as it finished each, while
    /// the band was still in cache (see `tracer::render_frame`); `take_rgb8` hands them on.
    pub(crate) levels8: Option<Vec<u8>>,
}

/// A frame's compositing passes: each channel's name and its f32 values (row-major from the
/// top left), in the order of `settings::Aov::ALL`, and the table of object ids.
#[derive(Debug, Clone, PartialEq)]
pub struct Passes {
    pub channels: Vec<(&'static str, Vec<f32>)>,
    /// One line per object of `objects:`, `ID KIND` (and a mesh's file name): what
    /// `objectId` values mean.
    pub objects: String,
}

impl Frame {
    pub fn pixel(&self, row: u32, col: u32) -> [f32; 3] {
        let i = 3 * (row as usize * self.width as usize + col as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// 8-bit RGB(A) in the frame's encoding (see `levels`), in a recycled buffer when one of
    /// its length is spare (`recycle_bytes`).
    pub fn to_rgb8(&self) -> Vec<u8> {
        let len = self.rgb.len() / 3 * if self.alpha.is_some() { 4 } else { 3 };
        self.levels(255.0, spare_bytes(len))
    }

    /// `to_rgb8`, taking the bytes the tracer already made when it made them.
    pub(crate) fn take_rgb8(&mut self) -> Vec<u8> {
        self.levels8.take().unwrap_or_else(|| self.to_rgb8())
    }

    /// 16-bit RGB(A) in the frame's encoding.
    pub(crate) fn to_rgb16(&self) -> Vec<u16> {
        self.levels(65535.0, Vec::new())
    }

    /// Linear: round(max · clamp(c, 0, 1)); sRGB: the exact curve's level (`transfer`). With
    /// alpha the colour is made straight first (c/α, 0 where α = 0) and α is appended, linear.
    /// `out` is overwritten whole (its length is set to the frame's values).
    fn levels<T: Level>(&self, max: f32, mut out: Vec<T>) -> Vec<T> {
        let Some(alpha) = &self.alpha else {
            out.resize(self.rgb.len(), T::from_level(0));
            encode_slice(&self.rgb, &mut out, max, self.encoding);
            return out;
        };
        let mut rgba = Vec::with_capacity(4 * alpha.len());
        for (c, &a) in self.rgb.chunks_exact(3).zip(alpha) {
            let straight = |v: f32| if a > 0.0 { v / a } else { 0.0 };
            rgba.extend([straight(c[0]), straight(c[1]), straight(c[2]), a]);
        }
        out.resize(rgba.len(), T::from_level(0));
        encode_slice(&rgba, &mut out, max, self.encoding);
        for (o, &a) in out.chunks_exact_mut(4).zip(alpha) {
            o[3] = T::from_level(quantize(a, max));
        }
        out
    }

    /// Gives the frame's buffers back for the next frame of the same size: a 1080p frame is
    /// 25 MB, and every fresh page of it costs a page fault.
    pub(crate) fn recycle(self) {
        if let Some(bytes) = self.levels8 {
            BYTES.give(bytes);
        }
        for buffer in std::iter::once(self.rgb)
            .chain(self.depth)
            .chain(self.alpha)
        {
            FLOATS.give(buffer);
        }
    }
}

/// Buffers of frames gone, kept for the next frames of the same size: a run keeps at most
/// threads + 2 frames in flight, so `MAX_SPARE` of each kind suffice.
struct Spare<T>(std::sync::Mutex<Vec<Vec<T>>>);

const MAX_SPARE: usize = 8;

impl<T> Spare<T> {
    const fn new() -> Spare<T> {
        Spare(std::sync::Mutex::new(Vec::new()))
    }

    /// A spare buffer of length `len`, if there is one.
    fn take(&self, len: usize) -> Option<Vec<T>> {
        let mut spare = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let i = spare.iter().position(|b| b.len() == len)?;
        Some(spare.swap_remove(i))
    }

    fn give(&self, buffer: Vec<T>) {
        let mut spare = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if spare.len() < MAX_SPARE {
            spare.push(buffer);
        }
    }
}

/// The tracer's float planes (colour, depth, coverage).
static FLOATS: Spare<f32> = Spare::new();
/// 8-bit frames: a 1080p stream wrote 6.2 MB of fresh pages a frame, each page a fault and a
/// clearing (about 3% of the talk's f32 stream in `perf`). The raw stream's writer and the PNG
/// encoder give them back (`recycle_bytes`).
static BYTES: Spare<u8> = Spare::new();

/// A buffer of `len` floats, recycled when one of that length is spare. Its contents are
/// whatever the last frame left: the tracer writes every value before anything reads it.
pub(crate) fn buffer(len: usize) -> Vec<f32> {
    FLOATS.take(len).unwrap_or_else(|| vec![0.0; len])
}

/// A byte buffer of length `len` if one is spare, else an empty one to be grown.
fn spare_bytes(len: usize) -> Vec<u8> {
    BYTES.take(len).unwrap_or_default()
}

/// A buffer for `to_rgb8`'s bytes of `len` values (alpha-free frames), recycled when one is
/// spare; `levels8` fills it a slice at a time.
pub(crate) fn bytes8(len: usize) -> Vec<u8> {
    let mut bytes = spare_bytes(len);
    bytes.resize(len, 0);
    bytes
}

/// `to_rgb8`'s bytes of a slice of an alpha-free frame's colour values.
pub(crate) fn levels8(rgb: &[f32], out: &mut [u8], encoding: Encoding) {
    encode_slice(rgb, out, 255.0, encoding);
}

/// Gives back bytes that were written out (a stream's frame), for the next `to_rgb8`.
pub(crate) fn recycle_bytes(bytes: Vec<u8>) {
    BYTES.give(bytes);
}

fn encode_slice<T: Level>(src: &[f32], dst: &mut [T], max: f32, encoding: Encoding) {
    match encoding {
        Encoding::Linear => quantize_slice(src, dst, max),
        Encoding::Srgb => srgb_each(src, dst, Curve::of(max as u32)),
    }
}

/// The sRGB levels of a slice: table lookups, about 2 ns a value one at a time (the compiler
/// makes no vector gathers of them); with AVX2 eight at a time, one gather of their buckets,
/// 3.2 ms for a 1080p frame against 1.2 ms for linear values (two gathers took 5.5 ms;
/// `frame::tests::encoding_speed`, 2026-11-28, 2-core AMD EPYC).
fn srgb_each<T: Level>(src: &[f32], dst: &mut [T], curve: &Curve) {
    #[cfg(target_arch = "x86_64")]
    if curve.packed() && is_x86_feature_detected!("avx512f") {
        // SAFETY: the feature was just detected, and the curve is packed.
        return unsafe { srgb_packed_avx512(src, dst, curve) };
    }
    #[cfg(target_arch = "x86_64")]
    if curve.packed() && is_x86_feature_detected!("avx2") {
        // SAFETY: the feature was just detected, and the curve is packed.
        return unsafe { srgb_packed_avx2(src, dst, curve) };
    }
    if curve.single() {
        for (d, &c) in dst.iter_mut().zip(src) {
            *d = T::from_level(curve.level_single(c));
        }
        return;
    }
    for (d, &c) in dst.iter_mut().zip(src) {
        *d = T::from_level(curve.level(c));
    }
}

/// `srgb_each` of a packed curve eight values at a time (a gather); the tail one by one.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn srgb_packed_avx2<T: Level>(src: &[f32], dst: &mut [T], curve: &Curve) {
    let mut d = dst.chunks_exact_mut(8);
    let mut s = src.chunks_exact(8);
    for (d, s) in (&mut d).zip(&mut s) {
        // SAFETY: AVX2 is enabled here, and the caller checked the curve.
        let levels = unsafe { curve.levels_packed_avx2(s.try_into().unwrap()) };
        for (d, l) in d.iter_mut().zip(levels) {
            *d = T::from_level(l);
        }
    }
    for (d, &c) in d.into_remainder().iter_mut().zip(s.remainder()) {
        *d = T::from_level(curve.level_single(c));
    }
}

/// `srgb_each` of a packed curve sixteen values at a time (one gather), each group's levels
/// narrowed in the register and stored at once (vpmovdb or vpmovdw: levels never exceed the
/// type's maximum, so truncation is exact); the tail one by one. `frame::tests::encoding_speed`
/// (a whole 1080p frame, out of cache) moved only within its noise on 2026-12-03 (3.5–4.2 ms
/// against 4.0–4.2 on the 2-core AMD EPYC): it is meant for bands still in cache.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn srgb_packed_avx512<T: Level>(src: &[f32], dst: &mut [T], curve: &Curve) {
    use std::arch::x86_64::*;
    let mut d = dst.chunks_exact_mut(16);
    let mut s = src.chunks_exact(16);
    for (d, s) in (&mut d).zip(&mut s) {
        // SAFETY: AVX-512F is enabled here, and the caller checked the curve.
        let levels = unsafe { curve.levels_packed_avx512(s.try_into().unwrap()) };
        // SAFETY: d holds 16 values of T, whose size picks the store that fills exactly them.
        unsafe {
            match std::mem::size_of::<T>() {
                1 => _mm_storeu_si128(d.as_mut_ptr().cast(), _mm512_cvtepi32_epi8(levels)),
                2 => _mm256_storeu_si256(d.as_mut_ptr().cast(), _mm512_cvtepi32_epi16(levels)),
                _ => unreachable!("levels are u8 or u16"),
            }
        }
    }
    for (d, &c) in d.into_remainder().iter_mut().zip(s.remainder()) {
        *d = T::from_level(curve.level_single(c));
    }
}

/// round(max · clamp(c, 0, 1)), halves rounding up, NaN to 0, over a whole slice with the
/// widest vectors the CPU has: the same bytes as one value at a time, which the tests check
/// for every f32.
fn quantize_slice<T: Level>(src: &[f32], dst: &mut [T], max: f32) {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512bw") {
            // SAFETY: the features were just detected.
            return unsafe { quantize_avx512(src, dst, max) };
        }
        if is_x86_feature_detected!("avx2") {
            // SAFETY: the feature was just detected.
            return unsafe { quantize_avx2(src, dst, max) };
        }
    }
    quantize_each(src, dst, max)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512bw")]
unsafe fn quantize_avx512<T: Level>(src: &[f32], dst: &mut [T], max: f32) {
    quantize_each(src, dst, max)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn quantize_avx2<T: Level>(src: &[f32], dst: &mut [T], max: f32) {
    quantize_each(src, dst, max)
}

/// A branch-free loop the compiler turns into vector code inside the feature functions.
#[inline(always)]
fn quantize_each<T: Level>(src: &[f32], dst: &mut [T], max: f32) {
    for (d, &c) in dst.iter_mut().zip(src) {
        *d = T::from_level(quantize(c, max));
    }
}

/// An integer channel value; `quantize` never exceeds the type's maximum.
trait Level: Copy {
    fn from_level(q: u32) -> Self;
}

impl Level for u8 {
    #[inline(always)]
    fn from_level(q: u32) -> u8 {
        q as u8
    }
}

impl Level for u16 {
    #[inline(always)]
    fn from_level(q: u32) -> u16 {
        q as u16
    }
}

/// round(max · clamp(c, 0, 1)) with halves rounding up: the integer part and y − it are both
/// exact for y < 2^24, and no rounding instruction or libm call is needed. `f32::max` turns
/// NaN into 0 (NaN never reaches a frame; `finite` replaces it first).
#[inline(always)]
#[allow(clippy::manual_clamp)] // clamp keeps NaN; max(NaN, 0) is 0, which this needs
fn quantize(c: f32, max: f32) -> u32 {
    let y = c.max(0.0).min(1.0) * max;
    // SAFETY: y is finite and within [0, 65535], so the truncation is exact and in range.
    let whole: i32 = unsafe { y.to_int_unchecked() };
    (whole + i32::from(y - whole as f32 >= 0.5)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantization_rounds_and_clamps() {
        let f = Frame {
            width: 2,
            height: 1,
            rgb: vec![0.0, 0.5, 1.0, -3.0, 7.0, 0.2],
            depth: None,
            alpha: None,
            aov: None,
            encoding: Encoding::Linear,
            non_finite: 0,
            samples: 2,
            rays: 2,
            levels8: None,
        };
        assert_eq!(f.to_rgb8(), vec![0, 128, 255, 0, 255, 51]);
        assert_eq!(f.to_rgb16()[1], 32768);
    }

    /// A recycled byte buffer is overwritten whole: garbage left in it never reaches a frame,
    /// with alpha (4 values a pixel, from a buffer of 3-value length) or without.
    /// A slice's sRGB bytes, whatever the widest kernel the CPU has (sixteen, eight or one at
    /// a time, with a tail), are each value's own level.
    #[test]
    fn srgb_slices_are_each_values_level() {
        let curve = Curve::of(255);
        let odd = [
            f32::NAN,
            -0.0,
            -1.0,
            2.0,
            f32::INFINITY,
            1.0,
            0.0031308,
            1e-45,
        ];
        for len in [0, 1, 15, 16, 17, 1000, 1007] {
            let src: Vec<f32> = (0..len)
                .map(|i| match i % 11 {
                    0 => odd[i / 11 % odd.len()],
                    _ => (i as f32 * 0.618_034).fract(),
                })
                .collect();
            let mut out = vec![7u8; len];
            levels8(&src, &mut out, Encoding::Srgb);
            let want: Vec<u8> = src.iter().map(|&c| curve.level_single(c) as u8).collect();
            assert_eq!(out, want, "{len} values");
        }
    }

    #[test]
    fn recycled_bytes_are_overwritten_whole() {
        for alpha in [None, Some(vec![1.0, 0.5, 0.0, 0.25])] {
            for encoding in [Encoding::Linear, Encoding::Srgb] {
                let f = Frame {
                    width: 4,
                    height: 1,
                    rgb: (0..12).map(|i| i as f32 / 11.0 - 0.1).collect(),
                    depth: None,
                    alpha: alpha.clone(),
                    aov: None,
                    encoding,
                    non_finite: 0,
                    samples: 1,
                    rays: 1,
                    levels8: None,
                };
                let fresh = f.to_rgb8();
                for len in [12, 16] {
                    recycle_bytes(vec![0xab; len]);
                }
                let again = f.to_rgb8();
                assert_eq!(again, fresh, "{alpha:?} {encoding:?}");
                recycle_bytes(again);
            }
        }
    }

    /// Milliseconds to encode a 1920×1080 frame of varied values, each encoding and depth:
    /// `cargo test --release --lib encoding_speed -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn encoding_speed() {
        let n = 1920 * 1080 * 3;
        let rgb: Vec<f32> = (0..n).map(|i| (i % 1000) as f32 / 900.0).collect();
        for encoding in [Encoding::Linear, Encoding::Srgb] {
            let f = Frame {
                width: 1920,
                height: 1080,
                rgb: rgb.clone(),
                depth: None,
                alpha: None,
                aov: None,
                encoding,
                non_finite: 0,
                samples: 0,
                rays: 0,
                levels8: None,
            };
            let _ = (f.to_rgb8(), f.to_rgb16());
            let mut best = [f64::MAX; 2];
            for _ in 0..5 {
                let t = std::time::Instant::now();
                std::hint::black_box(f.to_rgb8());
                best[0] = best[0].min(t.elapsed().as_secs_f64() * 1e3);
                let t = std::time::Instant::now();
                std::hint::black_box(f.to_rgb16());
                best[1] = best[1].min(t.elapsed().as_secs_f64() * 1e3);
            }
            println!(
                "{encoding:?}: 8-bit {:.1} ms, 16-bit {:.1} ms",
                best[0], best[1]
            );
        }
    }

    /// The definition the fast loop must equal: clamp, scale, round halves up.
    fn reference(c: f32, max: f32) -> u32 {
        let y = c.clamp(0.0, 1.0) * max;
        let whole = y as u32 as f32;
        (if y - whole >= 0.5 { whole + 1.0 } else { whole }) as u32
    }

    /// Values where rounding could go either way: ±4 ulps around every level's half-way point
    /// and the level itself, for both depths; the ends, NaN, infinities, zeros, subnormals;
    /// and 4 million random bit patterns. Each goes through the vector loop in one slice.
    #[test]
    fn vector_quantization_matches_the_definition() {
        let mut values = vec![
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            0.0,
            1.0,
            1.5,
        ];
        values.extend([
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::MAX,
            -f32::MAX,
            2.0,
            -1.0,
        ]);
        for max in [255.0f32, 65535.0] {
            for level in 0..=max as u32 {
                for x in [level as f32 / max, (level as f32 + 0.5) / max] {
                    for ulps in -4i32..=4 {
                        values.push(f32::from_bits(x.to_bits().wrapping_add_signed(ulps)));
                    }
                }
            }
        }
        let mut state = 0x9e37_79b9u32;
        values.extend((0..1 << 22).map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            f32::from_bits(state)
        }));
        let (mut q8, mut q16) = (vec![0u8; values.len()], vec![0u16; values.len()]);
        quantize_slice(&values, &mut q8, 255.0);
        quantize_slice(&values, &mut q16, 65535.0);
        for (i, &c) in values.iter().enumerate() {
            let c0 = if c.is_nan() { 0.0 } else { c };
            assert_eq!(u32::from(q8[i]), reference(c0, 255.0), "{c:e}");
            assert_eq!(u32::from(q16[i]), reference(c0, 65535.0), "{c:e}");
        }
        // The sRGB levels of the same values through the slice loop (gathers where the CPU
        // has AVX2, and a tail) equal the lookup one value at a time; −0 is 0.
        let mut s8 = vec![0u8; values.len()];
        srgb_each(&values, &mut s8, Curve::of(255));
        for (i, &c) in values.iter().enumerate() {
            assert_eq!(u32::from(s8[i]), Curve::of(255).level(c), "{c:e}");
        }
        assert_eq!(Curve::of(255).level(-0.0), 0);
    }
}
