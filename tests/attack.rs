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
