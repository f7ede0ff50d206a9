//! The shape of a smooth track between two keys: a centripetal Catmull-Rom segment written as a
//! cubic Hermite curve, with its arc length and the point at a given arc length.
//!
//! For keys p0, p1, p2, p3 (p1 → p2 is the segment) with chords u = p1 − p0, v = p2 − p1,
//! w = p3 − p2 and centripetal knot intervals a = √|u|, b = √|v|, c = √|w|, the segment is
//! C(x) = h00(x)·p1 + h10(x)·T1 + h01(x)·p2 + h11(x)·T2 for x in [0, 1], with
//! T1 = a·b²/(a + b)·(û + v̂) and T2 = b²·c/(b + c)·(v̂ + ŵ) (û = u/|u| etc.). This is the
//! Barry–Goldman form rewritten; it shows that the tangent at a key bisects the chords. A
//! missing or coincident neighbour gives the chord as tangent: T1 = v, T2 = v.

use glam::DVec3;

/// Equal parts of [0, 1] on which the arc length is integrated.
pub(crate) const PARTS: usize = 16;

/// 8-point Gauss–Legendre nodes (on [−1, 1], positive half) and weights.
const NODES: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
const WEIGHTS: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// Below this |û + v̂| the chords at a key point straight back at each other.
const TURN_BACK: f64 = 1e-12;

/// One curved segment from `p1` to `p2`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Curve {
    pub(crate) p1: DVec3,
    pub(crate) p2: DVec3,
    pub(crate) t1: DVec3,
    pub(crate) t2: DVec3,
    /// Arc length from x = 0 to x = j/PARTS, j = 0..=PARTS.
    pub(crate) parts: [f64; PARTS + 1],
}

fn unit(d: DVec3) -> Option<DVec3> {
    let len = d.length();
    (len > 0.0 && len.is_finite()).then(|| d / len)
}

/// T1, the tangent at p1 of the segment p1 → p2, given the key before p1 (if any).
pub(crate) fn start_tangent(p0: Option<DVec3>, p1: DVec3, p2: DVec3) -> DVec3 {
    let v = p2 - p1;
    match (p0.and_then(|p0| unit(p1 - p0)), unit(v)) {
        (Some(u_hat), Some(v_hat)) => {
            let (a, b) = ((p1 - p0.unwrap()).length().sqrt(), v.length().sqrt());
            (u_hat + v_hat) * (a * b * b / (a + b))
        }
        _ => v,
    }
}

/// T2, the tangent at p2 of the segment p1 → p2, given the key after p2 (if any).
pub(crate) fn end_tangent(p1: DVec3, p2: DVec3, p3: Option<DVec3>) -> DVec3 {
    let v = p2 - p1;
    match (unit(v), p3.and_then(|p3| unit(p3 - p2))) {
        (Some(v_hat), Some(w_hat)) => {
            let (b, c) = (v.length().sqrt(), (p3.unwrap() - p2).length().sqrt());
            (v_hat + w_hat) * (b * b * c / (b + c))
        }
        _ => v,
    }
}

/// Whether a track arriving from `prev` at `at` leaves straight back towards where it came
/// from: its tangent there is zero, so it must stop rather than reverse at full speed.
pub(crate) fn turns_back(prev: DVec3, at: DVec3, next: DVec3) -> bool {
    match (unit(at - prev), unit(next - at)) {
        (Some(u), Some(v)) => (u + v).length() < TURN_BACK,
        _ => false,
    }
}

impl Curve {
    pub(crate) fn new(p1: DVec3, p2: DVec3, t1: DVec3, t2: DVec3) -> Curve {
        let mut c = Curve {
            p1,
            p2,
            t1,
            t2,
            parts: [0.0; PARTS + 1],
        };
        for j in 0..PARTS {
            let (a, b) = (j as f64 / PARTS as f64, (j + 1) as f64 / PARTS as f64);
            c.parts[j + 1] = c.parts[j] + c.gauss(a, b);
        }
        c
    }

    pub(crate) fn length(&self) -> f64 {
        self.parts[PARTS]
    }

    pub(crate) fn point(&self, x: f64) -> DVec3 {
        let (x2, x3) = (x * x, x * x * x);
        let h00 = 2.0 * x3 - 3.0 * x2 + 1.0;
        let h10 = x3 - 2.0 * x2 + x;
        let h01 = -2.0 * x3 + 3.0 * x2;
        let h11 = x3 - x2;
        self.p1 * h00 + self.t1 * h10 + self.p2 * h01 + self.t2 * h11
    }

    pub(crate) fn derivative(&self, x: f64) -> DVec3 {
        let x2 = x * x;
        let d00 = 6.0 * x2 - 6.0 * x;
        let d10 = 3.0 * x2 - 4.0 * x + 1.0;
        let d11 = 3.0 * x2 - 2.0 * x;
        (self.p2 - self.p1) * -d00 + self.t1 * d10 + self.t2 * d11
    }

    /// ∫ |C'| from `a` to `b` by the 8-point Gauss–Legendre rule.
    fn gauss(&self, a: f64, b: f64) -> f64 {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        let mut sum = 0.0;
        for i in 0..4 {
            let (d, w) = (half * NODES[i], WEIGHTS[i]);
            sum += w * (self.derivative(mid - d).length() + self.derivative(mid + d).length());
        }
        half * sum
    }

    /// The point at arc length `s` from p1, for s in [0, length].
    pub(crate) fn at_length(&self, s: f64) -> DVec3 {
        if s <= 0.0 {
            return self.p1;
        }
        if s >= self.length() {
            return self.p2;
        }
        self.point(self.parameter(s))
    }

    /// The parameter x whose arc length from 0 is `s`: the part holding it, then a root of
    /// gauss(x_j, x) = s − parts[j] by Newton steps kept inside a shrinking bracket.
    fn parameter(&self, s: f64) -> f64 {
        let j = (self.parts.partition_point(|&a| a <= s) - 1).min(PARTS - 1);
        let start = j as f64 / PARTS as f64;
        let (mut lo, mut hi) = (start, (j + 1) as f64 / PARTS as f64);
        let target = s - self.parts[j];
        let span = self.parts[j + 1] - self.parts[j];
        let guess = if span > 0.0 {
            (target / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut x = start + (hi - lo) * guess;
        for _ in 0..100 {
            let f = self.gauss(start, x) - target;
            if f == 0.0 {
                return x;
            }
            if f > 0.0 {
                hi = x
            } else {
                lo = x
            }
            let mut next = x - f / self.derivative(x).length();
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if next == x || hi - lo <= f64::EPSILON * hi {
                return next;
            }
            x = next;
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(p: [DVec3; 4]) -> Curve {
        Curve::new(
            p[1],
            p[2],
            start_tangent(Some(p[0]), p[1], p[2]),
            end_tangent(p[1], p[2], Some(p[3])),
        )
    }

    /// Barry–Goldman's pyramid, the textbook definition, at spline parameter x.
    fn barry_goldman(p: [DVec3; 4], x: f64) -> DVec3 {
        let k = |a: DVec3, b: DVec3| a.distance(b).sqrt();
        let t1 = k(p[0], p[1]);
        let t2 = t1 + k(p[1], p[2]);
        let t3 = t2 + k(p[2], p[3]);
        let t = t1 + x * (t2 - t1);
        let l = |a: DVec3, b: DVec3, ta: f64, tb: f64| a + (b - a) * ((t - ta) / (tb - ta));
        let (a1, a2, a3) = (
            l(p[0], p[1], 0.0, t1),
            l(p[1], p[2], t1, t2),
            l(p[2], p[3], t2, t3),
        );
        l(l(a1, a2, 0.0, t2), l(a2, a3, t1, t3), t1, t2)
    }

    fn sample() -> [DVec3; 4] {
        [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.2, -0.3),
            DVec3::new(5.0, 1.0, 0.5),
            DVec3::new(5.5, -2.0, 1.0),
        ]
    }

    #[test]
    fn hermite_form_is_barry_goldman() {
        let p = sample();
        let c = curve(p);
        for i in 0..=20 {
            let x = i as f64 / 20.0;
            assert!(c.point(x).distance(barry_goldman(p, x)) < 1e-13, "{x}");
        }
        assert_eq!(c.point(0.0), p[1]);
        assert_eq!(c.point(1.0), p[2]);
    }

    #[test]
    fn arc_length_matches_a_fine_polyline() {
        let c = curve(sample());
        let n = 200_000;
        let mut fine = 0.0;
        for i in 0..n {
            fine += c
                .point(i as f64 / n as f64)
                .distance(c.point((i + 1) as f64 / n as f64));
        }
        // A polyline of n chords falls short by O(1/n²); 1e-9 is far below what it resolves.
        assert!(
            (c.length() - fine).abs() < 1e-9 * fine,
            "{} {fine}",
            c.length()
        );
    }

    #[test]
    fn the_point_at_a_length_has_that_length() {
        let c = curve(sample());
        let total = c.length();
        for i in 0..=50 {
            let s = total * i as f64 / 50.0;
            let x = if i == 50 { 1.0 } else { c.parameter(s) };
            let j = ((x * PARTS as f64) as usize).min(PARTS - 1);
            let back = c.parts[j] + c.gauss(j as f64 / PARTS as f64, x);
            assert!((back - s).abs() < 1e-13 * total, "{s}: {back}");
        }
    }

    #[test]
    fn straight_back_is_a_zero_tangent() {
        let (a, b) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(0.3, 0.6, 0.9));
        assert!(turns_back(a, b, DVec3::new(0.2, 0.4, 0.6)));
        assert!(turns_back(a, b, a));
        assert!(!turns_back(a, b, DVec3::new(0.3, 0.6, 1.0)));
        assert!(!turns_back(a, a, b));
        assert_eq!(start_tangent(Some(a), b, a), DVec3::ZERO);
    }
}
