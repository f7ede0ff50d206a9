//! Meshes made in memory for benchmarks and examples: a heightfield terrain and a bumpy
//! closed blob standing in for a scanned model. Deterministic: the same triangles every run.

use crate::scene::Mesh;
use crate::sequence::mesh::from_triangles;
use glam::DVec3;

/// An n × n grid of vertices over [−1, 1]² in x and z, heights from a sum of sines: 2(n − 1)²
/// triangles (n = 1001 gives 2 million).
pub fn terrain(n: usize) -> Mesh {
    let n = n.max(2);
    let mut positions = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (
                2.0 * i as f64 / (n - 1) as f64 - 1.0,
                2.0 * j as f64 / (n - 1) as f64 - 1.0,
            );
            let y = 0.12 * (3.1 * x + 0.4).sin() * (2.3 * z).cos()
                + 0.05 * (11.0 * x * z + 1.0).sin()
                + 0.02 * (31.0 * x).sin() * (27.0 * z + 0.7).sin();
            positions.push(DVec3::new(x, y, z));
        }
    }
    let at = |i: usize, j: usize| (i * n + j) as u32;
    let mut triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    from_triangles(&format!("terrain-{n}"), positions, triangles)
}

/// A closed, bumpy ball of radius about 1 from a `segments` × `rings` latitude-longitude grid:
/// about 2·segments·rings triangles.
pub fn blob(segments: usize, rings: usize) -> Mesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let pi = std::f64::consts::PI;
    let mut positions = vec![DVec3::new(0.0, radius(0.0, 0.0), 0.0)];
    for i in 1..rings {
        for j in 0..segments {
            let (th, ph) = (
                pi * i as f64 / rings as f64,
                2.0 * pi * j as f64 / segments as f64,
            );
            let r = radius(th, ph);
            positions.push(r * DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    positions.push(DVec3::new(0.0, -radius(pi, 0.0), 0.0));
    let last = (positions.len() - 1) as u32;
    let at = |i: usize, j: usize| match i {
        0 => 0,
        i if i == rings => last,
        i => (1 + (i - 1) * segments + j % segments) as u32,
    };
    let mut triangles = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j + 1), at(i + 1, j + 1), at(i + 1, j), at(i, j));
            if i > 0 {
                triangles.push([a, b, d]);
            }
            if i + 1 < rings {
                triangles.push([b, c, d]);
            }
        }
    }
    from_triangles(&format!("blob-{segments}x{rings}"), positions, triangles)
}

fn radius(th: f64, ph: f64) -> f64 {
    1.0 + 0.12 * (5.0 * th).sin() * (7.0 * ph).cos()
        + 0.05 * (13.0 * th + 1.0).sin() * (11.0 * ph).sin()
        + 0.02 * (29.0 * th).cos() * (23.0 * ph + 0.3).cos()
}

/// `mesh` as a binary little-endian PLY (float x y z, uchar/int faces).
pub fn ply(mesh: &Mesh) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\ncomment made by rayreel's meshgen\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    for p in &mesh.positions {
        for v in [p.x, p.y, p.z] {
            out.extend((v as f32).to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        out.push(3);
        for &i in t {
            out.extend((i as i32).to_le_bytes());
        }
    }
    out
}
