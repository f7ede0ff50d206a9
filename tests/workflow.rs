//! A user's own shot from start to finish, through the binary: a video encoded from the
//! frames on disk (rendering only what is missing), drafts that never meet finished frames,
//! and the smaller things a first session trips over (messages, `check` beside `preview`,
//! channel files).

mod common;
use common::*;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::Stdio;

/// `rayreel ARGS` in `dir` is refused (exit 2) with `want` in its message.
fn refused(dir: &Path, args: &[&str], want: &str) {
    let out = run_in(dir, args);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    assert!(stderr(&out).contains(want), "{want} in {}", stderr(&out));
}

fn tools() -> bool {
    have_tool("ffmpeg") && have_tool("ffprobe")
}

/// A 12-frame shot of the test scene at 48×28 in `dir/seq.yaml`.
fn shot(dir: &Path) {
    let timeline = "timeline:\n  fps: 12\n  keyframes:\n    - { time: 0, position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }\n    - { time: 0.9166666666666666, position: [1.5, 0.4, 0.5] }\n";
    std::fs::write(dir.join("seq.yaml"), sequence(48, 28, timeline)).unwrap();
}

/// The frames of a video decoded by ffmpeg as raw rgb24.
fn decoded(video: &Path) -> Vec<u8> {
    let out = std::process::Command::new("ffmpeg")
        .args(["-v", "error", "-i"])
        .arg(video)
        .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    out.stdout
}

/// When each file below `dir` was last written.
fn modified(dir: &Path) -> Vec<std::time::SystemTime> {
    let time = |f: &String| std::fs::metadata(dir.join(f)).unwrap().modified().unwrap();
    files(dir).iter().map(time).collect()
}

/// Lossless video, so decoded frames can be compared with the stream byte for byte.
const LOSSLESS: &str = "-c:v ffv1 -pix_fmt bgr0";

#[test]
fn a_video_from_finished_frames_renders_nothing_and_holds_the_streams_frames() {
    if !tools() {
        return;
    }
    let dir = scratch("workflow-video-files");
    shot(&dir);
    let o = ["-o", "out/f_####.png"];
    let rendered = run_in(&dir, &["render", "seq.yaml", "-q", o[0], o[1]]);
    assert!(rendered.status.success(), "{}", stderr(&rendered));
    let before = modified(&dir.join("out"));
    // The dry run says what is rendered (nothing) and what is encoded.
    let dry = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            o[0],
            o[1],
            "--video",
            "v.mkv",
            "--dry-run",
        ],
    );
    let text = String::from_utf8_lossy(&dry.stdout);
    assert!(
        text.contains("12 frames: 12 up to date → rendering 0"),
        "{text}"
    );
    assert!(
        text.contains("would render: nothing: every selected frame is finished"),
        "{text}"
    );
    assert!(
        text.contains("then would encode frames 0-11 from out/f_%04d.png into v.mkv"),
        "{text}"
    );
    let args = [
        "render",
        "seq.yaml",
        o[0],
        o[1],
        "--video",
        "v.mkv",
        "--video-args",
        LOSSLESS,
    ];
    let made = run_in(&dir, &args);
    let log = stderr(&made);
    assert!(made.status.success(), "{log}");
    assert!(log.contains("rendering 0"), "{log}");
    assert!(
        log.contains("encoding 12 frames from out/f_%04d.png into v.mkv"),
        "{log}"
    );
    assert!(!log.contains("rendered "), "nothing is rendered: {log}");
    let after = modified(&dir.join("out"));
    assert_eq!(before, after, "the frames are read, not written");
    // The video holds exactly the frames the stream carries.
    let stream = run_in(&dir, &["render", "seq.yaml", "--pipe", "raw", "-q"]);
    assert!(stream.status.success(), "{}", stderr(&stream));
    assert_eq!(decoded(&dir.join("v.mkv")), stream.stdout);
}

#[test]
fn a_video_with_missing_frames_renders_only_those_then_encodes_them_all() {
    if !tools() {
        return;
    }
    let dir = scratch("workflow-video-missing");
    shot(&dir);
    let first = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "-q",
            "-o",
            "out/f_####.png",
            "--frames",
            "0-7",
        ],
    );
    assert!(first.status.success(), "{}", stderr(&first));
    let args = [
        "render",
        "seq.yaml",
        "-o",
        "out/f_####.png",
        "--video",
        "v.mkv",
        "--video-args",
        LOSSLESS,
    ];
    let made = run_in(&dir, &args);
    let log = stderr(&made);
    assert!(made.status.success(), "{log}");
    assert!(
        log.contains("12 frames: 8 up to date, 4 missing → rendering 4"),
        "{log}"
    );
    assert!(log.contains("rendered 4 frames"), "{log}");
    assert!(log.contains("encoded 12 frames"), "{log}");
    assert_eq!(files(&dir.join("out")).len(), 12);
    let stream = run_in(&dir, &["render", "seq.yaml", "--pipe", "raw", "-q"]);
    assert_eq!(decoded(&dir.join("v.mkv")), stream.stdout);
    // A file that is not a finished frame stops the video before ffmpeg starts.
    std::fs::write(dir.join("out/f_0003.png"), b"not a frame").unwrap();
    let again = [
        "render",
        "seq.yaml",
        "-o",
        "out/f_####.png",
        "--video",
        "w.mkv",
        "--dry-run",
    ];
    let dry = run_in(&dir, &again);
    let text = String::from_utf8_lossy(&dry.stdout);
    assert!(text.contains("would render: 3"), "{text}");
}

#[test]
fn an_interrupted_video_keeps_its_frames_and_says_what_it_keeps() {
    if !tools() {
        return;
    }
    let dir = scratch("workflow-video-interrupt");
    // Frames slow enough to be stopped between them (about 0.2 s each on one thread).
    let timeline = "timeline:\n  fps: 12\n  keyframes:\n    - { time: 0, position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }\n    - { time: 2, position: [1.5, 0.4, 0.5] }\n";
    let yaml = sequence(160, 90, timeline).replace(
        "render: { width: 160, height: 90 }",
        "render: { width: 160, height: 90, samples: 36 }",
    );
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
    let mut child = bin()
        .args([
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--video",
            "v.mp4",
            "-j",
            "1",
        ])
        .current_dir(&dir)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut log = String::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        log += &line;
        log.push('\n');
        if line.starts_with("frame 1 written") {
            signal(&child, libc::SIGINT);
            break;
        }
    }
    lines.for_each(|l| log += &(l.unwrap() + "\n"));
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{log}");
    assert!(log.contains("frames already written stay"), "{log}");
    assert!(
        log.contains("no video was made yet: run the same command again"),
        "{log}"
    );
    assert!(!dir.join("v.mp4").exists());
    let kept = files(&dir.join("out")).len();
    assert!(kept >= 2, "{log}");
    // Without -o, the run says at the start that an interruption keeps nothing.
    let dry = run_in(
        &dir,
        &["render", "seq.yaml", "--video", "w.mp4", "--dry-run"],
    );
    let text = String::from_utf8_lossy(&dry.stdout);
    assert!(
        text.contains("would render frames 0-24 straight into w.mp4"),
        "{text}"
    );
    assert!(
        text.contains("an interruption keeps nothing of w.mp4"),
        "{text}"
    );
}

#[test]
fn drafts_go_beside_the_frames_and_a_resize_never_replaces_them() {
    let dir = scratch("workflow-draft");
    shot(&dir);
    let full = run_in(&dir, &["render", "seq.yaml", "-q", "--frames", "0-2"]);
    assert!(full.status.success(), "{}", stderr(&full));
    let finished: Vec<Vec<u8>> = files(&dir.join("frames/seq"))
        .iter()
        .map(|f| std::fs::read(dir.join("frames/seq").join(f)).unwrap())
        .collect();
    let draft = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "--quality",
            "draft",
            "--frames",
            "0-2",
        ],
    );
    let log = stderr(&draft);
    assert!(draft.status.success(), "{log}");
    assert!(log.contains("3 frames: 3 missing → rendering 3"), "{log}");
    assert_eq!(
        files(&dir.join("frames/seq")),
        [
            "draft/frame_0000.png",
            "draft/frame_0001.png",
            "draft/frame_0002.png",
            "frame_0000.png",
            "frame_0001.png",
            "frame_0002.png"
        ]
    );
    let (w, h, _) = read_png(&dir.join("frames/seq/draft/frame_0000.png"));
    assert_eq!((w, h), (24, 14));
    // Another size at the frames' own name is refused unforced, with the reason.
    let small = run_in(
        &dir,
        &["render", "seq.yaml", "--size", "24x14", "--frames", "0-2"],
    );
    let log = stderr(&small);
    assert!(small.status.success(), "{log}");
    assert!(log.contains("3 frames: 3 kept → rendering 0"), "{log}");
    assert!(
        log.contains("made at another size (size: 48x28 → 24x14)"),
        "{log}"
    );
    let now: Vec<Vec<u8>> = ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
        .iter()
        .map(|f| std::fs::read(dir.join("frames/seq").join(f)).unwrap())
        .collect();
    assert_eq!(now, finished);
}

#[test]
fn check_and_preview_give_one_running_time() {
    let dir = scratch("workflow-running-time");
    shot(&dir);
    let check = run_in(&dir, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(text.contains("12 at 12 fps (1 s)"), "{text}");
    let yaml = std::fs::read_to_string(dir.join("seq.yaml")).unwrap();
    let longer = yaml.replace("time: 0.9166666666666666", "time: 1");
    std::fs::write(dir.join("seq.yaml"), longer).unwrap();
    let check = run_in(&dir, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&check.stdout);
    // 13 frames at 12 fps run 1.0833 s, whatever the last key's time.
    assert!(text.contains("13 at 12 fps (1.08 s)"), "{text}");
}

#[test]
fn channel_files_have_no_negative_zero() {
    let dir = scratch("workflow-chan");
    shot(&dir);
    let out = run_in(&dir, &["camera", "seq.yaml", "--format", "chan"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(!text.contains("-0.0 ") && !text.ends_with("-0.0"), "{text}");
    let out = run_in(
        &dir,
        &["camera", "seq.yaml", "--format", "chan", "--frames", "0"],
    );
    let first = String::from_utf8_lossy(&out.stdout);
    assert!(first.starts_with("0 0.0 0.3 2.0 "), "{first}");
}

#[test]
fn a_changed_material_names_its_field() {
    let dir = scratch("workflow-material-field");
    shot(&dir);
    let out = run_in(&dir, &["render", "seq.yaml", "-q", "--frames", "0"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let yaml = std::fs::read_to_string(dir.join("seq.yaml")).unwrap();
    std::fs::write(
        dir.join("seq.yaml"),
        yaml.replace("shininess: 100", "shininess: 50"),
    )
    .unwrap();
    let out = run_in(&dir, &["status", "seq.yaml", "--frames", "0"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("stale 0: materials.red (shininess)"),
        "{text}"
    );
}

#[test]
fn partly_given_normals_are_said_as_they_are() {
    let dir = scratch("workflow-normals");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2 4 3\n";
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    let yaml = sequence(32, 18, "").replace(
        "objects:\n",
        "objects:\n  - mesh: { file: m.obj, material: red, translate: [0, 0, -3] }\n",
    );
    std::fs::write(
        dir.join("seq.yaml"),
        yaml + "camera: { position: [0, 0, 1], look_at: [0, 0, 0] }\n",
    )
    .unwrap();
    let out = run_in(&dir, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        text.contains(
            "normals from the file for 3 of 6 vertices, averaged from the faces for the rest"
        ),
        "{text}"
    );
}

#[test]
fn models_come_from_libraries_the_user_names_and_nowhere_else() {
    let dir = scratch("workflow-assets");
    std::fs::create_dir_all(dir.join("lib/statues")).unwrap();
    std::fs::create_dir_all(dir.join("shot")).unwrap();
    std::fs::write(dir.join("lib/statues/m.obj"), uv_sphere(8, 4, false, false)).unwrap();
    let yaml = sequence(32, 18, "").replace(
        "objects:\n",
        "objects:\n  - mesh: { file: statues/m.obj, material: red, translate: [0, 0, -3] }\n",
    ) + "camera: { position: [0, 0, 1], look_at: [0, 0, -3] }\n";
    std::fs::write(dir.join("shot/seq.yaml"), &yaml).unwrap();
    // The sequence's folder alone does not hold it.
    refused(
        &dir,
        &["check", "shot/seq.yaml"],
        "shot/statues/m.obj: cannot read: No such file",
    );
    // Named on the command line (or in RAYREEL_ASSETS), the library is looked in after it.
    let out = run_in(&dir, &["check", "shot/seq.yaml", "--assets", "lib"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("lib/statues/m.obj"));
    let out = bin()
        .args(["render", "shot/seq.yaml", "--dry-run"])
        .env("RAYREEL_ASSETS", dir.join("lib"))
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    // A link out of the folder is refused unless it leads into a library the user named.
    std::os::unix::fs::symlink(dir.join("lib/statues"), dir.join("shot/statues")).unwrap();
    refused(
        &dir,
        &["check", "shot/seq.yaml"],
        "give the folder it is in with --assets",
    );
    let out = run_in(&dir, &["check", "shot/seq.yaml", "--assets", "lib"]);
    assert!(out.status.success(), "{}", stderr(&out));
    // The file itself still cannot name an absolute path or climb out.
    let abs = dir.join("lib/statues/m.obj");
    for file in [abs.to_str().unwrap(), "../lib/statues/m.obj"] {
        let bad = yaml.replace("statues/m.obj", file);
        std::fs::write(dir.join("shot/bad.yaml"), bad).unwrap();
        let args = ["check", "shot/bad.yaml", "--assets", "lib"];
        refused(&dir, &args, "must be a relative path");
    }
    refused(
        &dir,
        &["check", "shot/seq.yaml", "--assets", "nowhere"],
        "--assets nowhere: not a directory",
    );
}

/// A z-up pillar as a scan might come: 2 × 4 across, 10 tall along z, its foot at z = 5.
const PILLAR: &str = "v 10 20 5\nv 12 20 5\nv 12 24 5\nv 10 24 5\nv 10 20 15\nv 12 20 15\nv 12 24 15\nv 10 24 15\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";

/// `check`'s bounds of object 0 as six numbers.
fn bounds(text: &str) -> Vec<f64> {
    let line = text
        .lines()
        .find(|l| l.contains("objects[0]:"))
        .expect("a bounds line");
    let nums: String = line
        .split("bounds ")
        .nth(1)
        .unwrap()
        .chars()
        .map(|c| if "0123456789.-".contains(c) { c } else { ' ' })
        .collect();
    nums.split_whitespace()
        .map(|n| n.parse().unwrap())
        .collect()
}

fn pillar_scene(dir: &Path, mesh: &str, timeline: &str) {
    std::fs::write(dir.join("pillar.obj"), PILLAR).unwrap();
    let yaml = sequence(32, 18, timeline).replace(
        "objects:\n",
        &format!(
            "objects:\n  - name: pillar\n    mesh: {{ file: pillar.obj, material: red, {mesh} }}\n"
        ),
    );
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
}

#[test]
fn up_fit_and_origin_stand_a_z_up_model_where_it_is_asked() {
    let dir = scratch("workflow-placement");
    let still = "camera: { position: [0, 1, 6], look_at: [0, 1, 0] }\n";
    // Up z turns the pillar's 10 to y; fit 2 makes that 2; bottom stands it on translate.
    pillar_scene(
        &dir,
        "up: z, fit: 2, origin: bottom, translate: [1, 0.5, -1]",
        still,
    );
    let out = run_in(&dir, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", stderr(&out));
    let b = bounds(&text);
    let near = |a: f64, b: f64| (a - b).abs() < 1e-4;
    // x: 2 wide → 0.4, centred on 1; y: 0.5 to 2.5; z: the file's y (4 deep → 0.8), centred on −1.
    let want = [0.8, 0.5, -1.4, 1.2, 2.5, -0.6];
    assert!(
        b.iter().zip(want).all(|(&g, w)| near(g, w)),
        "{b:?} in {text}"
    );
    // Without up, the same fit makes the largest extent of the file's own axes 2.
    pillar_scene(&dir, "fit: 2, origin: center", still);
    let text = String::from_utf8_lossy(&run_in(&dir, &["check", "seq.yaml"]).stdout).into_owned();
    let b = bounds(&text);
    let want = [-0.2, -0.4, -1.0, 0.2, 0.4, 1.0];
    assert!(
        b.iter().zip(want).all(|(&g, w)| near(g, w)),
        "{b:?} in {text}"
    );
    // Every up axis is a quarter turn; a wrong one is refused with the choices.
    for up in ["x", "-x", "y", "-y", "z", "-z", "+z"] {
        pillar_scene(&dir, &format!("up: {up}, fit: 1"), still);
        let out = run_in(&dir, &["check", "seq.yaml"]);
        assert!(out.status.success(), "{up}: {}", stderr(&out));
    }
    pillar_scene(&dir, "up: w", still);
    let out = run_in(&dir, &["check", "seq.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains(
            "objects[0].mesh.up: the file's up axis is one of y, z, x, -y, -z, -x (got `w`)"
        ),
        "{}",
        stderr(&out)
    );
}

#[test]
fn cameras_aim_at_objects_by_name() {
    let dir = scratch("workflow-aim");
    let keys = "timeline:\n  fps: 4\n  keyframes:\n    - { time: 0, position: [0, 1, 6], look_at: { object: pillar } }\n    - { time: 1, position: [3, 1, 6] }\n";
    pillar_scene(&dir, "up: z, fit: 2, origin: bottom", keys);
    let out = run_in(&dir, &["camera", "seq.yaml", "--format", "json"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", stderr(&out));
    // The centre of the pillar's bounds, carried to the next key.
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let at: Vec<f64> = v["look_at"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert!(
            (at[0]).abs() < 1e-12 && (at[1] - 1.0).abs() < 1e-12 && at[2].abs() < 1e-12,
            "{line}"
        );
    }
    let orbit =
        "timeline:\n  orbit: { center: { object: pillar }, radius: 5, height: 1, duration: 1 }\n";
    pillar_scene(&dir, "translate: [0, 0, -30]", orbit);
    let out = run_in(&dir, &["camera", "seq.yaml", "--frames", "0"]);
    assert!(out.status.success(), "{}", stderr(&out));
    // A name nobody has, a plane, and a name given twice are refused where they are written.
    let bad = [
        (
            "look_at: { object: pillar }",
            "look_at: { object: pilar }",
            "no object is named `pilar` (named: `pillar`)",
        ),
        (
            "- name: pillar\n",
            "- name: pillar\n  - name: pillar\n    sphere: { center: [0, 0, 0], radius: 1, material: red }\n",
            "`pillar` already names objects[0]",
        ),
    ];
    pillar_scene(&dir, "fit: 1", keys);
    let yaml = std::fs::read_to_string(dir.join("seq.yaml")).unwrap();
    for (from, to, want) in bad {
        std::fs::write(dir.join("bad.yaml"), yaml.replacen(from, to, 1)).unwrap();
        let out = run_in(&dir, &["check", "bad.yaml"]);
        assert_eq!(out.status.code(), Some(2), "{to}");
        assert!(stderr(&out).contains(want), "{want} in {}", stderr(&out));
    }
    let floor = yaml
        .replace("  - plane:", "  - name: floor\n    plane:")
        .replace("object: pillar", "object: floor");
    std::fs::write(dir.join("bad.yaml"), floor).unwrap();
    let out = run_in(&dir, &["check", "bad.yaml"]);
    assert!(stderr(&out).contains("timeline.keyframes[0].look_at.object: objects[3] (`floor`) is a plane, which has no centre to aim at"), "{}", stderr(&out));
}

#[test]
fn check_warns_of_a_camera_inside_a_model_and_a_model_never_seen() {
    let dir = scratch("workflow-framing");
    let still = "camera: { position: [0, 1, 6], look_at: [0, 1, 0] }\n";
    // A scan 50 units across at the origin swallows the camera.
    pillar_scene(&dir, "scale: 3, translate: [-33, -66, -30]", still);
    let out = run_in(&dir, &["check", "seq.yaml"]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("warning: the camera starts inside the bounds of objects[0] (pillar, pillar.obj, 30 units across): is the model scaled for this scene?"), "{err}");
    // Behind the camera for the whole shot.
    pillar_scene(&dir, "fit: 1, translate: [0, 0, 20]", still);
    let err = stderr(&run_in(&dir, &["check", "seq.yaml"]));
    assert!(
        err.contains("warning: objects[0] (pillar, pillar.obj, 1 units across) is never in view"),
        "{err}"
    );
    // Seen: no warning.
    pillar_scene(&dir, "fit: 1", still);
    let err = stderr(&run_in(&dir, &["check", "seq.yaml"]));
    assert!(
        !err.contains("never in view") && !err.contains("inside the bounds"),
        "{err}"
    );
}

/// The test scene under `background` (a YAML value), seen by a still camera looking a little up.
fn under_sky(dir: &Path, background: &str) {
    let yaml = sequence(
        48,
        28,
        "camera: { position: [0, 0.1, 2.5], look_at: [0, 0.3, -1] }\n",
    )
    .replace(
        "render: { width: 48, height: 28 }",
        &format!("render: {{ width: 48, height: 28, background: {background} }}"),
    );
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
}

#[test]
fn a_sky_is_seen_by_misses_and_mirrors_and_a_flat_colour_costs_nothing() {
    let dir = scratch("workflow-sky");
    let render = |name: &str, extra: &[&str]| {
        let mut args = vec!["render", "seq.yaml", "-q", "-o", name];
        args.extend(extra);
        let out = run_in(&dir, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        read_png(&dir.join(name))
    };
    // A flat colour, then a gradient whose horizon is that colour and whose zenith is blue.
    under_sky(&dir, "[0.5, 0.5, 0.5]");
    let (w, _, flat) = render("flat.png", &[]);
    under_sky(
        &dir,
        "{ gradient: { zenith: [0, 0, 1], horizon: [0.5, 0.5, 0.5], ground: [0, 1, 0] } }",
    );
    let (_, _, sky) = render("sky.png", &[]);
    let px = |img: &[u8], x: usize, y: usize| img[3 * (y * w as usize + x)..][..3].to_vec();
    // The top corner sees the sky above the horizon: bluer than grey.
    assert_eq!(px(&flat, 0, 0), [188u8, 188, 188]);
    assert!(
        px(&sky, 0, 0)[2] > px(&sky, 0, 0)[0] + 20,
        "{:?}",
        px(&sky, 0, 0)
    );
    // The same scene where nothing misses is unchanged; the image differs only where rays leave.
    assert_ne!(flat, sky);
    let check = run_in(&dir, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        text.contains(
            "sky:        gradient, zenith [0, 0, 1], horizon [0.5, 0.5, 0.5], ground [0, 1, 0]"
        ),
        "{text}"
    );
    // A changed sky makes the frames stale, and says so.
    under_sky(
        &dir,
        "{ gradient: { zenith: [0, 0, 0.9], horizon: [0.5, 0.5, 0.5] } }",
    );
    let status = run_in(&dir, &["status", "seq.yaml", "-o", "sky.png"]);
    assert!(
        String::from_utf8_lossy(&status.stdout).contains("stale 0: background"),
        "{}",
        String::from_utf8_lossy(&status.stdout)
    );
    // An image sky: its line in check, and `rotate` turns what the camera sees.
    std::fs::create_dir_all(dir.join("skies")).unwrap();
    std::fs::copy(
        repo().join("sequences/textures/sky.png"),
        dir.join("skies/noon.png"),
    )
    .unwrap();
    under_sky(&dir, "{ image: skies/noon.png }");
    let text = String::from_utf8_lossy(&run_in(&dir, &["check", "seq.yaml"]).stdout).into_owned();
    assert!(
        text.contains("sky:        skies/noon.png 1024x512 (equirectangular), 11 mip levels"),
        "{text}"
    );
    let (_, _, ahead) = render("image.png", &[]);
    under_sky(&dir, "{ image: skies/noon.png, rotate: 90 }");
    let (_, _, turned) = render("turned.png", &[]);
    assert_ne!(ahead, turned);
    // With alpha, the sky does not fill what the camera sees of it: those pixels stay clear.
    let alpha = run_in(
        &dir,
        &["render", "seq.yaml", "-q", "--alpha", "-o", "alpha.png"],
    );
    assert!(alpha.status.success(), "{}", stderr(&alpha));
    let rgba = image::open(dir.join("alpha.png")).unwrap().to_rgba8();
    assert_eq!(rgba.get_pixel(0, 0)[3], 0);
    // Mistakes name the field.
    for (bad, want) in [
        (
            "{ gradient: { zenith: [0, 0, 1] } }",
            "missing field `horizon`",
        ),
        (
            "{ image: skies/noon.png, gradient: { zenith: [0, 0, 1], horizon: [1, 1, 1] } }",
            "give `image:` or `gradient:`, not both",
        ),
        ("{ rotate: 3 }", "a sky needs `image:` or `gradient:`"),
        ("{ image: skies/none.png }", "render.background.image"),
    ] {
        under_sky(&dir, bad);
        let out = run_in(&dir, &["check", "seq.yaml"]);
        assert_eq!(out.status.code(), Some(2), "{bad}");
        assert!(stderr(&out).contains(want), "{want}: {}", stderr(&out));
    }
}

#[test]
fn estimates_are_measured_and_nothing_to_render_says_so() {
    let dir = scratch("workflow-estimate");
    shot(&dir);
    let check = run_in(&dir, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&check.stdout);
    // `about N s for 12 frames (measured: … tiles … on N threads, … s; … a frame with its file)`,
    // then the ray count as an upper bound.
    // The bound goes on a line of its own, and lines past 120 columns are wrapped under the
    // summary's indent.
    let at = text.find("  cost:").unwrap();
    let cost = text[at..].replace("\n              ", " ");
    assert!(
        cost.contains("about ") && cost.contains(" for 12 frames (measured: "),
        "{cost}"
    );
    assert!(cost.contains(" a frame with its file); at most "), "{cost}");
    assert!(
        cost.contains(" rays (an upper bound: pixels × samples × (1 + lights) × max_depth)"),
        "{cost}"
    );
    // The dry run estimates what it would render, on the threads asked for.
    let dry = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "--dry-run",
            "--frames",
            "0-3",
            "-j",
            "1",
        ],
    );
    let text = String::from_utf8_lossy(&dry.stdout);
    assert!(
        text.contains(" for 4 frames (measured: ") && text.contains("on 1 thread,"),
        "{text}"
    );
    let out = run_in(&dir, &["render", "seq.yaml", "-q", "--frames", "0-3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let dry = run_in(
        &dir,
        &["render", "seq.yaml", "--dry-run", "--frames", "0-3"],
    );
    let text = String::from_utf8_lossy(&dry.stdout);
    assert!(
        text.contains("would render: nothing: every selected frame is finished"),
        "{text}"
    );
    assert!(text.contains("cost: nothing to render"), "{text}");
    assert!(
        !text.contains("0.00e0") && !text.contains("would render: \n"),
        "{text}"
    );
}
