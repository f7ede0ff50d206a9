//! What users coming from Blender and from a shell trip over, through the real binary: an
//! output directory that cannot take files is refused before anything renders; keys by frame
//! number and as exact fractions of seconds; `--frames` misses that say how frames are
//! numbered; a pattern lost to a YAML comment; an output without a file type.

mod common;
use common::*;
use std::path::Path;

/// A file of the test scene at 32×18 with `timeline` (a YAML block), in `dir/NAME`.
fn write(dir: &Path, name: &str, timeline: &str) {
    std::fs::write(dir.join(name), sequence(32, 18, timeline)).unwrap();
}

fn keys(fps: &str, first: u64, a: &str, b: &str) -> String {
    format!(
        "timeline:\n  fps: {fps}\n  first_frame: {first}\n  keyframes:\n    - {{ {a}, position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }}\n    - {{ {b}, position: [1.5, 0.4, 0.5] }}\n"
    )
}

fn camera_csv(dir: &Path, file: &str) -> String {
    let out = run_in(dir, &["camera", file]);
    assert!(out.status.success(), "{file}: {}", stderr(&out));
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn an_output_directory_that_takes_no_files_is_refused_before_rendering() {
    let dir = scratch("unwritable");
    write(&dir, "seq.yaml", THREE_KEYS);
    for (output, named) in [
        (
            "/proc/frame_####.png",
            "/proc: cannot write files in this directory",
        ),
        (
            "/proc/self/frame_####.png",
            "/proc/self: cannot write files in this directory",
        ),
    ] {
        let out = run_in(
            &dir,
            &["render", "seq.yaml", "-o", output, "--progress", "json"],
        );
        assert_eq!(out.status.code(), Some(1), "{output}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(err.contains(named), "{output}: {err}");
        assert!(
            !err.contains("frame_done") && !err.contains("frame_0"),
            "{output}: {err}"
        );
    }
    // A file where the directory should be.
    std::fs::write(dir.join("taken"), "x").unwrap();
    let out = run_in(&dir, &["render", "seq.yaml", "-o", "taken/frame_####.png"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("taken: cannot create directory"),
        "{}",
        stderr(&out)
    );
    // A video's folder too, whatever ffmpeg's presence.
    let out = run_in(&dir, &["render", "seq.yaml", "--video", "/proc/x.mp4"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(!stderr(&out).contains("frame 0"), "{}", stderr(&out));
    assert_eq!(files(&dir), ["seq.yaml", "taken"]);
}

#[test]
fn keys_by_frame_number_and_fraction_fall_exactly_on_their_frames() {
    let dir = scratch("frame-keys");
    // At 24000/1001 from frame 1001, frame 1072 shows (71·1001)/24000 s.
    write(
        &dir,
        "frames.yaml",
        &keys("24000/1001", 1001, "frame: 1001", "frame: 1072"),
    );
    write(
        &dir,
        "fraction.yaml",
        &keys("24000/1001", 1001, "time: 0", "time: 71071/24000"),
    );
    let by_frame = camera_csv(&dir, "frames.yaml");
    assert_eq!(by_frame, camera_csv(&dir, "fraction.yaml"));
    assert_eq!(by_frame.lines().count(), 1 + 72, "{by_frame}");
    assert!(
        by_frame.lines().last().unwrap().starts_with("1072,"),
        "{by_frame}"
    );
    write(&dir, "plain.yaml", &keys("24", 0, "time: 0", "time: 71/24"));
    write(&dir, "frame.yaml", &keys("24", 0, "frame: 0", "frame: 71"));
    assert_eq!(
        camera_csv(&dir, "plain.yaml"),
        camera_csv(&dir, "frame.yaml")
    );
}

#[test]
fn a_key_takes_one_of_time_and_frame() {
    let dir = scratch("frame-keys-bad");
    for (a, want) in [
        (
            "time: 0, frame: 0",
            "seq.yaml:15:25: timeline.keyframes[0].frame: give either `time:`",
        ),
        (
            "fov: 60",
            "seq.yaml:15:7: timeline.keyframes[0]: needs `time:`",
        ),
        (
            "frame: 3",
            "timeline.keyframes[0].frame: frame 3 is before the first frame, timeline.first_frame (10)",
        ),
        (
            "time: 1/0",
            "seconds as a number or a fraction of whole numbers such as 71/24 (got `1/0`)",
        ),
    ] {
        write(&dir, "seq.yaml", &keys("24", 10, a, "frame: 40"));
        let out = run_in(&dir, &["check", "seq.yaml"]);
        assert_eq!(out.status.code(), Some(2), "{a}: {}", stderr(&out));
        assert!(stderr(&out).contains(want), "{a}: {}", stderr(&out));
    }
}

#[test]
fn frames_outside_the_timeline_say_how_frames_are_numbered() {
    let dir = scratch("frames-numbering");
    let talk = repo().join("sequences/talk.yaml");
    let out = run_in(
        &dir,
        &[
            "render",
            talk.to_str().unwrap(),
            "--frames",
            "1",
            "--dry-run",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(err.contains("which has frames 0-0"), "{err}");
    assert!(
        err.contains("numbered from 0") && err.contains("first_frame: 1"),
        "{err}"
    );
    write(&dir, "seq.yaml", &keys("24", 1, "frame: 1", "frame: 73"));
    let out = run_in(
        &dir,
        &["render", "seq.yaml", "--frames", "0-72", "--dry-run"],
    );
    assert!(
        stderr(&out).contains("numbered from timeline.first_frame (1)"),
        "{}",
        stderr(&out)
    );
    let out = run_in(
        &dir,
        &["render", "seq.yaml", "--frames", "1-73", "--dry-run"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn a_pattern_lost_to_a_yaml_comment_is_a_warning() {
    let dir = scratch("lost-pattern");
    let text = sequence(32, 18, THREE_KEYS) + "output: ####.png\n";
    std::fs::write(dir.join("seq.yaml"), &text).unwrap();
    let out = run_in(&dir, &["check", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("seq.yaml:"), "{err}");
    assert!(
        err.contains("starts a YAML comment") && err.contains("output: \"####.png\""),
        "{err}"
    );
    assert!(err.contains("frames/seq/frame_####.png"), "{err}");
    // Quoted, or a plain comment after a pattern, says nothing.
    for line in [
        "output: \"####.png\"\n",
        "output: out/f_####.png  # where they go\n",
    ] {
        let text = sequence(32, 18, THREE_KEYS) + line;
        std::fs::write(dir.join("seq.yaml"), &text).unwrap();
        let out = run_in(&dir, &["check", "seq.yaml"]);
        assert!(
            !stderr(&out).contains("YAML comment"),
            "{line}: {}",
            stderr(&out)
        );
    }
}

#[test]
fn an_output_without_a_file_type_says_which_to_add() {
    let dir = scratch("no-extension");
    write(&dir, "seq.yaml", THREE_KEYS);
    let out = run_in(&dir, &["render", "seq.yaml", "-o", "out/frame_####"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("add .png or .exr (e.g. `out/frame_####.png`)"),
        "{err}"
    );
    assert!(!err.contains("`.`"), "{err}");
}
