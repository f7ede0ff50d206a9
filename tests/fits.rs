//! Issue 20: what a new user tries first, through the real binary — ffmpeg command lines that
//! paste into a shell, `status` on the render line, Ctrl-C while piping, stills and `%04d`,
//! JSON progress a farm manager can read, frame specs, messages, stdin, frame numbers from
//! 1001 and fractional frame rates.

mod common;
use common::*;
use std::io::{Read, Write};
use std::process::Stdio;
use std::time::{Duration, Instant};

/// A 64×36 slow orbit of `frames` frames at 24 fps in `dir/seq.yaml`.
fn small(dir: &std::path::Path, frames: u32) {
    let timeline = format!(
        "timeline:\n  fps: 24\n  orbit: {{ center: [-0.1, 0, -0.6], radius: 1.6, height: 0.35, duration: {}, turns: 0.05, look_at: [-0.1, -0.1, -0.6] }}\n",
        f64::from(frames) / 24.0
    );
    let yaml = sequence(64, 36, &timeline);
    std::fs::write(dir.join("seq.yaml"), yaml).unwrap();
}

/// The line of `text` that starts with `ffmpeg `.
fn ffmpeg_line(text: &str) -> String {
    let line = text.lines().find(|l| l.starts_with("ffmpeg "));
    line.unwrap_or_else(|| panic!("no ffmpeg line in {text}"))
        .into()
}

/// Whether bash parses `line` as one simple command (without running it).
fn bash_parses(dir: &std::path::Path, line: &str) -> bool {
    sh(dir, &format!("bash -n -c {}", shell_quote(line)))
        .status
        .success()
}

fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

#[test]
fn print_ffmpeg_pastes_into_a_shell_for_streams_and_files() {
    let tmp = scratch("fits-ffmpeg");
    small(&tmp, 2);
    let args = ["render", "seq.yaml", "--size", "65x37", "--frames", "0"];
    let piped = [&args[..], &["--pipe", "raw", "--print-ffmpeg", "-q"]].concat();
    let out = run_in(&tmp, &piped);
    assert!(out.status.success(), "{}", stderr(&out));
    let line = ffmpeg_line(&stderr(&out));
    assert!(
        line.contains("-s 65x37 -r 24 -i - -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2'"),
        "{line}"
    );
    assert!(bash_parses(&tmp, &line), "{line}");
    // Files: the command that reads them, and the odd-size note too.
    let files = [&args[..], &["-o", "out dir/f_####.png", "--print-ffmpeg"]].concat();
    let out = run_in(&tmp, &files);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stderr(&out);
    let line = ffmpeg_line(&text);
    assert!(
        line.starts_with("ffmpeg -framerate 24 -i 'out dir/f_%04d.png' -vf 'pad="),
        "{line}"
    );
    assert!(bash_parses(&tmp, &line), "{line}");
    assert!(text.contains("65x37 is odd"), "{text}");
    // RGBA files: ProRes 4444 keeps the alpha H.264 would drop, and takes the odd size.
    let rgba = [
        &args[..],
        &["-o", "rgba/f_####.png", "--alpha", "--print-ffmpeg"],
    ]
    .concat();
    let out = run_in(&tmp, &rgba);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stderr(&out);
    let line = ffmpeg_line(&text);
    assert_eq!(
        line,
        "ffmpeg -framerate 24 -i rgba/f_%04d.png -c:v prores_ks -profile:v 4444 -pix_fmt yuva444p10le seq.mov"
    );
    assert!(!text.contains("is odd"), "{text}");
    if have_tool("ffmpeg") && have_tool("ffprobe") {
        let made = std::process::Command::new("bash")
            .args(["-c", &line.replacen("ffmpeg", "ffmpeg -v error", 1)])
            .current_dir(&tmp)
            .output()
            .unwrap();
        assert!(made.status.success(), "{line}: {}", stderr(&made));
        let probe = std::process::Command::new("ffprobe")
            .args([
                "-v",
                "error",
                "-show_entries",
                "stream=width,height,pix_fmt",
                "seq.mov",
            ])
            .current_dir(&tmp)
            .output()
            .unwrap();
        let info = String::from_utf8_lossy(&probe.stdout);
        assert!(
            info.contains("width=65") && info.contains("height=37"),
            "{info}"
        );
        assert!(info.contains("pix_fmt=yuva444"), "{info}");
    }
}

#[test]
fn status_takes_the_render_command_line() {
    let tmp = scratch("fits-status");
    small(&tmp, 3);
    // The Slurm script's line, as an array task runs it and as the final check repeats it.
    let run = [
        "seq.yaml",
        "--shard",
        "auto",
        "--threads",
        "2",
        "--progress",
        "json",
        "-q",
    ];
    let status = [&["status"][..], &run].concat();
    let out = run_in(&tmp, &status);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    for task in ["0", "1"] {
        let out = bin()
            .args([&["render"][..], &run].concat())
            .current_dir(&tmp)
            .env("SLURM_ARRAY_TASK_ID", task)
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        let out = run_in(&tmp, &status);
        let complete = if task == "0" { 1 } else { 0 };
        assert_eq!(out.status.code(), Some(complete), "{}", stderr(&out));
    }
    // Run-time flags are accepted and change nothing.
    let more = [
        "--claim",
        "--claim-timeout",
        "60",
        "--force",
        "--print-ffmpeg",
    ];
    let out = run_in(&tmp, &[&status[..], &more].concat());
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn ctrl_c_while_piping_says_so_at_once_and_exits_130() {
    let tmp = scratch("fits-sigint");
    small(&tmp, 2000);
    let mut child = bin()
        .args(["render", "seq.yaml", "--pipe", "raw", "--threads", "1"])
        .current_dir(&tmp)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut frame = vec![0u8; 64 * 36 * 3];
    stdout.read_exact(&mut frame).unwrap();
    // The terminal signals the whole pipeline: rayreel, and the reader, which then exits.
    let sent = Instant::now();
    // SAFETY: kill only sends a signal to our own child process.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    drop(stdout);
    let status = child.wait().unwrap();
    let mut text = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut text)
        .unwrap();
    assert!(sent.elapsed() < Duration::from_secs(10));
    assert_eq!(status.code(), Some(130), "{text}");
    assert!(text.contains("Ctrl-C again to abort"), "{text}");
    assert!(!text.contains("reader closed"), "{text}");
}

#[test]
fn a_still_needs_no_hash_and_percent_d_patterns_work() {
    let tmp = scratch("fits-still");
    small(&tmp, 30);
    let out = run_in(
        &tmp,
        &["render", "seq.yaml", "-o", "still.png", "--frames", "24"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(read_png(&tmp.join("still.png")).0, 64);
    let out = run_in(
        &tmp,
        &["status", "seq.yaml", "-o", "still.png", "--frames", "24"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let out = run_in(&tmp, &["render", "seq.yaml", "-o", "still.png"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("30 frames are selected"),
        "{}",
        stderr(&out)
    );
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "p/f_%04d.png",
            "--frames",
            "0-2",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files(&tmp.join("p")),
        ["f_0000.png", "f_0001.png", "f_0002.png"]
    );
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "p/f_####.png",
            "--frames",
            "0-2",
        ],
    );
    assert!(stderr(&out).contains("3 up to date"), "{}", stderr(&out));
}

#[test]
fn json_progress_is_one_object_a_line_with_plan_counts_and_totals() {
    let tmp = scratch("fits-json");
    small(&tmp, 4);
    let json = |args: &[&str]| {
        let out = run_in(
            &tmp,
            &[&["render", "seq.yaml", "--progress", "json"][..], args].concat(),
        );
        let lines: Vec<serde_json::Value> = stderr(&out)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect();
        (out.status.code(), lines)
    };
    let (code, first) = json(&["--frames", "0-1"]);
    assert_eq!(code, Some(0));
    assert_eq!(first[0]["event"], "start");
    assert_eq!(
        (first[0]["missing"].as_u64(), first[0]["rendering"].as_u64()),
        (Some(2), Some(2))
    );
    let frames: Vec<_> = first.iter().filter(|l| l["event"] == "frame").collect();
    assert_eq!(frames.last().unwrap()["done"], 2);
    assert_eq!(frames.last().unwrap()["total"], 2);
    let summary = first.last().unwrap();
    assert_eq!(summary["event"], "summary");
    assert_eq!(summary["interrupted"], false);
    assert_eq!(summary["frames"], 2);
    let (_, second) = json(&[]);
    assert_eq!(second[0]["up_to_date"], 2);
    assert_eq!(second[0]["missing"], 2);
    // A run that fails still speaks JSON on every line, its error included.
    std::fs::write(tmp.join("frames/seq/frame_0000.png"), b"not ours").unwrap();
    let (code, failed) = json(&[
        "--frames",
        "0",
        "--output",
        "frames/seq/frame_####.exr",
        "--bit-depth",
        "16",
    ]);
    assert_eq!(code, Some(2));
    assert_eq!(failed.last().unwrap()["event"], "error");
    assert_eq!(failed.last().unwrap()["exit_code"], 2);
}

#[test]
fn frame_specs_of_other_tools_and_dry_runs_beside_streams() {
    let tmp = scratch("fits-specs");
    small(&tmp, 10);
    let dry = |spec: &str| {
        let out = run_in(&tmp, &["render", "seq.yaml", "--dry-run", "--frames", spec]);
        assert!(out.status.success(), "{spec}: {}", stderr(&out));
        String::from_utf8(out.stdout).unwrap()
    };
    assert!(dry("1..3").contains("would render: 1-3"), "{}", dry("1..3"));
    assert!(dry("7-").contains("would render: 7-9"), "{}", dry("7-"));
    assert!(dry("last").contains("would render: 9\n"), "{}", dry("last"));
    let out = run_in(&tmp, &["render", "seq.yaml", "--dry-run", "--pipe", "raw"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(out.stdout.is_empty(), "the plan went into the stream");
    assert!(
        stderr(&out).contains("would stream frames: 0-9"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn messages_count_round_and_read_the_file() {
    let tmp = scratch("fits-messages");
    let yaml = sequence(
        64,
        36,
        "timeline:\n  fps: 7.5\n  duration: 2.5\n  orbit: { center: [0, 0, 0], radius: 2, height: 0.5, duration: 2.5, turns: 1 }\n",
    );
    std::fs::write(tmp.join("seq.yaml"), &yaml).unwrap();
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(text.contains("(2 spheres, 1 plane)"), "{text}");
    assert!(text.contains("(1 turn)"), "{text}");
    assert!(text.contains("19 at 7.5 fps (2.53 s)"), "{text}");
    // `-` reads the sequence from stdin.
    let mut child = bin()
        .args(["check", "-"])
        .current_dir(&tmp)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(yaml.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("-: ok"));
    // One error style: clap's errors read like rayreel's own.
    let out = run_in(&tmp, &["render", "seq.yaml", "--size", "0x10"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).starts_with("rayreel: invalid value '0x10'"),
        "{}",
        stderr(&out)
    );
    let out = run_in(&tmp, &["check", "missing.yaml"]);
    assert!(
        stderr(&out).starts_with("rayreel: missing.yaml"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn studio_frame_numbers_and_fractional_rates() {
    let tmp = scratch("fits-1001");
    let timeline = "timeline:\n  fps: 24000/1001\n  first_frame: 1001\n  keyframes:\n    - { time: 0, position: [0, 0, 3], look_at: [0, 0, 0] }\n    - { time: 1.001, position: [1, 0, 3], look_at: [0, 0, 0] }\n";
    std::fs::write(tmp.join("seq.yaml"), sequence(64, 36, timeline)).unwrap();
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    let summary = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        summary.contains("25 at 24000/1001 fps (1.04 s, frames 1001-1025)"),
        "{summary}"
    );
    let out = run_in(&tmp, &["camera", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 25, "{csv}");
    assert!(rows[0].starts_with("1001,0.0,"), "{}", rows[0]);
    // t = (n − first_frame)·den/num: frame 1025 is 24·1001/24000 = 1.001 s exactly.
    assert!(rows[24].starts_with("1025,1.001,1.0,"), "{}", rows[24]);
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "--frames",
            "1001,last",
            "--print-ffmpeg",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files(&tmp.join("frames/seq")),
        ["frame_1001.png", "frame_1025.png"]
    );
    let line = ffmpeg_line(&stderr(&out));
    assert!(
        line.contains("-framerate 24000/1001 -start_number 1001"),
        "{line}"
    );
    let out = run_in(&tmp, &["render", "seq.yaml", "--frames", "0"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("frames 1001-1025"),
        "{}",
        stderr(&out)
    );
    // --first-frame renumbers a file that has none.
    small(&tmp, 3);
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "--first-frame",
            "1",
            "-o",
            "one/f_##.png",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files(&tmp.join("one")),
        ["f_01.png", "f_02.png", "f_03.png"]
    );
}

#[test]
fn preview_lands_beside_the_frames() {
    let tmp = scratch("fits-preview");
    let yaml = format!(
        "output: shots/a/f_####.png\n{}",
        sequence(64, 36, &orbit(24, 0.5))
    );
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["preview", "seq.yaml", "--tiles", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        files(&tmp.join("shots/a/preview")),
        ["seq_path.png", "seq_sheet.png"]
    );
}

#[test]
fn ctrl_c_in_json_mode_is_json_too() {
    let tmp = scratch("fits-json-sigint");
    small(&tmp, 2000);
    let mut child = bin()
        .args(["render", "seq.yaml", "--progress", "json", "--threads", "1"])
        .current_dir(&tmp)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut lines = Vec::new();
    // Wait for the first frame, then interrupt.
    loop {
        let mut line = String::new();
        assert!(std::io::BufRead::read_line(&mut stderr, &mut line).unwrap() > 0);
        let done = line.contains("\"event\": \"frame\"");
        lines.push(line);
        if done {
            break;
        }
    }
    // SAFETY: kill only sends a signal to our own child process.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let mut rest = String::new();
    stderr.read_to_string(&mut rest).unwrap();
    let status = child.wait().unwrap();
    lines.extend(rest.lines().map(String::from));
    let events: Vec<serde_json::Value> = lines
        .iter()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert_eq!(status.code(), Some(130));
    let kinds: Vec<&str> = events
        .iter()
        .map(|e| e["event"].as_str().unwrap())
        .collect();
    assert_eq!(kinds[0], "start", "{kinds:?}");
    let interrupt = events.iter().find(|e| e["event"] == "interrupt").unwrap();
    assert_eq!(interrupt["signal"], "SIGINT");
    assert!(
        interrupt["text"]
            .as_str()
            .unwrap()
            .contains("Ctrl-C again to abort")
    );
    let summary = events.iter().find(|e| e["event"] == "summary").unwrap();
    assert_eq!(summary["interrupted"], true);
    let error = events.last().unwrap();
    assert_eq!(
        (error["event"].as_str(), error["exit_code"].as_u64()),
        (Some("error"), Some(130))
    );
}
