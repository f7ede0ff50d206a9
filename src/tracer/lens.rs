//! Where on the lens an eye ray leaves: the concentric map of a sample's lens coordinates,
//! computed in the lanes.

use crate::lanes::{Lanes, Mask};

/// The concentric map (`concentric`) of lanes of lens coordinates, its sine and cosine from Taylor
/// polynomials (the angle stays within ±π/4, where they are exact to an ulp or two): libm's
/// per lane cost more than the rest of the camera ray.
#[inline(always)]
pub(super) fn disc<V: Lanes>(a: V, b: V) -> (V, V) {
    let (zero, one, two) = (V::splat(0.0), V::splat(1.0), V::splat(2.0));
    let (a, b) = (two * a - one, two * b - one);
    let wide = b.max(zero - b).lt(a.max(zero - a));
    let r = V::select(wide, a, b);
    let x = V::splat(std::f64::consts::FRAC_PI_4) * V::select(wide, b / a, a / b);
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

/// Shirley and Chiu's concentric map of [0, 1)² onto the unit disc: squares around the centre
/// become rings, so stratified points stay stratified and evenly spread.
#[inline]
pub fn concentric(a: f64, b: f64) -> (f64, f64) {
    let (a, b) = (2.0 * a - 1.0, 2.0 * b - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let quarter = std::f64::consts::FRAC_PI_4;
    let (r, phi) = if a.abs() > b.abs() {
        (a, quarter * (b / a))
    } else {
        (b, 2.0 * quarter - quarter * (a / b))
    };
    (r * libm::cos(phi), r * libm::sin(phi))
}
