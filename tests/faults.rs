//! Disk and file-system faults: a full disk, a read-only directory, a directory where a frame
//! should go, a frame that vanishes mid-run. Each is a clear error naming the path with exit
//! 1; frames written before stay intact, no temporary file is left, and once the fault is
//! fixed a rerun completes the job identically to a clean render. Mounting tmpfs needs root
//! (CI runs as root); elsewhere these tests skip with a notice unless RAYREEL_REQUIRE_TOOLS=1.

mod common;
use common::*;
use std::path::Path;
use std::process::Command;

fn seq() -> String {
    sequence(320, 180, &orbit(24, 1.0))
}

/// A tmpfs of `size` mounted at `dir`, unmounted on drop.
struct Tmpfs(std::path::PathBuf);

impl Tmpfs {
    fn mount(dir: &Path, size: &str) -> Option<Tmpfs> {
        std::fs::create_dir_all(dir).unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            if std::env::var("RAYREEL_REQUIRE_TOOLS").as_deref() == Ok("1") {
                panic!("mounting a tmpfs failed (these tests need root)");
            }
            eprintln!("SKIPPED: cannot mount a tmpfs (not root?)");
            return None;
        }
        Some(Tmpfs(dir.to_path_buf()))
    }

    fn remount(&self, options: &str) {
        let s = Command::new("mount")
            .args(["-o", &format!("remount,{options}")])
            .arg(&self.0)
            .status()
            .unwrap();
        assert!(s.success(), "remount {options}");
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

fn setup(name: &str) -> Scratch {
    with_clean_render(name, &seq())
}

/// Every file in `out` is a clean frame, byte for byte, and none is a temporary.
fn assert_intact(tmp: &Path, out: &str) -> usize {
    let names = files(&tmp.join(out));
    for f in &names {
        assert!(!f.starts_with('.'), "leftover {f}");
        let same = std::fs::read(tmp.join(out).join(f)).unwrap()
            == std::fs::read(tmp.join("clean").join(f)).unwrap();
        assert!(same, "{f} is not the clean frame");
    }
    names.len()
}

fn render_out(tmp: &Path) -> std::process::Output {
    run_in(
        tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "-q",
            "--threads",
            "1",
        ],
    )
}

#[test]
fn a_full_disk_fails_cleanly_and_the_rerun_completes() {
    let tmp = setup("full");
    let Some(fs) = Tmpfs::mount(&tmp.join("out"), "400k") else {
        return;
    };
    let out = render_out(&tmp);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("out/f_00") && err.contains("No space left on device"),
        "{err}"
    );
    let kept = assert_intact(&tmp, "out");
    assert!(kept > 0 && kept < 24, "{kept} frames fit");
    fs.remount("size=64m");
    assert!(render_out(&tmp).status.success());
    assert_eq!(assert_intact(&tmp, "out"), 24);
}

#[test]
fn a_read_only_directory_fails_cleanly_and_the_rerun_completes() {
    let tmp = setup("readonly");
    let Some(fs) = Tmpfs::mount(&tmp.join("out"), "64m") else {
        return;
    };
    let out = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "-q",
            "--frames",
            "0-3",
        ],
    );
    assert!(out.status.success());
    fs.remount("ro");
    let out = render_out(&tmp);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        // Found before any frame renders, naming the directory.
        stderr(&out).contains("out: cannot write files in this directory")
            && stderr(&out).contains("Read-only file system"),
        "{}",
        stderr(&out)
    );
    assert_eq!(assert_intact(&tmp, "out"), 4);
    fs.remount("rw");
    assert!(render_out(&tmp).status.success());
    assert_eq!(assert_intact(&tmp, "out"), 24);
}

#[test]
fn a_directory_in_place_of_a_frame_is_named() {
    let tmp = setup("isdir");
    std::fs::create_dir_all(tmp.join("out/f_0005.png")).unwrap();
    let out = render_out(&tmp);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("out/f_0005.png"), "{}", stderr(&out));
    std::fs::remove_dir(tmp.join("out/f_0005.png")).unwrap();
    assert!(render_out(&tmp).status.success());
    assert_eq!(assert_intact(&tmp, "out"), 24);
}

#[test]
fn a_frame_that_vanishes_during_the_run_is_reported() {
    let tmp = setup("vanish");
    let child = Command::new(env!("CARGO_BIN_EXE_rayreel"))
        .args([
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "-q",
            "--threads",
            "1",
            "--size",
            "640x360",
        ])
        .current_dir(&tmp)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let first = tmp.join("out/f_0000.png");
    while !first.exists() {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    std::fs::remove_file(&first).unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("out/f_0000.png (vanished)"),
        "{}",
        stderr(&out)
    );
    let rerun = run_in(
        &tmp,
        &[
            "render",
            "seq.yaml",
            "-o",
            "out/f_####.png",
            "--size",
            "640x360",
        ],
    );
    assert!(
        stderr(&rerun).contains("24 frames: 23 up to date, 1 missing → rendering 1"),
        "{}",
        stderr(&rerun)
    );
}
