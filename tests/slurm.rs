//! A real single-node Slurm cluster runs examples/slurm/render.sbatch as a job array
//! (.ci/slurm-test.sh). It needs root and installs Debian packages, so it runs only with
//! RAYREEL_SLURM=1 (CI sets it): `RAYREEL_SLURM=1 cargo test --release --test slurm`.

use std::process::Command;

#[test]
fn slurm_job_array_renders_every_frame_once() {
    if std::env::var("RAYREEL_SLURM").as_deref() != Ok("1") {
        println!("SKIPPED: set RAYREEL_SLURM=1 to run the Slurm array test");
        return;
    }
    let root = env!("CARGO_MANIFEST_DIR");
    // The binary cargo already built: the script must not run `cargo build` inside `cargo test`.
    let status = Command::new("bash")
        .arg(format!("{root}/.ci/slurm-test.sh"))
        .current_dir(root)
        .env("RAYREEL", env!("CARGO_BIN_EXE_rayreel"))
        .status()
        .expect("cannot run bash .ci/slurm-test.sh");
    assert!(
        status.success(),
        ".ci/slurm-test.sh failed ({status}); its output above says why"
    );
}
