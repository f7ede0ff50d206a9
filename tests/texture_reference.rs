//! The independent reference for textured frames: `tests/reference/texture_reference.py`, written
//! from docs/spec/texture.md (and the tracer, mesh and output pages) alone, on top of
//! `mesh_reference.py`'s tracer, renders its scenes and compares every channel byte with rayreel.

mod common;
use common::{scratch, stderr};

#[test]
fn the_independent_reference_reproduces_texture_frames() {
    let have = std::process::Command::new("python3")
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
    let tmp = scratch("texture-reference");
    let from = common::repo().join("tests/reference");
    for script in ["texture_reference.py", "mesh_reference.py"] {
        std::fs::copy(from.join(script), tmp.join(script)).unwrap();
    }
    std::fs::create_dir(tmp.join("texture")).unwrap();
    for e in std::fs::read_dir(from.join("texture")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, tmp.join("texture").join(p.file_name().unwrap())).unwrap();
    }
    let out = std::process::Command::new("python3")
        .arg("texture_reference.py")
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
