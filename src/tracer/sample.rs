//! Where a pixel's samples fall. One sample looks through the pixel centre (the talk's image);
//! N = n² samples are jittered on an n×n grid; other counts follow the R2 low-discrepancy
//! sequence with a per-pixel random shift. Every random number is a hash of (frame, pixel,
//! sample), so any pixel of any frame is reproducible alone, on any thread or machine.
//!
//! With motion blur or depth of field, stratified samples are Owen-scrambled Sobol' points
//! that place the pixel position, the lens point and the instant together (`sobol`); a lone
//! sample keeps the pixel centre and independent samples stay independent, each with a time
//! and a lens point drawn beside them (`Dims`; R2 samples of `sampler: random` continue
//! with the R3 sequence).

/// How a pass places a pixel's samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pattern {
    /// One sample, the pixel centre.
    Centre,
    /// n² samples jittered on an n×n grid.
    Grid(u32),
    /// The R2 sequence with a per-pixel shift (other counts, and samples added to a pixel).
    R2,
    /// Independent uniform positions.
    Independent,
    /// Owen-scrambled Sobol' points in the pixel, on the lens and in time at once (frames
    /// with motion blur or depth of field; see `sobol`).
    Sobol,
}

impl Pattern {
    /// The pattern of `count` stratified samples from scratch.
    pub fn stratified(count: u32) -> Pattern {
        let n = count.isqrt();
        match count {
            0 | 1 => Pattern::Centre,
            _ if n * n == count => Pattern::Grid(n),
            _ => Pattern::R2,
        }
    }
}

/// What a pixel's samples need that depends only on (frame, pixel): computed once per pixel.
#[derive(Debug, Clone, Copy)]
pub struct Seed {
    /// The hash state after mixing in the frame and the pixel.
    state: u64,
    /// R2's shift for this pixel.
    shift: (f64, f64),
}

impl Seed {
    pub fn new(pattern: Pattern, frame: u64, pixel: u64) -> Seed {
        let frame = match pattern {
            Pattern::Centre => {
                return Seed {
                    state: 0,
                    shift: (0.0, 0.0),
                };
            }
            Pattern::Independent => frame ^ 0x5bd1_e995,
            _ => frame,
        };
        let state = state(frame, pixel);
        let shift = match pattern {
            Pattern::R2 => random2(state, u32::MAX),
            _ => (0.0, 0.0),
        };
        Seed { state, shift }
    }

    /// Sub-pixel offsets in [0, 1)² of sample `k`.
    #[inline]
    pub fn offset(&self, pattern: Pattern, k: u32) -> (f64, f64) {
        match pattern {
            Pattern::Centre => (0.5, 0.5),
            Pattern::Grid(n) => {
                let (jx, jy) = random2(self.state, k);
                let (cx, cy) = (f64::from(k % n), f64::from(k / n));
                ((cx + jx) / f64::from(n), (cy + jy) / f64::from(n))
            }
            Pattern::R2 => {
                // Sample k of the R2 sequence (Roberts 2018, the 2-D golden-ratio sequence):
                // every prefix is well spread, so adaptive sampling can extend a pixel.
                const A1: f64 = 0.754_877_666_246_692_7;
                const A2: f64 = 0.569_840_290_998_053_2;
                let i = f64::from(k) + 1.0;
                (
                    (self.shift.0 + i * A1).fract(),
                    (self.shift.1 + i * A2).fract(),
                )
            }
            Pattern::Independent => random2(self.state, k),
            Pattern::Sobol => unreachable!("Sobol' points come from `sobol::Packet::at`"),
        }
    }
}

/// A pixel's hash state, mix(mix(0x9e37_79b9_7f4a_7c15 ⊕ frame) ⊕ pixel): what its
/// samples' random numbers are drawn from.
#[inline]
pub fn state(frame: u64, pixel: u64) -> u64 {
    mix(mix(0x9e37_79b9_7f4a_7c15 ^ frame) ^ pixel)
}

/// Sub-pixel offsets in [0, 1)² of sample `k` of `count` for pixel `pixel` of frame `frame`.
pub fn offset(frame: u64, pixel: u64, k: u32, count: u32) -> (f64, f64) {
    let pattern = Pattern::stratified(count);
    Seed::new(pattern, frame, pixel).offset(pattern, k)
}

/// Sample `k` of the R2 sequence shifted for pixel `pixel` of frame `frame`.
pub fn r2(frame: u64, pixel: u64, k: u32) -> (f64, f64) {
    Seed::new(Pattern::R2, frame, pixel).offset(Pattern::R2, k)
}

/// Independent uniform offsets (the baseline jittering is measured against).
pub fn independent(frame: u64, pixel: u64, k: u32) -> (f64, f64) {
    Seed::new(Pattern::Independent, frame, pixel).offset(Pattern::Independent, k)
}

/// Time and lens coordinates of a pixel's samples: what depends only on (frame, pixel).
#[derive(Debug, Clone, Copy)]
pub struct Dims {
    /// The hash state of this pixel's extra dimensions.
    state: u64,
    /// R3's shift for this pixel.
    shift: [f64; 3],
}

/// Separates the hashes of the extra dimensions from those of the pixel position.
const DIMS: u64 = 0x6a09_e667_f3bc_c909;

impl Dims {
    pub fn new(pattern: Pattern, frame: u64, pixel: u64) -> Dims {
        let state = mix(mix(mix(0x9e37_79b9_7f4a_7c15 ^ frame) ^ pixel) ^ DIMS);
        let shift = match pattern {
            Pattern::R2 => random3(mix(state ^ u64::from(u32::MAX))),
            _ => [0.0; 3],
        };
        Dims { state, shift }
    }

    /// Sample `k`'s time and lens coordinates, [t, a, b] ∈ [0, 1)³.
    #[inline]
    pub fn at(&self, pattern: Pattern, k: u32) -> [f64; 3] {
        match pattern {
            Pattern::R2 => {
                // The R3 sequence (Roberts 2018): 1/φ₃^d, φ₃ the real root of x⁴ = x + 1.
                const B: [f64; 3] = [
                    0.819_172_513_396_164_5,
                    0.671_043_606_703_789_3,
                    0.549_700_477_901_970_3,
                ];
                let i = f64::from(k) + 1.0;
                [0, 1, 2].map(|d| (self.shift[d] + i * B[d]).fract())
            }
            // A lone sample, independent samples (a grid's are Sobol' points on film).
            _ => random3(mix(self.state ^ u64::from(k))),
        }
    }
}

/// Separates the hashes of light samples from the others (SHA-256's second initial word).
const LIGHTS: u64 = 0xbb67_ae85_84ca_a73b;

/// A pixel's light state: what the points it takes on area lights depend on besides the
/// light and the sample, mix(mix(mix(0x9e37_79b9_7f4a_7c15 ⊕ frame) ⊕ pixel) ⊕ LIGHTS).
#[inline]
pub fn light_seed(frame: u64, pixel: u64) -> u64 {
    mix(mix(mix(0x9e37_79b9_7f4a_7c15 ^ frame) ^ pixel) ^ LIGHTS)
}

/// The digital shift (sx, sy) of light `index` (its place in the file's `lights:`, every kind
/// counted) for a pixel whose light state is `seed`: the high and low 32 bits of
/// mix(seed ⊕ index).
#[inline]
pub fn light_shift(seed: u64, index: usize) -> (u32, u32) {
    let h = mix(seed ^ index as u64);
    ((h >> 32) as u32, h as u32)
}

/// Point `g` of the (0,2)-sequence in base 2, as 32-bit fractions: the van der Corput radical
/// inverse (g's bits reversed) and Sobol's second dimension, the XOR of v_i over the set bits
/// i of g with v_0 = 2^31, v_i = v_(i-1) ⊕ (v_(i-1) ≫ 1). Every aligned run of 2^k points
/// puts one point in each of the 2^k elementary rectangles of every shape, and an XOR shift
/// keeps that.
#[inline]
pub fn sobol02(g: u32) -> (u32, u32) {
    let (mut y, mut v, mut bits) = (0u32, 1u32 << 31, g);
    while bits != 0 {
        if bits & 1 != 0 {
            y ^= v;
        }
        bits >>= 1;
        v ^= v >> 1;
    }
    (g.reverse_bits(), y)
}

/// The points g, g + 1, … of `sobol02` in turn, each from the one before by the bits that
/// change: g ⊕ (g + 1) is a run of t + 1 low ones (t the trailing ones of g), and both
/// coordinates are linear in g's bits over XOR, so the radical inverse flips the run's
/// reversal and Sobol's coordinate takes the XOR of v_0 … v_t (`RUNS`). The same words as
/// `sobol02(g)` for every g, at a few instructions a point instead of a loop over g's bits.
#[derive(Debug, Clone, Copy)]
pub struct Points02 {
    g: u32,
    x: u32,
    y: u32,
}

/// RUNS[t] = v_0 ⊕ v_1 ⊕ … ⊕ v_t, Sobol's second coordinate of 2^(t+1) − 1.
const RUNS: [u32; 32] = {
    let (mut runs, mut v, mut acc, mut t) = ([0u32; 32], 1u32 << 31, 0u32, 0);
    while t < 32 {
        acc ^= v;
        runs[t] = acc;
        v ^= v >> 1;
        t += 1;
    }
    runs
};

impl Points02 {
    /// The walk from point `g`.
    #[inline]
    pub fn at(g: u32) -> Points02 {
        let (x, y) = sobol02(g);
        Points02 { g, x, y }
    }

    /// The current point's two 32-bit coordinates (`sobol02` of its index).
    #[inline]
    pub fn words(&self) -> (u32, u32) {
        (self.x, self.y)
    }

    /// Moves to the next point (after 2^32 − 1 it wraps to 0, as `sobol02` of g + 1 would).
    #[inline]
    pub fn advance(&mut self) {
        let t = self.g.trailing_ones();
        if t == 32 {
            *self = Points02::at(0);
            return;
        }
        self.x ^= !(u32::MAX >> (t + 1));
        self.y ^= RUNS[t as usize];
        self.g += 1;
    }
}

/// 32 bits as a fraction in [0, 1): b·2^-32, exact.
#[inline]
pub fn unit32(b: u32) -> f64 {
    f64::from(b) * (1.0 / 4_294_967_296.0)
}

/// Three uniform numbers in [0, 1) from one hash.
#[inline]
fn random3(h: u64) -> [f64; 3] {
    [unit(h), unit(mix(h)), unit(mix(mix(h)))]
}

/// The top 53 bits of a hash as a number in [0, 1).
#[inline]
fn unit(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Two uniform numbers in [0, 1) from a hash of the pixel's state and the sample index.
#[inline]
fn random2(state: u64, k: u32) -> (f64, f64) {
    let h = mix(state ^ u64::from(k));
    (unit(h), unit(mix(h)))
}

/// splitmix64's finaliser: a fast bijective mix with good avalanche.
#[inline]
pub(super) fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_is_the_centre() {
        assert_eq!(offset(3, 99, 0, 1), (0.5, 0.5));
    }

    #[test]
    fn square_counts_put_one_sample_in_each_cell() {
        let mut cells = [false; 16];
        for k in 0..16 {
            let (u, v) = offset(7, 12345, k, 16);
            assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
            let cell = (v * 4.0) as usize * 4 + (u * 4.0) as usize;
            assert!(!cells[cell], "two samples in cell {cell}");
            cells[cell] = true;
        }
    }

    /// Every aligned run of 2^k points of the shifted (0,2)-sequence has one point in each
    /// elementary rectangle of area 2^-k, of every shape.
    #[test]
    fn light_points_are_a_shifted_0_2_sequence() {
        let (sx, sy) = light_shift(light_seed(7, 1234), 3);
        for k in 0..=10u32 {
            for start in [0u32, 1 << k, 5 << k] {
                for bits_x in 0..=k {
                    let bits_y = k - bits_x;
                    let mut seen = vec![false; 1 << k];
                    for g in start..start + (1 << k) {
                        let (x, y) = sobol02(g);
                        let (x, y) = (x ^ sx, y ^ sy);
                        let cx = if bits_x == 0 { 0 } else { x >> (32 - bits_x) };
                        let cy = if bits_y == 0 { 0 } else { y >> (32 - bits_y) };
                        let cell = (cx << bits_y | cy) as usize;
                        assert!(!seen[cell], "k {k} start {start} shape {bits_x}");
                        seen[cell] = true;
                    }
                }
            }
        }
        assert_eq!(sobol02(0), (0, 0));
        // The walk gives the same words as the definition, from any start and across carries.
        for start in [0, 1, 7, 4095 * 16, (1 << 24) - 3, u32::MAX - 2] {
            let mut walk = Points02::at(start);
            for n in 0..70u32 {
                assert_eq!(
                    walk.words(),
                    sobol02(start.wrapping_add(n)),
                    "{start} + {n}"
                );
                walk.advance();
            }
        }
        assert_eq!(sobol02(1), (1 << 31, 1 << 31));
        assert_eq!(sobol02(2), (1 << 30, 0xc000_0000));
        assert_eq!(sobol02(3), (0xc000_0000, 0x4000_0000));
        assert_eq!(unit32(u32::MAX), 1.0 - 1.0 / 4_294_967_296.0);
    }

    #[test]
    fn time_and_lens_coordinates_are_the_readmes() {
        // Bits from tests/reference/sample_dims_reference.py, written from "Time and lens
        // coordinates" in docs/spec/tracer.md alone. Grid has none: on film frames its
        // samples are Sobol' points (see sobol.rs's film_points_are_the_specs).
        let cases = [
            (
                Pattern::R2,
                7,
                12345,
                0,
                [0x3fd4bfaf88c29604, 0x3feac619c943e4eb, 0x3fda58d6708254b0],
            ),
            (
                Pattern::R2,
                7,
                12345,
                31,
                [0x3fe6fe57494d6460, 0x3fe472f77c12b1c0, 0x3fdcf3e8c03071c0],
            ),
            (
                Pattern::Centre,
                7,
                12345,
                0,
                [0x3fe9539a7dce2440, 0x3fe99d1b48f03702, 0x3fee0671cead9d54],
            ),
        ];
        for (pattern, frame, pixel, k, want) in cases {
            let got = Dims::new(pattern, frame, pixel)
                .at(pattern, k)
                .map(f64::to_bits);
            assert_eq!(
                got, want,
                "{pattern:?} frame {frame} pixel {pixel} sample {k}"
            );
        }
    }

    #[test]
    fn samples_depend_only_on_their_indices() {
        assert_eq!(offset(1, 2, 3, 5), offset(1, 2, 3, 5));
        assert_ne!(offset(1, 2, 3, 5), offset(2, 2, 3, 5));
        assert_ne!(offset(1, 2, 3, 16), offset(1, 3, 3, 16));
    }
}
