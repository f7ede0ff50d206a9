//! `--video`: rendering and encoding in one step through the system's ffmpeg — the job's own
//! size (presets included) and exact frame rate, ProRes 4444 for alpha, ffmpeg missing or
//! failing said clearly, nothing under the final name but a whole video, and no file
//! replaced without --force. Tests that need ffmpeg skip without it unless
//! RAYREEL_REQUIRE_TOOLS=1.

mod common;
use common::*;
use std::path::Path;
use std::process::Command;

/// A 64×36 orbit of 24 frames at `fps` in `dir/seq.yaml`.
fn small(dir: &Path, fps: &str) {
    let timeline = format!(
        "timeline:\n  fps: {fps}\n  orbit: {{ center: [-0.1, 0, -0.6], radius: 1.6, height: 0.35, duration: 1, turns: 0.05, look_at: [-0.1, -0.1, -0.6] }}\n"
    );
    std::fs::write(dir.join("seq.yaml"), sequence(64, 36, &timeline)).unwrap();
}

/// ffprobe's `key=value` lines for the first video stream of `video`.
fn probe(video: &Path) -> String {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0"])
        .args([
            "-show_entries",
            "stream=width,height,r_frame_rate,nb_read_frames,codec_name,pix_fmt",
            "-of",
            "default=noprint_wrappers=1",
        ])
        .arg(video)
        .output()
        .unwrap();
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn tools() -> bool {
    have_tool("ffmpeg") && have_tool("ffprobe")
}

#[test]
fn a_draft_video_has_the_drafts_size_every_frame_and_the_exact_rate() {
    if !tools() {
        return;
    }
    let dir = scratch("video-draft");
    small(&dir, "24000/1001");
    // Draft halves the size (32×18): a hard-coded size would scramble the frames.
    let out = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "--quality",
            "draft",
            "-q",
            "--video",
            "v/out.mp4",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(out.stdout.is_empty(), "stdout stays clean");
    let p = probe(&dir.join("v/out.mp4"));
    for want in [
        "codec_name=h264",
        "width=32",
        "height=18",
        "pix_fmt=yuv420p",
        "r_frame_rate=24000/1001",
        "nb_read_frames=24",
    ] {
        assert!(p.contains(want), "{want} in {p}");
    }
    // Only the video: no frame files, no temporaries.
    assert_eq!(files(&dir.join("v")), ["out.mp4"]);
    assert!(!dir.join("frames").exists());
}

#[test]
fn alpha_makes_prores_4444_in_a_mov_and_mp4_refuses_it() {
    if !tools() {
        return;
    }
    let dir = scratch("video-alpha");
    small(&dir, "24");
    let out = run_in(
        &dir,
        &["render", "seq.yaml", "--alpha", "-q", "--video", "a.mov"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let p = probe(&dir.join("a.mov"));
    assert!(p.contains("codec_name=prores"), "{p}");
    assert!(p.contains("pix_fmt=yuva444p"), "{p}");
    let out = run_in(&dir, &["render", "seq.yaml", "--alpha", "--video", "a.mp4"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains(".mov"), "{}", stderr(&out));
}

#[test]
fn an_existing_video_is_replaced_only_with_force() {
    if !tools() {
        return;
    }
    let dir = scratch("video-force");
    small(&dir, "24");
    std::fs::write(dir.join("out.mkv"), "mine").unwrap();
    let out = run_in(&dir, &["render", "seq.yaml", "--video", "out.mkv"]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("out.mkv: already exists") && err.contains("--force"),
        "{err}"
    );
    assert!(!err.contains("frame 0"), "refused before rendering: {err}");
    assert_eq!(std::fs::read(dir.join("out.mkv")).unwrap(), b"mine");
    let out = run_in(
        &dir,
        &["render", "seq.yaml", "-q", "--force", "--video", "out.mkv"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(probe(&dir.join("out.mkv")).contains("nb_read_frames=24"));
}

#[test]
fn ffmpegs_failure_is_surfaced_and_leaves_nothing() {
    if !tools() {
        return;
    }
    let dir = scratch("video-fail");
    small(&dir, "24");
    let out = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "-q",
            "--video",
            "x.mp4",
            "--video-args",
            "-c:v no-such-codec",
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("ffmpeg failed") && err.contains("no-such-codec"),
        "{err}"
    );
    assert!(
        files(&dir).iter().all(|f| f == "seq.yaml"),
        "{:?}",
        files(&dir)
    );
}

#[test]
fn without_ffmpeg_nothing_renders() {
    let dir = scratch("video-missing");
    small(&dir, "24");
    let out = bin()
        .args(["render", "seq.yaml", "--video", "x.mp4"])
        .current_dir(&dir)
        .env("PATH", dir.join("nowhere"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(err.contains("ffmpeg, which is not on the PATH"), "{err}");
    assert!(!err.contains("frame 0"), "{err}");
    assert_eq!(files(&dir), ["seq.yaml"]);
}

#[test]
fn video_names_its_containers_and_keeps_apart_from_pipes() {
    let dir = scratch("video-usage");
    small(&dir, "24");
    let out = run_in(&dir, &["render", "seq.yaml", "--video", "x.avi"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains(".mp4, .mov or .mkv"),
        "{}",
        stderr(&out)
    );
    let out = run_in(
        &dir,
        &["render", "seq.yaml", "--video", "x.mp4", "--pipe", "raw"],
    );
    assert_eq!(out.status.code(), Some(2));
    // A dry run says what the video would take and prints the command, making nothing.
    let out = run_in(
        &dir,
        &[
            "render",
            "seq.yaml",
            "--video",
            "v.mp4",
            "--dry-run",
            "--print-ffmpeg",
            "--quality",
            "draft",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let plan = String::from_utf8_lossy(&out.stdout);
    assert!(
        plan.contains("would render frames 0-23 straight into v.mp4"),
        "{plan}"
    );
    let err = stderr(&out);
    assert!(
        err.contains("-s 32x18 -r 24/1 -i -") && err.ends_with("v.mp4\n"),
        "{err}"
    );
    assert_eq!(files(&dir), ["seq.yaml"]);
}

#[test]
fn a_stopped_video_leaves_nothing_under_any_name() {
    if !tools() {
        return;
    }
    let dir = scratch("video-stop");
    // 2000 frames: long enough to be stopped while frames go to ffmpeg.
    let timeline = "timeline:\n  fps: 24\n  orbit: { center: [-0.1, 0, -0.6], radius: 1.6, height: 0.35, duration: 83.3, turns: 0.05, look_at: [-0.1, -0.1, -0.6] }\n";
    std::fs::write(dir.join("seq.yaml"), sequence(64, 36, timeline)).unwrap();
    for sig in [libc::SIGINT, libc::SIGTERM] {
        let mut child = bin()
            .args(["render", "seq.yaml", "--threads", "1", "--progress", "json"])
            .args(["--video", "out.mp4"])
            .current_dir(&dir)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for a frame to reach ffmpeg.
        let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
        let mut line = String::new();
        while std::io::BufRead::read_line(&mut err, &mut line).unwrap() > 0
            && !line.contains("to ffmpeg")
        {
            line.clear();
        }
        assert!(line.contains("to ffmpeg"), "no frame went to ffmpeg");
        signal(&child, sig);
        let status = child.wait().unwrap();
        let mut rest = String::new();
        std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
        assert_eq!(status.code(), Some(128 + sig), "{rest}");
        assert!(rest.contains("no video was made"), "{rest}");
        assert_eq!(files(&dir), ["seq.yaml"], "after signal {sig}");
    }
}
