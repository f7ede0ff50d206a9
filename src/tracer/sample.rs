//! Where a pixel's samples fall. One sample looks through the pixel centre (the talk's image);
//! N = n² samples are jittered on an n×n grid; other counts follow the R2 low-discrepancy
//! sequence with a per-pixel random shift. Every random number is a hash of (frame, pixel,
//! sample), so any pixel of any frame is reproducible alone, on any thread or machine.

/// Sub-pixel offsets in [0, 1)² of sample `k` of `count` for pixel `pixel` of frame `frame`.
#[inline]
pub fn offset(frame: u64, pixel: u64, k: u32, count: u32) -> (f64, f64) {
    if count <= 1 {
        return (0.5, 0.5);
    }
    let n = count.isqrt();
    if n * n == count {
        let (jx, jy) = random2(frame, pixel, k);
        let (cx, cy) = (f64::from(k % n), f64::from(k / n));
        return ((cx + jx) / f64::from(n), (cy + jy) / f64::from(n));
    }
    r2(frame, pixel, k)
}

/// Sample `k` of the R2 sequence (Roberts 2018, the 2-D golden-ratio sequence) shifted per
/// pixel: every prefix is well spread, so adaptive sampling can extend a pixel's samples.
#[inline]
pub fn r2(frame: u64, pixel: u64, k: u32) -> (f64, f64) {
    const A1: f64 = 0.754_877_666_246_692_7;
    const A2: f64 = 0.569_840_290_998_053_2;
    let (sx, sy) = random2(frame, pixel, u32::MAX);
    let i = f64::from(k) + 1.0;
    ((sx + i * A1).fract(), (sy + i * A2).fract())
}

/// Independent uniform offsets (the baseline jittering is measured against).
#[inline]
pub fn independent(frame: u64, pixel: u64, k: u32) -> (f64, f64) {
    random2(frame ^ 0x5bd1_e995, pixel, k)
}

/// Two uniform numbers in [0, 1) from a hash of the three indices.
#[inline]
fn random2(frame: u64, pixel: u64, k: u32) -> (f64, f64) {
    let h = mix(mix(mix(0x9e37_79b9_7f4a_7c15 ^ frame) ^ pixel) ^ u64::from(k));
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
