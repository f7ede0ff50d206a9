//! The watertight ray/triangle test, for any lane type. With a = v0 − o, b = v1 − o and
//! c = v2 − o (the vertices seen from the ray's origin), the three edge functions
//!
//!   w0 = (b × c)·d,  w1 = (c × a)·d,  w2 = (a × b)·d
//!
//! are the signed volumes the ray spans with each edge. The ray passes through the triangle
//! when no two of them have opposite signs. Two triangles sharing an edge compute that edge's
//! function from the same two vertices in the opposite order, and (p × q)·d = −((q × p)·d)
//! holds exactly in IEEE arithmetic (each product appears in both, the differences are
//! antisymmetric under rounding to nearest), so a ray through a shared edge is inside at least
//! one of the two triangles: no ray slips between them, whatever the rounding. The test is the
//! edge-function form of Embree's watertight Plücker test; it accepts both sides of a triangle.
//!
//! Distance: t = (a·n) / (d·n) with n = (v1 − v0) × (v2 − v0) precomputed per triangle.
//! Barycentrics: u = w1 / (w0 + w1 + w2), v = w2 / (w0 + w1 + w2) (weights of v1 and v2).

use crate::lanes::{Lanes, Mask, V3};

/// (b × c)·d in the operation order of docs/spec/mesh.md: x, y and z of the cross product as
/// glam forms them (b.y·c.z − c.y·b.z, …), then the dot product ((x·dx + y·dy) + z·dz).
#[inline(always)]
pub fn edge<V: Lanes>(b: V3<V>, c: V3<V>, d: V3<V>) -> V {
    cross(b, c).dot(d)
}

/// glam's `DVec3::cross`: (a.y·b.z − b.y·a.z, a.z·b.x − b.z·a.x, a.x·b.y − b.x·a.y).
#[inline(always)]
pub fn cross<V: Lanes>(a: V3<V>, b: V3<V>) -> V3<V> {
    V3 {
        x: a.y * b.z - b.y * a.z,
        y: a.z * b.x - b.z * a.x,
        z: a.x * b.y - b.x * a.y,
    }
}

/// Which lanes of `active` meet the triangle `v` (normal `n` = (v1 − v0) × (v2 − v0)) at
/// 0 < t < ∞: the mask, t, and the edge functions (w0, w1, w2) for the barycentrics. With
/// `skipped` (f32 frames), the test runs from a point that far along the ray: t is that plus
/// the test's own distance.
#[inline(always)]
pub fn triangle_hit<V: Lanes>(
    v: [V3<V>; 3],
    n: V3<V>,
    origin: V3<V>,
    d: V3<V>,
    skipped: Option<V>,
    active: V::M,
) -> (V::M, V, [V; 3]) {
    let zero = V::splat(0.0);
    let (a, b, c) = (v[0] - origin, v[1] - origin, v[2] - origin);
    let w0 = edge(b, c, d);
    let w1 = edge(c, a, d);
    let w2 = edge(a, b, d);
    let negative = w0.lt(zero).or(w1.lt(zero)).or(w2.lt(zero));
    let positive = w0.gt(zero).or(w1.gt(zero)).or(w2.gt(zero));
    let inside = active.andnot(negative.and(positive));
    if !inside.any() {
        return (inside, zero, [zero; 3]);
    }
    let t = a.dot(n) / d.dot(n);
    let t = match skipped {
        Some(t0) => t0 + t,
        None => t,
    };
    // t > 0 and finite; NaN (a ray in the triangle's plane: 0/0) compares false.
    let ahead = t.gt(zero).and(t.lt(V::splat(f64::INFINITY)));
    (inside.and(ahead), t, [w0, w1, w2])
}

/// The barycentric weights (u, v) of v1 and v2 from the edge functions.
#[inline(always)]
pub fn barycentrics<V: Lanes>(w: [V; 3]) -> (V, V) {
    let sum = w[0] + w[1] + w[2];
    (w[1] / sum, w[2] / sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::F64x1;
    use glam::DVec3;

    fn hit(tri: [DVec3; 3], o: DVec3, d: DVec3) -> Option<f64> {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let (h, t, _) = triangle_hit::<F64x1>(
            tri.map(V3::splat),
            V3::splat(n),
            V3::splat(o),
            V3::splat(d),
            None,
            true,
        );
        h.then_some(t.0)
    }

    #[test]
    fn cross_matches_glam() {
        let (a, b) = (DVec3::new(0.3, -1.7, 2.9), DVec3::new(1e-3, 5.5, -0.25));
        let c = cross(V3::<F64x1>::splat(a), V3::splat(b)).lane(0);
        assert_eq!(c, a.cross(b));
    }

    #[test]
    fn hits_inside_both_sides_and_misses_outside() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(hit(tri, DVec3::new(0.2, 0.2, 1.0), -DVec3::Z), Some(1.0));
        assert_eq!(hit(tri, DVec3::new(0.2, 0.2, -2.0), DVec3::Z), Some(2.0));
        assert_eq!(hit(tri, DVec3::new(0.8, 0.8, 1.0), -DVec3::Z), None);
        assert_eq!(hit(tri, DVec3::new(0.2, 0.2, 1.0), DVec3::Z), None);
        // In the plane: no hit. At a vertex and on an edge: a hit.
        assert_eq!(hit(tri, DVec3::new(-1.0, 0.2, 0.0), DVec3::X), None);
        assert_eq!(hit(tri, DVec3::new(0.0, 0.0, 1.0), -DVec3::Z), Some(1.0));
        assert_eq!(hit(tri, DVec3::new(0.5, 0.5, 1.0), -DVec3::Z), Some(1.0));
    }

    /// Rays aimed at points on the shared diagonal of a quad, from many origins: each hits at
    /// least one of the two triangles (watertight), never neither.
    #[test]
    fn no_ray_slips_through_a_shared_edge() {
        let (p0, p1, p2, p3) = (
            DVec3::new(-1.3, 0.1, -0.7),
            DVec3::new(2.1, 0.3, -1.1),
            DVec3::new(1.7, -0.2, 2.3),
            DVec3::new(-0.9, 0.4, 1.9),
        );
        let (a, b) = ([p0, p1, p2], [p0, p2, p3]);
        let mut s = 7u64;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20000 {
            let f = rnd();
            let target = p0 + (p2 - p0) * f;
            let o = DVec3::new(rnd() - 0.5, 2.0 + rnd() * 50.0, rnd() - 0.5) * 3.0;
            let d = (target - o).normalize();
            assert!(
                hit(a, o, d).is_some() || hit(b, o, d).is_some(),
                "{o} → {target}"
            );
        }
    }
}
