//! Transfer functions from the tracer's linear colour to the integer values of PNG files and
//! streams (`render.encoding`). The sRGB curve is evaluated exactly: an output level is the
//! number of thresholds at or below the value, and each threshold is the smallest f32 at which
//! the exact real curve (IEC 61966-2-1 with its decimal constants) reaches the level's halfway
//! point. So no pow of any library, and no evaluation order, can change a byte.

use std::sync::OnceLock;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// The sRGB transfer function, as viewers and video players expect.
    #[default]
    Srgb,
    /// The linear value itself (the talk's images).
    Linear,
}

impl Encoding {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Encoding::Srgb => "srgb",
            Encoding::Linear => "linear",
        }
    }
}

/// The sRGB curve of one bit depth as a lookup: `thresholds[k]` is where level k + 1 starts
/// (a last +inf stops the scan), and `start[b]` the level at the bottom of bucket b, the
/// values sharing their exponent and top mantissa bits. A bucket is narrower than a level near
/// 1, so the scan from its start takes at most a step or two.
pub(crate) struct Curve {
    thresholds: Vec<f32>,
    /// u32, not u16: AVX2 gathers 32-bit lanes.
    start: Vec<u32>,
    /// `thresholds[start[b]]`: with `single`, the level of x is start[b] + (x ≥ next[b]).
    next: Vec<f32>,
    /// Whether every bucket holds at most one threshold (8 bits: yes), so one comparison
    /// finds the level and the loop has no branch left to stop vectorising.
    single: bool,
    shift: u32,
    low: u32,
    /// With `single`, per bucket: its start level above bit 17, and below it where in the
    /// bucket its threshold lies (the threshold's low `shift` bits; 1 << `shift` for none:
    /// a bucket's values share their other bits), so one gather finds the level. Empty
    /// when bucket 0, which also takes every value below it, holds a threshold.
    packed: Vec<u32>,
}

/// Linear values up to this take the straight segment, 12.92·x.
const LINEAR_END: f64 = 0.0031308;

impl Curve {
    fn new(max: u32, shift: u32, low_exponent: i32) -> Curve {
        let mut thresholds: Vec<f32> = (1..=max).map(|k| threshold(k, max)).collect();
        thresholds.push(f32::INFINITY);
        let low = ((127 + low_exponent) as u32) << 23 >> shift;
        let top = 1f32.to_bits() >> shift;
        let start: Vec<u32> = (low..=top)
            .map(|b| {
                let lo = if b == low {
                    0.0
                } else {
                    f32::from_bits(b << shift)
                };
                thresholds.partition_point(|&t| t <= lo) as u32
            })
            .collect();
        let next = start.iter().map(|&s| thresholds[s as usize]).collect();
        // The largest value of bucket b is just below the next bucket's first; 1 ends the last.
        let single = (low..=top).zip(&start).all(|(b, &s)| {
            let hi = if b == top {
                1.0
            } else {
                f32::from_bits(((b + 1) << shift) - 1)
            };
            thresholds.get(s as usize + 1).is_none_or(|&t| t > hi)
        });
        let packed = match single && thresholds[0].to_bits() >> shift > low {
            true => (low..)
                .zip(&start)
                .map(|(b, &s)| {
                    let t = thresholds[s as usize];
                    let mine = t.is_finite() && t.to_bits() >> shift == b;
                    let edge = if mine {
                        t.to_bits() & ((1 << shift) - 1)
                    } else {
                        1 << shift
                    };
                    s << 17 | edge
                })
                .collect(),
            false => Vec::new(),
        };
        Curve {
            thresholds,
            start,
            next,
            single,
            shift,
            low,
            packed,
        }
    }

    /// The curve for 8-bit (`max` 255) or 16-bit (65535) values, built once.
    pub(crate) fn of(max: u32) -> &'static Curve {
        static EIGHT: OnceLock<Curve> = OnceLock::new();
        static SIXTEEN: OnceLock<Curve> = OnceLock::new();
        match max {
            255 => EIGHT.get_or_init(|| Curve::new(255, 16, -14)),
            _ => SIXTEEN.get_or_init(|| Curve::new(65535, 13, -22)),
        }
    }

    /// The level of linear value `c`: NaN and negatives are 0, values above 1 the maximum.
    #[inline(always)]
    pub(crate) fn level(&self, c: f32) -> u32 {
        if self.single {
            return self.level_single(c);
        }
        let (x, bucket) = self.bucket(c);
        let mut level = self.start[bucket] as usize;
        while x >= self.thresholds[level] {
            level += 1;
        }
        level as u32
    }

    /// `level` when every bucket holds at most one threshold: branch-free.
    #[inline(always)]
    pub(crate) fn level_single(&self, c: f32) -> u32 {
        let (x, bucket) = self.bucket(c);
        self.start[bucket] + u32::from(x >= self.next[bucket])
    }

    /// The clamped value and its bucket.
    #[inline(always)]
    #[allow(clippy::manual_clamp)] // clamp keeps NaN; max(NaN, 0) is 0, which this needs
    fn bucket(&self, c: f32) -> (f32, usize) {
        let x = c.max(0.0).min(1.0);
        let b = (x.to_bits() >> self.shift).saturating_sub(self.low) as usize;
        (x, b.min(self.start.len() - 1))
    }

    /// `level_single` of eight values at once: one gather of their buckets' `packed` and an
    /// integer comparison of their low bits, the same levels as one value at a time.
    ///
    /// # Safety
    /// The CPU must have AVX2, and `packed` must not be empty.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) unsafe fn levels_packed_avx2(&self, c: &[f32; 8]) -> [u32; 8] {
        use std::arch::x86_64::*;
        // SAFETY: c is 8 floats.
        let c = unsafe { _mm256_loadu_ps(c.as_ptr()) };
        // max_ps returns its second operand for NaN (and for −0), as `bucket`'s max(c, 0) does.
        let x = _mm256_min_ps(_mm256_max_ps(c, _mm256_setzero_ps()), _mm256_set1_ps(1.0));
        let bits = _mm256_castps_si256(x);
        let shift = _mm_cvtsi32_si128(self.shift as i32);
        let low = _mm256_set1_epi32(self.low as i32);
        let last = _mm256_set1_epi32(self.packed.len() as i32 - 1);
        let b = _mm256_srl_epi32(bits, shift);
        let b = _mm256_min_epu32(_mm256_sub_epi32(_mm256_max_epu32(b, low), low), last);
        // SAFETY: every lane of b is at most packed.len() − 1.
        let e = unsafe { _mm256_i32gather_epi32::<4>(self.packed.as_ptr().cast(), b) };
        let start = _mm256_srli_epi32::<17>(e);
        let edge = _mm256_and_si256(e, _mm256_set1_epi32(0x1_ffff));
        let mine = _mm256_and_si256(bits, _mm256_set1_epi32((1 << self.shift) - 1));
        // All ones (−1) where mine ≥ edge: subtracting it adds one.
        let up = _mm256_cmpgt_epi32(_mm256_add_epi32(mine, _mm256_set1_epi32(1)), edge);
        let mut out = [0u32; 8];
        // SAFETY: out is 8 u32.
        unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), _mm256_sub_epi32(start, up)) };
        out
    }

    /// `levels_packed_avx2` of sixteen values at once in AVX-512 registers (the same
    /// operations a lane: vmaxps and vminps treat NaN and −0 as their AVX2 forms do), the
    /// levels left in a register for the caller to narrow and store.
    ///
    /// # Safety
    /// The CPU must have AVX-512F, and `packed` must not be empty.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub(crate) unsafe fn levels_packed_avx512(&self, c: &[f32; 16]) -> std::arch::x86_64::__m512i {
        use std::arch::x86_64::*;
        // SAFETY: c is 16 floats.
        let c = unsafe { _mm512_loadu_ps(c.as_ptr()) };
        let x = _mm512_min_ps(_mm512_max_ps(c, _mm512_setzero_ps()), _mm512_set1_ps(1.0));
        let bits = _mm512_castps_si512(x);
        let shift = _mm_cvtsi32_si128(self.shift as i32);
        let low = _mm512_set1_epi32(self.low as i32);
        let last = _mm512_set1_epi32(self.packed.len() as i32 - 1);
        let b = _mm512_srl_epi32(bits, shift);
        let b = _mm512_min_epu32(_mm512_sub_epi32(_mm512_max_epu32(b, low), low), last);
        // SAFETY: every lane of b is at most packed.len() − 1.
        let e = unsafe { _mm512_i32gather_epi32::<4>(b, self.packed.as_ptr().cast()) };
        let start = _mm512_srli_epi32::<17>(e);
        let edge = _mm512_and_si512(e, _mm512_set1_epi32(0x1_ffff));
        let mine = _mm512_and_si512(bits, _mm512_set1_epi32((1 << self.shift) - 1));
        // One level up where mine ≥ edge, i.e. mine + 1 > edge, as in the AVX2 form.
        let up = _mm512_cmpgt_epi32_mask(_mm512_add_epi32(mine, _mm512_set1_epi32(1)), edge);
        _mm512_mask_add_epi32(start, up, start, _mm512_set1_epi32(1))
    }

    /// Whether `levels_packed_avx2` may be used.
    pub(crate) fn packed(&self) -> bool {
        !self.packed.is_empty()
    }

    /// Whether one comparison decides every level (see `single`).
    pub(crate) fn single(&self) -> bool {
        self.single
    }

    #[cfg(test)]
    pub(crate) fn thresholds(&self) -> &[f32] {
        &self.thresholds[..self.thresholds.len() - 1]
    }
}

/// Where the exact curve reaches y = (k − ½)/max, in f64: the straight segment's inverse
/// y/12.92, or ((y + 0.055)/1.055)^2.4 on the power segment (libm's pow).
pub(crate) fn inverse(k: u32, max: u32) -> f64 {
    let y = f64::from(2 * k - 1) / f64::from(2 * max);
    if y <= 12.92 * LINEAR_END {
        y / 12.92
    } else {
        libm::pow((y + 0.055) / 1.055, 2.4)
    }
}

/// The smallest f32 at or above `inverse(k, max)`. The f64 inverse is within about 1e-15 of
/// the exact real one, and the tests check that no threshold's real value lies that close to
/// an f32, so this is the exact threshold.
fn threshold(k: u32, max: u32) -> f32 {
    let g = inverse(k, max);
    let f = g as f32;
    if f64::from(f) < g {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The curve in f64, for comparisons away from thresholds.
    fn srgb(x: f64) -> f64 {
        if x <= LINEAR_END {
            12.92 * x
        } else {
            1.055 * libm::pow(x, 1.0 / 2.4) - 0.055
        }
    }

    /// Every threshold's f64 value is at least 1e-13 (relative) away from an f32, far beyond
    /// the f64 evaluation's error: rounding it up to an f32 gives the exact threshold. And no
    /// level's halfway point falls in the curve's tiny jump at 0.0031308.
    #[test]
    fn thresholds_are_exact() {
        for max in [255u32, 65535] {
            for k in 1..=max {
                let g = inverse(k, max);
                let f = g as f32;
                let (below, above) = if f64::from(f) < g {
                    (f, f32::from_bits(f.to_bits() + 1))
                } else {
                    (f32::from_bits(f.to_bits() - 1), f)
                };
                let margin = (g - f64::from(below)).min(f64::from(above) - g);
                assert!(margin > 1e-13 * g, "level {k} of {max}: {g:e}");
                let y = f64::from(2 * k - 1) / f64::from(2 * max);
                let jump = 1.055 * libm::pow(LINEAR_END, 1.0 / 2.4) - 0.055;
                assert!(!(y > 12.92 * LINEAR_END && y <= jump), "level {k} of {max}");
            }
        }
    }

    /// The lookup against the definition (the count of thresholds at or below the value), for
    /// every threshold ± 2 ulps and random values, and against round(max·sRGB(x)) in f64 where
    /// that is not within 1e-9 of a half.
    #[test]
    #[allow(clippy::manual_clamp)] // NaN must count as 0, as `level` takes it
    fn lookup_counts_thresholds() {
        assert!(Curve::of(255).single());
        for max in [255u32, 65535] {
            let curve = Curve::of(max);
            let t = curve.thresholds();
            let mut values = vec![0.0f32, 1.0, -1.0, 2.0, f32::NAN, f32::MIN_POSITIVE, 1e-45];
            for &x in t {
                values.extend((-2..=2).map(|d| f32::from_bits(x.to_bits().wrapping_add_signed(d))));
            }
            let mut state = 0x2545_f491u32;
            values.extend((0..200_000).map(|_| {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                (state >> 8) as f32 / (1 << 24) as f32
            }));
            for x in values {
                let want = t.partition_point(|&th| th <= x.max(0.0).min(1.0));
                assert_eq!(curve.level(x) as usize, want, "{x:e}");
                if (0.0..=1.0).contains(&x) {
                    let y = srgb(f64::from(x)) * f64::from(max);
                    if ((y - y.floor()) - 0.5).abs() > 1e-9 {
                        assert_eq!(want as f64, (y + 0.5).floor(), "{x:e} of {max}");
                    }
                }
            }
        }
    }

    /// The eight- and sixteen-at-a-time levels are `level_single`'s for every f32 from 0 to 1
    /// (about 1.07e9 values, a few seconds on two cores) and for the values around them.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_vector_levels_are_exact_for_every_f32() {
        use rayon::prelude::*;
        use std::arch::x86_64::*;
        let curve = Curve::of(255);
        assert!(curve.packed());
        let (avx2, avx512) = (
            is_x86_feature_detected!("avx2"),
            is_x86_feature_detected!("avx512f"),
        );
        let check = |xs: &[f32; 16]| {
            let want: [u32; 16] = std::array::from_fn(|i| curve.level_single(xs[i]));
            let mut ok = true;
            if avx2 {
                for half in 0..2 {
                    let x: &[f32; 8] = xs[8 * half..][..8].try_into().unwrap();
                    // SAFETY: AVX2 was detected, and the curve is packed.
                    let fast = unsafe { curve.levels_packed_avx2(x) };
                    ok &= fast[..] == want[8 * half..][..8];
                }
            }
            if avx512 {
                let mut fast = [0u32; 16];
                // SAFETY: AVX-512F was detected, the curve is packed, fast holds 16 u32.
                unsafe {
                    let v = curve.levels_packed_avx512(xs);
                    _mm512_storeu_si512(fast.as_mut_ptr().cast(), v);
                }
                ok &= fast == want;
            }
            ok
        };
        let one = 1f32.to_bits();
        let bad = (0..=one / 16)
            .into_par_iter()
            .filter(|&chunk| {
                let xs = std::array::from_fn(|i| f32::from_bits((chunk * 16 + i as u32).min(one)));
                !check(&xs)
            })
            .count();
        assert_eq!(bad, 0, "vectors of f32 in [0, 1] with a wrong level");
        let odd = [
            -0.0,
            -1.0,
            -f32::MAX,
            1.000_000_1,
            2.0,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::MIN_POSITIVE,
            1e-45,
            0.0031308,
            0.5,
            1.0,
            0.999_999_94,
            -f32::INFINITY,
            f32::MAX,
        ];
        assert!(check(&odd));
    }
}
