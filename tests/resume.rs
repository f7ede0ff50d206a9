//! Resuming: atomic frames, fingerprints, incremental re-render, interruption. Every check
//! compares against a clean, uninterrupted render byte for byte.

mod common;
use common::*;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

fn seq() -> String {
    sequence(160, 90, THREE_KEYS)
}

fn setup(name: &str) -> Scratch {
    let tmp = scratch(name);
    std::fs::write(tmp.join("seq.yaml"), seq()).unwrap();
    tmp
}

fn render(dir: &Path, args: &[&str]) -> String {
    let mut all = vec!["render", "seq.yaml"];
    all.extend(args);
    let out = run_in(dir, &all);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    stderr(&out)
}

#[test]
fn killed_at_any_moment_resumes_to_the_identical_sequence() {
    let tmp = setup("kill");
    // Enough work per run (9 samples a pixel) that most kills land mid-run however fast
    // the tracer gets.
    let heavy = ["--size", "640x360", "--samples", "9", "-q"];
    render(&tmp, &[&["-o", "clean/f_####.png"][..], &heavy].concat());
    let mut cut_short = 0;
    let expected = rayreel::output::Expected {
        width: 640,
        height: 360,
        format: rayreel::output::FileFormat::Png {
            sixteen_bit: false,
            compression: rayreel::output::png::Compression::Fast,
        },
        alpha: false,
    };
    for (i, delay_ms) in [30u64, 60, 90, 120, 150, 200, 260, 330, 420, 520, 40, 75]
        .iter()
        .enumerate()
    {
        let threads = if i % 2 == 0 { "2" } else { "1" };
        let args = [&["-o", "out/f_####.png", "--threads", threads][..], &heavy].concat();
        let mut child = start(&tmp, &args, Stdio::null());
        std::thread::sleep(Duration::from_millis(*delay_ms));
        child.kill().unwrap(); // SIGKILL
        cut_short += usize::from(!child.wait().unwrap().success());
        // Whatever survived with a final name is a complete frame.
        for f in files(&tmp.join("out"))
            .iter()
            .filter(|f| !f.starts_with('.'))
        {
            let bytes = std::fs::read(tmp.join("out").join(f)).unwrap();
            assert!(
                matches!(
                    rayreel::output::png::inspect(&bytes, &expected),
                    rayreel::output::Existing::Ours(_)
                ),
                "{f}"
            );
        }
    }
    assert!(cut_short >= 6, "only {cut_short} kills landed mid-run");
    render(&tmp, &[&["-o", "out/f_####.png"][..], &heavy].concat());
    assert_same_files(&tmp.join("clean"), &tmp.join("out"));
}

#[test]
fn damaged_files_are_rerendered_and_foreign_ones_kept() {
    let tmp = setup("damaged");
    render(&tmp, &["-o", "clean/f_####.png", "-q"]);
    render(&tmp, &["-o", "out/f_####.png", "-q"]);
    let out = tmp.join("out");
    let full = std::fs::read(out.join("f_0003.png")).unwrap();
    std::fs::write(out.join("f_0003.png"), &full[..full.len() / 2]).unwrap();
    let mut garbled = std::fs::read(out.join("f_0005.png")).unwrap();
    let mid = garbled.len() / 2;
    garbled[mid..mid + 16].copy_from_slice(b"garbage garbage!");
    std::fs::write(out.join("f_0005.png"), &garbled).unwrap();
    std::fs::write(out.join("f_0006.png"), b"not a png at all").unwrap();
    image::RgbImage::new(160, 90)
        .save(out.join("f_0007.png"))
        .unwrap();
    let foreign = std::fs::read(out.join("f_0007.png")).unwrap();

    let result = run_in(&tmp, &["render", "seq.yaml", "-o", "out/f_####.png"]);
    let log = stderr(&result);
    assert_eq!(result.status.code(), Some(1), "{log}");
    assert!(
        log.contains("49 frames: 45 up to date, 3 corrupt, 1 foreign → rendering 3"),
        "{log}"
    );
    assert!(
        log.contains("out/f_0007.png: not written by rayreel (no fingerprint); leaving it alone"),
        "{log}"
    );
    assert!(log.contains("frame 7 was not written"), "{log}");
    assert_eq!(std::fs::read(out.join("f_0007.png")).unwrap(), foreign);
    for n in [3, 5, 6] {
        let name = format!("f_{n:04}.png");
        assert_eq!(
            std::fs::read(out.join(&name)).unwrap(),
            std::fs::read(tmp.join("clean").join(&name)).unwrap()
        );
    }
    // --force overwrites the foreign file too; then everything matches the clean render.
    render(&tmp, &["-o", "out/f_####.png", "--force", "-q"]);
    assert_same_files(&tmp.join("clean"), &out);
}

#[test]
fn editing_a_keyframe_rerenders_exactly_the_frames_it_moves() {
    let tmp = setup("edit");
    render(&tmp, &["-q"]);
    let again = render(&tmp, &[]);
    assert!(
        again.contains("49 frames: 49 up to date → rendering 0"),
        "{again}"
    );
    // Move the last key: with linear interpolation only frames 25-48 (t in (2, 4]) change;
    // frame 24 sits exactly on the middle key, frame 48 on the last.
    let edited = seq().replace("position: [0, 0.5, -2.5]", "position: [0.2, 0.5, -2.5]");
    std::fs::write(tmp.join("seq.yaml"), edited).unwrap();
    let dry = run_in(&tmp, &["render", "seq.yaml", "--dry-run"]);
    let plan = String::from_utf8_lossy(&dry.stdout);
    assert!(
        plan.contains("49 frames: 25 up to date, 24 stale → rendering 24"),
        "{plan}"
    );
    assert!(plan.contains("would render: 25-48"), "{plan}");
    let log = render(&tmp, &[]);
    assert!(log.contains("frame 25 written"), "{log}");
    assert!(
        !log.contains("frame 24 written") && !log.contains("frame 3 written"),
        "{log}"
    );
    // A different resolution never replaces finished frames unforced.
    let dry = run_in(
        &tmp,
        &["render", "seq.yaml", "--size", "80x45", "--dry-run"],
    );
    assert!(String::from_utf8_lossy(&dry.stdout).contains("49 frames: 49 kept → rendering 0"));
}

#[test]
fn ctrl_c_stops_cleanly_with_exit_130_and_the_rerun_finishes() {
    let tmp = setup("sigint");
    render(&tmp, &["-o", "clean/f_####.png", "--size", "640x360", "-q"]);
    let args = [
        "-o",
        "out/f_####.png",
        "--size",
        "640x360",
        "--threads",
        "1",
    ];
    let child = start(&tmp, &args, Stdio::piped());
    std::thread::sleep(Duration::from_millis(150));
    // SAFETY: sends SIGINT to our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let out = child.wait_with_output().unwrap();
    let log = stderr(&out);
    assert_eq!(out.status.code(), Some(130), "{log}");
    assert!(
        log.contains("interrupted:") && log.contains("run the same command again"),
        "{log}"
    );
    let written = files(&tmp.join("out"));
    assert!(
        written.len() < 49,
        "the interrupt came too late to test anything"
    );
    assert!(
        written.iter().all(|f| !f.starts_with('.')),
        "temporary files left: {written:?}"
    );
    render(&tmp, &["-o", "out/f_####.png", "--size", "640x360", "-q"]);
    assert_same_files(&tmp.join("clean"), &tmp.join("out"));
}

#[test]
fn exr_frames_resume_too() {
    let tmp = setup("exr");
    render(
        &tmp,
        &["-o", "e/f_####.exr", "--depth", "-q", "--frames", "0-5"],
    );
    let log = render(&tmp, &["-o", "e/f_####.exr", "--depth", "--frames", "0-5"]);
    assert!(
        log.contains("6 frames: 6 up to date → rendering 0"),
        "{log}"
    );
    let log = render(&tmp, &["-o", "e/f_####.exr", "--frames", "0-5"]);
    assert!(
        log.contains("6 frames: 6 stale → rendering 6"),
        "without depth the files differ: {log}"
    );
}

/// The frame numbers of the `written` events of a `--progress json` log, in order.
fn written_order(log: &str) -> Vec<u64> {
    log.lines()
        .filter(|l| l.contains("\"status\": \"written\""))
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["frame"].as_u64().unwrap()
        })
        .collect()
}

#[test]
fn frames_are_written_in_ascending_order() {
    let tmp = setup("order");
    let small = "--size 96x54 --samples 4 --frames 0-23 --progress json --force";
    for threads in ["2", "1"] {
        let args = format!("-o out/f_####.png {small} --threads {threads}");
        let log = render(&tmp, &args.split(' ').collect::<Vec<_>>());
        assert_eq!(written_order(&log), (0..24).collect::<Vec<_>>());
    }
}

/// `rayreel render seq.yaml ARGS` started in `dir`, its stderr going to `err`.
fn start(dir: &Path, args: &[&str], err: Stdio) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_rayreel"))
        .args(["render", "seq.yaml"])
        .args(args)
        .current_dir(dir)
        .stderr(err)
        .spawn()
        .unwrap()
}

#[test]
fn an_interrupted_run_leaves_a_prefix_of_its_frames() {
    use std::io::BufRead;
    let tmp = setup("prefix");
    let args = "-o out/f_####.png --size 320x180 --samples 4 --progress json --threads 2";
    let mut child = start(&tmp, &args.split(' ').collect::<Vec<_>>(), Stdio::piped());
    let mut lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    let mut log = String::new();
    let mut seen = 0;
    while seen < 3 {
        let line = lines.next().expect("the run writes 3 frames").unwrap();
        seen += usize::from(line.contains("\"status\": \"written\""));
        log += &line;
        log += "\n";
    }
    // SAFETY: sends SIGINT to our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    lines.for_each(|l| log += &(l.unwrap() + "\n"));
    assert_eq!(child.wait().unwrap().code(), Some(130), "{log}");
    let written = files(&tmp.join("out"));
    assert!(written.len() < 49, "the interrupt came too late: {log}");
    let prefix: Vec<String> = (0..written.len())
        .map(|n| format!("f_{n:04}.png"))
        .collect();
    assert_eq!(written, prefix, "{log}");
    assert_eq!(
        written_order(&log),
        (0..written.len() as u64).collect::<Vec<_>>()
    );
}

/// `rayreel ARGS` in `dir` with `ARGS` split at spaces: (exit code, stdout + stderr).
fn rayreel(dir: &Path, args: &str) -> (Option<i32>, String) {
    let out = run_in(dir, &args.split(' ').collect::<Vec<_>>());
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &stderr(&out);
    (out.status.code(), text)
}

/// Runs `rayreel ARGS`, which must exit with `code` and say every one of `wants`.
fn says(dir: &Path, args: &str, code: i32, wants: &[&str]) {
    let (got, log) = rayreel(dir, args);
    assert_eq!(got, Some(code), "{args}: {log}");
    let missing: Vec<&&str> = wants.iter().filter(|w| !log.contains(**w)).collect();
    assert!(missing.is_empty(), "{args}: no {missing:?} in {log}");
}

/// The bytes of every frame file below `dir`.
fn frame_bytes(dir: &Path) -> Vec<Vec<u8>> {
    let names = files(dir);
    names
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect()
}

/// A scratch directory with `frames` of the test sequence rendered at 64x36 with `extra`
/// arguments, and the job's arguments (without `extra`).
fn rendered_small(name: &str, frames: &str, extra: &str) -> (Scratch, String) {
    let tmp = setup(name);
    let job = format!("seq.yaml -o out/f_####.png --size 64x36 --frames {frames}");
    says(&tmp, &format!("render {job} {extra}"), 0, &[]);
    (tmp, job)
}

#[test]
fn a_rerun_at_lower_quality_keeps_the_frames_and_says_what_differs() {
    let (tmp, job) = rendered_small("quality", "0-5", "--samples 16 --max-depth 4");
    let finished = frame_bytes(&tmp.join("out"));
    let lower = format!("{job} --samples 4 --max-depth 4");
    let kept =
        "kept 0-5 made with other quality settings (samples: 16 → 4); --force re-renders them";
    for command in ["render", "render --dry-run", "status"] {
        says(
            &tmp,
            &format!("{command} {lower}"),
            0,
            &["6 frames: 6 kept", kept],
        );
    }
    assert_eq!(frame_bytes(&tmp.join("out")), finished);
    // Raising every quality setting re-renders; so does --force, and a content change.
    let raised = format!("status {job} --samples 16 --max-depth 5");
    says(&tmp, &raised, 1, &["stale 0-5: max_depth: 4 → 5"]);
    let forced = format!("render {lower} --force --dry-run");
    says(&tmp, &forced, 0, &["6 stale → rendering 6 (--force)"]);
    let exposed = format!("status {lower} --exposure 1");
    says(
        &tmp,
        &exposed,
        1,
        &["stale 0-5: samples: 16 → 4, exposure: 0 → 1"],
    );
    let smaller = format!("status {job} --samples 16 --max-depth 4").replace("64x36", "32x18");
    // A finished frame of another size is kept too: only --force replaces it.
    let resized = "kept 0-5 made at another size (size: 64x36 → 32x18); a finished frame is not replaced by one of another size: --force replaces them, or write them elsewhere with -o";
    says(&tmp, &smaller, 0, &["6 frames: 6 kept", resized]);
    let forced = format!("render {job} --force --dry-run").replace("64x36", "32x18");
    says(&tmp, &forced, 0, &["6 stale → rendering 6 (--force)"]);
    let redder = seq().replace("[0.7, 0, 0]", "[0.6, 0, 0]");
    std::fs::write(tmp.join("seq.yaml"), redder).unwrap();
    let same = format!("status {job} --samples 16 --max-depth 4");
    says(&tmp, &same, 1, &["stale 0-5: materials.red (diffuse)"]);
    // --skip-existing trusts any complete frame of the job's size.
    let why = "kept 0-5 by --skip-existing (samples: 16 → 4, materials.red (diffuse))";
    let args = format!("render {lower} --skip-existing");
    says(&tmp, &args, 0, &["6 kept → rendering 0", why]);
    assert_eq!(frame_bytes(&tmp.join("out")), finished);
}

/// A PNG without the chunk that records its settings, as rayreel wrote them before it had one.
fn without_record(png: &[u8]) -> Vec<u8> {
    let mut out = png[..8].to_vec();
    let mut at = 8;
    while at + 12 <= png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().unwrap()) as usize;
        let chunk = &png[at..at + 12 + len];
        if !chunk[4..].starts_with(b"tEXtrayreel:settings\0") {
            out.extend(chunk);
        }
        at += 12 + len;
    }
    out
}

#[test]
fn frames_without_a_settings_record_are_rerendered_as_before() {
    let (tmp, job) = rendered_small("older", "0-2", "--samples 16");
    for f in files(&tmp.join("out")) {
        let path = tmp.join("out").join(f);
        let old = without_record(&std::fs::read(&path).unwrap());
        std::fs::write(&path, old).unwrap();
    }
    // The fingerprint alone still says up to date.
    says(
        &tmp,
        &format!("status {job} --samples 16"),
        0,
        &["3 up to date"],
    );
    let why = "stale 0-2: made by an older rayreel; differs: unknown";
    let args = format!("render {job} --samples 4");
    says(&tmp, &args, 0, &["3 stale → rendering 3", why]);
}
