//! Transparent materials: an index-1 sphere is invisible, a glass ball inverts what is behind
//! it, refraction follows Snell's law to 1e-12, total internal reflection keeps the path's
//! weight, the path tree equals the plain path where nothing branches, and no glass scene
//! produces a non-finite pixel.

use glam::DVec3;
use rayreel::frame::Frame;
use rayreel::scene::{Material, Shape};
use rayreel::sequence;
use rayreel::tracer::glass::scatter_one;
use rayreel::tracer::intersect::{Ray, intersect};
use std::path::Path;

fn render(yaml: &str) -> Frame {
    let seq =
        sequence::parse(Path::new("glass.yaml"), yaml).unwrap_or_else(|e| panic!("{e}\n{yaml}"));
    let frame = rayreel::schedule::render_frame(&seq, 0).unwrap();
    assert_eq!(frame.non_finite, 0);
    frame
}

/// The talk's three spheres on a plane floor, reflections `r`, seen from `camera`.
fn talk(r: f64, depth: u32, extra: &str) -> String {
    format!(
        "render: {{ width: 160, height: 90, max_depth: {depth} }}
camera: {{ position: [0.3, 0.2, 1.2], look_at: [-0.1, -0.2, -0.6] }}
materials:
  red:    {{ ambient: [0.1, 0, 0], diffuse: [0.7, 0, 0], specular: [1, 1, 1], reflection: {r} }}
  green:  {{ ambient: [0, 0.1, 0], diffuse: [0, 0.6, 0], specular: [1, 1, 1], reflection: {r} }}
  floor:  {{ ambient: [0.1, 0.1, 0.1], diffuse: [0.6, 0.6, 0.6], specular: [1, 1, 1], reflection: {r} }}
  invisible: {{ diffuse: [0, 0, 0], transmission: 1, ior: 1 }}
  glass:  {{ diffuse: [0, 0, 0], specular: [1, 1, 1], transmission: [0.9, 0.95, 1], fresnel: true }}
objects:
  - sphere: {{ center: [-0.2, 0, -1], radius: 0.7, material: red }}
  - sphere: {{ center: [0.1, -0.3, 0], radius: 0.1, material: green }}
  - sphere: {{ center: [-0.3, 0, 0], radius: 0.15, material: green }}
  - plane:  {{ point: [0, -0.7, 0], normal: [0, 1, 0], material: floor }}
{extra}lights:
  - point: {{ position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
"
    )
}

/// (largest difference in 8-bit levels, pixels that differ at all).
fn compare(a: &Frame, b: &Frame) -> (u8, usize) {
    let (a, b) = (a.to_rgb8(), b.to_rgb8());
    let mut largest = 0;
    let mut differ = 0;
    for (pa, pb) in a.chunks(3).zip(b.chunks(3)) {
        let d = pa
            .iter()
            .zip(pb)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        largest = largest.max(d);
        differ += usize::from(d > 0);
    }
    (largest, differ)
}

#[test]
fn a_sphere_of_index_1_that_only_transmits_is_invisible() {
    // In front of the red sphere and between it and the light, so shadows are crossed too.
    let sphere = "  - sphere: { center: [0.15, 0.15, -0.35], radius: 0.3, material: invisible }\n";
    // Without reflections 3 surfaces hold eye → both glass surfaces → the object behind; with
    // reflections, deep enough that the two extra surfaces a path spends cannot show.
    for (r, depth) in [(0.0, 3), (0.5, 14)] {
        let without = render(&talk(r, depth, ""));
        let with = render(&talk(r, depth, sphere));
        let (largest, differ) = compare(&without, &with);
        let pixels = (without.width * without.height) as usize;
        assert!(largest <= 1, "r {r}: {largest} levels");
        assert!(
            differ * 200 <= pixels,
            "r {r}: {differ} of {pixels} pixels differ"
        );
    }
}

#[test]
fn the_path_tree_equals_the_plain_path_where_nothing_branches() {
    // Glass that no ray can reach (inside the floor's far side) turns the tracer to trees;
    // every path there is still a chain, and must give the plain tracer's bytes.
    let scene = |extra: &str| {
        talk(0.5, 5, extra).replace(
            "  - plane:  { point: [0, -0.7, 0], normal: [0, 1, 0], material: floor }",
            "  - sphere: { center: [0, -9000, 0], radius: 8999.3, material: floor }",
        )
    };
    let plain = render(&scene(""));
    let buried = render(&scene(
        "  - sphere: { center: [0, -100, 0], radius: 1, material: glass }\n",
    ));
    assert_eq!(plain.rgb, buried.rgb);
    assert_eq!(plain.rays, buried.rays);
}

#[test]
fn a_glass_ball_turns_the_scene_behind_it_upside_down_and_left_to_right() {
    // A red sphere up-left and a green one down-right far behind a ball lens: the ball
    // shows them the other way round, as any lens with a real image does.
    let yaml = "render: { width: 121, height: 121, max_depth: 4, background: [0, 0, 0] }
camera: { position: [0, 0, 4], look_at: [0, 0, 0], fov: 16 }
materials:
  red:   { ambient: [1, 0, 0], diffuse: [0, 0, 0] }
  green: { ambient: [0, 1, 0], diffuse: [0, 0, 0] }
  glass: { diffuse: [0, 0, 0], transmission: 1, ior: 1.5 }
objects:
  - sphere: { center: [-3, 3, -20], radius: 2.5, material: red }
  - sphere: { center: [3, -3, -20], radius: 2.5, material: green }
  - sphere: { center: [0, 0, 0], radius: 0.5, material: glass }
lights:
  - ambient: { color: [1, 1, 1] }
";
    let f = render(yaml);
    let at = |row: u32, col: u32| f.pixel(row, col);
    // Without the ball the red sphere would be up-left: through it, it is down-right.
    let (down_right, up_left) = (at(75, 75), at(45, 45));
    assert!(down_right[0] > 0.5 && down_right[1] < 0.1, "{down_right:?}");
    assert!(up_left[1] > 0.5 && up_left[0] < 0.1, "{up_left:?}");
}

fn glass(reflection: f64, transmission: f64, ior: f64, fresnel: bool) -> Material {
    Material {
        ambient: DVec3::ZERO,
        diffuse: DVec3::ZERO,
        specular: DVec3::ZERO,
        exponent: 0.0,
        specular_floor: 0.0,
        reflection,
        transmission: DVec3::splat(transmission),
        ior,
        fresnel,
        diffuse_map: None,
        ambient_map: None,
    }
}

/// Follows a ray into and out of a unit sphere at the origin with the tracer's own
/// intersection and refraction: the direction it leaves in.
fn through_unit_sphere(origin: DVec3, dir: DVec3, m: &Material) -> DVec3 {
    let sphere = Shape::Sphere {
        center: DVec3::ZERO,
        radius: 1.0,
    };
    let ray = Ray {
        origin,
        dir,
        leaving: None,
    };
    let t = intersect(&sphere, &ray, false).unwrap();
    let p = origin + t * dir;
    let (_, _, inside) = scatter_one(m, dir, p.normalize(), true);
    let ray = Ray {
        origin: p,
        dir: inside,
        leaving: Some(0),
    };
    let t = intersect(&sphere, &ray, true).expect("the far side");
    let q = p + t * inside;
    // Leaving: the normal facing the ray points into the sphere.
    let (_, _, out) = scatter_one(m, inside, -q.normalize(), false);
    out
}

#[test]
fn refraction_through_a_sphere_follows_snells_law_to_1e_12() {
    let m = glass(0.0, 1.0, 1.5, false);
    // Through the centre: straight on.
    let out = through_unit_sphere(DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z, &m);
    assert!((out - DVec3::NEG_Z).length() < 1e-12, "{out}");
    // Half a radius off the axis: θ₁ = 30°, sin θ₂ = sin θ₁ / 1.5, and the ray turns towards
    // the axis by 2(θ₁ − θ₂) in all.
    for h in [0.5, 0.9, -0.3] {
        let out = through_unit_sphere(DVec3::new(0.0, h, 5.0), DVec3::NEG_Z, &m);
        let theta1 = f64::asin(h.abs());
        let theta2 = f64::asin(h.abs() / 1.5);
        let deviation = 2.0 * (theta1 - theta2);
        let got = f64::acos(-out.z);
        assert!(
            (got - deviation).abs() < 1e-12,
            "h {h}: {got} vs {deviation}"
        );
        assert!(
            out.y * h < 0.0 && out.x == 0.0,
            "h {h}: turns towards the axis: {out}"
        );
        // And at the first surface alone: Snell's sin θ₁ = 1.5 sin θ₂.
        let n = DVec3::new(0.0, h, (1.0 - h * h).sqrt());
        let (_, _, inside) = scatter_one(&m, DVec3::NEG_Z, n, true);
        let sin2 = inside.cross(-n).length();
        assert!((1.5 * sin2 - h.abs()).abs() < 1e-12, "h {h}");
    }
}

#[test]
fn total_internal_reflection_keeps_the_paths_weight() {
    // From inside glass of index 1.5 the critical angle is asin(1/1.5) ≈ 41.8°.
    let n = DVec3::Z;
    let at = |degrees: f64| {
        let a = degrees.to_radians();
        DVec3::new(a.sin(), 0.0, -a.cos())
    };
    for m in [glass(0.2, 0.8, 1.5, false), glass(0.0, 1.0, 1.5, true)] {
        let (reflect, transmit, _) = scatter_one(&m, at(60.0), n, false);
        assert_eq!(reflect, DVec3::ONE, "{m:?}");
        assert_eq!(transmit, DVec3::ZERO, "{m:?}");
        // Below the critical angle the weights still add up to 1 (to rounding).
        let (reflect, transmit, _) = scatter_one(&m, at(30.0), n, false);
        assert!((reflect + transmit - DVec3::ONE).abs().max_element() < 1e-15);
        assert!(transmit.x > 0.5, "{m:?}: most light passes at 30°");
    }
}

#[test]
fn grazing_rays_critical_angles_and_index_1_stay_finite() {
    let n = DVec3::Z;
    let critical = f64::asin(1.0 / 1.5);
    for m in [glass(0.0, 1.0, 1.5, true), glass(0.5, 0.5, 1.0, false)] {
        for a in [
            0.0,
            1e-300,
            critical - 1e-15,
            critical,
            critical + 1e-15,
            std::f64::consts::FRAC_PI_2 - 1e-17,
            std::f64::consts::FRAC_PI_2,
        ] {
            let d = DVec3::new(a.sin(), 0.0, -a.cos());
            for entering in [true, false] {
                let (r, t, dir) = scatter_one(&m, d, n, entering);
                assert!(
                    r.is_finite() && t.is_finite() && dir.is_finite(),
                    "{a} {entering}"
                );
            }
        }
    }
    // Whole frames: a glass ball seen edge-on past the talk's spheres (every frame is
    // checked for non-finite values by `render`).
    let ball = "  - sphere: { center: [0.3, -0.45, -0.2], radius: 0.25, material: glass }\n";
    render(&talk(0.5, 8, ball));
    let slab = "  - plane: { point: [0, 0.3, 0], normal: [0, 1, 0.01], material: glass }\n  - plane: { point: [0, 0.25, 0], normal: [0, -1, -0.01], material: glass }\n";
    render(&talk(0.5, 8, slab));
}
