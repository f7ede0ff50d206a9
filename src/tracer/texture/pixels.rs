//! Four lanes' pixels at a time in AVX2 registers (docs/spec/texture.md, **The pixel**): each
//! lane's parallelogram (`Patch::new`'s operations in its order, on the same values) and, where
//! that parallelogram's box lies in one cell along every axis, the checker's sign there (the
//! axes' test of `patch::checker`). Both are the scalar rule bit for bit (unit tests compare
//! them); lanes whose box crosses a cell boundary are left to the scalar closed forms. One lane
//! at a time these were two dependent chains of divisions, a quarter of the checker talk's time.

use super::{Patch, Quad, TINY_BOX, footprint::dot, taps::sign};
use glam::DVec3;
use std::arch::x86_64::*;

/// The patches (`Patch::new`) of four lanes' eye rays from origins `o` with hits `p`, unit
/// normals `n` facing the rays and pixel rays `(centre, right, down)`, and the lanes (bit j
/// for lane j) for which `Patch::new` gives one.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn patches(
    o: &Quad,
    p: &Quad,
    n: &Quad,
    (c, right, down): (&Quad, &Quad, &Quad),
) -> ([Patch; 4], u32) {
    // SAFETY: each row holds four f64.
    let load = |a: &Quad| a.map(|x| unsafe { _mm256_loadu_pd(x.as_ptr()) });
    let (o, p, n, c) = (load(o), load(p), load(n), load(c));
    let (right, down) = (load(right), load(down));
    let q = dot(n, c);
    let to_hit: [__m256d; 3] = std::array::from_fn(|i| _mm256_sub_pd(p[i], o[i]));
    let t = _mm256_div_pd(dot(to_hit, n), q);
    // q < 0 and t > 0, both false for NaN.
    let ahead = _mm256_and_pd(
        _mm256_cmp_pd::<_CMP_LT_OQ>(q, _mm256_setzero_pd()),
        _mm256_cmp_pd::<_CMP_GT_OQ>(t, _mm256_setzero_pd()),
    );
    let half = _mm256_mul_pd(_mm256_set1_pd(0.5), t);
    let edge = |s: [__m256d; 3]| -> [__m256d; 3] {
        let k = _mm256_div_pd(dot(s, n), q);
        std::array::from_fn(|i| _mm256_mul_pd(_mm256_sub_pd(s[i], _mm256_mul_pd(c[i], k)), half))
    };
    let offset: [__m256d; 3] =
        std::array::from_fn(|i| _mm256_sub_pd(_mm256_add_pd(o[i], _mm256_mul_pd(c[i], t)), p[i]));
    let (a, b) = (edge(right), edge(down));
    let mut valid = ahead;
    for v in offset.iter().chain(&a).chain(&b) {
        valid = _mm256_and_pd(valid, finite(*v));
    }
    let out = |v: [__m256d; 3]| {
        v.map(|x| {
            let mut a = [0.0f64; 4];
            // SAFETY: `a` holds four f64.
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), x) };
            a
        })
    };
    let (offset, a, b) = (out(offset), out(a), out(b));
    let lane = |j: usize| Patch {
        offset: DVec3::new(offset[0][j], offset[1][j], offset[2][j]),
        a: DVec3::new(a[0][j], a[1][j], a[2][j]),
        b: DVec3::new(b[0][j], b[1][j], b[2][j]),
    };
    (std::array::from_fn(lane), _mm256_movemask_pd(valid) as u32)
}

/// For four lanes' parallelograms (centre `c`, half-edges `a`, `b`) and checker cell sizes
/// `size`: σ, the product of the axes' signs, and the lanes (bit j for lane j) whose every axis
/// is held (`patch::checker`'s test), where the checker's mean is σ.
///
/// # Safety
/// The CPU must have AVX2.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn one_cell(c: &Quad, a: &Quad, b: &Quad, size: &[f64; 4]) -> ([f64; 4], u32) {
    // SAFETY: `size` holds four f64.
    let size = unsafe { _mm256_loadu_pd(size.as_ptr()) };
    let abs = |v: __m256d| _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
    let (mut sigma, mut held) = (
        _mm256_set1_pd(1.0),
        _mm256_castsi256_pd(_mm256_set1_epi64x(-1)),
    );
    for i in 0..3 {
        // SAFETY: each row holds four f64.
        let ld = |q: &Quad| unsafe { _mm256_loadu_pd(q[i].as_ptr()) };
        let x = _mm256_div_pd(ld(c), size);
        let h = _mm256_div_pd(_mm256_add_pd(abs(ld(a)), abs(ld(b))), size);
        let tiny = _mm256_cmp_pd::<_CMP_LT_OQ>(h, _mm256_set1_pd(TINY_BOX));
        let low = _mm256_floor_pd(_mm256_sub_pd(x, h));
        let same = _mm256_cmp_pd::<_CMP_EQ_OQ>(low, _mm256_floor_pd(_mm256_add_pd(x, h)));
        let k = _mm256_blendv_pd(low, _mm256_floor_pd(x), tiny);
        held = _mm256_and_pd(held, _mm256_or_pd(tiny, same));
        sigma = _mm256_mul_pd(sigma, sign(k));
    }
    let mut out = [0.0f64; 4];
    // SAFETY: `out` holds four f64.
    unsafe { _mm256_storeu_pd(out.as_mut_ptr(), sigma) };
    (out, _mm256_movemask_pd(held) as u32)
}

/// All ones in the lanes whose value is finite (not ±∞, not NaN).
#[inline]
#[target_feature(enable = "avx2")]
fn finite(v: __m256d) -> __m256d {
    let abs = _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
    _mm256_cmp_pd::<_CMP_LT_OQ>(abs, _mm256_set1_pd(f64::INFINITY))
}

#[cfg(test)]
mod tests {
    use super::super::{Native, patch};
    use super::*;

    /// Random eye rays and pixels (grazing and head-on, behind the ray, zero, huge, tiny, NaN
    /// and infinite components) through the four-lane patches and `Patch::new`, then random
    /// cells through the four-lane axes' test and `patch::checker`: the same bits, the same
    /// lanes given a patch, and σ's colour wherever the four-lane test claims a lane.
    #[test]
    fn four_pixels_at_once_are_the_scalar_ones_bit_for_bit() {
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut next = crate::testing::uniform(0x2545_f491_4f6c_dd1d);
        let specials = [0.0, -0.0, 1e-300, 1e300, f64::INFINITY, f64::NAN];
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let colors = [DVec3::new(1.0, 2.0, 3.0), DVec3::new(5.0, 7.0, 11.0)];
        let (mut claimed, mut patched) = (0, 0);
        for case in 0..50_000usize {
            let mut q: [Quad; 6] = [[[0.0; 4]; 3]; 6];
            for (j, k) in (0..4).map(|j| (j, case + j)) {
                let scale = [1e-3, 1.0, 1e4][k % 3];
                #[allow(clippy::needless_range_loop)] // six arrays, one index
                for i in 0..3 {
                    q[0][i][j] = (next() - 0.5) * scale; // o
                    q[1][i][j] = q[0][i][j] + (next() - 0.5) * 20.0; // p
                    q[2][i][j] = next() - 0.5; // n
                    q[3][i][j] = q[1][i][j] - q[0][i][j] + (next() - 0.5) * 1e-2; // centre
                    q[4][i][j] = (next() - 0.5) * 1e-3; // right
                    q[5][i][j] = (next() - 0.5) * 1e-3; // down
                }
                // Normals facing the centre ray, mostly.
                let dot: f64 = (0..3).map(|i| q[2][i][j] * q[3][i][j]).sum();
                if dot > 0.0 && k % 7 != 0 {
                    (0..3).for_each(|i| q[2][i][j] = -q[2][i][j]);
                }
                if k % 13 == 0 {
                    q[k % 6][(k / 6) % 3][j] = specials[(case / 13) % specials.len()];
                }
            }
            // SAFETY: AVX2 was detected.
            let (fast, valid) = unsafe { patches(&q[0], &q[1], &q[2], (&q[3], &q[4], &q[5])) };
            let (mut c, mut a, mut b) = ([[0.0; 4]; 3], [[0.0; 4]; 3], [[0.0; 4]; 3]);
            for j in 0..4 {
                let v = |x: &Quad| DVec3::new(x[0][j], x[1][j], x[2][j]);
                let slow = Patch::new(v(&q[0]), v(&q[1]), v(&q[2]), (v(&q[3]), v(&q[4]), v(&q[5])));
                assert_eq!(valid >> j & 1 == 1, slow.is_some(), "case {case} lane {j}");
                let Some(slow) = slow else { continue };
                patched += 1;
                let f = fast[j];
                let pairs = [(f.offset, slow.offset), (f.a, slow.a), (f.b, slow.b)];
                for (x, y) in pairs
                    .iter()
                    .flat_map(|(x, y)| x.to_array().into_iter().zip(y.to_array()))
                {
                    assert!(same(x, y), "case {case} lane {j}: {x:e} against {y:e}");
                }
                for i in 0..3 {
                    c[i][j] = q[1][i][j] + f.offset[i];
                    (a[i][j], b[i][j]) = (f.a[i], f.b[i]);
                }
                if case % 5 == 0 {
                    c[case % 3][j] = (c[case % 3][j] * 4.0).round() / 4.0; // on a cell edge
                }
            }
            let size = [0.25, 1.0, 0.1, 3.0].map(|s| s * [1.0, 1e-2, 1e2][case % 3]);
            // SAFETY: AVX2 was detected.
            let (sigma, one) = unsafe { one_cell(&c, &a, &b, &size) };
            for j in (0..4).filter(|j| (valid & one) >> j & 1 == 1) {
                claimed += 1;
                let v = |x: &Quad| DVec3::new(x[0][j], x[1][j], x[2][j]);
                let slow = patch::checker::<Native>(size[j], &colors, (v(&c), v(&a), v(&b)));
                assert_eq!(
                    slow,
                    Some(patch::mix(&colors, sigma[j])),
                    "case {case} lane {j}"
                );
            }
        }
        // Both paths were exercised.
        assert!(
            patched > 100_000 && claimed > 20_000,
            "{patched} patches, {claimed} claimed"
        );
    }
}
