//! The checker averaged exactly over an eye ray's pixel (docs/spec/texture.md, **The pixel**).
//!
//! An eye ray's hit knows more than its cone: the pixel it was cast through. Seen on the hit's
//! tangent plane that pixel is a parallelogram (the ray through the pixel's centre, and its
//! steps one pixel right and one pixel down, met with the plane), and the checker's average
//! over a parallelogram has a closed form: by Green's theorem the integral of S(x)·S(y) over
//! it is the boundary integral of T(x)·S(y) dy (T the triangle wave, T′ = S), and along each
//! edge that is a sum over the rows of cells the edge crosses of differences of T's own
//! integral. Every sample of a pixel on one flat surface so reads the same value, the pixel's
//! box-filtered checker: the grain of sub-pixel cells and of their edges is gone, and adaptive
//! sampling no longer spends samples on what the filter has resolved.

use super::{Round, TINY_BOX, sign, square_average_with, triangle};
use glam::DVec3;

/// The rows of cells a parallelogram's narrower axis may span before the lookup leaves the
/// pixel to the cone's taps (its edges are summed row by row).
pub const MOST_ROWS: f64 = 32.0;
/// A projected parallelogram thinner than this (|a × b| against (|a|₁·|b|₁)) is left to the
/// cone's taps: its area, the average's divisor, would be rounding.
pub const SKEW: f64 = 1.0 / 1024.0;
/// Below this area (in cells², a quarter of the parallelogram's) the closed forms would
/// divide rounding by almost nothing.
pub const SMALL: f64 = 1.0 / 17_179_869_184.0; // 2⁻³⁴
/// Edges steeper than this (|dx/dy|) take T at the middle of each row instead of the
/// difference of its integral over the row.
pub const FLAT: f64 = 1.0 / 1_048_576.0; // 2⁻²⁰

/// The checker's colour averaged over the parallelogram centred at `c` with half-edge vectors
/// `a` and `b` (world units), or None where the rule leaves it to the cone's taps: three axes
/// crossing cell boundaries, a parallelogram seen edge-on, or one spanning too many cells.
#[inline(always)]
pub(super) fn checker<R: Round>(
    size: f64,
    colors: &[DVec3; 2],
    (c, a, b): (DVec3, DVec3, DVec3),
) -> Option<DVec3> {
    let (c, a, b) = (c.to_array(), a.to_array(), b.to_array());
    let (mut x, mut h) = ([0.0; 3], [0.0; 3]);
    // The sign of the axes whose cell is the same over the whole parallelogram's box.
    let mut held = 1.0;
    let (mut vary, mut n) = ([0usize; 3], 0);
    for i in 0..3 {
        x[i] = c[i] / size;
        h[i] = (a[i].abs() + b[i].abs()) / size;
        if h[i] < TINY_BOX {
            held *= sign(R::floor(x[i]));
            continue;
        }
        let k = R::floor(x[i] - h[i]);
        if k == R::floor(x[i] + h[i]) {
            held *= sign(k);
        } else {
            vary[n] = i;
            n += 1;
        }
    }
    let cells = |i: usize| (x[i], a[i] / size, b[i] / size);
    let mean = match n {
        0 => held,
        1 => held * along::<R>(cells(vary[0])),
        2 => {
            // y is the axis of fewer rows: the edges are summed row by row along it.
            let (i, j) = match h[vary[0]] >= h[vary[1]] {
                true => (vary[0], vary[1]),
                false => (vary[1], vary[0]),
            };
            held * across::<R>(cells(i), cells(j), h[j])?
        }
        _ => return None,
    };
    if !mean.is_finite() {
        return None;
    }
    Some(mix(colors, mean.clamp(-1.0, 1.0)))
}

/// The colour of a checker whose mean of S over the pixel is `mean` (in [−1, 1]).
#[inline(always)]
pub(super) fn mix(colors: &[DVec3; 2], mean: f64) -> DVec3 {
    colors[0] * (0.5 + 0.5 * mean) + colors[1] * (0.5 - 0.5 * mean)
}

/// One axis crossing boundaries: the mean of S(x + α·a + β·b) over α, β in [−1, 1], which is
/// [U(x+a+b) − U(x+a−b) − U(x−a+b) + U(x−a−b)] / (4ab) with U″ = S; the box average of the
/// wider half-edge where the other is negligible.
#[inline(always)]
fn along<R: Round>((x, a, b): (f64, f64, f64)) -> f64 {
    let (a, b) = (a.abs(), b.abs());
    let (a, b) = if a >= b { (a, b) } else { (b, a) };
    if b <= a * FLAT || a * b < SMALL {
        return square_average_with::<R>(x, a);
    }
    let x = x - 2.0 * R::floor(x * 0.5);
    let sum = ((ramp::<R>((x + a) + b) - ramp::<R>((x + a) - b)) - ramp::<R>((x - a) + b))
        + ramp::<R>((x - a) - b);
    sum / ((4.0 * a) * b)
}

/// Two axes crossing boundaries, (x, half-edge a, half-edge b) in cells along each, `hy` the
/// box's half-height along y: ∮ T(x)·S(y) dy around the parallelogram over its signed area.
#[inline(always)]
fn across<R: Round>(
    (cx, ax, bx): (f64, f64, f64),
    (cy, ay, by): (f64, f64, f64),
    hy: f64,
) -> Option<f64> {
    let cross = ax * by - ay * bx;
    let span = (ax.abs() + ay.abs()) * (bx.abs() + by.abs());
    // NaN must fail, as the spec's "not ≥" does.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(cross.abs() >= span * SKEW) || cross.abs() < SMALL {
        return None;
    }
    if R::floor(cy + hy) - R::floor(cy - hy) > MOST_ROWS {
        return None;
    }
    // S and T repeat every two cells: centred near 0, the sums keep their digits.
    let cx = cx - 2.0 * R::floor(cx * 0.5);
    let cy = cy - 2.0 * R::floor(cy * 0.5);
    let corner = |s: f64, t: f64| {
        let x = if s > 0.0 { cx + ax } else { cx - ax };
        let y = if s > 0.0 { cy + ay } else { cy - ay };
        if t > 0.0 {
            (x + bx, y + by)
        } else {
            (x - bx, y - by)
        }
    };
    let p = [
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        corner(1.0, 1.0),
        corner(-1.0, 1.0),
    ];
    let mut sum = 0.0;
    for k in 0..4 {
        sum += edge::<R>(p[k], p[(k + 1) % 4])?;
    }
    Some(sum / (4.0 * cross))
}

/// ∫ T(x)·S(y) dy along the segment from p to q, row of cells by row of cells.
#[inline(always)]
fn edge<R: Round>((x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> Option<f64> {
    if y1 == y0 {
        return Some(0.0);
    }
    let m = (x1 - x0) / (y1 - y0);
    if !m.is_finite() {
        return None;
    }
    let up = y1 > y0;
    let mut row = R::floor(y0);
    let (mut ya, mut xa, mut ua) = (y0, x0, ramp::<R>(x0));
    let mut sum = 0.0;
    for _ in 0..MOST_ROWS as usize + 3 {
        let bound = if up { row + 1.0 } else { row };
        let last = if up { bound >= y1 } else { bound <= y1 };
        let (yb, xb) = match last {
            true => (y1, x1),
            false => (bound, x0 + (bound - y0) * m),
        };
        let ub = ramp::<R>(xb);
        let piece = match m.abs() < FLAT {
            true => triangle::<R>(0.5 * (xa + xb)) * (yb - ya),
            false => (ub - ua) / m,
        };
        sum += sign(row) * piece;
        if last {
            return Some(sum);
        }
        (ya, xa, ua) = (yb, xb, ub);
        row = if up { row + 1.0 } else { row - 1.0 };
    }
    None
}

/// U(u) = ∫₀ᵘ T: n + V(f) for n = ⌊u/2⌋, f = u − 2n, V(f) = f²/2 below 1, else 2f − f²/2 − 1.
#[inline(always)]
fn ramp<R: Round>(u: f64) -> f64 {
    let n = R::floor(u * 0.5);
    let f = u - 2.0 * n;
    let v = if f < 1.0 {
        (0.5 * f) * f
    } else {
        (2.0 * f - (0.5 * f) * f) - 1.0
    };
    n + v
}

#[cfg(test)]
mod tests {
    use super::super::Portable;
    use super::*;
    use glam::Vec3Swizzles;

    /// The checker's mean over the parallelogram by brute force: a fine grid of its points.
    fn brute(c: DVec3, a: DVec3, b: DVec3, size: f64) -> f64 {
        let n = 400;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let s = -1.0 + (2.0 * i as f64 + 1.0) / n as f64;
                let t = -1.0 + (2.0 * j as f64 + 1.0) / n as f64;
                let p = (c + a * s + b * t) / size;
                sum += sign(p.x.floor()) * sign(p.y.floor()) * sign(p.z.floor());
            }
        }
        sum / (n * n) as f64
    }

    fn mean(c: DVec3, a: DVec3, b: DVec3, size: f64) -> Option<f64> {
        let colors = [DVec3::ONE, -DVec3::ONE];
        checker::<Portable>(size, &colors, (c, a, b)).map(|v| v.x)
    }

    #[test]
    fn the_closed_forms_are_the_mean_over_the_parallelogram() {
        let mut next = crate::testing::uniform(0x51ed_270b_2d1f_0a37);
        let mut checked = [0; 3];
        for case in 0..1200 {
            let size = [0.25, 1.0, 0.7][case % 3];
            let c = DVec3::new(next() * 9.0 - 4.0, 0.0, next() * 9.0 - 4.0);
            let scale = [0.05, 0.4, 2.0][(case / 3) % 3];
            let v =
                |next: &mut dyn FnMut() -> f64| DVec3::new(next() - 0.5, 0.0, next() - 0.5) * scale;
            let (a, b) = (v(&mut next), v(&mut next));
            // Floors (y held), walls (x held), and 1-D footprints along one axis.
            let (c, a, b) = match case % 4 {
                0 => (c, a, b),
                1 => (c.zxy(), a.zxy(), b.zxy()),
                2 => (
                    c,
                    DVec3::new(a.x, 0.0, 0.0),
                    DVec3::new(b.x, 0.0, b.z * 0.01),
                ),
                _ => (c.yzx() + DVec3::X * 0.3, a.yzx(), b.yzx()),
            };
            let Some(got) = mean(c, a, b, size) else {
                continue;
            };
            let want = brute(c, a, b, size);
            // The grid's own error: a boundary crossing a cell of the grid's 400².
            assert!(
                (got - want).abs() < 0.02,
                "case {case}: {got} against {want}"
            );
            checked[usize::from(got.abs() < 1.0) + usize::from(got.abs() < 0.5)] += 1;
        }
        assert!(checked.iter().all(|&n| n > 40), "{checked:?}");
    }

    #[test]
    fn an_axis_aligned_patch_is_the_product_of_box_averages() {
        let mut next = crate::testing::uniform(7);
        for _ in 0..20_000 {
            let c = DVec3::new(next() * 6.0 - 3.0, 0.5, next() * 6.0 - 3.0);
            let (hx, hz) = (next() * 3.0 + 1e-3, next() * 3.0 + 1e-3);
            let got = mean(c, DVec3::X * hx, DVec3::Z * hz, 1.0).unwrap();
            let want = square_average_with::<Portable>(c.x, hx)
                * square_average_with::<Portable>(c.z, hz)
                * sign(c.y.floor());
            assert!(
                (got - want).abs() < 1e-9,
                "{c} {hx} {hz}: {got} against {want}"
            );
        }
    }

    #[test]
    fn what_the_closed_forms_cannot_hold_is_left_to_the_taps() {
        let c = DVec3::new(0.5, 0.5, 0.5);
        // Three axes crossing boundaries.
        assert_eq!(mean(c, DVec3::ONE, DVec3::new(1.0, -1.0, 0.3), 1.0), None);
        // Edge-on in the two axes that vary.
        let a = DVec3::new(1.0, 0.0, 1.0);
        assert_eq!(mean(c, a, a * 0.5, 1.0), None);
        // Too many rows along the narrower axis.
        assert_eq!(mean(c, DVec3::X * 40.0, DVec3::Z * 40.0, 1.0), None);
        // Not finite.
        assert_eq!(mean(c, DVec3::X * f64::NAN, DVec3::Z, 1.0), None);
        assert_eq!(
            mean(c * 1e300, DVec3::X * 1e300, DVec3::Z * 1e300, 1.0),
            None
        );
        // One cell: its colour exactly.
        assert_eq!(mean(c, DVec3::X * 0.1, DVec3::Z * 0.2, 1.0), Some(1.0));
    }
}
