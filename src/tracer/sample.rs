//! Where a pixel's samples fall. One sample looks through the pixel centre (the talk's image);
//! N = n² samples are jittered on an n×n grid; other counts follow the R2 low-discrepancy
//! sequence with a per-pixel random shift. Every random number is a hash of (frame, pixel,
//! sample), so any pixel of any frame is reproducible alone, on any thread or machine.

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
        let state = mix(mix(0x9e37_79b9_7f4a_7c15 ^ frame) ^ pixel);
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
        }
    }
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

/// Two uniform numbers in [0, 1) from a hash of the pixel's state and the sample index.
#[inline]
fn random2(state: u64, k: u32) -> (f64, f64) {
    let h = mix(state ^ u64::from(k));
    let unit = |bits: u64| (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    (unit(h), unit(mix(h)))
}

/// splitmix64's finaliser: a fast bijective mix with good avalanche.
#[inline]
fn mix(mut z: u64) -> u64 {
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

    #[test]
    fn samples_depend_only_on_their_indices() {
        assert_eq!(offset(1, 2, 3, 5), offset(1, 2, 3, 5));
        assert_ne!(offset(1, 2, 3, 5), offset(2, 2, 3, 5));
        assert_ne!(offset(1, 2, 3, 16), offset(1, 3, 3, 16));
    }
}
