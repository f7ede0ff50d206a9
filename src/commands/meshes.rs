//! The `meshes:` lines of `rayreel check`: per mesh file its size, what was read and skipped,
//! the hierarchy's memory and build time, and per placement its bounds.

use super::screen::Screen;
use crate::console::printable;
use crate::scene::{Mesh, Scene, Shape};
use crate::tracer::bvh::Bvh;
use std::fmt::Write;
use std::sync::Arc;

/// Nothing for a scene without meshes; the first few mesh files and, under each, the first few
/// placements (everything with `--full`). A hierarchy is built to be measured only where the
/// memory budget admits it.
pub(super) fn summary(scene: &Scene, screen: Screen) -> Result<String, String> {
    let total = scene.meshes.len();
    let mut files = Vec::new();
    for (i, m) in scene.meshes.iter().enumerate().take(screen.keep(total)) {
        files.push(file(scene, i, m, screen)?);
    }
    Ok(screen.lines(&files, total, "              ", "mesh files"))
}

/// One mesh file's lines: its figures, skipped triangles, notes and placements.
fn file(scene: &Scene, i: usize, m: &Arc<Mesh>, screen: Screen) -> Result<String, String> {
    crate::budget::admit(
        crate::budget::hierarchy_bytes(m.triangles.len() as u64),
        || {
            format!(
                "the hierarchy of {} (built to be measured)",
                m.file.display()
            )
        },
    )
    .map_err(|e| e.to_string())?;
    let mut out = String::new();
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
    let _ = write!(
        out,
        "  mesh:       {}: {} triangles, {} vertices ({}{}); {} placement{}\n              {} read in {}; memory {} + hierarchy {} built in {}",
        printable(&m.file.display().to_string()),
        m.triangles.len(),
        m.positions.len(),
        normals(m.file_normals, m.positions.len()),
        if m.uvs.is_some() {
            ", texture coordinates"
        } else {
            ""
        },
        placements.len(),
        if placements.len() == 1 { "" } else { "s" },
        bytes(m.bytes as usize),
        seconds(m.load_seconds),
        bytes(data),
        bytes(bvh.bytes()),
        seconds(built),
    );
    if m.skipped > 0 {
        let _ = write!(
            out,
            "\n              {} degenerate triangles skipped (zero area, a repeated index or a non-finite vertex)",
            m.skipped
        );
    }
    for note in &m.notes {
        let _ = write!(out, "\n              note: {}", printable(note));
    }
    let lines: Vec<String> = placements
        .iter()
        .take(screen.keep(placements.len()))
        .map(|&k| placement(scene, k))
        .collect();
    out.push('\n');
    out.push_str(&screen.lines(
        &lines,
        placements.len(),
        "              ",
        "placements of this file",
    ));
    Ok(out)
}

/// `objects[k]: phong shading, bounds [..] to [..]`.
fn placement(scene: &Scene, k: usize) -> String {
    let Shape::Mesh {
        mesh,
        place,
        shading,
    } = scene.objects[k].shape
    else {
        return String::new();
    };
    let (lo, hi) = scene.mesh_bounds(mesh, &place);
    format!(
        "              objects[{k}]: {} shading, bounds [{}] to [{}]",
        shading.name(),
        triple(lo),
        triple(hi)
    )
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
