//! Four lanes' footprints at a time in AVX2 registers: each lane does `Footprint::new`'s
//! operations (docs/spec/texture.md, **Footprint**) in their order on the same values, so every
//! footprint is the scalar one bit for bit (a unit test compares the two). One lane at a time
//! the rule is a dependent chain of three square roots and three divisions, which took a
//! quarter of the checker talk's time.

use super::{Axes, Footprint};
use crate::lanes::MAX_LANES;
use glam::DVec3;
use std::arch::x86_64::*;

/// The footprints of lanes `first .. first + 4` for the cones of full width `width`, and the
/// lanes (bit j for lane first + j) that the scalar rule must make instead: those whose
/// d × n is the zero vector, where the rule falls back to another axis.
///
/// # Safety
/// The CPU must have AVX2; `first + 4 ≤ MAX_LANES`.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn four(
    n: &Axes,
    d: &Axes,
    width: &[f64; MAX_LANES],
    first: usize,
) -> ([Footprint; 4], u32) {
    assert!(first + 4 <= MAX_LANES);
    let load = |a: &[f64; MAX_LANES]| {
        // SAFETY: `a[first..first + 4]` is in bounds (asserted above).
        unsafe { _mm256_loadu_pd(a[first..].as_ptr()) }
    };
    let (n, d) = (n.each_ref().map(load), d.each_ref().map(load));
    let r = _mm256_mul_pd(_mm256_set1_pd(0.5), load(width));
    let m = cross(d, n);
    let zero = _mm256_setzero_pd();
    let is_zero = m.map(|c| _mm256_cmp_pd::<_CMP_EQ_OQ>(c, zero));
    let redo = _mm256_and_pd(_mm256_and_pd(is_zero[0], is_zero[1]), is_zero[2]);
    let redo = _mm256_movemask_pd(redo) as u32;
    // normalize: m · (1 / |m|).
    let recip = _mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(dot(m, m)));
    let across = m.map(|c| _mm256_mul_pd(c, recip));
    let e2 = cross(across, d);
    let minor = across.map(|c| _mm256_mul_pd(c, r));
    let q = _mm256_div_pd(dot(e2, n), dot(d, n));
    let major: [__m256d; 3] =
        std::array::from_fn(|i| _mm256_mul_pd(_mm256_sub_pd(e2[i], _mm256_mul_pd(d[i], q)), r));
    let ratio = _mm256_ceil_pd(_mm256_div_pd(
        _mm256_sqrt_pd(dot(major, major)),
        _mm256_sqrt_pd(dot(minor, minor)),
    ));
    let out = |v: __m256d| {
        let mut a = [0.0f64; 4];
        // SAFETY: `a` holds four f64.
        unsafe { _mm256_storeu_pd(a.as_mut_ptr(), v) };
        a
    };
    let (minor, major, ratio) = (minor.map(out), major.map(out), out(ratio));
    let lane = |j: usize| Footprint {
        minor: DVec3::new(minor[0][j], minor[1][j], minor[2][j]),
        major: DVec3::new(major[0][j], major[1][j], major[2][j]),
        taps: super::taps_of(ratio[j]),
    };
    (std::array::from_fn(lane), redo)
}

/// a × b as `DVec3::cross` computes it.
#[inline]
#[target_feature(enable = "avx2")]
fn cross(a: [__m256d; 3], b: [__m256d; 3]) -> [__m256d; 3] {
    let term =
        |i: usize, j: usize| _mm256_sub_pd(_mm256_mul_pd(a[i], b[j]), _mm256_mul_pd(b[i], a[j]));
    [term(1, 2), term(2, 0), term(0, 1)]
}

/// a · b as `DVec3::dot` computes it: (x + y) + z.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) fn dot(a: [__m256d; 3], b: [__m256d; 3]) -> __m256d {
    let p = |i: usize| _mm256_mul_pd(a[i], b[i]);
    _mm256_add_pd(_mm256_add_pd(p(0), p(1)), p(2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random cones (unit and unnormalised directions and normals, grazing and head-on, zero,
    /// huge, tiny, NaN and infinite components and widths) through the four-lane footprints
    /// and the scalar rule: the same bits, and the lanes left to the scalar rule are those
    /// whose d × n is zero.
    #[test]
    fn four_footprints_at_once_are_the_scalar_ones_bit_for_bit() {
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut next = crate::testing::uniform(0x9e37_79b9_7f4a_7c15);
        let specials = [0.0, -0.0, 1.0, -1.0, 1e-300, 1e300, f64::INFINITY, f64::NAN];
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for case in 0..100_000usize {
            let (mut n, mut d, mut width) = (
                [[0.0; MAX_LANES]; 3],
                [[0.0; MAX_LANES]; 3],
                [0.0; MAX_LANES],
            );
            for k in 0..MAX_LANES {
                let scale = [1e-3, 1.0, 1e6][(case + k) % 3];
                for i in 0..3 {
                    n[i][k] = next() - 0.5;
                    d[i][k] = (next() - 0.5) * scale;
                }
                width[k] = next() * [1e-6, 1e-2, 3.0][(case + 2 * k) % 3];
                match (case + k) % 11 {
                    // d along n: the rule's fallback axes.
                    0 => (0..3).for_each(|i| d[i][k] = -2.0 * n[i][k]),
                    1 => d[(case + k) % 3][k] = specials[case % specials.len()],
                    2 => width[k] = specials[(case / 3) % specials.len()],
                    3 => (0..3).for_each(|i| n[i][k] = f64::from(u8::from(i == 1))),
                    _ => {}
                }
            }
            let first = 4 * (case % (MAX_LANES / 4));
            // SAFETY: AVX2 was detected; first + 4 ≤ MAX_LANES.
            let (fast, redo) = unsafe { four(&n, &d, &width, first) };
            for (j, f) in fast.iter().enumerate() {
                let k = first + j;
                let v = |a: &Axes| DVec3::new(a[0][k], a[1][k], a[2][k]);
                let (dk, nk) = (v(&d), v(&n));
                assert_eq!(
                    redo >> j & 1 == 1,
                    dk.cross(nk) == DVec3::ZERO,
                    "case {case}"
                );
                if redo >> j & 1 == 1 {
                    continue;
                }
                let s = Footprint::new(dk, nk, 0.5 * width[k]);
                let pairs = (f.minor.to_array().into_iter().zip(s.minor.to_array()))
                    .chain(f.major.to_array().into_iter().zip(s.major.to_array()));
                for (a, b) in pairs {
                    assert!(same(a, b), "case {case} lane {j}: {a:e} against {b:e}");
                }
                assert_eq!(f.taps, s.taps, "case {case} lane {j}");
            }
        }
    }
}
