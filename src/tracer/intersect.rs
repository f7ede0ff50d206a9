//! Ray/shape intersection in f64 with the stable forms of Ray Tracing Gems ch. 7.
//!
//! Secondary rays start exactly at the hit point and remember the surface they left
//! (`Ray::leaving`). Spheres and planes are convex, so such a ray can meet the surface it left
//! again only on a sphere's far side, which is found as the root away from the origin. No
//! epsilon is involved: no shadow acne at any scale, and no light leaking through thin gaps.

use crate::scene::{Object, Shape};
use glam::DVec3;

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

/// Both roots of |o + t·d − c|² = r² for unit d, smaller first, or None when the ray misses.
#[inline(always)]
pub fn sphere_roots(center: DVec3, radius: f64, origin: DVec3, dir: DVec3) -> Option<(f64, f64)> {
    let f = origin - center;
    let b = f.dot(dir);
    // r² − |f − (f·d)d|²: the squared distance from the centre to the line is computed
    // directly, so a small sphere seen from far away keeps its precision.
    let perp = f - b * dir;
    let disc = radius * radius - perp.dot(perp);
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let c = f.dot(f) - radius * radius;
    let q = -(b + disc.sqrt().copysign(b));
    if q == 0.0 {
        // Tangent at the origin itself: both roots are 0.
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (c / q, q);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// Nearest t > 0 at which `ray` meets `shape`. `own` says the ray starts on this shape.
#[inline(always)]
pub fn intersect(shape: &Shape, ray: &Ray, own: bool) -> Option<f64> {
    match *shape {
        Shape::Sphere { center, radius } => {
            let (t0, t1) = sphere_roots(center, radius, ray.origin, ray.dir)?;
            if own {
                // Heading into its own sphere the ray meets the far side; heading out, nothing.
                let inward = (ray.origin - center).dot(ray.dir) < 0.0;
                return (inward && t1 > 0.0).then_some(t1);
            }
            if t0 > 0.0 {
                Some(t0)
            } else if t1 > 0.0 {
                Some(t1)
            } else {
                None
            }
        }
        Shape::Plane { point, normal } => {
            if own {
                return None;
            }
            let denom = normal.dot(ray.dir);
            let t = (point - ray.origin).dot(normal) / denom;
            (t > 0.0 && t.is_finite()).then_some(t)
        }
    }
}

/// The nearest object `ray` hits, if any.
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

/// Whether any object lies on `ray` strictly before distance `max_t`.
pub fn occluded(objects: &[Object], ray: &Ray, max_t: f64) -> bool {
    objects.iter().enumerate().any(|(i, object)| {
        intersect(&object.shape, ray, ray.leaving == Some(i)).is_some_and(|t| t < max_t)
    })
}

/// Unit normal of `shape` at point `p`, not yet turned towards the viewer.
#[inline]
pub fn normal_at(shape: &Shape, p: DVec3) -> DVec3 {
    match *shape {
        Shape::Sphere { center, .. } => (p - center).normalize(),
        Shape::Plane { normal, .. } => normal,
    }
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
    fn plane_roots_and_parallel_ray() {
        let p = Shape::Plane {
            point: DVec3::new(0.0, -0.7, 0.0),
            normal: DVec3::Y,
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
