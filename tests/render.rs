//! The core tracer end to end: the talk's image through the binary, and single pixels through
//! the library against values worked out by hand from the shading formulas.

mod common;
use common::*;
use rayreel::sequence;
use std::path::Path;

#[test]
fn talk_renders_one_png_of_the_requested_size() {
    let tmp = scratch("talk");
    let out = run_in(
        &tmp,
        &[
            "render",
            repo().join("sequences/talk.yaml").to_str().unwrap(),
            "--size",
            "160x90",
            "--output",
            "out/frame_####.png",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(out.stdout.is_empty(), "stdout must stay clean");
    assert_eq!(files(&tmp), vec!["out/frame_0000.png"]);
    let (w, h, ours) = read_png(&tmp.join("out/frame_0000.png"));
    assert_eq!((w, h), (160, 90));
    // An independent float64 implementation of the same conventions (tests/reference/).
    let (_, _, reference) = read_png(&repo().join("tests/reference/talk_160x90.png"));
    let differing = ours.iter().zip(&reference).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "channels differing from the reference image");
}

/// Renders `yaml` (a 1×1 image unless it says otherwise) and returns pixel (0, 0) as floats.
fn pixel(yaml: &str) -> [f32; 3] {
    let mut seq = sequence::parse(Path::new("test.yaml"), yaml).unwrap_or_else(|e| panic!("{e}"));
    // One ray through the pixel centre, whose value the formulas give.
    (seq.settings.samples, seq.settings.adaptive) = (1, None);
    let frame = rayreel::schedule::render_frame(&seq, 0).unwrap();
    frame.pixel(0, 0)
}

fn assert_close(got: [f32; 3], want: [f64; 3]) {
    for c in 0..3 {
        assert!(
            (f64::from(got[c]) - want[c]).abs() < 1e-6,
            "got {got:?}, want {want:?}"
        );
    }
}

/// One pixel looking down −z at a sphere whose front is at z = −0.5, normal (0, 0, 1).
const HEAD_ON: &str = "
render: { width: 1, height: 1, max_depth: 1 }
camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
materials:
  m: { ambient: [0.1, 0, 0], diffuse: [0.5, 0.2, 0], specular: [0.25, 0.25, 0.25], shininess: 8 }
objects:
  - sphere: { center: [0, 0, -1], radius: 0.5, material: m }
";

#[test]
fn lit_head_on_is_ambient_plus_diffuse_plus_specular() {
    // L = V = N: N·L = N·H = 1.
    let yaml = format!(
        "{HEAD_ON}lights:\n  - point: {{ position: [0, 0, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}\n"
    );
    assert_close(pixel(&yaml), [0.85, 0.45, 0.25]);
}

#[test]
fn light_at_45_degrees() {
    // Hit (0,0,−0.5), light (0,2,1.5): L = (0,1,1)/√2, N·L = cos 45°, H halfway between L and
    // V = (0,0,1), so N·H = cos 22.5°; exponent 8/4 = 2 gives cos² 22.5° = 0.853553.
    let yaml = format!(
        "{HEAD_ON}lights:\n  - point: {{ position: [0, 2, 1.5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}\n"
    );
    let nl = std::f64::consts::FRAC_1_SQRT_2;
    let spec = (22.5f64.to_radians().cos()).powi(2);
    assert_close(
        pixel(&yaml),
        [
            0.1 + 0.5 * nl + 0.25 * spec,
            0.2 * nl + 0.25 * spec,
            0.25 * spec,
        ],
    );
}

#[test]
fn blocked_light_leaves_only_its_ambient() {
    let yaml = HEAD_ON.replace(
        "objects:\n",
        "objects:\n  - sphere: { center: [0, 1, 0.5], radius: 0.3, material: m }\n",
    ) + "lights:\n  - point: { position: [0, 2, 1.5], ambient: [0.5, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }\n";
    assert_close(pixel(&yaml), [0.05, 0.0, 0.0]);
}

#[test]
fn directional_and_ambient_lights() {
    // Directional light shining along −z: L = (0,0,1), so N·L = N·H = 1; ambient light adds ka∘c.
    let yaml = format!(
        "{HEAD_ON}lights:\n  - directional: {{ direction: [0, 0, -1], diffuse: [1, 1, 1], specular: [0, 0, 0] }}\n  - ambient: {{ color: [0.5, 0.5, 0.5] }}\n"
    );
    assert_close(pixel(&yaml), [0.5 + 0.05, 0.2, 0.0]);
}

#[test]
fn spot_light_falls_off_between_its_angles() {
    // The hit point is 30° off the spot's axis, halfway between 20° and 40° in cosine terms
    // only approximately, so compute the smoothstep by hand.
    let spot = "lights:\n  - spot: { position: [0, 0, 5], direction: [0, 0.5773502691896257, -1], inner_angle: 20, outer_angle: 40, diffuse: [1, 1, 1], specular: [0, 0, 0] }\n";
    let yaml = format!("{HEAD_ON}{spot}");
    let cos = |d: f64| d.to_radians().cos();
    let x = (cos(30.0) - cos(40.0)) / (cos(20.0) - cos(40.0));
    let falloff = x * x * (3.0 - 2.0 * x);
    assert_close(pixel(&yaml), [0.5 * falloff, 0.2 * falloff, 0.0]);
}

#[test]
fn reflection_adds_the_next_surface_weighted() {
    // The eye ray hits sphere A head on and reflects straight back to sphere B behind the
    // camera; with only an ambient light the pixel is kaA + rA·kaB.
    let yaml = "
render: { width: 1, height: 1, max_depth: 2 }
camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
objects:
  - sphere: { center: [0, 0, -1], radius: 0.5, material: { ambient: [0.2, 0, 0], diffuse: [0, 0, 0], reflection: 0.5 } }
  - sphere: { center: [0, 0, 3], radius: 0.5, material: { ambient: [0, 0.4, 0.8], diffuse: [0, 0, 0] } }
lights:
  - ambient: { color: [1, 1, 1] }
";
    assert_close(pixel(yaml), [0.2, 0.2, 0.4]);
    assert_close(
        pixel(&yaml.replace("max_depth: 2", "max_depth: 1")),
        [0.2, 0.0, 0.0],
    );
}

#[test]
fn miss_shows_the_background() {
    let yaml = "
render: { width: 1, height: 1, background: [0.25, 0.5, 1] }
camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
";
    assert_close(pixel(yaml), [0.25, 0.5, 1.0]);
}
