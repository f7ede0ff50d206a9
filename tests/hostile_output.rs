//! A second adversarial pass, through the real binary: what stands at a frame's or a claim's
//! name cannot make a run block or read without end, a failing stderr loses lines and not
//! frames, a signal while waiting on a claim stops the run with the true count, and what
//! files and messages say is exactly true (EXR frame rates, half floats, numbers, the ffmpeg
//! line).

mod common;
use common::*;
use std::os::unix::fs::FileTypeExt;
use std::path::Path;

fn small() -> String {
    sequence(32, 18, &orbit(24, 1.0))
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "{path:?}");
}

/// Starts rayreel in `dir` with `args`, stdout and stderr piped.
fn start(dir: &Path, args: &[&str]) -> std::process::Child {
    bin()
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

const FRAMES: [&str; 5] = ["seq.yaml", "-o", "out/f_####.png", "--frames", "0-3"];

#[test]
fn fifos_devices_and_huge_files_at_frame_names_neither_block_nor_get_read() {
    let tmp = scratch("frame-fifo");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // Frame 0: a FIFO nobody writes; frame 1: a link to /dev/zero (a read that never ends);
    // frame 3: a sparse 64 GiB file without a fingerprint.
    mkfifo(&out.join("f_0000.png"));
    std::os::unix::fs::symlink("/dev/zero", out.join("f_0001.png")).unwrap();
    std::fs::File::create(out.join("f_0003.png"))
        .unwrap()
        .set_len(64 << 30)
        .unwrap();
    let status = ends_within(
        start(&tmp, &[&["status"], &FRAMES[..]].concat()),
        10.0,
        "status",
    );
    let listing = String::from_utf8_lossy(&status.stdout);
    assert_eq!(
        status.status.code(),
        Some(1),
        "{listing}{}",
        stderr(&status)
    );
    assert!(listing.contains("foreign     0-1,3"), "{listing}");
    assert!(listing.contains("missing     2"), "{listing}");

    let render = ends_within(
        start(&tmp, &[&["render"], &FRAMES[..]].concat()),
        30.0,
        "render",
    );
    let log = stderr(&render);
    assert_eq!(render.status.code(), Some(1), "{log}");
    for said in [
        "out/f_0000.png: a FIFO, not a regular file; leaving it alone (use --force to overwrite)",
        "out/f_0001.png: a character device, not a regular file; leaving it alone",
        "out/f_0003.png: 68719476736 bytes, more than a frame of this job can take, and no rayreel fingerprint in its header; leaving it alone",
        "frames 0-1,3 were not written: files rayreel did not write are in the way",
    ] {
        assert!(log.contains(said), "{said}: {log}");
    }
    // Nothing of the user's was replaced; frame 2 was written.
    let kind = |n: &str| std::fs::symlink_metadata(out.join(n)).unwrap().file_type();
    assert!(kind("f_0000.png").is_fifo());
    assert!(kind("f_0001.png").is_symlink());
    assert_eq!(
        std::fs::metadata(out.join("f_0003.png")).unwrap().len(),
        64 << 30
    );
    assert!(kind("f_0002.png").is_file());

    // A frame of ours grown past what a frame of the job can be is judged by its header: its
    // own fingerprint, so corrupt (re-rendered), not foreign.
    let grown = std::fs::OpenOptions::new()
        .append(true)
        .open(out.join("f_0002.png"))
        .unwrap();
    grown.set_len(64 << 30).unwrap();
    let status = ends_within(
        start(&tmp, &[&["status"], &FRAMES[..]].concat()),
        10.0,
        "status",
    );
    let listing = String::from_utf8_lossy(&status.stdout);
    assert!(listing.contains("corrupt     2"), "{listing}");
}

#[test]
fn anything_but_a_file_at_a_claims_name_stops_the_run_naming_it() {
    let tmp = scratch("claim-fifo");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let claim = out.join(".f_0002.png.rayreel-claim");
    for (what, plant) in [
        ("a FIFO", &(|p: &Path| mkfifo(p)) as &dyn Fn(&Path)),
        ("a symbolic link", &|p: &Path| {
            std::os::unix::fs::symlink("/dev/zero", p).unwrap()
        }),
    ] {
        plant(&claim);
        let args = [&["render"], &FRAMES[..], &["--claim", "--threads", "1"]].concat();
        let run = ends_within(start(&tmp, &args), 30.0, what);
        let log = stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{what}: {log}");
        assert!(
            log.contains(&format!(
                "rayreel: out/.f_0002.png.rayreel-claim: cannot create claim: {what} stands at the claim's name, where rayreel only ever writes regular files; remove it"
            )),
            "{what}: {log}"
        );
        // Left where it was.
        let meta = std::fs::symlink_metadata(&claim).unwrap();
        assert!(meta.file_type().is_fifo() || meta.file_type().is_symlink());
        std::fs::remove_file(&claim).unwrap();
    }
}

#[test]
fn a_failing_stderr_loses_lines_not_frames() {
    let tmp = with_clean_render("full-stderr", &small());
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    for (dir, extra) in [("lines", &[][..]), ("json", &["--progress", "json"][..])] {
        let pattern = format!("{dir}/f_####.png");
        let run = bin()
            .args(["render", "seq.yaml", "-o", &pattern])
            .args(extra)
            .current_dir(&tmp)
            .stderr(full())
            .output()
            .unwrap();
        // Once: "failed printing to stderr", exit 101 and no frame.
        assert_eq!(run.status.code(), Some(0), "{dir}");
        assert_same_files(&tmp.join(dir), &tmp.join("clean"));
    }
    // An error still ends with its exit code.
    let run = bin()
        .args(["render", "missing.yaml"])
        .current_dir(&tmp)
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let run = bin()
        .args(["render", "--no-such-flag"])
        .current_dir(&tmp)
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
}

#[test]
fn one_sigterm_while_waiting_on_a_claim_stops_with_the_frames_written() {
    let tmp = scratch("claim-sigterm");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // Held by this test process: alive, so the run waits on it.
    std::fs::write(out.join(".f_0002.png.rayreel-claim"), my_claim_owner()).unwrap();
    let args = [&["render"], &FRAMES[..], &["--claim", "--threads", "1"]].concat();
    let mut child = start(&tmp, &args);
    let err = std::io::BufReader::new(child.stderr.take().unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufRead::lines(err) {
            let _ = tx.send(line.unwrap());
        }
    });
    let mut log = String::new();
    loop {
        match rx.recv_timeout(std::time::Duration::from_secs(30)) {
            Ok(line) => {
                log += &line;
                log.push('\n');
                if line.contains("waiting for 1 frame (2)") {
                    break;
                }
            }
            Err(e) => {
                child.kill().unwrap();
                panic!("the worker did not wait: {e}: {log}");
            }
        }
    }
    let sent = std::time::Instant::now();
    signal(&child, libc::SIGTERM);
    let run = ends_within(child, 10.0, "after SIGTERM");
    assert!(sent.elapsed().as_secs_f64() < 5.0);
    while let Ok(line) = rx.recv_timeout(std::time::Duration::from_secs(1)) {
        log += &line;
        log.push('\n');
    }
    assert_eq!(run.status.code(), Some(143), "{log}");
    assert!(
        log.contains("rayreel: stopping on SIGTERM: no frame is in flight"),
        "{log}"
    );
    // The closing line agrees with what was written (it once said 0).
    assert!(log.contains("rendered 3 frames in"), "{log}");
    assert!(
        log.contains("rayreel: interrupted: 3 frames written in this run"),
        "{log}"
    );
    let written: Vec<String> = files(&out);
    assert_eq!(
        written,
        [
            ".f_0002.png.rayreel-claim",
            "f_0000.png",
            "f_0001.png",
            "f_0003.png"
        ],
        "{log}"
    );
}

/// A still camera, so that a change of fps changes no pixel, at `fps` (YAML).
fn still_at(fps: &str) -> String {
    format!(
        "render: {{ width: 16, height: 9 }}\n{SCENE}timeline:\n  fps: {fps}\n  duration: 10\n  keyframes:\n    - {{ time: 0, position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }}\n"
    )
}

/// The header attribute `name` of type `kind` in an EXR file: its value bytes.
fn exr_attribute<'a>(bytes: &'a [u8], name: &str, kind: &str) -> &'a [u8] {
    let key = format!("{name}\0{kind}\0");
    let at = bytes
        .windows(key.len())
        .position(|w| w == key.as_bytes())
        .unwrap_or_else(|| panic!("no {name}"))
        + key.len();
    let size = i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    &bytes[at + 4..at + 4 + size]
}

fn frames_per_second(path: &Path) -> (i32, u32) {
    let bytes = std::fs::read(path).unwrap();
    let v = exr_attribute(&bytes, "framesPerSecond", "rational");
    (
        i32::from_le_bytes(v[..4].try_into().unwrap()),
        u32::from_le_bytes(v[4..8].try_into().unwrap()),
    )
}

#[test]
fn exr_frame_rates_are_exact_and_a_new_rate_makes_frames_stale() {
    let tmp = scratch("exr-fps");
    let args = ["seq.yaml", "-o", "out/f_####.exr", "--frames", "1-2"];
    let frame = tmp.join("out/f_0001.exr");
    // As written; the same rate written otherwise; a decimal as written, in lowest terms.
    for (fps, stored, before) in [
        ("30000/1001", (30000, 1001), None),
        ("60000/2002", (30000, 1001), Some("up to date  1-2")),
        // The pixels are the same at any rate (the camera holds still), but the header's
        // `framesPerSecond` and `rayreel:time` are not: the frames are stale.
        ("23.976", (2997, 125), Some("stale       1-2")),
        ("0.5", (1, 2), Some("stale       1-2")),
    ] {
        std::fs::write(tmp.join("seq.yaml"), still_at(fps)).unwrap();
        if let Some(expect) = before {
            let status = run_in(&tmp, &[&["status"], &args[..]].concat());
            let listing = String::from_utf8_lossy(&status.stdout);
            assert!(listing.contains(expect), "{fps}: {listing}");
        }
        let run = run_in(&tmp, &[&["render"], &args[..]].concat());
        assert!(run.status.success(), "{}", stderr(&run));
        assert_eq!(frames_per_second(&frame), stored, "{fps}");
        let bytes = std::fs::read(&frame).unwrap();
        let time = exr_attribute(&bytes, "rayreel:time", "double");
        let time = f64::from_le_bytes(time.try_into().unwrap());
        let exact = f64::from(stored.1) / f64::from(stored.0);
        assert!((time - exact).abs() <= 1e-15 * exact, "{fps}: {time}");
    }
}

/// A PNG frame states its time in a text chunk (`rayreel:time`); its fingerprint once did not
/// cover it, so a new fps with a still camera left frames up to date that claim the old time.
/// Now it does: they are stale, and the rerun writes the true time.
#[test]
fn png_frames_whose_stated_time_changes_are_stale() {
    let tmp = scratch("png-time");
    let args = ["seq.yaml", "-o", "out/f_####.png", "--frames", "1-2"];
    std::fs::write(tmp.join("seq.yaml"), still_at("24")).unwrap();
    let run = run_in(&tmp, &[&["render"], &args[..]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    std::fs::write(tmp.join("seq.yaml"), still_at("25")).unwrap();
    let status = run_in(&tmp, &[&["status"], &args[..]].concat());
    let listing = String::from_utf8_lossy(&status.stdout);
    assert!(listing.contains("stale       1-2"), "{listing}");
    let run = run_in(&tmp, &[&["render"], &args[..]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let bytes = std::fs::read(tmp.join("out/f_0001.png")).unwrap();
    let key = b"rayreel:time\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len();
    // 1/25 s, not 1/24 (0.041666…).
    let time = &bytes[at..at + 5];
    assert!(time.starts_with(b"0.04") && time != b"0.041", "{time:?}");
}

#[test]
fn half_floats_hold_65504_where_the_light_is_brighter_with_one_warning() {
    let tmp = scratch("half-inf");
    let yaml = small().replace(
        "diffuse: [1, 1, 1], specular: [1, 1, 1] }",
        "diffuse: [1000000, 1000000, 1000000], specular: [1, 1, 1] }",
    );
    assert!(yaml.contains("1000000"));
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let run = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.exr",
            "--frames",
            "0-1",
        ],
    );
    let log = stderr(&run);
    assert!(run.status.success(), "{log}");
    assert_eq!(log.matches("beyond 65504").count(), 1, "{log}");
    // The warning names the first frame to finish encoding: either, as the pool runs them.
    assert!(
        log.contains("warning: frame 0 (out/f_0000.exr): ")
            || log.contains("warning: frame 1 (out/f_0001.exr): "),
        "{log}"
    );
    assert!(log.contains("stored as 65504 instead of infinity"), "{log}");
    for n in 0..2 {
        let image =
            exr::prelude::read_all_flat_layers_from_file(tmp.join(format!("out/f_000{n}.exr")))
                .unwrap();
        let mut top = 0f32;
        for channel in &image.layer_data[0].channel_data.list {
            for v in channel.sample_data.values_as_f32() {
                assert!(v.is_finite(), "frame {n}: {v}");
                top = top.max(v);
            }
        }
        assert_eq!(top, 65504.0, "frame {n}");
    }
    // 32-bit floats hold the values themselves, without a warning.
    let run = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "float/f_####.exr",
            "--frames",
            "0",
            "--exr-precision",
            "float",
        ],
    );
    assert!(
        run.status.success() && !stderr(&run).contains("65504"),
        "{}",
        stderr(&run)
    );
}

#[test]
fn numbers_in_messages_are_exact_and_short() {
    let tmp = scratch("exact-numbers");
    for (field, value, said) in [
        (
            "shutter",
            "360.0001",
            "must be an angle in [0, 360] degrees (0: no motion blur, 180: film) (got 360.0001)",
        ),
        ("shutter", "-1e-300", "(got -1e-300)"),
        ("shutter", "360.00000000000006", "(got 360.00000000000006)"),
        ("shutter", "1e300", "(got 1e300)"),
        ("exposure", "-1000000000000000000000.5", "(got -1e21)"),
        (
            "exposure",
            "64.00000000000001",
            "must be within ±64 stops (got 64.00000000000001)",
        ),
    ] {
        let yaml = small().replace("render: {", &format!("render: {{ {field}: {value},"));
        std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
        let out = run_in(&tmp, &["check", "seq.yaml"]);
        let log = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{value}: {log}");
        assert!(log.contains(said), "{value}: {log}");
        assert!(log.len() < 400, "{value}: {log}");
    }
}

#[test]
fn the_ffmpeg_line_names_files_with_newlines_and_tabs_exactly() {
    let tmp = scratch("ffmpeg-quoting");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let dir = "it's\tmy\nframes";
    let pattern = format!("{dir}/f_####.png");
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            &pattern,
            "--frames",
            "0",
            "--print-ffmpeg",
            "-q",
        ],
    );
    let log = stderr(&out);
    assert!(out.status.success(), "{log}");
    assert!(tmp.join(dir).join("f_0000.png").is_file());
    let line = log
        .lines()
        .find(|l| l.starts_with("ffmpeg "))
        .unwrap_or_else(|| panic!("{log}"));
    // Pasted into bash, with ffmpeg standing in for a function that prints its arguments.
    let script = format!("ffmpeg() {{ printf '%s\\0' \"$@\"; }}\n{line}\n");
    let run = sh(&tmp, &script);
    assert!(run.status.success(), "{line}: {}", stderr(&run));
    let words: Vec<String> = String::from_utf8(run.stdout)
        .unwrap()
        .split('\0')
        .map(str::to_string)
        .collect();
    let input = words.iter().position(|w| w == "-i").expect("-i") + 1;
    assert_eq!(words[input], format!("{dir}/f_%04d.png"), "{line}");
}

/// An 8192×8192 EXR with alpha and depth under a 3 GB address-space limit (issue 29): it once
/// rendered until an allocation failed and aborted with a backtrace (exit 134). Its memory is
/// now worked out before the first frame: about 6.4 GB a frame (3.2 GB of planes, and the
/// adaptive pass's or the film filter's buffers) does not fit, so the run is
/// refused at once, naming the limit; a size that fits two frames at a time runs with a note.
#[test]
fn a_job_that_cannot_fit_in_memory_is_refused_before_it_starts() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("memory-limit");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let started = std::time::Instant::now();
    let big = "\"$RAYREEL\" render seq.yaml --size 8192x8192 --alpha --depth --frames 0-3 --threads 2 -o big_####.exr";
    let out = sh(&tmp, &format!("prlimit --as=3000000000 {big}"));
    let said = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(started.elapsed().as_secs() < 20, "{said}");
    assert!(
        said.contains("not enough memory: one frame needs about 6.")
            && said.contains("under RLIMIT_AS (ulimit -v)")
            && !said.contains("panicked"),
        "{said}"
    );
    assert!(files(&tmp).iter().all(|f| !f.starts_with("big_")));
    // 1024×1024 with alpha and depth: about 80 MB a frame (with adaptive sampling's buffers).
    // Raising the limit from below what the process maps and keeps for its threads' arenas
    // (about 0.7 GB here), each run is refused until one renders all four frames, never
    // aborting; that one keeps fewer frames in flight than the 4 two threads would.
    let mut shrunk = false;
    for mb in (600..=3000).step_by(25) {
        let out = sh(
            &tmp,
            &format!(
                "prlimit --as={mb}000000 \"$RAYREEL\" render seq.yaml --size 1024x1024 --alpha --depth --frames 0-3 --threads 2 -o fit{mb}_####.exr"
            ),
        );
        let said = stderr(&out);
        match out.status.code() {
            Some(0) => assert_eq!(
                files(&tmp)
                    .iter()
                    .filter(|f| f.starts_with(&format!("fit{mb}_")))
                    .count(),
                4
            ),
            Some(1) => assert!(
                said.contains("not enough memory: one frame needs about 8")
                    && said.contains(" MB (rendered, then encoded)")
                    && !said.contains("0.00"),
                "{mb} MB: {said}"
            ),
            code => panic!("{mb} MB: exit {code:?}: {said}"),
        }
        assert!(!said.contains("memory allocation"), "{mb} MB: {said}");
        shrunk |= said.contains("at a time instead of 4");
        if out.status.success() {
            break;
        }
    }
    assert!(shrunk, "no limit made the run keep fewer frames in flight");
}

/// A 920-byte EXR at a frame's name whose header claims 262144×3 pixels in 4 channels (found
/// by the `frame_files` fuzzer): the frame check once decoded what the header claimed, 2 GB,
/// and under a 1.5 GB limit aborted. The header alone now decides: a stale frame (it carries
/// a fingerprint, not this job's).
#[test]
fn a_frame_file_whose_header_claims_gigabytes_is_judged_by_its_header() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("exr-header-claims");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let fixture = repo().join("tests/fixtures/fuzz/frame_files/exr_header_claims_2gb.exr");
    std::fs::copy(fixture, tmp.join("f_0000.exr")).unwrap();
    let out = sh(
        &tmp,
        "prlimit --as=1500000000 \"$RAYREEL\" status seq.yaml -o f_####.exr --frames 0",
    );
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(
        said.contains("1 stale") && !said.contains("memory allocation"),
        "{said}"
    );
}

/// A claim whose owner line is empty (or unreadable) held a waiting run, whose line showed it
/// as `(, heartbeat 0 s ago)`; it now says the owner is unknown.
#[test]
fn a_claim_with_no_owner_line_is_shown_as_owner_unknown() {
    let tmp = scratch("claim-empty-owner");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = tmp.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join(".f_0002.png.rayreel-claim"), "").unwrap();
    let args = [&["render"], &FRAMES[..], &["--claim", "--threads", "1"]].concat();
    let mut child = start(&tmp, &args);
    let err = std::io::BufReader::new(child.stderr.take().unwrap());
    let waiting = std::io::BufRead::lines(err)
        .map(|l| l.unwrap())
        .find(|l| l.contains("waiting for 1 frame (2)"));
    child.kill().unwrap();
    child.wait().unwrap();
    let line = waiting.expect("the run waits on the claim");
    assert!(line.contains("(owner unknown, heartbeat "), "{line}");
}

/// `--alpha --depth --aov normal,albedo,id,motion,position` writes 17 EXR channels, which the
/// frame check refused (more than 16): every run and every resume rendered every frame again
/// and `status` called them corrupt, so a farm looped for ever. Every channel set rayreel
/// writes is now its own: the second run renders nothing and `status` exits 0.
#[test]
fn frames_with_every_channel_are_up_to_date_on_the_next_run() {
    let tmp = scratch("exr-every-channel");
    std::fs::write(tmp.join("seq.yaml"), sequence(24, 16, &orbit(24, 1.0))).unwrap();
    let args = [
        "seq.yaml",
        "--alpha",
        "--depth",
        "--aov",
        "normal,albedo,id,motion,position",
        "--frames",
        "0-1",
        "-o",
        "f_####.exr",
    ];
    let first = run_in(&tmp, &[&["render"], &args[..]].concat());
    assert!(first.status.success(), "{}", stderr(&first));
    let again = run_in(&tmp, &[&["render"], &args[..]].concat());
    let said = stderr(&again);
    assert!(again.status.success(), "{said}");
    assert!(
        said.contains("2 frames: 2 up to date → rendering 0"),
        "{said}"
    );
    let status = run_in(&tmp, &[&["status"], &args[..]].concat());
    assert_eq!(status.status.code(), Some(0), "{}", stderr(&status));
}

/// A directory `bin/` holding an `ffmpeg` that reads the stream, writes `bytes` where the
/// video should go, prints `said` on stderr and exits 0: ffmpeg 5.1 on a full disk prints
/// "Error writing trailer … No space left on device" and exits 0.
fn lying_ffmpeg(dir: &Path, said: &str, bytes: &[u8]) -> String {
    use std::os::unix::fs::PermissionsExt;
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::write(dir.join("written"), bytes).unwrap();
    let script = format!(
        "#!/bin/sh\nfor last; do :; done\ncat > /dev/null\ncp \"{}\" \"$last\"\nprintf '%s\\n' \"{said}\" >&2\nexit 0\n",
        dir.join("written").display()
    );
    let ffmpeg = bin.join("ffmpeg");
    std::fs::write(&ffmpeg, script).unwrap();
    std::fs::set_permissions(&ffmpeg, std::fs::Permissions::from_mode(0o755)).unwrap();
    format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    )
}

/// An MP4 cut where ffmpeg 5.1 leaves it when its trailer cannot be written: the file type
/// box and the frames' box, but no index (`moov`).
fn mp4_without_index() -> Vec<u8> {
    let mut b = Vec::new();
    b.extend(16u32.to_be_bytes());
    b.extend(b"ftypisom\0\0\x02\0");
    b.extend(24u32.to_be_bytes());
    b.extend(b"mdat");
    b.extend([0u8; 16]);
    b
}

/// ffmpeg exiting 0 is not enough: a video whose encoder reported an error, or whose
/// container is not whole, is not renamed into place, and the run exits 1 saying why; nothing
/// is left under any name.
#[test]
fn a_video_ffmpeg_could_not_finish_is_never_published() {
    let tmp = scratch("video-lying-ffmpeg");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let cases = [
        (
            "[mp4 @ 0x5581] Error writing trailer of out.mp4: No space left on device",
            mp4_without_index(),
            "ffmpeg exited 0 but reported an error; ffmpeg said: [mp4 @ 0x5581] Error writing trailer",
        ),
        (
            "",
            mp4_without_index(),
            "ffmpeg exited 0 but the file it wrote is not whole: no `moov` box",
        ),
    ];
    for (said, bytes, want) in cases {
        let path = lying_ffmpeg(&tmp, said, &bytes);
        let out = bin()
            .args(["render", "seq.yaml", "-q", "--video", "v/out.mp4"])
            .current_dir(&tmp)
            .env("PATH", &path)
            .output()
            .unwrap();
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(
            err.contains("v/out.mp4: ") && err.contains(want),
            "wanted `{want}` in {err}"
        );
        assert!(err.contains("nothing was written there"), "{err}");
        let left: Vec<String> = files(&tmp.join("v"));
        assert!(left.is_empty(), "{left:?}");
    }
}

/// The real ffmpeg writing into a small tmpfs (root only): whatever the size, a run either
/// publishes a video ffprobe reads with every frame, or exits 1 and publishes nothing. Before,
/// sizes that let ffmpeg write the frames but not its trailer gave exit 0 and an unplayable
/// file.
#[test]
fn a_full_disk_never_leaves_a_broken_video_under_its_name() {
    if !(have_tool("ffmpeg") && have_tool("ffprobe")) {
        return;
    }
    let tmp = scratch("video-full-disk");
    // 24 frames at 320×180 make about 28 kB of H.264: disks of 4 to 24 kB fill before the
    // trailer (ffmpeg 5.1 then exits 0), larger ones take it all.
    std::fs::write(tmp.join("seq.yaml"), sequence(320, 180, &orbit(24, 1.0))).unwrap();
    let disk = tmp.join("disk");
    std::fs::create_dir_all(&disk).unwrap();
    let (mut published, mut refused) = (0, 0);
    for kb in (4..=36).step_by(8) {
        let mounted = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={kb}k"), "tmpfs"])
            .arg(&disk)
            .status()
            .is_ok_and(|s| s.success());
        if !mounted {
            assert!(
                std::env::var("RAYREEL_REQUIRE_TOOLS").as_deref() != Ok("1"),
                "mounting a tmpfs failed (this test needs root)"
            );
            eprintln!("SKIPPED: cannot mount a tmpfs (not root?)");
            return;
        }
        let out = run_in(
            &tmp,
            &["render", "seq.yaml", "-q", "--video", "disk/out.mp4"],
        );
        let video = disk.join("out.mp4");
        match out.status.code() {
            Some(0) => {
                let probe = std::process::Command::new("ffprobe")
                    .args(["-v", "error", "-count_packets", "-select_streams", "v:0"])
                    .args(["-show_entries", "stream=nb_read_packets", "-of", "csv=p=0"])
                    .arg(&video)
                    .output()
                    .unwrap();
                let count = String::from_utf8_lossy(&probe.stdout).trim().to_string();
                assert!(
                    probe.status.success() && probe.stderr.is_empty() && count == "24",
                    "{kb} kB: published, but ffprobe says {count:?} {}",
                    String::from_utf8_lossy(&probe.stderr)
                );
                published += 1;
            }
            Some(1) => {
                assert!(!video.exists(), "{kb} kB: exit 1 with a video in place");
                refused += 1;
            }
            code => panic!("{kb} kB: exit {code:?}: {}", stderr(&out)),
        }
        assert!(
            files(&disk).iter().all(|f| f == "out.mp4"),
            "{kb} kB: {:?}",
            files(&disk)
        );
        let _ = std::process::Command::new("umount").arg(&disk).status();
    }
    assert!(
        published > 0 && refused > 0,
        "{published} published, {refused} refused"
    );
}

/// `check` printed a line per area light note and per placement (1,000 area lights: 1,009
/// lines, one of 4,044 characters; 10,000 placements: 10,010 lines). Lists are now cut to
/// their first few and counted, samples grouped, noisy area lights in one note, lines wrapped
/// at 120 columns, and `--full` lists everything.
#[test]
fn check_stays_on_one_screen_for_any_scene() {
    let tmp = scratch("check-screen");
    std::fs::write(tmp.join("t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let mut yaml = String::from("render: { width: 32, height: 24, samples: 1 }\nobjects:\n");
    for i in 0..10_000 {
        yaml += &format!(
            "  - mesh: {{ file: t.obj, translate: [{}, 0, -5], material: {{ diffuse: [0.5, 0.5, 0.5] }} }}\n",
            i as f64 * 0.01
        );
    }
    yaml += "lights:\n";
    for i in 0..1000 {
        yaml += &format!(
            "  - sphere: {{ center: [{i}, 5, 0], radius: 0.5, samples: {}, diffuse: [0.001, 0.001, 0.001], specular: [0, 0, 0] }}\n",
            [8, 16, 32][i % 3]
        );
    }
    yaml += "camera: { position: [0, 0, 5], look_at: [0, 0, 0] }\n";
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let lines = text.lines().count() + stderr(&out).lines().count();
    let longest = text.lines().map(|l| l.chars().count()).max().unwrap();
    assert!(
        lines <= 24 && longest <= 120,
        "{lines} lines, longest {longest}:\n{text}"
    );
    // Lines past 120 columns are wrapped under the summary's indent.
    let text = text.replace("\n              ", " ");
    assert!(
        text.contains(
            "lights:     1000 (1000 sphere (334 with 8, 333 with 16 and 333 with 32 samples))"
        ),
        "{text}"
    );
    assert!(
        text.contains("note: lights[0-999] (sphere): 8 to 32 points on the light per pixel (their samples × 1 pixel sample), under 64"),
        "{text}"
    );
    assert!(
        text.contains(
            "… and 9997 more placements of this file (`rayreel check --full` lists them)"
        ),
        "{text}"
    );
    let full = run_in(&tmp, &["check", "seq.yaml", "--full"]);
    let text = String::from_utf8(full.stdout).unwrap();
    assert!(text.contains("objects[9999]: phong shading") && text.lines().count() > 10_000);
}

/// `camera --format chan` gave a pan of −180 for a camera looking straight up, where the docs
/// say 0 with the roll taking the rest, and an orbit's pan jumped from 180 to −172.5 between
/// frames, so importers that interpolate spun the long way. Pans and rolls now continue from
/// the line before.
#[test]
fn chan_pans_are_zero_straight_up_and_never_jump() {
    let tmp = scratch("chan-unwrap");
    let still = sequence(
        32,
        24,
        "camera: { position: [0, -5, 0], look_at: [0, 0, 0], up: [0, 0, -1] }\n",
    );
    std::fs::write(tmp.join("up.yaml"), still).unwrap();
    std::fs::write(tmp.join("orbit.yaml"), sequence(32, 24, &orbit(24, 2.0))).unwrap();
    let columns = |file: &str| -> Vec<Vec<f64>> {
        let out = run_in(&tmp, &["camera", file, "--format", "chan"]);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .map(|l| l.split(' ').map(|v| v.parse().unwrap()).collect())
            .collect()
    };
    let up = columns("up.yaml");
    assert!(
        (up[0][4] - 90.0).abs() < 1e-9 && up[0][5] == 0.0,
        "{:?}",
        up[0]
    );
    let orbit = columns("orbit.yaml");
    assert_eq!(orbit.len(), 48);
    for pair in orbit.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        assert!(
            (b[5] - a[5]).abs() < 180.0 && (b[6] - a[6]).abs() < 180.0,
            "{a:?} → {b:?}"
        );
    }
    assert!(orbit[47][5].abs() > 300.0, "{:?}", orbit[47]);
}

/// `camera --format chan` printed −180 for the pan of a camera at (0, 0, −5) looking at the
/// origin (atan2 of −0), and −180 for the roll with up −y or looking straight down with up
/// +z, where the docs give angles in (−180, 180]: a half turn now reads 180.
#[test]
fn chan_half_turns_read_180() {
    let tmp = scratch("chan-half-turn");
    let cases = [
        ("back.yaml", "position: [0, 0, -5], look_at: [0, 0, 0]", 5),
        (
            "flip.yaml",
            "position: [0, 0, 5], look_at: [0, 0, 0], up: [0, -1, 0]",
            6,
        ),
        (
            "down.yaml",
            "position: [0, 5, 0], look_at: [0, 0, 0], up: [0, 0, 1]",
            6,
        ),
    ];
    for (file, camera, column) in cases {
        let yaml = sequence(32, 24, &format!("camera: {{ {camera} }}\n"));
        std::fs::write(tmp.join(file), yaml).unwrap();
        let out = run_in(&tmp, &["camera", file, "--format", "chan", "--frames", "0"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let text = String::from_utf8(out.stdout).unwrap();
        let angles: Vec<f64> = text.split(' ').map(|v| v.trim().parse().unwrap()).collect();
        assert_eq!(angles[column], 180.0, "{file}: {text}");
        assert!(angles[4..7].iter().all(|a| *a > -180.0), "{file}: {text}");
    }
}

/// A 32×24 frame whose process peaks at about 144 MB (VmPeak, --threads 1) was refused under
/// 800 MB of address space ("only 0 bytes is free … once 713.0 MB … is kept for 5 threads'
/// stacks"): 136 MiB was kept for each thread, stacks already mapped counted again and arenas
/// beyond glibc's cap of 8 a core. It now renders there.
#[test]
fn a_small_job_is_admitted_where_its_peak_fits() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("memory-small-job");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    for (mb, threads) in [(800, 1), (800, 2)] {
        let out = sh(
            &tmp,
            &format!(
                "prlimit --as={mb}000000 \"$RAYREEL\" render seq.yaml -q --threads {threads} --frames 0 -o t{threads}.png"
            ),
        );
        assert!(out.status.success(), "{mb} MB: {}", stderr(&out));
        assert!(files(&tmp).contains(&format!("t{threads}.png")));
    }
}

/// 32 threads of a 32×18 frame were refused under 2 GB of address space, where the process
/// peaks at 1.13 GB (VmPeak, 2 cores): the check kept an allocator arena for each worker
/// though the workers had theirs already (glibc's cap of 8 a core was reached), and for 4
/// other threads a run may not start. It counts the arenas present once and the threads
/// the run will really start, and renders there.
#[test]
fn many_threads_are_admitted_where_their_arenas_fit() {
    if !have_tool("prlimit") {
        return;
    }
    let tmp = scratch("memory-many-threads");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    for threads in [32, 64] {
        let out = sh(
            &tmp,
            &format!(
                "prlimit --as=2000000000 \"$RAYREEL\" render seq.yaml -q --threads {threads} --frames 0-1 -o t{threads}_#.png"
            ),
        );
        assert!(out.status.success(), "{threads} threads: {}", stderr(&out));
        assert_eq!(
            files(&tmp)
                .iter()
                .filter(|f| f.starts_with(&format!("t{threads}_")))
                .count(),
            2
        );
    }
    // Still refused, with the figures, where even the process's start does not fit.
    let out = sh(
        &tmp,
        "prlimit --as=600000000 \"$RAYREEL\" render seq.yaml -q --threads 32 --frames 0 -o low.png",
    );
    let said = stderr(&out);
    assert!(matches!(out.status.code(), Some(1) | Some(2)), "{said}");
    assert!(
        !said.contains("memory allocation") && !said.contains("panicked"),
        "{said}"
    );
}

/// With `--force`, a video whose ffmpeg fails leaves the file already there as it was, and
/// the message names the video and quotes ffmpeg's error.
#[test]
fn a_forced_video_whose_ffmpeg_fails_names_it_and_keeps_the_old_one() {
    if !have_tool("ffmpeg") {
        return;
    }
    let tmp = scratch("video-force-fails");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    std::fs::write(tmp.join("x.mp4"), "the video rendered yesterday").unwrap();
    for extra in [&[][..], &["-o", "f/f_####.png"][..]] {
        let args = [
            &["render", "seq.yaml", "-q", "--frames", "0-3", "--force"][..],
            &["--video", "x.mp4", "--video-args", "-c:v no-such-codec"][..],
            extra,
        ]
        .concat();
        let out = run_in(&tmp, &args);
        let said = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{said}");
        assert!(
            said.contains("x.mp4: ffmpeg failed")
                && said.contains("Unknown encoder 'no-such-codec'")
                && said.contains("nothing was written there"),
            "{said}"
        );
        assert_eq!(
            std::fs::read_to_string(tmp.join("x.mp4")).unwrap(),
            "the video rendered yesterday"
        );
        assert!(
            (files(&tmp).iter())
                .all(|f| ["seq.yaml", "x.mp4"].contains(&f.as_str()) || f.starts_with("f/f_")),
            "{:?}",
            files(&tmp)
        );
    }
}

/// `check` on a mixed scene (60 mesh files with notes and long names, 60 textures, 300
/// lights) printed 44 lines, the longest 298 columns: each mesh file's block, long paths
/// whole. Mesh files and textures past the first few are now summed up with the largest,
/// names keep their tail, and lines wrap at 120 columns; `--full` lists every file.
#[test]
fn check_of_a_mixed_scene_fits_one_screen() {
    let tmp = scratch("check-mixed");
    let models = "models_exported_with_a_long_directory_name/and_a_subdirectory_too";
    let textures = "textures_from_the_asset_library/wood_and_stone_collection";
    std::fs::create_dir_all(tmp.join(models)).unwrap();
    std::fs::create_dir_all(tmp.join(textures)).unwrap();
    let obj = "usemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nf 1/1 2/2 3/3\nf 2/2/7 4/4/7 3/3/7\nf 1/1 2/2\n";
    let mut yaml = String::from("render: { width: 48, height: 27, samples: 1 }\nmaterials:\n");
    let mut objects = String::from("objects:\n");
    for i in 0..60 {
        let model =
            format!("{models}/model_{i:03}_exported_from_a_modelling_tool_with_a_long_name.obj");
        std::fs::write(tmp.join(&model), obj).unwrap();
        let texture =
            format!("{textures}/texture_{i:03}_with_a_descriptive_and_rather_long_name.png");
        image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
            .save(tmp.join(&texture))
            .unwrap();
        yaml += &format!("  m{i}: {{ diffuse: {{ image: {texture} }} }}\n");
        objects += &format!(
            "  - mesh: {{ file: {model}, material: m{i}, translate: [{}, 0, {}], scale: 0.5 }}\n",
            i % 10 - 5,
            -(i / 10) - 2
        );
    }
    yaml += &objects;
    yaml += "lights:\n";
    for i in 0..300 {
        yaml += &match i % 3 {
            1 => format!(
                "  - sphere: {{ center: [{i}, 5, 5], radius: 0.2, samples: {}, diffuse: [0.01, 0.01, 0.01], specular: [0, 0, 0] }}\n",
                [4, 8][i % 2]
            ),
            _ => format!(
                "  - point: {{ position: [{i}, 5, 5], diffuse: [0.01, 0.01, 0.01], specular: [0, 0, 0] }}\n"
            ),
        };
    }
    yaml += "camera: { position: [0, 2, 8], look_at: [0, 0, -4] }\n";
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let err = stderr(&out);
    let lines = text.lines().count() + err.lines().count();
    let longest = text
        .lines()
        .chain(err.lines())
        .map(|l| l.chars().count())
        .max()
        .unwrap();
    assert!(
        lines <= 25 && longest <= 120,
        "{lines} lines, longest {longest}:\n{text}{err}"
    );
    assert!(
        text.contains("  meshes:     60 files: 120 triangles, 240 vertices, 60 placements;")
            && text.contains("largest: …/model_0")
            && text.contains("_long_name.obj: 2 triangles, 1 placement, 3 notes")
            && text.contains("notes: 180 on 60 files, the first: ")
            && text
                .contains("`rayreel check --full` lists each file with its notes and placements")
            && text.contains("… and 57 more texture images, 60 in all:"),
        "{text}"
    );
    let full = run_in(&tmp, &["check", "seq.yaml", "--full"]);
    let all = String::from_utf8(full.stdout).unwrap();
    assert_eq!(all.matches("  mesh:       ").count(), 60, "{all}");
    assert_eq!(all.matches("  texture:    ").count(), 60, "{all}");
    assert_eq!(
        all.matches("note: ignored statements: usemtl").count(),
        60,
        "{all}"
    );
}
