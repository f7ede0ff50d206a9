//! What users coming from Blender and from a shell trip over, through the real binary: an
//! output directory that cannot take files is refused before anything renders.

mod common;
use common::*;
use std::path::Path;

/// A file of the test scene at 32×18 with `timeline` (a YAML block), in `dir/NAME`.
fn write(dir: &Path, name: &str, timeline: &str) {
    std::fs::write(dir.join(name), sequence(32, 18, timeline)).unwrap();
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
    assert_eq!(files(&dir), ["seq.yaml", "taken"]);
}
