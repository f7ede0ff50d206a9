//! What an adversarial pass over the output directory, claims, signals and input found (issue
//! 14), each through the real binary: nothing the user has is lost or overwritten, nothing is
//! written outside where it should be, broken frames do not pass as done, and nothing hangs.

mod common;
use common::*;
use std::path::Path;

fn small() -> String {
    sequence(32, 18, &orbit(24, 1.0))
}

#[test]
fn exr_frames_are_byte_identical_across_processes() {
    let tmp = scratch("exr-determinism");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    // The header's custom attributes used to follow a per-process hash order: eight separate
    // renders all agreeing would have had a chance of about 1 in 6^7.
    let renders: Vec<Vec<u8>> = (0..8)
        .map(|i| {
            let pattern = format!("e{i}/f_####.exr");
            let out = run_in(
                &tmp,
                &["render", "seq.yaml", "-o", &pattern, "--frames", "1"],
            );
            assert!(out.status.success(), "{}", stderr(&out));
            std::fs::read(tmp.join(format!("e{i}/f_0001.exr"))).unwrap()
        })
        .collect();
    for (i, bytes) in renders.iter().enumerate() {
        assert!(bytes == &renders[0], "render {i} differs from render 0");
    }
    let again = run_in(
        &tmp,
        &["status", "seq.yaml", "-o", "e3/f_####.exr", "--frames", "1"],
    );
    assert_eq!(again.status.code(), Some(0), "{}", stderr(&again));
}

/// Runs rayreel in `dir` with a stdout whose reader has already gone.
fn with_closed_stdout(dir: &Path, args: &[&str]) -> std::process::Output {
    use std::os::fd::FromRawFd;
    let mut fds = [0; 2];
    // SAFETY: pipe fills both descriptors; we own them from here on.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // SAFETY: the read end is ours and is closed once, here.
    unsafe { libc::close(fds[0]) };
    // SAFETY: the write end is ours; the Stdio takes it over.
    let write_end = unsafe { std::process::Stdio::from_raw_fd(fds[1]) };
    bin()
        .args(args)
        .current_dir(dir)
        .stdout(write_end)
        .output()
        .expect("rayreel runs")
}

#[test]
fn a_closed_stdout_is_a_normal_end() {
    let tmp = scratch("closed-stdout");
    std::fs::write(tmp.join("seq.yaml"), small()).unwrap();
    let out = run_in(&tmp, &["render", "seq.yaml", "-o", "f/f_####.png", "-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    for (args, code) in [
        (vec!["check", "seq.yaml"], 0),
        (vec!["status", "seq.yaml", "-o", "f/f_####.png"], 0),
        // The listing ends; the verdict (frames missing) still decides the exit code.
        (vec!["status", "seq.yaml", "-o", "g/f_####.png"], 1),
        (
            vec!["render", "seq.yaml", "-o", "g/f_####.png", "--dry-run"],
            0,
        ),
        (vec!["render", "seq.yaml", "--pipe", "raw", "--dry-run"], 0),
        (vec!["preview", "seq.yaml", "--out", "p", "--tiles", "2"], 0),
    ] {
        let out = with_closed_stdout(&tmp, &args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

const STILL: &str = "render: { width: 32, height: 18 }
camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
objects:
  - sphere: { center: [0, 0, -1], radius: 0.5, material: { diffuse: [1, 0, 0] } }
lights:
  - point: { position: [5, 5, 5], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";

/// `check` on `yaml` written to `name` in `dir`.
fn check(dir: &Path, name: &str, yaml: &str) -> std::process::Output {
    std::fs::write(dir.join(name), yaml).unwrap();
    run_in(dir, &["check", name])
}

#[test]
fn messages_read_well_whatever_the_file_holds() {
    let tmp = scratch("messages");
    let out = check(&tmp, "bom.yaml", &format!("\u{feff}{STILL}"));
    assert!(out.status.success(), "a byte-order mark: {}", stderr(&out));

    let keys = "  keyframes:\n    - { time: 0 }\n";
    let tagged = format!("{STILL}timeline:\n  fps: !!float \"24\"\n  duration: 1\n{keys}");
    let out = check(&tmp, "tagged.yaml", &tagged);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("tagged.yaml:8:8: timeline.fps:")
            && stderr(&out).contains("write it plainly, without tag or quotes: `fps: 24`"),
        "{}",
        stderr(&out)
    );

    let tiny = format!("{STILL}timeline:\n  duration: 1e-300\n{keys}");
    let out = check(&tmp, "tiny.yaml", &tiny);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        stderr(&out),
        "rayreel: tiny.yaml:8:13: timeline.duration: duration × fps must give 1 to 10000000 frames (got 1e-300 s × 24 fps = 0 frames)\n"
    );
}

#[test]
fn control_characters_from_a_file_never_reach_the_terminal() {
    let tmp = scratch("escapes");
    let hostile = "\\e[31mred/\\e]0;owned\\a\\e[2Jf_####";
    let yaml = format!("{STILL}output: \"{hostile}.png\"\n");
    let clean = |o: &std::process::Output| {
        for bytes in [&o.stdout, &o.stderr] {
            assert!(
                !bytes.iter().any(|&b| b == 0x1b || b == 0x07),
                "{}",
                String::from_utf8_lossy(bytes)
            );
        }
    };
    let out = check(&tmp, "esc.yaml", &yaml);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("\\u{1b}[31mred/"));
    clean(&out);
    for args in [
        vec!["render", "esc.yaml"],
        vec!["render", "esc.yaml", "--dry-run"],
        vec!["status", "esc.yaml"],
    ] {
        let out = run_in(&tmp, &args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        clean(&out);
    }
    let bad = format!("{STILL}output: \"{hostile}.txt\"\n");
    let out = check(&tmp, "bad.yaml", &bad);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("(got `\\u{1b}[31mred/"),
        "{}",
        stderr(&out)
    );
    clean(&out);
}
