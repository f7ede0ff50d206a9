//! Helpers shared by the end-to-end tests: run the real binary, make scratch directories.
#![allow(dead_code)]

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rayreel"))
}

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs rayreel with `args` in `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("rayreel runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh, empty scratch directory, removed when dropped (tempfile); it reads as the `Path`
/// it is, so `tmp.join(…)` and `&tmp` work as with a `PathBuf`.
pub struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A fresh, empty scratch directory named after `name` (which shows in the path, to tell
/// leftovers of a killed test apart); `RAYREEL_KEEP_SCRATCH=1` keeps it for a look.
pub fn scratch(name: &str) -> Scratch {
    let mut dir = tempfile::Builder::new()
        .prefix(&format!("rayreel-test-{name}-"))
        .tempdir()
        .unwrap();
    if std::env::var_os("RAYREEL_KEEP_SCRATCH").is_some() {
        dir.disable_cleanup(true);
        eprintln!("scratch: {}", dir.path().display());
    }
    Scratch(dir)
}

/// Every file below `dir`, relative, sorted.
pub fn files(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_string_lossy().into_owned());
            }
        }
    }
    out.sort();
    out
}

/// Decodes a PNG into (width, height, bytes).
pub fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let rgb = img.to_rgb8();
    (rgb.width(), rgb.height(), rgb.into_raw())
}

/// Whether an external tool is on PATH. When it is not: panic if RAYREEL_REQUIRE_TOOLS=1
/// (CI installs every tool), otherwise print a notice and let the caller skip.
pub fn have_tool(name: &str) -> bool {
    let found = Command::new("sh")
        .args(["-c", &format!("command -v {name}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        if std::env::var("RAYREEL_REQUIRE_TOOLS").as_deref() == Ok("1") {
            panic!("{name} is required (RAYREEL_REQUIRE_TOOLS=1) but not installed");
        }
        eprintln!("SKIPPED: {name} is not installed");
    }
    found
}

/// Runs a shell pipeline in `dir`, returning its output.
pub fn sh(dir: &Path, script: &str) -> Output {
    Command::new("bash")
        .args(["-o", "pipefail", "-c", script])
        .current_dir(dir)
        .env("RAYREEL", env!("CARGO_BIN_EXE_rayreel"))
        .output()
        .expect("bash runs")
}

/// The test scene: the talk's big red sphere and a small one over a plane floor, one light.
pub const SCENE: &str = "materials:
  red:   { ambient: [0.1, 0, 0], diffuse: [0.7, 0, 0], specular: [1, 1, 1], shininess: 100, reflection: 0.5 }
  floor: { ambient: [0.1, 0.1, 0.1], diffuse: [0.6, 0.6, 0.6], specular: [1, 1, 1], reflection: 0.5 }
objects:
  - sphere: { center: [-0.2, 0, -1], radius: 0.7, material: red }
  - sphere: { center: [0.3, -0.4, -0.2], radius: 0.2, material: red }
  - plane:  { point: [0, -0.7, 0], normal: [0, 1, 0], material: floor }
lights:
  - point: { position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

/// A sequence file of the test scene at `width`×`height` with `timeline` (a YAML block).
/// A linear timeline of three keys at 12 fps (49 frames) moving past the test scene.
pub const THREE_KEYS: &str = "timeline:
  fps: 12
  interpolation: linear
  keyframes:
    - { time: 0, position: [0, 0.3, 2], look_at: [-0.1, -0.1, -0.6] }
    - { time: 2, position: [1.5, 0.4, 0.5] }
    - { time: 4, position: [0, 0.5, -2.5] }
";

pub fn sequence(width: u32, height: u32, timeline: &str) -> String {
    format!("render: {{ width: {width}, height: {height} }}\n{SCENE}{timeline}")
}

/// A `timeline:` block: a one-turn orbit of `duration` seconds at `fps`.
pub fn orbit(fps: u32, duration: f64) -> String {
    format!(
        "timeline:\n  fps: {fps}\n  orbit: {{ center: [-0.1, 0, -0.6], radius: 1.6, height: 0.35, duration: {duration}, look_at: [-0.1, -0.1, -0.6] }}\n"
    )
}

/// A scratch directory holding `seq.yaml` and, under `clean/`, its single-process render: the
/// reference the farm, fault and resume tests compare against.
pub fn with_clean_render(name: &str, yaml: &str) -> Scratch {
    let tmp = scratch(name);
    std::fs::write(tmp.join("seq.yaml"), yaml).unwrap();
    let out = run_in(
        &tmp,
        &["render", "seq.yaml", "-o", "clean/f_####.png", "-q"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    tmp
}

/// The two directories hold the same file names with the same bytes.
pub fn assert_same_files(a: &Path, b: &Path) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(fa, fb, "file lists differ");
    for f in fa {
        let same = std::fs::read(a.join(&f)).unwrap() == std::fs::read(b.join(&f)).unwrap();
        assert!(
            same,
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// How a child ended: exit code, stderr, wall time, CPU time and peak resident memory.
pub struct Run {
    pub code: Option<i32>,
    pub stderr: String,
    pub seconds: f64,
    /// User and system time: what a limit on work should test, as a shared machine's load
    /// stretches the wall time several-fold.
    pub cpu_seconds: f64,
    pub peak_kb: u64,
}

/// Runs `command` (stdin and stdout closed, stderr kept) and measures it: what a limit on the
/// work a run does should test, as the CPU time does not stretch with a shared machine's load.
pub fn cpu_timed(command: &mut Command) -> Run {
    let started = Instant::now();
    let child = command
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the command runs");
    measure(child, started, |_| {})
}

/// Waits for `child` while `feed` runs, with its exit code, stderr, wall and CPU time and peak
/// RSS.
pub fn measure(mut child: Child, started: Instant, feed: impl FnOnce(&mut Child)) -> Run {
    let pid = child.id() as libc::pid_t;
    let mut err = child.stderr.take().expect("stderr is piped");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    feed(&mut child);
    let mut status = 0;
    // SAFETY: a zeroed rusage is a valid value for wait4 to fill in.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let deadline = started + Duration::from_secs(60);
    loop {
        // SAFETY: pid is our own unreaped child; status and usage outlive the call.
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break;
        }
        assert_eq!(r, 0, "wait4: {}", std::io::Error::last_os_error());
        if Instant::now() > deadline {
            // Not reaped yet, so the pid is still ours to kill.
            child.kill().unwrap();
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let seconds = started.elapsed().as_secs_f64();
    Run {
        code: libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status)),
        stderr: reader.join().unwrap(),
        seconds,
        cpu_seconds: [usage.ru_utime, usage.ru_stime]
            .iter()
            .map(|t| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6)
            .sum(),
        peak_kb: usage.ru_maxrss as u64,
    }
}

/// A UV sphere of radius 1 around the origin as OBJ text: `rings` × `segments` quads (the
/// poles fanned), outward vertex normals when `normals`, wound clockwise seen from outside
/// when `inward` (the vertex normals still point out).
pub fn uv_sphere(segments: usize, rings: usize, normals: bool, inward: bool) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    // Vertex 1 is the north pole, then `rings - 1` rings of `segments`, then the south pole.
    let index = |i: usize, j: usize| match i {
        0 => 1,
        i if i == rings => 2 + (rings - 1) * segments,
        i => 2 + (i - 1) * segments + j % segments,
    };
    let mut put = |th: f64, ph: f64| {
        let p = [th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()];
        writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
        if normals {
            writeln!(s, "vn {} {} {}", p[0], p[1], p[2]).unwrap();
        }
    };
    let pi = std::f64::consts::PI;
    put(0.0, 0.0);
    for i in 1..rings {
        for j in 0..segments {
            put(
                pi * i as f64 / rings as f64,
                2.0 * pi * j as f64 / segments as f64,
            );
        }
    }
    put(pi, 0.0);
    for i in 0..rings {
        for j in 0..segments {
            let quad = [
                index(i, j + 1),
                index(i + 1, j + 1),
                index(i + 1, j),
                index(i, j),
            ];
            let mut corners: Vec<usize> = Vec::new();
            for c in quad {
                if !corners.contains(&c) {
                    corners.push(c);
                }
            }
            // As listed, the corners wind counter-clockwise seen from outside.
            if inward {
                corners.reverse();
            }
            let f: Vec<String> = corners
                .iter()
                .map(|c| {
                    if normals {
                        format!("{c}//{c}")
                    } else {
                        c.to_string()
                    }
                })
                .collect();
            writeln!(s, "f {}", f.join(" ")).unwrap();
        }
    }
    s
}

/// This machine's name as rayreel writes it into temporary names.
pub fn host() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap();
    name.trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '.')
        .take(64)
        .collect()
}

/// This test process's identity as a claim records it: `host=H pid=P start=S boot=B`.
pub fn my_claim_owner() -> String {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap();
    let start = stat[stat.rfind(')').unwrap() + 1..]
        .split_whitespace()
        .nth(19)
        .unwrap()
        .to_string();
    let boot = std::fs::read_to_string("/proc/sys/kernel/random/boot_id").unwrap();
    format!(
        "host={} pid={} start={start} boot={}",
        host(),
        std::process::id(),
        boot.trim()
    )
}

/// Waits at most `seconds` for `child` to end; kills it and fails if it is still running.
pub fn ends_within(
    mut child: std::process::Child,
    seconds: f64,
    what: &str,
) -> std::process::Output {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(seconds);
    while child.try_wait().unwrap().is_none() {
        if std::time::Instant::now() > deadline {
            child.kill().unwrap();
            let out = child.wait_with_output().unwrap();
            panic!("{what}: still running after {seconds} s: {}", stderr(&out));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// `ends_within`, successfully.
pub fn finishes_within(child: std::process::Child, seconds: u64, what: &str) -> String {
    let out = ends_within(child, seconds as f64, what);
    assert!(out.status.success(), "{what}: {}", stderr(&out));
    stderr(&out)
}

pub fn signal(child: &std::process::Child, signal: i32) {
    // SAFETY: sends a signal to our own child, which has not been reaped.
    unsafe { libc::kill(child.id() as i32, signal) };
}

/// Runs an independent reference implementation from `tests/reference/` (`scripts[0]`, the
/// other scripts it imports, and its `scenes` folder, copied to a scratch directory) against
/// this rayreel, and asserts that it reports every channel byte equal (`total: A/A channel
/// bytes equal`). Skipped without python3, numpy and Pillow, unless RAYREEL_REQUIRE_TOOLS=1.
pub fn independent_reference(scripts: &[&str], scenes: &str) {
    let have = Command::new("python3")
        .args(["-c", "import numpy, PIL"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        assert_ne!(
            std::env::var("RAYREEL_REQUIRE_TOOLS").as_deref(),
            Ok("1"),
            "python3 with numpy and Pillow is required (RAYREEL_REQUIRE_TOOLS=1)"
        );
        eprintln!("SKIPPED: python3 with numpy and Pillow is not installed");
        return;
    }
    let tmp = scratch(scenes);
    let from = repo().join("tests/reference");
    for script in scripts {
        std::fs::copy(from.join(script), tmp.join(script)).unwrap();
    }
    std::fs::create_dir(tmp.join(scenes)).unwrap();
    for e in std::fs::read_dir(from.join(scenes)).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, tmp.join(scenes).join(p.file_name().unwrap())).unwrap();
    }
    let out = Command::new("python3")
        .arg(scripts[0])
        .current_dir(&tmp)
        .env("RAYREEL", env!("CARGO_BIN_EXE_rayreel"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", stderr(&out));
    let total = text
        .lines()
        .find_map(|l| l.strip_prefix("total: "))
        .unwrap_or_else(|| panic!("no total in {text}"));
    let (equal, all) = total
        .trim_end_matches(" channel bytes equal")
        .split_once('/')
        .unwrap();
    assert_eq!(equal, all, "{text}");
}
