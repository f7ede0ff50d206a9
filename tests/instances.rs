//! Ten thousand placements of one model take the memory of the model once plus a little per
//! placement (its record and a share of the top-level hierarchy): measured through the binary
//! as each run's peak resident memory. One test in this binary, so no other test's child
//! process is counted in the peak (`getrusage(RUSAGE_CHILDREN)` reports the largest child).

mod common;

use common::{scratch, stderr};
use std::path::Path;

fn placements(n: usize) -> String {
    let mut objects = String::new();
    let side = (n as f64).sqrt().ceil() as usize;
    for i in 0..n {
        let (x, z) = ((i % side) as f64 * 1.2, (i / side) as f64 * -1.2);
        objects += &format!(
            "  - mesh: {{ file: blob.ply, scale: 0.4, rotate: [0, {}, 0], translate: [{x}, 0, {z}], material: clay }}\n",
            (i * 37) % 360
        );
    }
    format!(
        "materials:
  clay: {{ ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }}
objects:
{objects}lights:
  - point: {{ position: [30, 40, 50], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
camera: {{ position: [-8, 14, 12], look_at: [40, 0, -40], fov: 60 }}
"
    )
}

/// The peak resident memory, in bytes, of the largest child this process has waited for.
fn peak_of_children() -> u64 {
    // SAFETY: getrusage writes into the struct it is given.
    let usage = unsafe {
        let mut u: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut u);
        u
    };
    usage.ru_maxrss as u64 * 1024
}

fn render(dir: &Path, n: usize) -> u64 {
    std::fs::write(dir.join("seq.yaml"), placements(n)).unwrap();
    let out = common::bin()
        .args([
            "render", "seq.yaml", "--pipe", "raw", "-q", "--size", "320x180",
        ])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{n}: {}", stderr(&out));
    assert!(
        n == 1 || out.stdout.iter().any(|&b| b > 0),
        "{n} placements: a black frame"
    );
    peak_of_children()
}

#[test]
fn ten_thousand_placements_cost_a_little_memory_each() {
    let tmp = scratch("instances-memory");
    std::fs::copy(
        common::repo().join("sequences/models/blob.ply"),
        tmp.join("blob.ply"),
    )
    .unwrap();
    let one = render(&tmp, 1);
    let many = render(&tmp, 10_000);
    // The model (11,520 triangles) and its hierarchy are held once; a placement adds its
    // record (about 200 bytes), its top-level share and what loading its line took.
    let per = many.saturating_sub(one) / 10_000;
    eprintln!("peak resident memory: one placement {one} bytes, 10,000 placements {many} bytes");
    assert!(
        per < 4096,
        "10,000 placements peaked at {many} bytes, one at {one}: {per} bytes a placement"
    );
}
