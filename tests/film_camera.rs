//! Motion blur and depth of field: a closed shutter, a still camera and a pinhole give today's
//! bytes exactly; a blurred frame converges to the mean of the instantaneous frames across its
//! open interval; the plane in focus stays sharp while what lies far from it blurs by the
//! thin-lens amount; focus distances interpolate; fingerprints follow what a frame integrates.

mod common;
use common::*;
use glam::DVec3;
use rayreel::camera::{Degenerate, Pose};
use rayreel::frame::Frame;
use rayreel::sequence::{self, Sequence};
use rayreel::shutter::{Exposure, INSTANTS, Shutter};
use rayreel::timeline::{Ease, Interpolation, Key, Keyed, Path as TimelinePath, Speed, Timeline};
use rayreel::tracer::{self, Adaptive, Kernel, Settings, World};
use std::path::Path;

fn parse(yaml: &str) -> Sequence {
    sequence::parse(Path::new("test.yaml"), yaml).unwrap_or_else(|e| panic!("{e}\n{yaml}"))
}

/// A camera panning fast across the test scene: about 9 pixels a frame at 96 px wide.
fn panning(extra_render: &str) -> String {
    let keys = "timeline:
  fps: 24
  interpolation: linear
  keyframes:
    - { time: 0, position: [0, 0.3, 2], look_at: [-3, -0.1, -0.6], fov: 60 }
    - { time: 1, look_at: [3, -0.1, -0.6] }
";
    sequence(96, 54, keys).replacen("render: {", &format!("render: {{ {extra_render}"), 1)
}

/// Rendered frames: the `out` directory of a scratch directory that lives as long as this.
struct Rendered {
    _scratch: Scratch,
    out: std::path::PathBuf,
}

impl std::ops::Deref for Rendered {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.out
    }
}

/// Renders `yaml` to PNGs in a fresh directory with `args`; returns the frames' directory.
fn render_pngs(name: &str, yaml: &str, args: &[&str]) -> Rendered {
    let tmp = scratch(name);
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let mut all = vec!["render", "seq.yaml", "-q", "-o", "out/f_####.png"];
    all.extend(args);
    let out = run_in(&tmp, &all);
    assert!(out.status.success(), "{}", stderr(&out));
    Rendered {
        out: tmp.join("out"),
        _scratch: tmp,
    }
}

/// Pixels of every frame in `dir`, in frame order.
fn pixels(dir: &Path) -> Vec<Vec<u8>> {
    files(dir)
        .iter()
        .map(|f| read_png(&dir.join(f)).2)
        .collect()
}

#[test]
fn a_closed_shutter_or_a_still_camera_gives_the_bytes_of_no_blur() {
    let moving = panning("");
    let plain = pixels(&render_pngs("shutter-none", &moving, &["--frames", "0-3"]));
    let closed = moving.replace("render: {", "render: { shutter: 0, shutter_offset: 0.5,");
    let zero = pixels(&render_pngs("shutter-zero", &closed, &["--frames", "0-3"]));
    assert_eq!(plain, zero, "shutter 0 changed the frames");
    let open = moving.replace("render: {", "render: { shutter: 180,");
    let blurred = pixels(&render_pngs("shutter-180", &open, &["--frames", "0-3"]));
    assert!(
        blurred.iter().zip(&plain).all(|(a, b)| a != b),
        "a 180° shutter left a moving frame unblurred"
    );
    // A still camera: one key, and a keyframed film that holds still for its first frames.
    let still = sequence(
        96,
        54,
        "camera: { position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }\n",
    );
    for samples in ["1", "4", "5"] {
        let args = ["--samples", samples];
        let sharp = pixels(&render_pngs("still-none", &still, &args));
        let open = still.replace("render: {", "render: { shutter: 360, shutter_offset: -0.5,");
        assert_eq!(sharp, pixels(&render_pngs("still-360", &open, &args)));
    }
}

/// The frame `exposure` gives at `samples` samples (and adaptive extension when asked).
fn frame(seq: &Sequence, kernel: Kernel, exposure: &Exposure, settings: &Settings) -> Frame {
    let world = World::new(seq.scene.clone());
    tracer::render_with(kernel, &world, exposure, settings, 3)
}

#[test]
fn per_sample_cameras_that_all_equal_the_frames_trace_the_pinhole_rays() {
    // The path that gives each lane its own camera, forced on with 256 copies of the frame's
    // camera, must trace exactly the rays of the shared-origin pinhole path. (With more
    // samples a film frame places them differently, as Sobol' points: compared there, the
    // two frames agree within sampling noise.)
    let seq = parse(&panning(""));
    let exposure = Exposure::of_frame(&seq.timeline, None, 3).unwrap();
    let copies = Exposure {
        instants: vec![exposure.camera; INSTANTS],
        ..exposure.clone()
    };
    let adaptive = Some(Adaptive {
        threshold: 0.03,
        max_samples: 12,
    });
    let s = Settings {
        samples: 4,
        adaptive,
        ..seq.settings
    };
    let (a, b) = (
        frame(&seq, Kernel::chosen(), &exposure, &s),
        frame(&seq, Kernel::chosen(), &copies, &s),
    );
    let mean = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| (x - y).abs())
        .sum::<f32>()
        / a.rgb.len() as f32;
    assert!(mean > 0.0 && mean < 0.01, "mean difference {mean}");
    for kernel in Kernel::ALL.into_iter().filter(|k| k.supported()) {
        let s = Settings {
            samples: 1,
            adaptive: None,
            ..seq.settings
        };
        let (a, b) = (
            frame(&seq, kernel, &exposure, &s),
            frame(&seq, kernel, &copies, &s),
        );
        assert!(
            a.rgb
                .iter()
                .zip(&b.rgb)
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{} 1 spp: per-sample cameras changed the frame",
            kernel.name()
        );
    }
}

#[test]
fn an_aperture_of_0_gives_todays_bytes() {
    // The talk's image against the independent reference in tests/reference/, with a closed
    // lens, a focus distance and a shutter on its still camera.
    let talk = std::fs::read_to_string(repo().join("sequences/talk.yaml")).unwrap();
    let lensed = talk
        .replace(
            "  fov: 90\n",
            "  fov: 90\n  aperture: 0\n  focus_distance: 0.3\n",
        )
        .replace("render:\n", "render:\n  shutter: 180\n");
    assert!(lensed.contains("aperture: 0") && lensed.contains("shutter: 180"));
    let out = render_pngs("aperture-0", &lensed, &["--size", "160x90"]);
    let (_, _, reference) = read_png(&repo().join("tests/reference/talk_160x90.png"));
    assert!(
        pixels(&out)[0] == reference,
        "differs from the talk reference"
    );
    // A keyframed aperture that stays 0 on a moving camera.
    let moving = panning("");
    let keyed = moving.replace("fov: 60 }", "fov: 60, aperture: 0, focus_distance: 1 }");
    assert_ne!(moving, keyed);
    let args = ["--frames", "0-2", "--samples", "4"];
    assert_eq!(
        pixels(&render_pngs("pinhole", &moving, &args)),
        pixels(&render_pngs("pinhole-keyed", &keyed, &args))
    );
}

fn psnr(a: &[f32], b: &[f32]) -> f64 {
    let mse: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| f64::from(x.clamp(0.0, 1.0) - y.clamp(0.0, 1.0)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    -10.0 * mse.log10()
}

#[test]
fn a_blurred_frame_converges_to_the_mean_of_the_instants_across_its_interval() {
    let seq = parse(&panning("shutter: 360,"));
    let n = 12;
    let exposure = Exposure::of_frame(&seq.timeline, seq.settings.shutter, n).unwrap();
    assert_eq!(exposure.instants.len(), INSTANTS);
    let world = World::new(seq.scene.clone());
    // The mean of the instantaneous frames, each antialiased with 16 samples.
    let sharp = Settings {
        samples: 16,
        adaptive: None,
        shutter: None,
        ..seq.settings
    };
    let mut mean = vec![0f64; 3 * 96 * 54];
    for camera in &exposure.instants {
        let f = tracer::render(&world, &Exposure::still(*camera), &sharp, n);
        for (m, v) in mean.iter_mut().zip(&f.rgb) {
            *m += f64::from(*v) / INSTANTS as f64;
        }
    }
    let mean: Vec<f32> = mean.iter().map(|&v| v as f32).collect();
    let blurred = |samples| {
        let s = Settings {
            samples,
            adaptive: None,
            ..seq.settings
        };
        tracer::render(&world, &exposure, &s, n).rgb
    };
    let counts = [1, 4, 16, 64, 256];
    let quality: Vec<f64> = counts.iter().map(|&c| psnr(&blurred(c), &mean)).collect();
    let unblurred = psnr(
        &tracer::render(&world, &Exposure::still(exposure.camera), &sharp, n).rgb,
        &mean,
    );
    eprintln!(
        "PSNR against the mean of the instants: {quality:?} (unblurred at 16 spp: {unblurred:.1})"
    );
    assert!(
        quality.windows(2).all(|w| w[1] > w[0] + 1.0),
        "PSNR must rise with samples: {quality:?}"
    );
    assert!(quality[4] > 40.0, "{quality:?}");
    assert!(
        unblurred + 10.0 < quality[4],
        "the blur is too slight to test: {unblurred}"
    );
}

/// Where along `row` the values cross `level` going from `from` towards `to` (linear
/// interpolation between the pixels either side).
fn crossing(row: &[f64], from: usize, to: usize, level: f64) -> f64 {
    let step: isize = if to > from { 1 } else { -1 };
    let mut i = from as isize;
    while i != to as isize {
        let (a, b) = (row[i as usize], row[(i + step) as usize]);
        if (a - level) * (b - level) <= 0.0 && a != b {
            return i as f64 + step as f64 * (level - a) / (b - a);
        }
        i += step;
    }
    panic!("no crossing of {level} between {from} and {to}: {row:?}");
}

#[test]
fn the_plane_in_focus_stays_sharp_and_what_lies_far_from_it_blurs() {
    // Two white discs on black: one at the focus distance (2) but well off the view axis, so
    // that a sphere of focus (distance along each ray) would blur it, and one four times as far.
    // Both are about 30 pixels across.
    let scene = |lens: &str| {
        format!(
            "render: {{ width: 240, height: 120, max_depth: 1, samples: 256 }}
camera: {{ position: [0, 0, 0], look_at: [0, 0, -1], fov: 90{lens} }}
materials: {{ white: {{ ambient: [1, 1, 1], diffuse: [0, 0, 0] }} }}
objects:
  - sphere: {{ center: [-1.5, 0, -2], radius: 0.25, material: white }}
  - sphere: {{ center: [4, 0, -8], radius: 1, material: white }}
lights:
  - ambient: {{ color: [1, 1, 1] }}
"
        )
    };
    let row = |yaml: &str| {
        let f = rayreel::schedule::render_frame(&parse(yaml), 0).unwrap();
        (0..240)
            .map(|c| f64::from(f.pixel(59, c)[0]))
            .collect::<Vec<f64>>()
    };
    let pinhole = row(&scene(""));
    let (aperture, focus) = (0.2, 2.0);
    let lens = row(&scene(&format!(
        ", aperture: {aperture}, focus_distance: {focus}"
    )));
    // The near disc is centred on column 30, the far one on 180: edges from outside in.
    let edges = |r: &[f64]| {
        [(0, 30), (70, 30), (140, 180), (220, 180)].map(|(out, inside)| {
            let lo = crossing(r, out, inside, 0.1);
            let hi = crossing(r, out, inside, 0.9);
            (crossing(r, out, inside, 0.5), (hi - lo).abs())
        })
    };
    let (sharp, seen) = (edges(&pinhole), edges(&lens));
    eprintln!("edges (position, 10-90% width): pinhole {sharp:?}, lens {seen:?}");
    for k in 0..2 {
        assert!(
            (seen[k].0 - sharp[k].0).abs() <= 1.0 && seen[k].1 <= sharp[k].1 + 0.5,
            "the disc in focus lost its edge: {:?} vs {:?}",
            seen[k],
            sharp[k]
        );
    }
    // A point at depth z is spread over a disc of diameter aperture·(z − focus)/z on the plane
    // in focus; across a straight edge that disc takes 2·0.687 of its radius from 10% to 90%.
    let pixel = 2.0 * focus / 240.0;
    let diameter = aperture * (8.0 - focus) / 8.0 / pixel;
    for k in 2..4 {
        let width = seen[k].1;
        assert!(
            (width / (0.687 * diameter) - 1.0).abs() < 0.25,
            "far edge {k}: 10-90% over {width:.2} px, thin lens says {:.2}",
            0.687 * diameter
        );
        assert!(sharp[k].1 <= 1.5, "the pinhole's far edge: {:?}", sharp[k]);
    }
}

/// `rayreel camera` CSV rows of `yaml`, as numbers.
fn camera_rows(dir: &Path, yaml: &str) -> Vec<Vec<f64>> {
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
    let out = run_in(dir, &["camera", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().ends_with(",speed,focus_distance"));
    lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

#[test]
fn focus_distances_interpolate_and_print_as_the_frames_render_them() {
    let dir = scratch("focus-pull");
    // A focus pull from 1 to 3 over a second while the camera flies on: with two free keys
    // the track moves at one speed, so the focus is 1 + 2t.
    let keys = "timeline:
  fps: 12
  keyframes:
    - { time: 0, position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6], aperture: 0.05, focus_distance: 1 }
    - { time: 1, position: [0.6, 0.2, 1.4], focus_distance: 3 }
";
    let yaml = sequence(48, 27, keys);
    let rows = camera_rows(&dir, &yaml);
    assert_eq!(rows.len(), 13);
    for r in &rows {
        let want = 1.0 + 2.0 * r[1];
        assert!(
            (r[13] - want).abs() < 1e-12,
            "t = {}: focus {}",
            r[1],
            r[13]
        );
    }
    // Without focus distances the focus follows look_at; a key before the first focus
    // distance focuses on its own look_at.
    let auto = camera_rows(
        &dir,
        &yaml
            .replace(", focus_distance: 1", "")
            .replace(", focus_distance: 3", ""),
    );
    for r in &auto {
        let d = ((r[2] - r[5]).powi(2) + (r[3] - r[6]).powi(2) + (r[4] - r[7]).powi(2)).sqrt();
        assert!((r[13] - d).abs() <= 1e-12 * d, "{r:?}");
    }
    let late = camera_rows(&dir, &yaml.replace(", focus_distance: 1", ""));
    assert_eq!(late[0][13], auto[0][13]);
    assert_eq!(late[12][13], 3.0);
    // Frame n renders as a still camera given its printed pose, the aperture and the printed
    // focus distance, traced as frame n (the lens points are drawn per frame).
    std::fs::write(dir.join("seq.yaml"), &yaml).unwrap();
    let out = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "--samples",
            "4",
            "-o",
            "anim/f_##.png",
            "-q",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    for n in [0usize, 5, 12] {
        let r = &rows[n];
        let still = parse(&format!(
            "render: {{ width: 48, height: 27, samples: 4 }}\ncamera: {{ position: [{:?}, {:?}, {:?}], look_at: [{:?}, {:?}, {:?}], up: [{:?}, {:?}, {:?}], fov: {:?}, aperture: 0.05, focus_distance: {:?} }}\n{SCENE}",
            r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], r[10], r[11], r[13]
        ));
        let exposure = Exposure::of_frame(&still.timeline, None, 0).unwrap();
        let world = World::new(still.scene.clone());
        let f = tracer::render(&world, &exposure, &still.settings, n as u64);
        let (_, _, want) = read_png(&dir.join(format!("anim/f_{n:02}.png")));
        assert!(f.to_rgb8() == want, "frame {n}");
    }
}

#[test]
fn fingerprints_follow_the_lens_and_the_open_interval() {
    let plain = sequence(32, 18, THREE_KEYS);
    let dir = scratch("film-fingerprints");
    let run = |yaml: &str, output: &str, how: &str| {
        std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
        let out = run_in(&dir, &["render", "seq.yaml", "-o", output, how]);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8(out.stdout).unwrap()
    };
    let expect = |yaml: &str, want: &[&str]| {
        let p = run(yaml, "out/f_##.png", "--dry-run");
        assert!(want.iter().all(|w| p.contains(w)), "wanted {want:?}:\n{p}");
    };
    run(&plain, "out/f_##.png", "-q");
    // Writing out the defaults changes no frame; opening the lens changes every one.
    let first_key = "look_at: [-0.1, -0.1, -0.6] }";
    let explicit = plain
        .replace("render: {", "render: { shutter: 0, shutter_offset: 0.25,")
        .replace(first_key, "look_at: [-0.1, -0.1, -0.6], aperture: 0 }");
    expect(&explicit, &["49 frames: 49 up to date"]);
    let lens = plain.replace(first_key, "look_at: [-0.1, -0.1, -0.6], aperture: 0.05 }");
    expect(&lens, &["49 frames: 49 stale"]);
    // With a shutter, moving the last key also changes frame 24, which sits on the middle key
    // but whose open interval reaches past it; without one, only frames 25-48 change.
    let moved = |yaml: &str| yaml.replace("position: [0, 0.5, -2.5]", "position: [0.2, 0.5, -2.5]");
    expect(&moved(&plain), &["would render: 25-48"]);
    let film = plain.replace("render: {", "render: { shutter: 180,");
    run(&film, "out/f_##.png", "-q");
    expect(&film, &["49 frames: 49 up to date"]);
    expect(
        &moved(&film),
        &["49 frames: 24 up to date, 25 stale", "would render: 24-48"],
    );
    // A still camera's frame is the same image with a shutter, and keeps its fingerprint.
    let still = sequence(
        32,
        18,
        "camera: { position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }\n",
    );
    run(&still, "still.png", "-q");
    let shutter = still.replace("render: {", "render: { shutter: 180,");
    assert!(run(&shutter, "still.png", "--dry-run").contains("1 frame: 1 up to date"));
}

#[test]
fn a_camera_impossible_while_the_shutter_is_open_fails_that_frame() {
    // Loading rejects such keys, and every crossing of the up axis rolls the picture over
    // between the instants it checks; a degenerate instant is then only reachable through the
    // library. The camera looks straight down at t = 100.5/256 s: instant 100 of frame 0's
    // interval (1 fps, 360°, opening at the frame time), which must fail with that time.
    let pose = |z: f64| Pose {
        position: DVec3::ZERO,
        look_at: DVec3::new(0.0, -1.0, z),
        up: DVec3::Y,
        fov: 90.0,
    };
    let key = |time: f64, z: f64| Key {
        time,
        pose: pose(z),
        ease: Ease::Pass,
        aperture: 0.0,
        focus_distance: None,
    };
    let keys = vec![key(0.0, 1.0), key(0.392578125, 0.0), key(0.78515625, 1.0)];
    let timeline = Timeline {
        fps: 1.0,
        frame_count: 2,
        path: TimelinePath::Keys(Box::new(Keyed::new(
            keys,
            Interpolation::Linear,
            Speed::Keys,
        ))),
        clock: Default::default(),
        motion: Vec::new(),
    };
    let shutter = Shutter {
        angle: 360.0,
        offset: 0.5,
    };
    let e = Exposure::of_frame(&timeline, Some(shutter), 0).unwrap_err();
    assert_eq!((e.time, e.reason), (0.392578125, Degenerate::UpParallel));
    assert_eq!(
        e.to_string(),
        "up is parallel to the view direction, so the camera's roll is undefined (t = 0.392578125 s)"
    );
    assert!(Exposure::of_frame(&timeline, Some(shutter), 1).is_ok());
}

#[test]
fn blurred_and_defocused_frames_do_not_depend_on_the_thread_count() {
    // flyby.yaml: a 180° shutter, an open lens and a focus pull.
    let flyby = std::fs::read_to_string(repo().join("sequences/flyby.yaml")).unwrap();
    for samples in ["1", "4", "5"] {
        let args = |threads| {
            [
                "--size",
                "64x36",
                "--frames",
                "30,72,130",
                "--samples",
                samples,
                "--threads",
                threads,
            ]
        };
        let one = pixels(&render_pngs("film-threads-1", &flyby, &args("1")));
        let two = pixels(&render_pngs("film-threads-2", &flyby, &args("2")));
        assert_eq!(one.len(), 3);
        assert!(one == two, "{samples} samples: --threads 1 and 2 differ");
    }
}

/// A film frame with a lens at film's default sampling (Owen-scrambled Sobol' points, then
/// rounds from 4 to 64 samples), in f64 and in f32, is bit for bit what
/// tests/reference/film_reference.py and film_f32_reference.py compute from docs/spec alone.
#[test]
fn a_film_frame_is_what_the_spec_says_bit_for_bit() {
    let scene = std::fs::read_to_string(repo().join("tests/reference/film_40x24.yaml")).unwrap();
    let tmp = scratch("film-reference");
    for (precision, reference) in [
        ("f64", "film_40x24.f32"),
        ("f32", "film_40x24_precision_f32.f32"),
    ] {
        let yaml = scene.replace(
            "encoding: linear",
            &format!("encoding: linear, precision: {precision}"),
        );
        std::fs::write(tmp.join("s.yaml"), yaml).unwrap();
        let out = run_in(
            &tmp,
            &[
                "render",
                "s.yaml",
                "-q",
                "--exr-precision",
                "float",
                "-o",
                "f.exr",
                "--force",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let img = exr::prelude::read_all_flat_layers_from_file(tmp.join("f.exr")).unwrap();
        let channel = |name: &str| -> Vec<f32> {
            let c = (img.layer_data[0].channel_data.list.iter())
                .find(|c| c.name.to_string() == name)
                .unwrap_or_else(|| panic!("no channel {name}"));
            c.sample_data.values_as_f32().collect()
        };
        let (r, g, b) = (channel("R"), channel("G"), channel("B"));
        let got: Vec<u32> = (0..r.len())
            .flat_map(|i| [r[i], g[i], b[i]].map(f32::to_bits))
            .collect();
        let bytes = std::fs::read(repo().join("tests/reference").join(reference)).unwrap();
        let want: Vec<u32> = bytes
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).to_bits())
            .collect();
        assert_eq!(got.len(), want.len(), "{precision}");
        let differ = got.iter().zip(&want).filter(|(a, b)| a != b).count();
        assert_eq!(
            differ, 0,
            "{precision}: {differ} channels differ from {reference}"
        );
    }
}

/// The film filter: on by default on film, where it brings a frame closer to a converged one;
/// `--denoise off` and `render.denoise: false` both keep the rounds' means (the same bytes);
/// a sequence without film frames is neither changed nor re-fingerprinted by `--denoise on`.
#[test]
fn the_film_filter_is_on_for_film_and_can_be_turned_off() {
    let film = panning("shutter: 180,");
    let args = |more: &[&'static str]| [&["--frames", "5"], more].concat();
    let on = pixels(&render_pngs("denoise-on", &film, &args(&[])));
    let off = pixels(&render_pngs(
        "denoise-off",
        &film,
        &args(&["--denoise", "off"]),
    ));
    let file_off = film.replace("render: {", "render: { denoise: false,");
    let off_in_file = pixels(&render_pngs("denoise-off-file", &file_off, &args(&[])));
    assert_eq!(off, off_in_file);
    let truth = pixels(&render_pngs(
        "denoise-truth",
        &film,
        &args(&["--samples", "512"]),
    ));
    let rmse = |a: &[u8]| {
        let sum: f64 = (a.iter().zip(&truth[0]))
            .map(|(x, y)| (f64::from(*x) - f64::from(*y)).powi(2))
            .sum();
        (sum / a.len() as f64).sqrt()
    };
    assert!(on != off, "the filter changed nothing");
    assert!(
        rmse(&on[0]) < rmse(&off[0]),
        "{} >= {}",
        rmse(&on[0]),
        rmse(&off[0])
    );
    // A moving camera without a shutter is no film: the filter never runs, and asking for it
    // changes neither the bytes nor the fingerprint.
    let pinhole = panning("");
    let tmp = scratch("denoise-pinhole");
    std::fs::write(tmp.join("seq.yaml"), &pinhole).unwrap();
    let run = |more: &[&str]| {
        let out = run_in(
            &tmp,
            &[&["render", "seq.yaml", "-o", "out/f_#.png"], more].concat(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8_lossy(&out.stdout).into_owned() + &stderr(&out)
    };
    run(&["--frames", "5", "-q"]);
    let plain = pixels(&tmp.join("out"));
    let dry = run(&["--frames", "5", "--denoise", "on", "--dry-run"]);
    assert!(dry.contains("1 up to date"), "{dry}");
    run(&["--frames", "5", "--denoise", "on", "-q", "--force"]);
    assert_eq!(plain, pixels(&tmp.join("out")));
}
