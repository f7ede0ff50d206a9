//! `render.precision: f32` through the binary: what it changes (some pixels, by little), what
//! it keeps (every f64 byte, every frame's determinism), and where it gives way to f64 with a
//! warning naming the object.

mod common;

use common::{run_in, scratch, stderr};
use std::path::Path;

/// The raw rgb24 stream of `file` with `args`.
fn frames(dir: &Path, file: &str, args: &[&str]) -> Vec<u8> {
    let all = [&["render", file, "-q", "--pipe", "raw"][..], args].concat();
    let out = run_in(dir, &all);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    out.stdout
}

/// PSNR in dB and the share of pixels with a channel off by more than 2 levels.
fn errors(a: &[u8], b: &[u8]) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let se: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| f64::from(x.abs_diff(*y)).powi(2))
        .sum();
    let off = a
        .chunks(3)
        .zip(b.chunks(3))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 2))
        .count();
    let rmse = (se / a.len() as f64).sqrt();
    (
        20.0 * (255.0 / rmse).log10(),
        off as f64 / (a.len() / 3) as f64,
    )
}

fn copy(dir: &Path, from: &str, to: &str, edit: impl Fn(String) -> String) {
    let text = std::fs::read_to_string(common::repo().join(from)).unwrap();
    std::fs::write(dir.join(to), edit(text)).unwrap();
}

#[test]
fn the_talk_in_f32_is_within_the_targets_of_f64() {
    let tmp = scratch("precision-talk");
    copy(&tmp, "sequences/talk.yaml", "talk.yaml", |t| t);
    let size = ["--size", "960x540"];
    let f64 = frames(&tmp, "talk.yaml", &size);
    let f32 = frames(
        &tmp,
        "talk.yaml",
        &[&size[..], &["--precision", "f32"]].concat(),
    );
    assert_ne!(f64, f32, "f32 must actually trace in f32");
    let (psnr, off) = errors(&f64, &f32);
    assert!(psnr >= 45.0, "PSNR {psnr}");
    assert!(
        off <= 0.0005,
        "{off} of the pixels are off by more than 2 levels"
    );
    // The file's own field says the same as the flag.
    copy(&tmp, "sequences/talk.yaml", "talk32.yaml", |t| {
        t.replacen("render:\n", "render:\n  precision: f32\n", 1)
    });
    assert_eq!(frames(&tmp, "talk32.yaml", &size), f32);
    let out = run_in(&tmp, &["check", "talk32.yaml"]);
    assert!(out.status.success() && !stderr(&out).contains("f32"));
}

/// Every scene of sequences/extremes renders in f32 within 40 dB of f64 (or says it falls
/// back, which none does today).
#[test]
fn the_extreme_scenes_in_f32_stay_within_40_db() {
    let tmp = scratch("precision-extremes");
    for (name, frames_spec) in [
        ("giant_floor_grazing", "0-96:16"),
        ("parallel_mirrors", "0-48:24"),
        ("scaled_1e-4", "0"),
        ("scaled_1e4", "0"),
        ("translated_1e5", "0"),
    ] {
        let file = format!("{name}.yaml");
        copy(&tmp, &format!("sequences/extremes/{file}"), &file, |t| t);
        let args = ["--size", "320x180", "--frames", frames_spec];
        let f64 = frames(&tmp, &file, &args);
        let f32 = frames(&tmp, &file, &[&args[..], &["--precision", "f32"]].concat());
        for (k, (a, b)) in f64
            .chunks(320 * 180 * 3)
            .zip(f32.chunks(320 * 180 * 3))
            .enumerate()
        {
            let (psnr, _) = errors(a, b);
            assert!(psnr >= 40.0, "{name} frame {k}: {psnr} dB");
        }
    }
}

/// The talk's floor grown to radius 9e6 (its top still 0.7 below the camera): f32 places it
/// only to about 100 pixels at 320×180, so `check` and `render` name it and the frame is the
/// f64 frame, byte for byte; at radius 9e3 (the talk's own) f32 is used.
#[test]
fn a_scene_f32_cannot_resolve_is_named_and_traced_in_f64() {
    let tmp = scratch("precision-fallback");
    let grown = |t: String| {
        t.replacen("render:\n", "render:\n  precision: f32\n", 1)
            .replacen(
                "center: [0, -9000, 0],  radius: 8999.3",
                "center: [0, -9e6, 0],  radius: 8999999.3",
                1,
            )
    };
    copy(&tmp, "sequences/talk.yaml", "grown.yaml", grown);
    let out = run_in(&tmp, &["check", "grown.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let size = ["--size", "320x180"];
    let check = stderr(&run_in(&tmp, &["check", "grown.yaml"]));
    // At the file's 1280×720 the error is 4× that at 320×180.
    assert!(
        check.contains("frame 0: f32 places objects[3] (sphere) only to 386.")
            && check.contains("so it is traced in f64"),
        "{check}"
    );
    let render = run_in(
        &tmp,
        &["render", "grown.yaml", "--size", "320x180", "--pipe", "raw"],
    );
    assert!(
        stderr(&render).contains("objects[3] (sphere) only to 96."),
        "{}",
        stderr(&render)
    );
    let f64 = frames(
        &tmp,
        "grown.yaml",
        &[&size[..], &["--precision", "f64"]].concat(),
    );
    assert_eq!(render.stdout, f64, "the fallback is the f64 frame");
}

/// `scene` rendered at `size` in f32 says `warning` and is the f64 frame, byte for byte.
fn falls_back(dir: &Path, scene: &str, size: &str, warning: &str) {
    let f32 = run_in(
        dir,
        &[
            "render",
            scene,
            "--size",
            size,
            "--pipe",
            "raw",
            "--precision",
            "f32",
        ],
    );
    assert!(f32.status.success(), "{}", stderr(&f32));
    assert!(stderr(&f32).contains(warning), "{scene}: {}", stderr(&f32));
    let f64 = frames(dir, scene, &["--size", size, "--precision", "f64"]);
    assert_eq!(f32.stdout, f64, "{scene}: the fallback is the f64 frame");
}

/// A telephoto shot of spheres small against their distance (r = 3e-6 at 10, fov 5e-4°): E
/// is under a pixel at 200×112, but each normal is off by u·R/r ≈ 0.02 rad, which left 1.35%
/// of the pixels more than 2 levels off (max 67) with no word. Now it is traced in f64.
#[test]
fn a_telephoto_shot_of_small_spheres_falls_back_to_f64() {
    let tmp = scratch("precision-telephoto");
    let scene = "render: { width: 200, height: 112, max_depth: 3 }
camera: { position: [0, 0.001, 10], look_at: [0, 0, 0], fov: 0.0005 }
materials:
  red:   { ambient: [0.1, 0, 0], diffuse: [0.7, 0, 0], specular: [1, 1, 1], shininess: 100, reflection: 0.5 }
  floor: { ambient: [0.1, 0.1, 0.1], diffuse: [0.6, 0.6, 0.6], specular: [1, 1, 1], shininess: 100, reflection: 0.5 }
objects:
  - sphere: { center: [0, 0, 0], radius: 3e-6, material: red }
  - sphere: { center: [3e-6, 0, 3e-6], radius: 3e-6, material: red }
  - sphere: { center: [-3e-6, 3e-6, -3e-6], radius: 3e-6, material: red }
  - plane:  { point: [0, -3e-6, 0], normal: [0, 1, 0], material: floor }
lights:
  - point: { position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
timeline: { fps: 24, keyframes: [ { time: 0 } ] }
";
    std::fs::write(tmp.join("tele.yaml"), scene).unwrap();
    let needle = "f32 knows the normals of objects[2] (sphere) only to 1.99e-1 rad";
    falls_back(&tmp, "tele.yaml", "200x112", needle);
    let f32 = scene.replacen("max_depth: 3 }", "max_depth: 3, precision: f32 }", 1);
    std::fs::write(tmp.join("tele32.yaml"), f32).unwrap();
    let check = stderr(&run_in(&tmp, &["check", "tele32.yaml"]));
    assert!(check.contains(needle), "{check}");
}

/// A lens far wider than the scene moves every ray's origin up to half the aperture from the
/// camera: with aperture 1e8 f32 left 55% of the talk's pixels off, at 1e100 a black frame.
/// The spread is in every reach, so both are traced in f64 and named.
#[test]
fn a_huge_aperture_falls_back_to_f64() {
    let tmp = scratch("precision-aperture");
    for (aperture, needle) in [
        (
            "1e8",
            "f32 knows the normals of objects[1] (sphere) only to 2.98e1 rad",
        ),
        ("1e100", "objects[0] (sphere) has a size f32 cannot square"),
    ] {
        let name = format!("lens{aperture}.yaml");
        copy(&tmp, "sequences/talk.yaml", &name, |t| {
            t.replacen(
                "  fov: 90\n",
                &format!("  fov: 90\n  aperture: {aperture}\n"),
                1,
            )
        });
        falls_back(&tmp, &name, "200x112", needle);
    }
}

/// f32 frames are other frames: files rendered in f64 are not up to date for an f32 run (and
/// the other way round); an f32 run keeps the f64 frame (a quality difference, never lowered
/// unasked), an f64 run re-renders an f32 one.
#[test]
fn precision_is_in_the_fingerprint() {
    let tmp = scratch("precision-resume");
    copy(&tmp, "sequences/talk.yaml", "talk.yaml", |t| t);
    let render = |p: &str| {
        let out = run_in(
            &tmp,
            &[
                "render",
                "talk.yaml",
                "-q",
                "--size",
                "64x36",
                "-o",
                "f/####.png",
                "--precision",
                p,
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        std::fs::read(tmp.join("f/0000.png")).unwrap()
    };
    let status = |p: &str| {
        let out = run_in(
            &tmp,
            &[
                "status",
                "talk.yaml",
                "--size",
                "64x36",
                "-o",
                "f/####.png",
                "--precision",
                p,
            ],
        );
        String::from_utf8_lossy(&out.stdout).to_string() + &stderr(&out)
    };
    let a = render("f64");
    let done = status("f64");
    assert_ne!(
        done,
        status("f32"),
        "f64 frames must not count as done for f32"
    );
    assert_eq!(render("f32"), a, "an f32 run keeps the f64 frame");
    std::fs::remove_file(tmp.join("f/0000.png")).unwrap();
    let b = render("f32");
    assert_ne!(a, b);
    assert_ne!(status("f32"), status("f64"));
    assert_eq!(render("f64"), a, "an f64 run raises the f32 frame");
}
