//! Camera fly-arounds end to end through the binary: numbered frames, frame selection,
//! determinism across thread counts and selections, progress lines, the example sequences.

mod common;
use common::*;
use std::path::Path;

fn seq() -> String {
    sequence(48, 27, &orbit(12, 1.0))
}

fn write_seq(dir: &Path, name: &str, yaml: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, yaml).unwrap();
    path.to_str().unwrap().to_string()
}

fn render(dir: &Path, args: &[&str]) -> String {
    let out = run_in(dir, args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    assert!(out.stdout.is_empty(), "stdout must stay clean");
    stderr(&out)
}

#[test]
fn a_short_orbit_writes_every_numbered_frame() {
    let tmp = scratch("short");
    let seq = write_seq(&tmp, "short.yaml", &seq());
    let log = render(&tmp, &["render", &seq]);
    let names: Vec<String> = (0..12)
        .map(|n| format!("frames/short/frame_{n:04}.png"))
        .collect();
    assert_eq!(files(&tmp.join("frames")).len(), 12);
    for name in &names {
        assert_eq!(read_png(&tmp.join(name)).0, 48, "{name}");
        assert_eq!(read_png(&tmp.join(name)).1, 27, "{name}");
    }
    // Not a terminal: one plain line per frame, then the summary.
    assert!(
        log.contains("frame 3 written frames/short/frame_0003.png ("),
        "{log}"
    );
    assert!(log.contains("rendered 12 frames in "), "{log}");
    // The orbit moves: consecutive frames differ.
    assert_ne!(
        read_png(&tmp.join(&names[0])).2,
        read_png(&tmp.join(&names[1])).2
    );
}

#[test]
fn frames_are_identical_whatever_the_threads_or_selection() {
    let tmp = scratch("determinism");
    let seq = write_seq(&tmp, "d.yaml", &seq());
    render(
        &tmp,
        &["render", &seq, "-o", "one/f_##.png", "--threads", "1", "-q"],
    );
    render(
        &tmp,
        &["render", &seq, "-o", "two/f_##.png", "--threads", "2", "-q"],
    );
    render(
        &tmp,
        &[
            "render",
            &seq,
            "-o",
            "alone/f_##.png",
            "--frames",
            "7",
            "-q",
        ],
    );
    for n in 0..12 {
        let a = std::fs::read(tmp.join(format!("one/f_{n:02}.png"))).unwrap();
        let b = std::fs::read(tmp.join(format!("two/f_{n:02}.png"))).unwrap();
        assert_eq!(a, b, "frame {n} differs between 1 and 2 threads");
    }
    assert_eq!(files(&tmp.join("alone")), vec!["f_07.png"]);
    assert_eq!(
        std::fs::read(tmp.join("alone/f_07.png")).unwrap(),
        std::fs::read(tmp.join("one/f_07.png")).unwrap()
    );
}

#[test]
fn frame_specs_select_frames_and_quiet_is_silent() {
    let tmp = scratch("select");
    let seq = write_seq(&tmp, "s.yaml", &seq());
    let log = render(
        &tmp,
        &[
            "render",
            &seq,
            "-o",
            "s/f_####.png",
            "--frames",
            "0-11:5,3",
            "--quiet",
        ],
    );
    assert_eq!(log, "");
    assert_eq!(
        files(&tmp.join("s")),
        vec!["f_0000.png", "f_0003.png", "f_0005.png", "f_0010.png"]
    );
}

#[test]
fn a_single_key_is_a_still_camera() {
    let tmp = scratch("still");
    let yaml = seq().replace(
        "  orbit: { center: [-0.1, 0, -0.6], radius: 1.6, height: 0.35, duration: 1, look_at: [-0.1, -0.1, -0.6] }",
        "  duration: 0.25\n  keyframes:\n    - { time: 0, position: [0, 0.3, 1.5], look_at: [0, 0, -0.5] }",
    );
    let seq = write_seq(&tmp, "still.yaml", &yaml);
    // One centred sample: jittered samples move with the frame number, so noise never stands still.
    render(&tmp, &["render", &seq, "-q", "--samples", "1"]);
    let got = files(&tmp.join("frames/still"));
    assert_eq!(got.len(), 3, "{got:?}");
    let first = read_png(&tmp.join("frames/still/frame_0000.png"));
    assert_eq!(first, read_png(&tmp.join("frames/still/frame_0002.png")));
}

#[test]
fn example_sequences_check_and_render_a_frame() {
    let tmp = scratch("examples");
    for name in [
        "talk",
        "orbit",
        "flyby",
        "checker",
        "soft-shadows",
        "glass",
        "mesh",
        "model",
        "turntable",
    ] {
        let file = repo().join(format!("sequences/{name}.yaml"));
        let out = run_in(&tmp, &["check", file.to_str().unwrap()]);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let pattern = format!("{name}/f_####.png");
        render(
            &tmp,
            &[
                "render",
                file.to_str().unwrap(),
                "--size",
                "64x36",
                "-o",
                &pattern,
                "--frames",
                "0",
                "-q",
            ],
        );
        assert_eq!(read_png(&tmp.join(format!("{name}/f_0000.png"))).0, 64);
    }
}
