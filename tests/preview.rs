//! `rayreel preview`: the path plot draws the path where it is, the contact sheet holds the
//! very frames a draft render gives, problems are reported, and the command's files appear.

mod common;
use common::*;

use rayreel::schedule::render_frame;
use rayreel::sequence::{self, Sequence};
use rayreel::timeline::Path as TimelinePath;
use rayreel::tools::preview::{self, SheetLayout};
use std::path::Path;

fn load(path: &Path) -> Sequence {
    sequence::load(path).unwrap()
}

fn stdout_lines(o: &std::process::Output) -> Vec<String> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn orbit_traces_a_circle_in_the_top_view() {
    let seq = load(&repo().join("sequences/orbit.yaml"));
    let TimelinePath::Orbit(orbit) = seq.timeline.path.clone() else {
        panic!("orbit.yaml is an orbit");
    };
    let (img, warnings) = preview::path_plot(&seq, None);
    assert!(warnings.is_empty(), "{warnings:?}");
    let [top, _] = preview::panels(&seq);
    let (cx, cy) = top.to_px(orbit.center);
    let radius = orbit.radius * top.scale;
    assert!(radius > 100.0, "the orbit fills the panel: {radius} px");
    let mut traced = Vec::new();
    for y in top.y..top.y + top.height {
        for x in top.x..top.x + top.width {
            if *img.get_pixel(x, y) == preview::PATH {
                traced.push((f64::from(x) + 0.5, f64::from(y) + 0.5));
            }
        }
    }
    assert!(traced.len() > 500, "{} path pixels", traced.len());
    let mut angles = [false; 36];
    for &(x, y) in &traced {
        let d = (x - cx).hypot(y - cy);
        assert!(
            (d - radius).abs() <= 3.0,
            "({x}, {y}) is {d} px from the centre, not {radius}"
        );
        let a = (y - cy).atan2(x - cx).to_degrees() + 180.0;
        angles[(a / 10.0) as usize % 36] = true;
    }
    assert!(
        angles.iter().all(|&a| a),
        "the trace goes all round: {angles:?}"
    );
    // Independently of the mapping: the trace's bounding box is centred on the plotted centre
    // (its mean is not: markers cover parts of the trace, unevenly).
    let (xs, ys): (Vec<f64>, Vec<f64>) = traced.iter().copied().unzip();
    let mid = |v: &[f64]| {
        (v.iter().copied().fold(f64::INFINITY, f64::min)
            + v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
            / 2.0
    };
    let (mx, my) = (mid(&xs), mid(&ys));
    assert!(
        (mx - cx).hypot(my - cy) < 3.0,
        "({mx}, {my}) vs ({cx}, {cy})"
    );
}

#[test]
fn the_written_path_plot_is_the_drawn_one() {
    let dir = scratch("preview-orbit");
    let file = repo().join("sequences/orbit.yaml");
    let out = run_in(&dir, &["preview", file.to_str().unwrap(), "--out", "p"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (w, h, bytes) = read_png(&dir.join("p/orbit_path.png"));
    let (img, _) = preview::path_plot(&load(&file), None);
    assert_eq!((w, h), img.dimensions());
    assert!(bytes == img.into_raw(), "the PNG holds the plot");
}

#[test]
fn contact_sheet_tiles_are_draft_renders_of_evenly_spaced_frames() {
    let dir = scratch("preview-sheet");
    let file = repo().join("sequences/flyby.yaml");
    let out = run_in(&dir, &["preview", file.to_str().unwrap(), "--out", "."]);
    assert!(out.status.success(), "{}", stderr(&out));
    let seq = load(&file);
    let (tile_w, tile_h) = (
        preview::TILE_WIDTH,
        preview::tile_height(&seq, preview::TILE_WIDTH),
    );
    assert_eq!((tile_w, tile_h), (256, 144), "960x540 has a 16:9 tile");
    let frames = preview::evenly_spaced(seq.timeline.frame_count, 12);
    // flyby.yaml ends on its last key: frames 0-144.
    let want: Vec<u64> = (0..12)
        .map(|k| (k as f64 * 144.0 / 11.0).round() as u64)
        .collect();
    assert_eq!(frames, want);
    let layout = SheetLayout::new(12, tile_w, tile_h);
    assert_eq!(
        (layout.columns, layout.rows),
        (4, 3),
        "ceil(sqrt(12)) columns"
    );
    let (w, h, sheet) = read_png(&dir.join("flyby_sheet.png"));
    assert_eq!((w, h), (layout.width, layout.height));
    assert!(w >= 4 * tile_w && h >= 3 * tile_h);
    let small = preview::draft(&seq, tile_w, tile_h);
    assert_eq!(small.settings.max_depth, 2);
    for (k, &n) in frames.iter().enumerate() {
        let (x0, y0) = layout.origin(k);
        let tile = render_frame(&small, n).unwrap().to_rgb8();
        for row in 0..tile_h {
            let at = 3 * ((y0 + row) * w + x0) as usize;
            let line = 3 * (row * tile_w) as usize;
            assert!(
                sheet[at..at + 3 * tile_w as usize] == tile[line..line + 3 * tile_w as usize],
                "tile {k} (frame {n}) differs in row {row}"
            );
        }
    }
    let (img, origins) = preview::contact_sheet(&seq, &frames, tile_w).unwrap();
    assert_eq!(img.dimensions(), (w, h));
    let expected: Vec<(u64, u32, u32)> = frames
        .iter()
        .enumerate()
        .map(|(k, &n)| (n, layout.origin(k).0, layout.origin(k).1))
        .collect();
    assert_eq!(origins, expected);
}

#[test]
fn frames_and_tiles_choose_the_sheet() {
    let dir = scratch("preview-frames");
    let file = repo().join("sequences/orbit.yaml");
    let f = file.to_str().unwrap();
    let out = run_in(&dir, &["preview", f, "--out", "a", "--frames", "0,5,143"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let layout = SheetLayout::new(3, 256, 144);
    assert_eq!((layout.columns, layout.rows), (2, 2));
    let (w, h, _) = read_png(&dir.join("a/orbit_sheet.png"));
    assert_eq!((w, h), (layout.width, layout.height));
    let out = run_in(&dir, &["preview", f, "--out", "b", "--tiles", "5"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let layout = SheetLayout::new(5, 256, 144);
    assert_eq!((layout.columns, layout.rows), (3, 2));
    let (w, h, _) = read_png(&dir.join("b/orbit_sheet.png"));
    assert_eq!((w, h), (layout.width, layout.height));
    for bad in [
        &["--frames", "0-144"][..],
        &["--frames", "x"],
        &["--tiles", "0"],
    ] {
        let mut args = vec!["preview", f, "--out", "c"];
        args.extend_from_slice(bad);
        let out = run_in(&dir, &args);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", stderr(&out));
    }
    assert!(
        !dir.join("c").exists(),
        "nothing is written for a bad command line"
    );
}

const THROUGH_A_SPHERE: &str = "\
render: { width: 320, height: 180, max_depth: 2 }
objects:
  - sphere: { center: [0, 0, 0], radius: 0.5, material: { diffuse: [0.7, 0, 0] } }
  - sphere: { center: [1.5, 0, -1], radius: 0.3, material: { diffuse: [0, 0.5, 0.8] } }
lights:
  - point: { position: [2, 3, 2], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
timeline:
  fps: 10
  duration: 2
  interpolation: linear
  keyframes:
    - { time: 0, position: [0.2, 0.1, 3], look_at: [0, 0, -10] }
    - { time: 2, position: [0.2, -0.1, -3] }
";

#[test]
fn a_path_through_a_sphere_is_warned_about_and_drawn_red() {
    let dir = scratch("preview-through");
    std::fs::write(dir.join("through.yaml"), THROUGH_A_SPHERE).unwrap();
    // Without --out the pictures go to frames/NAME/preview.
    let out = run_in(&dir, &["preview", "through.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    // z = 3 − 0.3 n is inside |z| < 0.48 (the sphere at x = 0.2, y ≈ 0) for n = 9, 10, 11.
    let err = stderr(&out);
    assert!(
        err.contains("warning: frames 9-11: the camera is inside objects[0] (sphere)"),
        "{err}"
    );
    assert!(!err.contains("objects[1]"), "{err}");
    let plot = dir.join("frames/through/preview/through_path.png");
    assert_eq!(
        stdout_lines(&out),
        vec![
            plot.strip_prefix(&dir).unwrap().display().to_string(),
            "frames/through/preview/through_sheet.png".to_string()
        ]
    );
    let (_, _, bytes) = read_png(&plot);
    let red = bytes.chunks(3).filter(|p| *p == preview::BAD.0).count();
    assert!(red > 100, "{red} red pixels");
}

#[test]
fn flyby_preview_prints_both_paths() {
    let dir = scratch("preview-flyby");
    let file = repo().join("sequences/flyby.yaml");
    let out = run_in(&dir, &["preview", file.to_str().unwrap(), "--out", "out"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        stdout_lines(&out),
        vec!["out/flyby_path.png", "out/flyby_sheet.png"]
    );
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));
    for name in ["flyby_path.png", "flyby_sheet.png"] {
        let (w, h, _) = read_png(&dir.join("out").join(name));
        assert!(w > 500 && h > 300, "{name}: {w}x{h}");
    }
    let missing = run_in(&dir, &["preview", "nope.yaml"]);
    assert_eq!(missing.status.code(), Some(2), "{}", stderr(&missing));
}

#[test]
fn check_and_render_warn_about_the_frames_preview_flags() {
    let dir = scratch("preview-warnings");
    std::fs::write(dir.join("through.yaml"), THROUGH_A_SPHERE).unwrap();
    let inside = "warning: frames 9-11: the camera is inside objects[0] (sphere)";
    let out = run_in(&dir, &["check", "through.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains(inside), "{}", stderr(&out));
    assert!(!stderr(&out).contains("objects[1]"), "{}", stderr(&out));
    let out = run_in(&dir, &["render", "through.yaml", "--frames", "0", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains(inside), "{}", stderr(&out));
    let out = run_in(
        &dir,
        &[
            "render",
            "through.yaml",
            "--frames",
            "0",
            "--progress",
            "json",
        ],
    );
    let json = format!("{{\"event\": \"warning\", \"text\": \"{inside}\"}}");
    assert!(stderr(&out).contains(&json), "{}", stderr(&out));
}

#[test]
fn the_speed_panel_plots_the_camera_speed_under_the_views() {
    let file = repo().join("sequences/flyby.yaml");
    let seq = load(&file);
    let (img, _) = preview::path_plot(&seq, None);
    let [top, _] = preview::panels(&seq);
    let below = top.y + top.height + 40;
    let traced = (below..img.height())
        .flat_map(|y| (0..img.width()).map(move |x| (x, y)))
        .filter(|&(x, y)| *img.get_pixel(x, y) == preview::PATH)
        .count();
    // A curve across most of the width, two pixels thick.
    assert!(traced > img.width() as usize, "{traced} speed pixels");
}

#[test]
fn a_path_that_fails_validation_is_still_drawn_with_the_reason() {
    let dir = scratch("preview-invalid");
    let bad = repo().join("tests/fixtures/bad/path_through_up.yaml");
    std::fs::copy(&bad, dir.join("up.yaml")).unwrap();
    // Frame 24 looks straight down along up.
    let out = run_in(
        &dir,
        &["preview", "up.yaml", "--out", "p", "--frames", "22-26"],
    );
    // Both pictures, then the same error as `check` and exit 2: the file cannot render.
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert_eq!(stdout_lines(&out), vec!["p/up_path.png", "p/up_sheet.png"]);
    let check = run_in(&dir, &["check", "up.yaml"]);
    let reason = stderr(&check);
    assert!(
        reason.contains("up is parallel to the view direction"),
        "{reason}"
    );
    assert!(stderr(&out).ends_with(&reason), "{}", stderr(&out));
    let (_, _, path) = read_png(&dir.join("p/up_path.png"));
    let red = path.chunks(3).filter(|p| *p == preview::BAD.0).count();
    assert!(red > 500, "{red} red pixels: the bad frames and the reason");
    let (_, _, sheet) = read_png(&dir.join("p/up_sheet.png"));
    assert!(
        sheet.chunks(3).any(|p| p == [90, 20, 20]),
        "a no-camera tile"
    );
}

#[test]
fn moving_things_are_drawn_along_their_paths() {
    // The turntable: the ball rolls from x = -1.6 to 1.6 at z = 0.7 (teal), the spot sweeps
    // from (2, 2.5, 2) to (-2, 2.5, 2) (amber), the blob turns on its spot (a teal ring).
    let seq = load(&repo().join("sequences/turntable.yaml"));
    let (img, _) = preview::path_plot(&seq, None);
    let [top, _] = preview::panels(&seq);
    let near = |colour, at: glam::DVec3, px: f64| {
        let (cx, cy) = top.to_px(at);
        let mut hits = 0;
        for y in top.y..top.y + top.height {
            for x in top.x..top.x + top.width {
                let d = (f64::from(x) + 0.5 - cx).hypot(f64::from(y) + 0.5 - cy);
                hits += usize::from(d <= px && *img.get_pixel(x, y) == colour);
            }
        }
        hits
    };
    for x in [-1.2, -0.4, 0.4, 1.2] {
        let on = glam::DVec3::new(x, -0.25, 0.7);
        assert!(
            near(preview::OBJECT_PATH, on, 3.0) > 0,
            "the ball's path at x = {x}"
        );
    }
    for x in [-1.5, 0.0, 1.5] {
        // The spot's path is a curve through (0, 2.8, 2.4): from above, at z in [2, 2.4].
        let (col, top_row) = top.to_px(glam::DVec3::new(x, 2.5, 1.95));
        let (_, bottom_row) = top.to_px(glam::DVec3::new(x, 2.5, 2.45));
        let col = col as u32;
        let hits = (top_row as u32..bottom_row as u32)
            .flat_map(|y| (col - 2..=col + 2).map(move |x| (x, y)))
            .filter(|&(x, y)| *img.get_pixel(x, y) == preview::LIGHT_PATH)
            .count();
        assert!(hits > 0, "the spot's path at x = {x}");
    }
    assert!(near(preview::OBJECT_PATH, glam::DVec3::new(0.0, 0.05, 0.0), 8.0) > 0);
    // A scene where nothing moves has no such colours.
    let still = load(&repo().join("sequences/orbit.yaml"));
    let (img, _) = preview::path_plot(&still, None);
    let moving = |p: &image::Rgb<u8>| *p == preview::OBJECT_PATH || *p == preview::LIGHT_PATH;
    assert!(!img.pixels().any(moving));
}
