//! Camera moves like a film camera (issue 16): speed continuous through uneven keys, stops,
//! constant speed, the film ending on its last key, and `rayreel camera`, whose printed poses
//! render the same frames as the animation.

mod common;
use common::*;
use rayreel::sequence;
use std::path::Path;

/// One line of `rayreel camera --format csv`.
#[derive(Debug, Clone, PartialEq)]
struct Row {
    frame: u64,
    time: f64,
    position: [f64; 3],
    look_at: [f64; 3],
    up: [f64; 3],
    fov: f64,
    speed: f64,
    focus: f64,
}

fn parse_row(line: &str) -> Row {
    let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(v.len(), 14, "{line}");
    assert!(v.iter().all(|x| x.is_finite()), "{line}");
    Row {
        frame: v[0] as u64,
        time: v[1],
        position: [v[2], v[3], v[4]],
        look_at: [v[5], v[6], v[7]],
        up: [v[8], v[9], v[10]],
        fov: v[11],
        speed: v[12],
        focus: v[13],
    }
}

/// A sequence of the test scene with a keyframed timeline: `timeline` lines (indented by two)
/// then the keys, each the inside of a `{ … }` flow map.
fn keyed(fps: u32, timeline: &str, keys: &[&str]) -> String {
    let mut t = format!("timeline:\n  fps: {fps}\n{timeline}  keyframes:\n");
    for k in keys {
        t.push_str(&format!("    - {{ {k} }}\n"));
    }
    sequence(48, 27, &t)
}

/// `rayreel camera FILE` on `yaml`: stdout rows, stderr.
fn camera(dir: &Path, yaml: &str) -> (Vec<Row>, String) {
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
    let out = run_in(dir, &["camera", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("frame,time,position_x,"));
    (lines.map(parse_row).collect(), stderr(&out))
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Distance travelled from each frame to the next.
fn steps(rows: &[Row]) -> Vec<f64> {
    rows.windows(2)
        .map(|w| dist(w[0].position, w[1].position))
        .collect()
}

/// The largest |d_{n+1} − d_n| / max(d_n, d_{n+1}) over consecutive per-frame distances,
/// leaving out pairs that touch a frame in `skip`.
fn largest_change(rows: &[Row], skip: &dyn Fn(u64) -> bool) -> f64 {
    let d = steps(rows);
    (0..d.len() - 1)
        .filter(|&i| !skip(i as u64) && !skip(i as u64 + 2))
        .map(|i| (d[i + 1] - d[i]).abs() / d[i].max(d[i + 1]))
        .fold(0.0, f64::max)
}

/// Key sets, one a second: uneven distances (the 1, 4, 1), a curve in 3D, uneven
/// times.
const PATHS: [&[&str]; 4] = [
    &[
        "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
        "time: 1, position: [1, 0, 5]",
        "time: 2, position: [5, 0, 5]",
        "time: 3, position: [6, 0, 5]",
    ],
    &[
        "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
        "time: 1, position: [4, 0, 5]",
        "time: 2, position: [5, 0, 5]",
        "time: 3, position: [9, 0, 5]",
    ],
    &[
        "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
        "time: 1, position: [1, 0, 5.5]",
        "time: 2, position: [3, 1, 3]",
        "time: 3, position: [3.5, 1, 2.5]",
        "time: 4, position: [2, 0, 1], look_at: [0, 0, -5]",
    ],
    &[
        "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
        "time: 0.5, position: [1, 0, 5]",
        "time: 2.5, position: [3, 0, 6]",
        "time: 3, position: [4, 0, 6], fov: 60",
    ],
];

#[test]
fn speed_changes_smoothly_through_uneven_keys() {
    let dir = scratch("motion-continuity");
    for keys in PATHS {
        let (slow, _) = camera(&dir, &keyed(24, "", keys));
        let (fast, _) = camera(&dir, &keyed(96, "", keys));
        let (at_24, at_96) = (
            largest_change(&slow, &|_| false),
            largest_change(&fast, &|_| false),
        );
        // A speed jump would stay the same size per frame whatever the frame rate; a
        // continuous speed changes less the closer the frames.
        assert!(at_24 < 0.5, "{keys:?}: {at_24}");
        assert!(
            at_24 >= 3.0 * at_96,
            "{keys:?}: {at_24} at 24 fps, {at_96} at 96"
        );
    }
}

#[test]
fn keys_are_passed_at_their_times_and_never_backwards() {
    let dir = scratch("motion-keys");
    for keys in PATHS {
        let yaml = keyed(24, "", keys);
        let seq = sequence::parse(Path::new("k.yaml"), &yaml).unwrap();
        let rayreel::timeline::Path::Keys(k) = &seq.timeline.path else {
            panic!()
        };
        for key in &k.keys {
            let p = seq.timeline.camera_at(key.time);
            assert!(p.position.distance(key.pose.position) <= 1e-9, "{p:?}");
            assert!(p.look_at.distance(key.pose.look_at) <= 1e-9);
            assert!((p.fov - key.pose.fov).abs() <= 1e-9);
        }
        let (rows, _) = camera(&dir, &yaml);
        let d = steps(&rows);
        for i in 0..d.len() - 1 {
            let (a, b, c) = (rows[i].position, rows[i + 1].position, rows[i + 2].position);
            let along: f64 = (0..3).map(|j| (b[j] - a[j]) * (c[j] - b[j])).sum();
            assert!(along > 0.0, "{keys:?}: frame {} turns back", i + 1);
        }
    }
    // Keys on a line, unevenly spaced in time and distance: x only grows.
    let line = [
        "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
        "time: 0.3, position: [2, 0, 5]",
        "time: 2, position: [2.2, 0, 5]",
        "time: 2.2, position: [6, 0, 5]",
        "time: 4, position: [6.1, 0, 5]",
    ];
    let (rows, _) = camera(&dir, &keyed(24, "", &line));
    assert!(
        rows.windows(2)
            .all(|w| w[1].position[0] >= w[0].position[0])
    );
}

#[test]
fn a_stop_halts_the_camera_there_and_only_there() {
    let dir = scratch("motion-stop");
    let mut keys: Vec<String> = PATHS[2].iter().map(|k| k.to_string()).collect();
    keys[2].push_str(", ease: stop");
    let keys: Vec<&str> = keys.iter().map(|k| k.as_str()).collect();
    let (rows, _) = camera(&dir, &keyed(24, "", &keys));
    // Frame 48 is the stop at t = 2: no speed, the key's position, and the camera creeps
    // into and out of it.
    assert_eq!(rows[48].speed, 0.0);
    assert_eq!(rows[48].position, [3.0, 1.0, 3.0]);
    let d = steps(&rows);
    assert!(
        d[47] < 0.1 * d[40] && d[48] < 0.1 * d[56],
        "{:?}",
        &d[40..57]
    );
    // Away from it (more than a quarter second) speed changes smoothly as before.
    let near = |n: u64| n.abs_diff(48) <= 6;
    assert!(largest_change(&rows, &near) < 0.5);
    assert!(rows.iter().filter(|r| r.speed == 0.0).count() == 1);
}

#[test]
fn constant_speed_covers_equal_distances() {
    let dir = scratch("motion-constant");
    let yaml = keyed(24, "  speed: constant\n", PATHS[3]);
    let (rows, _) = camera(&dir, &yaml);
    let d = steps(&rows);
    let (lo, hi) = d
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(
        hi / lo - 1.0 < 0.005,
        "per-frame distance from {lo} to {hi}"
    );
    assert!(rows.iter().all(|r| (r.speed - rows[0].speed).abs() < 1e-12));
    // `check` says that the keys between the ends are not passed at their own times.
    std::fs::write(dir.join("c.yaml"), &yaml).unwrap();
    let out = run_in(&dir, &["check", "c.yaml"]);
    // `check` wraps lines past 120 columns under the summary's indent.
    let summary = String::from_utf8_lossy(&out.stdout).replace("\n              ", " ");
    assert!(
        summary.contains("timing:     constant speed")
            && summary.contains(
                "the times of keyframes between the first and last are ignored: passed 1 at 0."
            ),
        "{summary}"
    );
}

#[test]
fn the_film_ends_on_its_last_key() {
    let dir = scratch("motion-end");
    let keys = [
        "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
        "time: 1, position: [1, 0.5, 5], look_at: [0, 1, -10], up: [0.1, 1, 0]",
        "time: 2.5, position: [3.25, 0.125, 4.5], look_at: [0.5, 0, -10], up: [0, 1, 0.2], fov: 70",
    ];
    let (rows, err) = camera(&dir, &keyed(24, "", &keys));
    assert_eq!(rows.len(), 61, "frames 0 … round(2.5 × 24)");
    let last = &rows[60];
    assert_eq!((last.frame, last.time), (60, 2.5));
    assert_eq!(last.position, [3.25, 0.125, 4.5]);
    assert_eq!(last.look_at, [0.5, 0.0, -10.0]);
    let up = [0.0, 1.0 / 1.04f64.sqrt(), 0.2 / 1.04f64.sqrt()];
    assert!(dist(last.up, up) < 1e-15, "{:?}", last.up);
    assert_eq!(last.fov, 70.0);
    assert!(err.is_empty(), "{err}");
    // With a duration the film has round(duration × fps) frames; keys after its last frame
    // are named in a warning by check, camera and render.
    let (rows, err) = camera(&dir, &keyed(24, "  duration: 1.5\n", &keys));
    assert_eq!(rows.len(), 36);
    let warning = "warning: timeline.duration: 1.5 s at 24 fps ends with frame 35 (t = 1.4583333333333333 s), so keyframe 2 (t = 2.5 s) is never shown; remove `duration` to end on the last keyframe";
    assert!(err.contains(warning), "{err}");
    for command in ["check", "render"] {
        let out = run_in(
            &dir,
            &[command, "seq.yaml", "-q"][..if command == "check" { 2 } else { 3 }],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        assert!(
            stderr(&out).contains(warning),
            "{command}: {}",
            stderr(&out)
        );
    }
    assert_eq!(files(&dir.join("frames/seq")).len(), 36);
    // A longer duration holds the last key; no warning.
    let (rows, err) = camera(&dir, &keyed(24, "  duration: 3\n", &keys));
    assert_eq!(rows.len(), 72);
    assert_eq!(rows[71].position, [3.25, 0.125, 4.5]);
    assert!(err.is_empty(), "{err}");
    // Whole-turn orbits keep their seamless loop: 12 frames, the last one step before the first.
    let (rows, _) = camera(&dir, &sequence(48, 27, &orbit(12, 1.0)));
    assert_eq!(rows.len(), 12);
    let step = dist(rows[0].position, rows[1].position);
    assert!((dist(rows[11].position, rows[0].position) - step).abs() < 1e-12);
}

/// The numbers of `"name": [x, y, z]` in a JSON line, as printed.
fn json_vector<'a>(line: &'a str, name: &str) -> Vec<&'a str> {
    let start = line.find(&format!("\"{name}\": [")).unwrap() + name.len() + 5;
    let end = start + line[start..].find(']').unwrap();
    line[start..end].split(", ").collect()
}

fn json_number<'a>(line: &'a str, name: &str) -> &'a str {
    let start = line.find(&format!("\"{name}\": ")).unwrap() + name.len() + 4;
    let end = start + line[start..].find([',', '}']).unwrap();
    &line[start..end]
}

#[test]
fn printed_poses_render_the_same_frames() {
    let dir = scratch("motion-camera-json");
    let keys = [
        "time: 0, position: [0.3, 0.1, 2.2], look_at: [-0.2, -0.1, -1]",
        "time: 0.5, position: [1.1, 0.4, 1.0], look_at: [-0.1, 0, -1], up: [0.2, 1, 0]",
        "time: 1, position: [1.4, 0.2, -0.2], look_at: [-0.2, -0.2, -1], fov: 70, ease: stop",
        "time: 1.5, position: [0.9, 0.5, -2.1], up: [0, 1, 0]",
    ];
    std::fs::write(dir.join("seq.yaml"), keyed(12, "", &keys)).unwrap();
    let out = run_in(&dir, &["camera", "seq.yaml", "--format", "json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 19);
    let fields = [
        "\"frame\": ",
        "\"time\": ",
        "\"position\": [",
        "\"look_at\": [",
        "\"up\": [",
        "\"fov\": ",
        "\"speed\": ",
        "\"focus_distance\": ",
    ];
    for line in &lines {
        let mut at = 0;
        for f in fields {
            at += line[at..]
                .find(f)
                .unwrap_or_else(|| panic!("{f} missing or out of order: {line}"));
        }
        assert!(line.starts_with('{') && line.ends_with('}'));
    }
    // One centred sample: jittered positions depend on the frame number, the pose does not.
    let centre = ["--samples", "1"];
    let anim = ["render", "seq.yaml", "-o", "anim/f_##.png", "-q"];
    let out = run_in(&dir, &[&anim[..], &centre].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    for n in [0usize, 3, 7, 12, 18] {
        let line = lines[n];
        assert_eq!(json_number(line, "frame"), n.to_string());
        let v = |name| format!("[{}]", json_vector(line, name).join(", "));
        let still = format!(
            "render: {{ width: 48, height: 27 }}\ncamera: {{ position: {}, look_at: {}, up: {}, fov: {} }}\n{SCENE}",
            v("position"),
            v("look_at"),
            v("up"),
            json_number(line, "fov")
        );
        std::fs::write(dir.join("still.yaml"), still).unwrap();
        let name = format!("still/f_{n:02}.png");
        let still = ["render", "still.yaml", "-o", &name, "-q"];
        let out = run_in(&dir, &[&still[..], &centre].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        let want = read_png(&dir.join(format!("anim/f_{n:02}.png")));
        assert_eq!(read_png(&dir.join(&name)), want, "frame {n}");
        let (p, l) = (json_vector(line, "position"), json_vector(line, "look_at"));
        let d: f64 = (0..3)
            .map(|i| (p[i].parse::<f64>().unwrap() - l[i].parse::<f64>().unwrap()).powi(2))
            .sum::<f64>()
            .sqrt();
        let focus: f64 = json_number(line, "focus_distance").parse().unwrap();
        assert!((focus - d).abs() <= 1e-12 * d);
    }
    assert_eq!(json_number(lines[12], "speed"), "0.0", "the stop");
}

#[test]
fn degenerate_keyframes_give_finite_poses() {
    let dir = scratch("motion-degenerate");
    let cases: [&[&str]; 4] = [
        // Only look_at changes: the camera holds still while it pans.
        &[
            "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
            "time: 1, look_at: [3, 0, -10]",
            "time: 2, position: [1, 0, 5]",
        ],
        // Every key the same.
        &[
            "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
            "time: 1",
            "time: 2",
        ],
        // Keys a nanosecond apart.
        &[
            "time: 0, position: [0, 0, 5], look_at: [0, 0, -10]",
            "time: 0.5, position: [1, 0, 5]",
            "time: 0.500000001, position: [2, 0, 5]",
            "time: 1, position: [2, 1, 5]",
        ],
        // Huge coordinates.
        &[
            "time: 0, position: [1e90, 0, 5e89], look_at: [0, 0, -1e90]",
            "time: 1, position: [-1e90, 3e89, 5e89]",
            "time: 2, position: [2e90, 0, 1e90]",
        ],
    ];
    for keys in cases {
        for interpolation in ["smooth", "linear"] {
            let yaml = keyed(24, &format!("  interpolation: {interpolation}\n"), keys);
            // parse_row asserts every number is finite.
            let (rows, _) = camera(&dir, &yaml);
            assert_eq!(rows.len(), 1 + 24 * if keys.len() == 4 { 1 } else { 2 });
        }
    }
    let (rows, _) = camera(&dir, &keyed(24, "", cases[0]));
    assert!(rows[..25].iter().all(|r| r.position == [0.0, 0.0, 5.0]));
    assert!(rows[12].look_at[0] > 0.0 && rows[12].speed == 0.0);
}

#[test]
fn an_independent_implementation_of_the_readme_agrees_to_1e_9() {
    // tests/reference/camera_reference.py follows docs/spec/timeline.md and
    // wrote these CSV files; rayreel must print the same numbers to 1e-9.
    let dir = scratch("motion-reference");
    for (file, reference) in [
        ("sequences/flyby.yaml", "camera_flyby.csv"),
        ("tests/reference/camera_smooth.yaml", "camera_smooth.csv"),
        ("tests/reference/camera_linear.yaml", "camera_linear.csv"),
        (
            "tests/reference/camera_constant.yaml",
            "camera_constant.csv",
        ),
    ] {
        let out = run_in(&dir, &["camera", repo().join(file).to_str().unwrap()]);
        assert!(out.status.success(), "{}", stderr(&out));
        let ours = String::from_utf8(out.stdout).unwrap();
        let theirs =
            std::fs::read_to_string(repo().join("tests/reference").join(reference)).unwrap();
        assert_eq!(
            ours.lines().count(),
            theirs.lines().count(),
            "{file}: frame count"
        );
        for (a, b) in ours.lines().zip(theirs.lines()).skip(1) {
            let (a, b) = (parse_row(a), parse_row(b));
            assert_eq!((a.frame, a.time), (b.frame, b.time), "{file}");
            let numbers = |r: &Row| {
                let mut v = vec![r.fov, r.speed, r.focus];
                v.extend(r.position.iter().chain(&r.look_at).chain(&r.up));
                v
            };
            for (x, y) in numbers(&a).into_iter().zip(numbers(&b)) {
                assert!(
                    (x - y).abs() <= 1e-9,
                    "{file} frame {}: {x} vs {y}",
                    a.frame
                );
            }
        }
    }
}

/// A camera that turns more than 60° in one frame (issue 29): a whip pan, or an orbit at
/// `fps: 0.5` (120° a frame), was refused as rolling over through up, naming "keyframes 1 and
/// 1". A pan turns continuously, so it renders; a view that really swings past up between two
/// frames is still refused, naming that frame and the keys around it.
#[test]
fn whip_pans_render_and_only_true_roll_overs_are_refused() {
    let tmp = scratch("whip-pan");
    let slow_orbit = "timeline:\n  fps: 0.5\n  orbit: { center: [-0.1, 0, -0.6], radius: 1.6, height: 0.35, duration: 6, look_at: [-0.1, -0.1, -0.6] }\n";
    let keys = |first: &str, second: &str| {
        format!(
            "timeline:\n  fps: 24\n  keyframes:\n    - {{ time: 0, position: [0, 0.3, 2], look_at: {first} }}\n    - {{ time: 0.05, look_at: {second} }}\n    - {{ time: 1 }}\n"
        )
    };
    let whip = keys("[0, 0.3, 1]", "[1, 0.3, 2]");
    for (name, timeline) in [("orbit.yaml", slow_orbit.to_string()), ("whip.yaml", whip)] {
        std::fs::write(tmp.join(name), sequence(32, 18, &timeline)).unwrap();
        let out = run_in(
            &tmp,
            &["render", name, "-q", "-o", &format!("{name}_####.png")],
        );
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        // preview flags what the loader refuses, and no more.
        let out = run_in(
            &tmp,
            &["preview", name, "--out", &format!("{name}_preview")],
        );
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        assert!(!stderr(&out).contains("rolls"), "{name}: {}", stderr(&out));
    }
    // Over the top: from just before up to just past it, in one frame.
    std::fs::write(
        tmp.join("over.yaml"),
        sequence(32, 18, &keys("[0.001, 1.3, 2.1]", "[0.001, 1.3, 1.9]")),
    )
    .unwrap();
    let out = run_in(&tmp, &["check", "over.yaml"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let said = stderr(&out);
    assert!(
        said.contains("frame 1 (")
            && said.contains("between keyframes 0 and 1: the view swings past up"),
        "{said}"
    );
}
