use super::*;
use crate::tracer::intersect::nearest;

/// A deterministic field of spheres and a few rays from inside and outside it.
#[test]
fn hierarchy_finds_exactly_what_the_plain_loop_finds() {
    let mut objects = Vec::new();
    let mut rnd = crate::testing::uniform(12345);
    for _ in 0..500 {
        let center = DVec3::new(
            rnd() * 20.0 - 10.0,
            rnd() * 20.0 - 10.0,
            rnd() * 20.0 - 10.0,
        );
        objects.push(Object {
            shape: Shape::Sphere {
                center,
                radius: 0.05 + rnd() * 0.5,
            },
            material: 0,
        });
    }
    objects.push(Object {
        shape: Shape::Plane {
            point: DVec3::new(0.0, -11.0, 0.0),
            normal: DVec3::Y,
            u_axis: None,
        },
        material: 0,
    });
    let geometry = Geometry::new(&objects);
    assert!(geometry.has_bvh());
    for i in 0..4000 {
        let origin = if i % 2 == 0 {
            DVec3::new(0.0, 0.0, 30.0)
        } else {
            DVec3::new(rnd(), rnd(), rnd())
        };
        let dir = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5 - f64::from(i % 2)).normalize();
        let ray = Ray {
            origin,
            dir,
            leaving: None,
        };
        let (a, b) = (geometry.nearest_one(&ray), nearest(&objects, &ray));
        assert_eq!(a, b, "ray {i}");
        let limit = a.map_or(f64::INFINITY, |h| h.t * 0.999);
        assert!(
            !geometry.occluded_one(&ray, limit) || limit == f64::INFINITY,
            "ray {i}"
        );
        assert_eq!(
            geometry.occluded_one(&ray, f64::INFINITY),
            b.is_some(),
            "ray {i}"
        );
    }
}
