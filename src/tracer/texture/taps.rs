//! A checker lookup's taps four at a time in AVX2 registers: each lane does the scalar
//! definition's operations (`texture::checker` and `square_average`, docs/spec/texture.md)
//! in their order on the same values, so the sum is the scalar loop's bit for bit (a unit test
//! compares the two). Near a horizon a lookup takes up to 16 taps, each three box averages:
//! half the checker talk's instructions were these, one tap at a time.

use super::{Line, TINY_BOX};
use glam::DVec3;
use std::arch::x86_64::*;

/// Σ over the line's taps, k = 0 upwards from 0, of `texture::checker(size, colors, centre(k),
/// half)`.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn checker_sum(
    size: f64,
    colors: &[DVec3; 2],
    line: &Line,
    half: &[f64; 3],
) -> DVec3 {
    let taps = f64::from(line.taps);
    let (p, major) = (line.p.to_array(), line.major.to_array());
    let (c0, c1) = (colors[0].to_array(), colors[1].to_array());
    let mut sum = [0.0f64; 3];
    let cells = exact_reciprocal(size);
    for first in (0..line.taps).step_by(4) {
        let odd = |j: u32| f64::from(2 * (first + j) + 1);
        let step = _mm256_div_pd(
            _mm256_sub_pd(
                _mm256_setr_pd(odd(0), odd(1), odd(2), odd(3)),
                _mm256_set1_pd(taps),
            ),
            _mm256_set1_pd(taps),
        );
        // A = ((1·A_x)·A_y)·A_z, as `checker` multiplies them.
        let mut a = _mm256_set1_pd(1.0);
        for i in 0..3 {
            let c = match line.held[i] {
                Some(v) => _mm256_set1_pd(v),
                None => _mm256_add_pd(
                    _mm256_set1_pd(p[i]),
                    _mm256_mul_pd(_mm256_set1_pd(major[i]), step),
                ),
            };
            let x = match cells {
                Some(r) => _mm256_mul_pd(c, _mm256_set1_pd(r)),
                None => _mm256_div_pd(c, _mm256_set1_pd(size)),
            };
            a = _mm256_mul_pd(a, square_average(x, half[i]));
        }
        let half_a = _mm256_mul_pd(_mm256_set1_pd(0.5), a);
        let w0 = _mm256_add_pd(_mm256_set1_pd(0.5), half_a);
        let w1 = _mm256_sub_pd(_mm256_set1_pd(0.5), half_a);
        let lanes = (line.taps - first).min(4) as usize;
        for ch in 0..3 {
            let v = _mm256_add_pd(
                _mm256_mul_pd(_mm256_set1_pd(c0[ch]), w0),
                _mm256_mul_pd(_mm256_set1_pd(c1[ch]), w1),
            );
            let mut out = [0.0f64; 4];
            // SAFETY: out holds 4 f64.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
            for o in &out[..lanes] {
                sum[ch] += o;
            }
        }
    }
    DVec3::from_array(sum)
}

/// `square_average(x, h)` for four x and one h.
#[inline]
#[target_feature(enable = "avx2")]
fn square_average(x: __m256d, h: f64) -> __m256d {
    if h.is_nan() || h == f64::INFINITY {
        return _mm256_setzero_pd();
    }
    if h < TINY_BOX {
        return sign(_mm256_floor_pd(x));
    }
    let hv = _mm256_set1_pd(h);
    let (a, b) = (_mm256_sub_pd(x, hv), _mm256_add_pd(x, hv));
    let (ka, kb) = (_mm256_floor_pd(a), _mm256_floor_pd(b));
    let sa = sign(ka);
    let one_cell = _mm256_cmp_pd::<_CMP_EQ_OQ>(ka, kb);
    let next = _mm256_cmp_pd::<_CMP_EQ_OQ>(kb, _mm256_add_pd(ka, _mm256_set1_pd(1.0)));
    // The lane's case picks one of three values (in one cell: sa; across one boundary:
    // two_cells; else more); a value no lane picks is not made, which skips its division.
    let (one, two) = (
        _mm256_movemask_pd(one_cell),
        _mm256_movemask_pd(_mm256_andnot_pd(one_cell, next)),
    );
    if one == 0xf {
        return sa;
    }
    let width = _mm256_sub_pd(b, a);
    let mut picked = sa;
    if one | two != 0xf {
        let more = _mm256_div_pd(_mm256_sub_pd(triangle(b), triangle(a)), width);
        picked = _mm256_blendv_pd(more, sa, one_cell);
    }
    if two != 0 {
        let sb = sign(kb);
        let two_cells = _mm256_div_pd(
            _mm256_add_pd(
                _mm256_mul_pd(sa, _mm256_sub_pd(kb, a)),
                _mm256_mul_pd(sb, _mm256_sub_pd(b, kb)),
            ),
            width,
        );
        picked = _mm256_blendv_pd(picked, two_cells, _mm256_andnot_pd(one_cell, next));
    }
    picked
}

/// 1/size where dividing by `size` is multiplying by it, bit for bit: a power of two whose
/// reciprocal is a power of two too (x/2ᵏ and x·2⁻ᵏ are the same real number, rounded once).
pub(super) fn exact_reciprocal(size: f64) -> Option<f64> {
    let normal = size.is_normal() && size > 0.0;
    let power_of_two = size.to_bits() & ((1u64 << 52) - 1) == 0;
    let r = 1.0 / size;
    (normal && power_of_two && r.is_normal()).then_some(r)
}

/// `sign(k)` of whole numbers (or ±∞, NaN): +1 where k − 2⌊k/2⌋ == 0, else −1. k·0.5 is k/2
/// (both the correctly rounded half of k).
#[inline]
#[target_feature(enable = "avx2")]
pub(super) fn sign(k: __m256d) -> __m256d {
    let halves = _mm256_floor_pd(_mm256_mul_pd(k, _mm256_set1_pd(0.5)));
    let rest = _mm256_sub_pd(k, _mm256_mul_pd(_mm256_set1_pd(2.0), halves));
    let even = _mm256_cmp_pd::<_CMP_EQ_OQ>(rest, _mm256_setzero_pd());
    _mm256_blendv_pd(_mm256_set1_pd(-1.0), _mm256_set1_pd(1.0), even)
}

/// ∫₀ᵘ S: f = u − 2⌊u/2⌋ where f < 1, else 2 − f.
#[inline]
#[target_feature(enable = "avx2")]
fn triangle(u: __m256d) -> __m256d {
    let f = _mm256_sub_pd(
        u,
        _mm256_mul_pd(
            _mm256_set1_pd(2.0),
            _mm256_floor_pd(_mm256_mul_pd(u, _mm256_set1_pd(0.5))),
        ),
    );
    let below = _mm256_cmp_pd::<_CMP_LT_OQ>(f, _mm256_set1_pd(1.0));
    _mm256_blendv_pd(_mm256_sub_pd(_mm256_set1_pd(2.0), f), f, below)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random lines of taps (points, long axes, half-widths from a point sample's to many
    /// cells, held coordinates, NaN and infinite widths) through the vector sum and the
    /// scalar loop: the same bits.
    #[test]
    fn four_taps_at_once_are_the_scalar_taps_bit_for_bit() {
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let colors = [DVec3::new(0.8, 0.7, 0.6), DVec3::new(0.1, 0.05, 0.2)];
        for case in 0..200_000 {
            let scale = [1e-3, 1.0, 40.0, 1e6][case % 4];
            let mut v = || DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * scale;
            let (p, major) = (v() * 10.0, v());
            let mut half = [0.0; 3].map(|_| next() * 3.0);
            match case % 7 {
                0 => half[case % 3] = 0.0,
                1 => half[case % 3] = 1e-13,
                2 => half[case % 3] = f64::NAN,
                3 => half[case % 3] = f64::INFINITY,
                _ => {}
            }
            let mut held = [None; 3];
            if case % 5 == 0 {
                held[1] = Some((next() - 0.5) * scale);
            }
            let line = Line {
                p,
                major,
                taps: 1 + (case % 16) as u32,
                held,
            };
            let size = [0.25, 0.5, 1.0, 3.0][case % 4 / 2 + case % 2];
            // SAFETY: AVX2 was detected.
            let fast = unsafe { checker_sum(size, &colors, &line, &half) };
            let slow = super::super::checker_taps_one_by_one::<super::super::Native>(
                size, &colors, &line, &half,
            );
            for (f, s) in fast.to_array().iter().zip(slow.to_array()) {
                assert!(
                    f.to_bits() == s.to_bits() || (f.is_nan() && s.is_nan()),
                    "case {case}: {f:e} against {s:e}"
                );
            }
        }
    }
}
