//! The concentric map of the unit square onto the disc, computed in the lanes: where on the
//! lens an eye ray leaves, and where on a sphere light's disk a light point falls.

use crate::lanes::{Lanes, Mask};

/// Shirley and Chiu's concentric map of lanes of coordinates in [0, 1)² onto the unit disc
/// (squares around the centre become rings, so stratified points stay stratified), its sine
/// and cosine from Taylor polynomials: both branches need them only for angles within ±π/4,
/// where the polynomials are exact to an ulp or two, and they are a fixed sequence of IEEE
/// products and sums, so every lane width gives the same bits (libm's per lane cost more than
/// the rest of the camera ray). The thin lens and the area lights' disks both use it.
#[inline(always)]
pub(super) fn disc<V: Lanes>(a: V, b: V) -> (V, V) {
    let (zero, one, two) = (V::splat(0.0), V::splat(1.0), V::splat(2.0));
    let (a, b) = (two * a - one, two * b - one);
    let wide = b.max(zero - b).lt(a.max(zero - a));
    let r = V::select(wide, a, b);
    // One division a lane: the branch's quotient (b′/a′ or a′/b′) of the operands it picks.
    let x = V::splat(std::f64::consts::FRAC_PI_4) * (V::select(wide, b, a) / V::select(wide, a, b));
    let (sin, cos) = sin_cos(x);
    let centre = a.eq(zero).and(b.eq(zero));
    (
        V::select(centre, zero, r * V::select(wide, cos, sin)),
        V::select(centre, zero, r * V::select(wide, sin, cos)),
    )
}

/// (−1)^i/(2i+1)! and (−1)^i/(2i)!, i = 0..=8, each the nearest f64.
const SIN: [f64; 9] = [
    1.0,
    -0.16666666666666666,
    0.008333333333333333,
    -0.0001984126984126984,
    2.7557319223985893e-06,
    -2.505210838544172e-08,
    1.6059043836821613e-10,
    -7.647163731819816e-13,
    2.8114572543455206e-15,
];
const COS: [f64; 9] = [
    1.0,
    -0.5,
    0.041666666666666664,
    -0.001388888888888889,
    2.48015873015873e-05,
    -2.755731922398589e-07,
    2.08767569878681e-09,
    -1.1470745597729725e-11,
    4.779477332387385e-14,
];

/// sin x = x·S(x²) and cos x = C(x²), S and C by Horner from the highest coefficient.
#[inline(always)]
fn sin_cos<V: Lanes>(x: V) -> (V, V) {
    let y = x * x;
    (x * horner(&SIN, y), horner(&COS, y))
}

#[inline(always)]
fn horner<V: Lanes>(c: &[f64; 9], y: V) -> V {
    let mut p = V::splat(c[8]);
    for i in (0..8).rev() {
        p = p * y + V::splat(c[i]);
    }
    p
}

/// `disc` of each point of `ab` into `out`, `V::N` points at a time (the last group padded
/// with the centre), for the tests that compare lane widths.
#[cfg(test)]
pub(super) fn disc_all<V: Lanes>(ab: &[(f64, f64)], out: &mut [(f64, f64)]) {
    for (ab, out) in ab.chunks(V::N).zip(out.chunks_mut(V::N)) {
        let a = V::from_fn(|k| ab.get(k).map_or(0.5, |p| p.0));
        let b = V::from_fn(|k| ab.get(k).map_or(0.5, |p| p.1));
        let (x, y) = disc(a, b);
        let (x, y) = (x.array(), y.array());
        for (k, o) in out.iter_mut().enumerate() {
            *o = (x[k], y[k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Kernel, Precision};

    /// Inputs where the map changes branch or degenerates: a′ = ±b′, a′ or b′ zero, the
    /// centre, values next to them, tiny and extreme coordinates, and a pseudo-random spread.
    fn inputs() -> Vec<(f64, f64)> {
        let mut v = Vec::new();
        let near = |x: f64| {
            [
                x,
                f64::from_bits(x.to_bits() + 1),
                f64::from_bits(x.to_bits() - 1),
            ]
        };
        let special = [
            0.0,
            0.5,
            1.0 - f64::EPSILON / 2.0,
            0.25,
            0.75,
            1e-300,
            0.5 + 1e-17,
            1e-9,
        ];
        for &a in &special {
            for &b in &special {
                v.push((a, b));
            }
        }
        // The diagonals a′ = b′ and a′ = −b′, exactly and an ulp apart.
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..400 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = (s >> 11) as f64 / (1u64 << 53) as f64;
            let x = x.max(f64::MIN_POSITIVE);
            for y in near(x) {
                v.extend([
                    (x, y),
                    (y, x),
                    (x, 1.0 - y),
                    (1.0 - y, x),
                    (x, 0.5),
                    (0.5, x),
                ]);
            }
            let t = (s.rotate_left(17) >> 11) as f64 / (1u64 << 53) as f64;
            v.push((x, t));
        }
        // The 2^-32 grid the area lights use, near the centre and the edges.
        for k in [
            0u32,
            1,
            2,
            1 << 31,
            (1 << 31) + 1,
            (1 << 31) - 1,
            u32::MAX,
            u32::MAX - 1,
        ] {
            for l in [0u32, 1, 1 << 31, (1 << 31) - 1, u32::MAX, 12345] {
                let unit = |b: u32| f64::from(b) / 4_294_967_296.0;
                v.push((unit(k), unit(l)));
            }
        }
        v
    }

    /// Every kernel width gives the scalar kernel's bits for every point, in both precisions.
    #[test]
    fn every_width_maps_like_the_scalar_lane() {
        let ab = inputs();
        for precision in [Precision::F64, Precision::F32] {
            let want = Kernel::Scalar.disc(precision, &ab);
            for kernel in Kernel::ALL.into_iter().filter(|k| k.supported()) {
                let got = kernel.disc(precision, &ab);
                for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(
                        (g.0.to_bits(), g.1.to_bits()),
                        (w.0.to_bits(), w.1.to_bits()),
                        "{} {precision:?} at {:?}",
                        kernel.name(),
                        ab[i]
                    );
                }
            }
        }
    }

    /// In f64 the map agrees with the textbook one (libm's sin and cos of the angle) to a few
    /// ulps of the radius, lands in the unit disc, and keeps the centre and the axes exact.
    #[test]
    fn the_map_is_shirley_and_chius_to_a_few_ulps() {
        let ab = inputs();
        let got = Kernel::Scalar.disc(Precision::F64, &ab);
        for (&(a, b), &(x, y)) in ab.iter().zip(&got) {
            let (a2, b2) = (2.0 * a - 1.0, 2.0 * b - 1.0);
            let q = std::f64::consts::FRAC_PI_4;
            let (r, phi) = match (a2, b2) {
                (0.0, 0.0) => (0.0, 0.0),
                _ if a2.abs() > b2.abs() => (a2, q * (b2 / a2)),
                _ => (b2, 2.0 * q - q * (a2 / b2)),
            };
            let (wx, wy) = (r * libm::cos(phi), r * libm::sin(phi));
            let tol = 4.0 * f64::EPSILON * r.abs().max(f64::MIN_POSITIVE);
            assert!(
                (x - wx).abs() <= tol && (y - wy).abs() <= tol,
                "{a} {b}: {x} {y} vs {wx} {wy}"
            );
            assert!(x * x + y * y <= 1.0 + 4.0 * f64::EPSILON, "{a} {b}");
        }
        assert_eq!(
            Kernel::Scalar.disc(Precision::F64, &[(0.5, 0.5)]),
            [(0.0, 0.0)]
        );
        assert_eq!(
            Kernel::Scalar.disc(Precision::F64, &[(1.0, 0.5)]),
            [(1.0, 0.0)]
        );
        assert_eq!(
            Kernel::Scalar.disc(Precision::F64, &[(0.0, 0.5)]),
            [(-1.0, 0.0)]
        );
    }
}
