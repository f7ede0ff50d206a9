//! Ray/shape intersection in f64 with the stable forms of Ray Tracing Gems ch. 7, written once
//! for any lane type: `sphere_hit` and `plane_hit` test a packet of rays against one shape.
//!
//! Secondary rays start exactly at the hit point and remember the surface they left (`own`).
//! Spheres and planes are convex, so such a ray can meet the surface it left again only on a
//! sphere's far side, which is found as the root away from the origin. No epsilon is
//! involved: no shadow acne at any scale, and no light leaking through thin gaps.
//!
//! `Ray`, `intersect` and `nearest` are the one-ray view of the same code, for tests and tools.

use crate::lanes::{F64x1, Lanes, Mask, V3};
use crate::scene::{Object, Shape};
use glam::DVec3;

/// Where the packet's rays meet a sphere (centre c, radius r) given f = origin − c, r² and,
/// when the caller has it, |f|² − r² (eye rays share their origin, so it is computed once a
/// frame, in exactly this arithmetic). Lanes in `own` start on this sphere and can only meet
/// its far side, heading inwards. Returns the lanes of `active` that hit, and their t > 0.
#[inline(always)]
pub fn sphere_hit<V: Lanes>(
    f: V3<V>,
    c: Option<V>,
    r2: V,
    d: V3<V>,
    own: V::M,
    active: V::M,
) -> (V::M, V) {
    let zero = V::splat(0.0);
    let b = f.dot(d);
    // r² − |f − (f·d)d|²: the squared distance from the centre to the line is computed
    // directly, so a small sphere seen from far away keeps its precision. Most rays miss
    // most spheres, and this rejects them before any root or division.
    let perp = f - d * b;
    let disc = r2 - perp.dot(perp);
    // 0 ≤ disc is false for NaN, as the scalar `disc.is_nan() || disc < 0` rejection.
    let valid = active.and(zero.le(disc));
    if !valid.any() {
        return (valid, zero);
    }
    let c = c.unwrap_or_else(|| f.dot(f) - r2);
    // Heading away from the centre (b > 0) nothing is hit when starting outside (c ≥ 0:
    // q = −(b + √disc) < 0 and c/q ≤ 0, no root ahead) or when leaving this very sphere
    // (only inward rays meet their own sphere again; c may round either way on its surface).
    // Deciding it here spares the root and the division for every shadow and reflection ray
    // leaving a sphere, and for lines that meet a floor sphere behind them; no result changes.
    let valid = valid.andnot(zero.lt(b).and(zero.le(c).or(own)));
    if !valid.any() {
        return (valid, zero);
    }
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = (c / q, q);
    let ordered = t0.le(t1);
    let (lo, hi) = (V::select(ordered, t0, t1), V::select(ordered, t1, t0));
    let (lo_ahead, hi_ahead) = (lo.gt(zero), hi.gt(zero));
    // Heading into its own sphere the ray meets the far side; heading out, nothing.
    let inward = b.lt(zero);
    let own_hit = own.and(inward).and(hi_ahead);
    let other_hit = lo_ahead.or(hi_ahead).andnot(own);
    // q = 0: tangent at the origin itself, both roots 0, no hit.
    let hit = valid.and(own_hit.or(other_hit)).andnot(q.eq(zero));
    let t = V::select(lo_ahead.andnot(own), lo, hi);
    (hit, t)
}

/// Where the packet's rays meet the plane through `point` with unit `normal`. A ray leaving
/// the plane (`own`) never meets it again.
#[inline(always)]
pub fn plane_hit<V: Lanes>(
    point: V3<V>,
    normal: V3<V>,
    origin: V3<V>,
    d: V3<V>,
    own: V::M,
    active: V::M,
) -> (V::M, V) {
    let denom = normal.dot(d);
    let t = (point - origin).dot(normal) / denom;
    let ahead = t.gt(V::splat(0.0)).and(t.lt(V::splat(f64::INFINITY)));
    (active.and(ahead).andnot(own), t)
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    /// Unit length.
    pub dir: DVec3,
    /// Index of the object this ray starts on, if it is a secondary ray.
    pub leaving: Option<usize>,
}

/// The nearest hit: distance along the ray and index of the object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub object: usize,
}

/// Nearest t > 0 at which `ray` meets `shape`. `own` says the ray starts on this shape.
pub fn intersect(shape: &Shape, ray: &Ray, own: bool) -> Option<f64> {
    let (o, d) = (V3::<F64x1>::splat(ray.origin), V3::splat(ray.dir));
    let (hit, t) = match *shape {
        Shape::Sphere { center, radius } => {
            let f = o - V3::splat(center);
            sphere_hit(f, None, F64x1(radius * radius), d, own, true)
        }
        Shape::Plane { point, normal, .. } => {
            plane_hit(V3::splat(point), V3::splat(normal), o, d, own, true)
        }
        // Meshes need their file's triangles: `accel::Geometry` tests them.
        Shape::Mesh { .. } => return None,
    };
    hit.then_some(t.0)
}

/// The nearest object `ray` hits, if any, testing objects in file order (the earlier wins a
/// tie): the plain loop the tracer's geometry is checked against.
pub fn nearest(objects: &[Object], ray: &Ray) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for (i, object) in objects.iter().enumerate() {
        if let Some(t) = intersect(&object.shape, ray, ray.leaving == Some(i))
            && best.is_none_or(|b| t < b.t)
        {
            best = Some(Hit { t, object: i });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f64; 3], d: [f64; 3]) -> Ray {
        Ray {
            origin: DVec3::from(o),
            dir: DVec3::from(d).normalize(),
            leaving: None,
        }
    }

    fn sphere(c: [f64; 3], r: f64) -> Shape {
        Shape::Sphere {
            center: DVec3::from(c),
            radius: r,
        }
    }

    #[test]
    fn sphere_hand_roots() {
        // From (0,0,5) towards −z, the unit sphere at the origin: roots 4 and 6.
        let s = sphere([0.0, 0.0, 0.0], 1.0);
        assert_eq!(
            intersect(&s, &ray([0., 0., 5.], [0., 0., -1.]), false),
            Some(4.0)
        );
        // Offset by 0.6 in x: half chord 0.8, roots 4.2 and 5.8.
        let t = intersect(&s, &ray([0.6, 0., 5.], [0., 0., -1.]), false).unwrap();
        assert!((t - 4.2).abs() < 1e-12, "{t}");
        // Behind the ray: no hit.
        assert_eq!(intersect(&s, &ray([0., 0., 5.], [0., 0., 1.]), false), None);
    }

    #[test]
    fn ray_from_inside_hits_far_side() {
        let s = sphere([1.0, 2.0, 3.0], 2.0);
        let t = intersect(&s, &ray([1.5, 2., 3.], [1., 0., 0.]), false).unwrap();
        assert!((t - 1.5).abs() < 1e-12, "{t}");
    }

    #[test]
    fn tangent_ray_touches_once_and_grazing_miss_misses() {
        let s = sphere([0.0, 0.0, 0.0], 1.0);
        let t = intersect(&s, &ray([1., 0., 5.], [0., 0., -1.]), false).unwrap();
        assert!((t - 5.0).abs() < 1e-12, "{t}");
        let miss = ray([1.0 + 1e-9, 0., 5.], [0., 0., -1.]);
        assert_eq!(intersect(&s, &miss, false), None);
    }

    #[test]
    fn own_sphere_only_far_side_inward() {
        let s = sphere([0.0, 0.0, 0.0], 1.0);
        let mut r = ray([0., 0., 1.], [0., 0., 1.]);
        assert_eq!(intersect(&s, &r, true), None);
        r.dir = DVec3::new(0.0, 0.0, -1.0);
        assert_eq!(intersect(&s, &r, true), Some(2.0));
    }

    #[test]
    fn tangent_at_the_origin_is_no_hit() {
        // q = 0: the ray starts on the sphere and runs along its tangent plane.
        let s = sphere([0.0, 0.0, 0.0], 1.0);
        assert_eq!(intersect(&s, &ray([1., 0., 0.], [0., 0., 1.]), false), None);
        assert_eq!(intersect(&s, &ray([1., 0., 0.], [0., 0., 1.]), true), None);
    }

    #[test]
    fn plane_roots_and_parallel_ray() {
        let p = Shape::Plane {
            point: DVec3::new(0.0, -0.7, 0.0),
            normal: DVec3::Y,
            u_axis: None,
        };
        let t = intersect(&p, &ray([0., 0., 0.], [0., -1., 0.]), false).unwrap();
        assert!((t - 0.7).abs() < 1e-15);
        let t = intersect(&p, &ray([0., 0., 0.], [0., -1., 1.]), false).unwrap();
        assert!((t - 0.7 * 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(intersect(&p, &ray([0., 0., 0.], [1., 0., 0.]), false), None);
        assert_eq!(
            intersect(&p, &ray([0., -0.7, 0.], [1., 0., 0.]), false),
            None
        );
        assert_eq!(intersect(&p, &ray([0., 0., 0.], [0., 1., 0.]), false), None);
        assert_eq!(intersect(&p, &ray([0., 0., 0.], [0., -1., 0.]), true), None);
    }

    #[test]
    fn huge_sphere_just_above_its_surface() {
        // The talk's floor; an origin 1e-4 above it looking straight down meets it at 1e-4.
        let r = 9000.0 - 0.7;
        let s = sphere([0.0, -9000.0, 0.0], r);
        let o = [0.0, -0.7 + 1e-4, 0.0];
        let t = intersect(&s, &ray(o, [0., -1., 0.]), false).unwrap();
        assert!((t - 1e-4).abs() < 1e-9, "{t}");
    }
}
