//! The hierarchy decides only what is tested (docs/spec/mesh.md, "The hierarchy"): frames are
//! the same under the wide tree frames use and a binary one (`RAYREEL_HIERARCHY=binary`: 2
//! children a node, a triangle a leaf), in f64 and in f32, with one placement and under the
//! top level over many; and f32 frames of small, rotated, unevenly scaled placements agree
//! with f64 ones (the f32 test starts near the mesh). Packets whose rays diverge walk the
//! tree lane by lane, one ray at a time or both (`RAYREEL_DIVERGENT`): frames are the same
//! under each, on every kernel width and thread count.

mod common;

use common::{scratch, stderr};
use std::path::Path;

/// One frame of `seq` in `dir` as a raw RGB stream.
fn frame(dir: &Path, seq: &str, args: &[&str], hierarchy: &str) -> Vec<u8> {
    frame_with(dir, seq, args, &[("RAYREEL_HIERARCHY", hierarchy)])
}

/// One frame of `seq` in `dir` as a raw RGB stream, with the environment `env`.
fn frame_with(dir: &Path, seq: &str, args: &[&str], env: &[(&str, &str)]) -> Vec<u8> {
    let out = common::bin()
        .args(["render", seq, "--pipe", "raw", "-q"])
        .args(args)
        .current_dir(dir)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    out.stdout
}

fn same_under_both(dir: &Path, seq: &str, args: &[&str]) {
    for precision in ["f64", "f32"] {
        let args = [args, &["--precision", precision]].concat();
        let wide = frame(dir, seq, &args, "wide");
        let binary = frame(dir, seq, &args, "binary");
        assert!(!wide.is_empty());
        let differ = wide.iter().zip(&binary).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{seq} {args:?}: {differ} samples differ");
    }
}

#[test]
fn the_shipped_mesh_sequence_is_the_same_under_two_hierarchies() {
    let dir = common::repo().join("sequences");
    for f in ["0", "40", "97"] {
        same_under_both(&dir, "mesh.yaml", &["--size", "160x90", "--frames", f]);
    }
}

/// Forty placements (so the top level is built) of two files, rotated and unevenly scaled,
/// one of glass, over a mirror, from near and far.
#[test]
fn a_forest_of_placements_is_the_same_under_two_hierarchies() {
    let tmp = scratch("hierarchy-forest");
    std::fs::write(tmp.join("ball.obj"), common::uv_sphere(12, 6, true, false)).unwrap();
    std::fs::write(tmp.join("bare.obj"), common::uv_sphere(7, 4, false, true)).unwrap();
    let mut objects = String::new();
    for i in 0..40 {
        let (x, z) = ((i % 8) as f64 - 3.5, (i / 8) as f64 * -1.3);
        let file = if i % 3 == 0 { "bare.obj" } else { "ball.obj" };
        let glass = if i == 17 {
            ", transmission: 0.8, ior: 1.4"
        } else {
            ""
        };
        objects += &format!(
            "  - mesh: {{ file: {file}, scale: [0.4, {}, 0.3], rotate: [{}, {}, 5], translate: [{x}, 0, {z}], material: {{ diffuse: [0.6, 0.5, 0.3], specular: [1, 1, 1]{glass} }} }}\n",
            0.25 + 0.02 * i as f64,
            7 * i,
            13 * i
        );
    }
    let seq = format!(
        "objects:
{objects}  - plane: {{ point: [0, -0.6, 0], normal: [0, 1, 0], material: {{ diffuse: [0.5, 0.5, 0.5], reflection: 0.4 }} }}
lights:
  - point: {{ position: [4, 6, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
timeline:
  fps: 24
  keyframes:
    - {{ time: 0, position: [0.5, 1.5, 4], look_at: [0, 0, -2], fov: 60 }}
    - {{ time: 1, position: [-3, 0.4, -9], look_at: [0, 0, -2], fov: 40 }}
"
    );
    std::fs::write(tmp.join("seq.yaml"), seq).unwrap();
    for f in ["0", "12", "24"] {
        same_under_both(&tmp, "seq.yaml", &["--size", "120x68", "--frames", f]);
    }
}

/// Sixteen rotated, unevenly scaled placements of the shipped model, each a few dozen pixels
/// across: f32 frames agree with f64 ones on all but a few silhouette pixels.
#[test]
fn small_rotated_placements_agree_in_f32_and_f64() {
    let tmp = scratch("hierarchy-f32");
    std::fs::copy(
        common::repo().join("sequences/models/blob.ply"),
        tmp.join("blob.ply"),
    )
    .unwrap();
    let mut objects = String::new();
    for i in 0..16 {
        let (x, y) = ((i % 4) as f64 * 1.6 - 2.4, (i / 4) as f64 * 1.6 - 2.4);
        objects += &format!(
            "  - mesh: {{ file: blob.ply, scale: [{}, {}, 0.45], rotate: [{}, {}, {}], translate: [{x}, {y}, 0], material: clay }}\n",
            0.3 + 0.03 * i as f64,
            0.5 - 0.02 * i as f64,
            11 * i,
            23 * i,
            37 * i
        );
    }
    let seq = format!(
        "materials:
  clay: {{ ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }}
objects:
{objects}lights:
  - point: {{ position: [3, 4, 9], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
camera: {{ position: [0.2, 0.3, 14], look_at: [0, 0, 0], fov: 35 }}
"
    );
    std::fs::write(tmp.join("seq.yaml"), seq).unwrap();
    let args = ["--size", "480x480", "--samples", "1"];
    let f64 = frame(
        &tmp,
        "seq.yaml",
        &[&args[..], &["--precision", "f64"]].concat(),
        "wide",
    );
    let f32 = frame(
        &tmp,
        "seq.yaml",
        &[&args[..], &["--precision", "f32"]].concat(),
        "wide",
    );
    let pixels = |a: &[u8]| a.chunks(3).map(|p| p.to_vec()).collect::<Vec<_>>();
    let (a, b) = (pixels(&f64), pixels(&f32));
    let lit = a.iter().filter(|p| p.iter().any(|&c| c > 0)).count();
    let off = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 2))
        .count();
    assert!(lit > 20_000, "{lit} pixels see a mesh");
    assert!(
        off * 2000 <= lit,
        "{off} of {lit} mesh pixels differ by more than 2 levels between f32 and f64"
    );
}

/// The shipped model as glass and as a curved mirror on a mirror floor, a few placements so
/// the top level is walked too: rays scatter after the first bounce. Every policy for
/// divergent packets, every kernel width and 1 or 2 threads give the same bytes.
#[test]
fn glass_and_mirror_meshes_are_the_same_under_every_divergent_walk() {
    let tmp = scratch("hierarchy-divergent");
    std::fs::copy(
        common::repo().join("sequences/models/blob.ply"),
        tmp.join("blob.ply"),
    )
    .unwrap();
    let mut objects = String::new();
    for (i, m) in ["glass", "chrome", "glass", "chrome", "clay"]
        .iter()
        .enumerate()
    {
        let x = i as f64 * 0.9 - 1.8;
        objects += &format!(
            "  - mesh: {{ file: blob.ply, material: {m}, scale: 0.45, rotate: [0, {}, 0], translate: [{x}, 0.45, {}] }}\n",
            40 * i,
            -0.4 * (i % 2) as f64
        );
    }
    let seq = format!(
        "render: {{ max_depth: 6, background: {{ gradient: {{ zenith: [0.2, 0.35, 0.7], horizon: [0.8, 0.85, 0.9] }} }} }}
materials:
  glass:  {{ diffuse: [0, 0, 0], specular: [1, 1, 1], shininess: 400, transmission: [0.95, 0.97, 1], ior: 1.5, fresnel: true }}
  chrome: {{ diffuse: [0.1, 0.1, 0.1], specular: [1, 1, 1], shininess: 300, reflection: 0.8 }}
  clay:   {{ ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }}
objects:
{objects}  - plane: {{ point: [0, 0, 0], normal: [0, 1, 0], material: {{ diffuse: [0.1, 0.1, 0.1], reflection: 0.85 }} }}
lights:
  - point: {{ position: [3, 5, 3], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
camera: {{ position: [0.3, 1.6, 3.4], look_at: [0, 0.3, 0], fov: 55 }}
"
    );
    std::fs::write(tmp.join("seq.yaml"), seq).unwrap();
    for precision in ["f64", "f32"] {
        let args = [
            "--size",
            "128x72",
            "--samples",
            "2",
            "--precision",
            precision,
        ];
        let reference = frame_with(&tmp, "seq.yaml", &args, &[("RAYREEL_DIVERGENT", "lanes")]);
        assert!(!reference.is_empty());
        let runs = [
            ("rays", "avx512", "2"),
            ("below:3", "avx2", "1"),
            ("below:9", "avx512", "1"),
            ("default", "scalar", "2"),
            ("default", "avx2", "2"),
            ("default", "avx512", "1"),
        ];
        for (policy, kernel, threads) in runs {
            let args = [&args[..], &["--threads", threads]].concat();
            let env = [("RAYREEL_DIVERGENT", policy), ("RAYREEL_KERNEL", kernel)];
            let other = frame_with(&tmp, "seq.yaml", &args, &env);
            let differ = reference.iter().zip(&other).filter(|(a, b)| a != b).count();
            assert_eq!(
                differ, 0,
                "{precision} {policy} {kernel}: {differ} samples differ"
            );
            assert_eq!(reference.len(), other.len());
        }
    }
}
