//! Area lights end to end through the binary: the penumbra of a sphere light against the
//! analytic visible fraction of its disk, the same bytes whatever the thread count, what
//! `check` says about them, and the example sequence.

mod common;
use common::*;
use glam::DVec3;

/// The light, the occluder and the floor of the penumbra test.
const LIGHT: DVec3 = DVec3::new(0.0, 4.0, 0.0);
const LIGHT_RADIUS: f64 = 1.0;
const BALL: DVec3 = DVec3::new(0.25, 2.0, 0.0);
const BALL_RADIUS: f64 = 0.5;
const KD: f64 = 0.8;
/// The camera looks straight down at the floor y = 0 from here.
const EYE: DVec3 = DVec3::new(0.0, 9.0, 0.0);
const FOV: f64 = 36.0;
const SIZE: u32 = 128;

fn penumbra_scene() -> String {
    let v = |p: DVec3| format!("[{}, {}, {}]", p.x, p.y, p.z);
    format!(
        "render: {{ width: {SIZE}, height: {SIZE}, samples: 1, max_depth: 1, encoding: linear }}
camera: {{ position: {}, look_at: [0, 0, 0], up: [0, 0, -1], fov: {FOV} }}
objects:
  - plane: {{ point: [0, 0, 0], normal: [0, 1, 0], material: {{ diffuse: [{KD}, {KD}, {KD}] }} }}
  - sphere: {{ center: {}, radius: {BALL_RADIUS}, material: {{ diffuse: [0.2, 0.2, 0.2] }} }}
lights:
  - sphere: {{ center: {}, radius: {LIGHT_RADIUS}, diffuse: [1, 1, 1], specular: [1, 1, 1], samples: 256 }}
",
        v(EYE),
        v(BALL),
        v(LIGHT)
    )
}

/// The eye ray through the centre of pixel (row, col), by the camera rules of the spec:
/// forward = −y, up = −z, right = +x.
fn eye_dir(row: u32, col: u32) -> DVec3 {
    let n = f64::from(SIZE);
    let x = -1.0 + 2.0 * (f64::from(col) + 0.5) / n;
    let y = 1.0 - 2.0 * (f64::from(row) + 0.5) / n;
    let s = (FOV.to_radians() * 0.5).tan();
    (DVec3::NEG_Y + x * s * DVec3::X + y * s * DVec3::NEG_Z).normalize()
}

/// Whether the segment from `p` along unit `d`, for t in (0, len), meets the ball (grown by
/// `margin`).
fn blocked(p: DVec3, d: DVec3, len: f64, margin: f64) -> bool {
    let f = p - BALL;
    let b = f.dot(d);
    let c = f.length_squared() - (BALL_RADIUS + margin).powi(2);
    let disc = b * b - c;
    if disc < 0.0 {
        return false;
    }
    let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
    t1 > 0.0 && t0 < len
}

/// The reference at floor point `p`: the light's disk (radius R through its centre,
/// perpendicular to the direction from p) on a G×G grid, each point kept when inside the
/// disk; returns the visible fraction of those points and the mean over them of
/// kd·max(0, N·L) where visible, 0 where the ball hides it.
fn reference(p: DVec3, grid: usize) -> (f64, f64) {
    let w = (LIGHT - p).normalize();
    let helper = if w.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let e1 = w.cross(helper).normalize();
    let e2 = w.cross(e1);
    let (mut inside, mut visible, mut shade) = (0u64, 0u64, 0.0);
    for i in 0..grid {
        for j in 0..grid {
            let a = -1.0 + 2.0 * (i as f64 + 0.5) / grid as f64;
            let b = -1.0 + 2.0 * (j as f64 + 0.5) / grid as f64;
            if a * a + b * b > 1.0 {
                continue;
            }
            inside += 1;
            let q = LIGHT + LIGHT_RADIUS * (a * e1 + b * e2);
            let v = q - p;
            let len = v.length();
            let l = v / len;
            if !blocked(p, l, len, 0.0) {
                visible += 1;
                shade += KD * l.y.max(0.0);
            }
        }
    }
    (visible as f64 / inside as f64, shade / inside as f64)
}

/// Whether the ball can hide any part of the light from `p`: the cone towards the light's
/// sphere (bounding its disk) against the cone towards the ball, with room to spare.
fn may_be_shaded(p: DVec3) -> bool {
    let (to_light, to_ball) = (LIGHT - p, BALL - p);
    let apart = to_light.angle_between(to_ball);
    let light = (LIGHT_RADIUS / to_light.length()).asin();
    let ball = (BALL_RADIUS / to_ball.length()).asin();
    apart < light + ball + 0.01
}

/// At 256 light samples and one pixel sample, every penumbra pixel (visible fraction strictly
/// between 0.02 and 0.98) of a sphere light's shadow, seen straight down in linear 8-bit, is
/// within 2 levels of the analytic value on at least 99% of them.
#[test]
fn a_sphere_lights_penumbra_matches_the_visible_fraction_of_its_disk() {
    let tmp = scratch("area-penumbra");
    std::fs::write(tmp.join("seq.yaml"), penumbra_scene()).unwrap();
    let out = run_in(&tmp, &["render", "seq.yaml", "-o", "f.png", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (w, h, rgb) = read_png(&tmp.join("f.png"));
    assert_eq!((w, h), (SIZE, SIZE));
    let (mut penumbra, mut within, mut lit, mut worst) = (0u32, 0u32, 0u32, 0i32);
    for row in 0..SIZE {
        for col in 0..SIZE {
            let d = eye_dir(row, col);
            let t = -EYE.y / d.y;
            // Pixels that see the ball (or graze it) are not floor pixels.
            if blocked(EYE, d, t, 1e-3) {
                continue;
            }
            let p = EYE + t * d;
            let got = i32::from(rgb[3 * (row * SIZE + col) as usize]);
            if !may_be_shaded(p) {
                // Fully lit: the ball hides nothing, the mean of N·L over the disk.
                let (f, v) = reference(p, 64);
                assert_eq!(f, 1.0);
                let want = (255.0 * v).round() as i32;
                assert!(
                    (got - want).abs() <= 2,
                    "lit ({row}, {col}): {got} vs {want}"
                );
                lit += 1;
                continue;
            }
            let (fraction, value) = reference(p, 512);
            if !(fraction > 0.02 && fraction < 0.98) {
                continue;
            }
            penumbra += 1;
            let off = (got - (255.0 * value).round() as i32).abs();
            worst = worst.max(off);
            if off <= 2 {
                within += 1;
            }
        }
    }
    let share = f64::from(within) / f64::from(penumbra);
    eprintln!(
        "penumbra: {within} of {penumbra} pixels within 2 levels ({:.2}%), worst {worst} levels; {lit} fully lit pixels checked",
        100.0 * share
    );
    assert!(penumbra > 2000, "the penumbra covers {penumbra} pixels");
    assert!(lit > 1000, "{lit} lit pixels");
    assert!(share >= 0.99, "{within} of {penumbra} within 2 levels");
}

/// A scene with both kinds of area light, glass and a mirror renders the same bytes on one
/// thread as on all of them, in f64 and f32.
#[test]
fn area_light_frames_are_the_same_whatever_the_threads() {
    let tmp = scratch("area-threads");
    let soft = std::fs::read_to_string(repo().join("sequences/soft-shadows.yaml")).unwrap();
    let glass = soft.replace(
        "objects:\n",
        "objects:\n  - sphere: { center: [0.2, 0.35, 1.6], radius: 0.35, material: { diffuse: [0, 0, 0], transmission: 0.9, ior: 1.5, fresnel: true } }\n",
    );
    assert_ne!(glass, soft);
    std::fs::write(tmp.join("seq.yaml"), glass).unwrap();
    for precision in ["f64", "f32"] {
        let mut outputs = Vec::new();
        for threads in [None, Some("1")] {
            let name = format!("{precision}-{}.png", threads.unwrap_or("all"));
            let mut args = vec!["render", "seq.yaml", "-q", "--size", "96x54"];
            args.extend(["--quality", "final", "--precision", precision, "-o", &name]);
            if let Some(t) = threads {
                args.extend(["--threads", t]);
            }
            let out = run_in(&tmp, &args);
            assert!(out.status.success(), "{}", stderr(&out));
            outputs.push(std::fs::read(tmp.join(&name)).unwrap());
        }
        assert!(
            outputs[0] == outputs[1],
            "{precision}: threads change bytes"
        );
    }
}

/// More light samples, or more pixel samples, converge on the same penumbra: the mean
/// absolute difference from a render with 1024 points on the light per pixel shrinks as
/// either grows (the pixel samples continue the light points' sequence).
#[test]
fn more_samples_of_either_kind_refine_the_penumbra() {
    let tmp = scratch("area-refine");
    let render = |light: u32, pixel: u32| {
        let text = penumbra_scene().replace("samples: 256", &format!("samples: {light}"));
        let name = format!("l{light}-p{pixel}");
        let (file, png) = (format!("{name}.yaml"), format!("{name}.png"));
        std::fs::write(tmp.join(&file), text).unwrap();
        let samples = pixel.to_string();
        let args = ["render", &file, "-q", "--samples", &samples, "-o", &png];
        let out = run_in(&tmp, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        read_png(&tmp.join(&png)).2
    };
    let error = |img: &[u8], reference: &[u8]| {
        let sum: u64 = img
            .iter()
            .zip(reference)
            .map(|(&a, &b)| u64::from(a.abs_diff(b)))
            .sum();
        sum as f64 / img.len() as f64
    };
    // Light samples at one pixel sample (the pixel centre).
    let centre = render(1024, 1);
    let light: Vec<f64> = [4, 16, 64]
        .iter()
        .map(|&m| error(&render(m, 1), &centre))
        .collect();
    // Pixel samples with 4 light samples each, against 64 × 16 points per pixel.
    let spread = render(64, 16);
    let pixel: Vec<f64> = [1, 4, 16]
        .iter()
        .map(|&n| error(&render(4, n), &spread))
        .collect();
    eprintln!(
        "mean |error| in levels: 4/16/64 light samples at 1 pixel sample {light:.3?}; 4 light samples at 1/4/16 pixel samples {pixel:.3?}"
    );
    assert!(light[0] > light[1] && light[1] > light[2], "{light:?}");
    assert!(pixel[0] > pixel[1] && pixel[1] > pixel[2], "{pixel:?}");
}

/// `check` lists area lights with their samples, counts their shadow rays, and notes a
/// penumbra that will be noisy at the file's sampling.
#[test]
fn check_lists_area_lights_and_notes_a_noisy_penumbra() {
    let tmp = scratch("area-check");
    let soft = repo().join("sequences/soft-shadows.yaml");
    let out = run_in(&tmp, &["check", soft.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        text.contains("  lights:     2 (1 sphere (16 samples), 1 rect (16 samples))\n"),
        "{text}"
    );
    assert!(!text.contains("note: lights"), "{text}");
    // 640×360 pixels × 4 samples × (1 + 16 + 16) × max_depth 3.
    let rays = 640.0 * 360.0 * 4.0 * 33.0 * 3.0;
    assert!(
        text.contains(&format!("at most {rays:.2e} rays (an upper bound")),
        "{text}"
    );
    let few = std::fs::read_to_string(&soft)
        .unwrap()
        .replace("samples: 4\n", "samples: 1\n");
    std::fs::write(tmp.join("few.yaml"), few).unwrap();
    let out = run_in(&tmp, &["check", "few.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        text.contains("note: lights[0] (sphere): 16 samples × 1 pixel sample = 16 points on the light per pixel, under 64"),
        "{text}"
    );
    assert!(text.contains("note: lights[1] (rect)"), "{text}");
}

#[test]
fn the_soft_shadows_example_checks_and_renders() {
    let tmp = scratch("area-example");
    let file = repo().join("sequences/soft-shadows.yaml");
    let out = run_in(
        &tmp,
        &[
            "render",
            file.to_str().unwrap(),
            "--size",
            "64x36",
            "-o",
            "f.png",
            "-q",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let (w, h, rgb) = read_png(&tmp.join("f.png"));
    assert_eq!((w, h), (64, 36));
    assert!(rgb.iter().any(|&v| v > 100), "the lights light something");
}

/// Skipping the shadow rays of lanes whose cone towards an area light meets no opaque object
/// changes no byte: the talk with a sphere light and with a rect light (spheres resting on a
/// huge floor sphere, partly shadowed cones), the penumbra scene (a plane floor) and the soft
/// shadows example with a glass ball (whose filter still applies), in f64 and f32, rendered
/// with the test on and switched off (`RAYREEL_SHADOW_CONES=off`: every shadow ray traced).
#[test]
fn skipping_shadow_rays_of_open_cones_changes_no_byte() {
    let tmp = scratch("area-cones");
    let talk = std::fs::read_to_string(repo().join("sequences/talk.yaml")).unwrap();
    let point = "- point: { position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }";
    assert!(talk.contains(point));
    let sphere = talk.replace(
        point,
        "- sphere: { center: [5, 5, 5], radius: 0.5, ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1], samples: 16 }",
    );
    let rect = talk.replace(
        point,
        "- rect: { corner: [4.45, 5.15, 5.4], edge_u: [0.4, 0.4, -0.8], edge_v: [0.7, -0.7, 0], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1], samples: 16 }",
    );
    let soft = std::fs::read_to_string(repo().join("sequences/soft-shadows.yaml")).unwrap();
    let glass = soft.replace(
        "objects:\n",
        "objects:\n  - sphere: { center: [0.2, 0.35, 1.6], radius: 0.35, material: { diffuse: [0, 0, 0], transmission: 0.9, ior: 1.5, fresnel: true } }\n",
    );
    let scenes = [
        ("talk-sphere", sphere),
        ("talk-rect", rect),
        ("penumbra", penumbra_scene()),
        ("glass", glass),
    ];
    for (name, text) in scenes {
        std::fs::write(tmp.join(format!("{name}.yaml")), text).unwrap();
        for precision in ["f64", "f32"] {
            let mut outputs = Vec::new();
            for cones in ["on", "off"] {
                let png = format!("{name}-{precision}-{cones}.png");
                let file = format!("{name}.yaml");
                let args = [
                    "render",
                    &file,
                    "-q",
                    "--size",
                    "96x54",
                    "--samples",
                    "2",
                    "--precision",
                    precision,
                    "-o",
                    &png,
                ];
                let out = bin()
                    .args(args)
                    .current_dir(&tmp)
                    .env("RAYREEL_SHADOW_CONES", cones)
                    .output()
                    .expect("rayreel runs");
                assert!(out.status.success(), "{}", stderr(&out));
                outputs.push(std::fs::read(tmp.join(&png)).unwrap());
            }
            assert!(
                outputs[0] == outputs[1],
                "{name} {precision}: the skip changed bytes"
            );
        }
    }
}
