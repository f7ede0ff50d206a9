//! The `meshes:` lines of `rayreel check`: per mesh file its size, what was read and skipped,
//! the hierarchy's memory and build time, and per placement its bounds.

use crate::scene::{Scene, Shape};
use crate::tracer::bvh::Bvh;
use std::fmt::Write;

/// Nothing for a scene without meshes.
pub(super) fn summary(scene: &Scene) -> String {
    let mut out = String::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        let started = std::time::Instant::now();
        let bvh = Bvh::build(m);
        let built = started.elapsed().as_secs_f64();
        let data = m.positions.len() * 24 * 2
            + m.uvs.as_ref().map_or(0, |u| u.len() * 16)
            + m.triangles.len() * 12;
        let placements: Vec<usize> = scene
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| matches!(o.shape, Shape::Mesh { mesh, .. } if mesh == i))
            .map(|(k, _)| k)
            .collect();
        let _ = writeln!(
            out,
            "  mesh:       {}: {} triangles, {} vertices ({}{}), {} read in {}; memory {} + hierarchy {} built in {}; {} placement{}",
            m.file.display(),
            m.triangles.len(),
            m.positions.len(),
            normals(m.file_normals, m.positions.len()),
            if m.uvs.is_some() {
                ", texture coordinates"
            } else {
                ""
            },
            bytes(m.bytes as usize),
            seconds(m.load_seconds),
            bytes(data),
            bytes(bvh.bytes()),
            seconds(built),
            placements.len(),
            if placements.len() == 1 { "" } else { "s" },
        );
        if m.skipped > 0 {
            let _ = writeln!(
                out,
                "              {} degenerate triangles skipped (zero area, a repeated index or a non-finite vertex)",
                m.skipped
            );
        }
        for note in &m.notes {
            let _ = writeln!(out, "              note: {note}");
        }
        for k in placements {
            if let Shape::Mesh {
                mesh,
                place,
                shading,
            } = scene.objects[k].shape
            {
                let (lo, hi) = scene.mesh_bounds(mesh, &place);
                let _ = writeln!(
                    out,
                    "              objects[{k}]: {} shading, bounds [{}] to [{}]",
                    shading.name(),
                    triple(lo),
                    triple(hi)
                );
            }
        }
    }
    out
}

fn triple(v: glam::DVec3) -> String {
    [v.x, v.y, v.z].map(|x| format!("{x:.4}")).join(", ")
}

fn bytes(n: usize) -> String {
    match n {
        n if n >= 1 << 30 => format!("{:.1} GiB", n as f64 / (1u64 << 30) as f64),
        n if n >= 1 << 20 => format!("{:.1} MiB", n as f64 / (1u64 << 20) as f64),
        n if n >= 1 << 10 => format!("{:.1} KiB", n as f64 / 1024.0),
        n => format!("{n} B"),
    }
}

fn seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else {
        format!("{:.1} ms", s * 1000.0)
    }
}

/// Where a mesh's vertex normals came from: `normals from the file`, `normals averaged from
/// the faces`, or for a file that gives some, `normals from the file for 120 of 200
/// vertices, averaged from the faces for the rest`.
fn normals(from_file: usize, vertices: usize) -> String {
    match from_file {
        0 => "normals averaged from the faces".into(),
        n if n == vertices => "normals from the file".into(),
        n => format!(
            "normals from the file for {n} of {vertices} vertices, averaged from the faces for the rest"
        ),
    }
}
