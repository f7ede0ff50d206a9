//! The `meshes:` lines of `rayreel check`: per mesh file its size, what was read and skipped,
//! the hierarchy's memory and build time, and per placement its bounds; past `SHOWN` files,
//! the files summed up with the largest few, and the count of their notes.

use super::screen::{SHOWN, Screen, short_name};
use crate::scene::{Mesh, Scene, Shape};
use crate::tracer::bvh::Bvh;
use std::fmt::Write;

/// Where the lines under `mesh:` start.
const INDENT: &str = "              ";

/// A mesh's hierarchy as built: bytes (nodes, order and triangle copies made) and seconds.
pub(crate) type Built = (usize, f64);

/// Nothing for a scene without meshes; each mesh file with its notes and first placements
/// when there are few (everything with `--full`), else the files summed up. `built` is what
/// the cost probe measured; without one, each hierarchy is built here to be measured, where
/// the memory budget admits it.
pub(super) fn summary(
    scene: &Scene,
    screen: Screen,
    built: Option<&[Built]>,
) -> Result<String, String> {
    if scene.meshes.is_empty() {
        return Ok(String::new());
    }
    let built = match built {
        Some(b) if b.len() == scene.meshes.len() => b.to_vec(),
        _ => build(scene)?,
    };
    if !screen.full && scene.meshes.len() > SHOWN {
        return Ok(grouped(scene, &built));
    }
    let mut out = String::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        out += &file(scene, i, m, built[i], screen);
    }
    Ok(out)
}

/// Each mesh's hierarchy built once, measured and dropped.
fn build(scene: &Scene) -> Result<Vec<Built>, String> {
    let mut built = Vec::with_capacity(scene.meshes.len());
    for m in &scene.meshes {
        let need = crate::budget::hierarchy_bytes(m.triangles.len() as u64, false);
        crate::budget::admit(need, || {
            format!(
                "the hierarchy of {} (built to be measured)",
                m.file.display()
            )
        })
        .map_err(|e| e.to_string())?;
        let bvh = Bvh::build(m).map_err(|e| e.to_string())?;
        bvh.prepare(false).map_err(|e| e.to_string())?;
        built.push((bvh.bytes(), bvh.seconds));
    }
    Ok(built)
}

/// The objects placing mesh `i`.
fn placements(scene: &Scene, i: usize) -> Vec<usize> {
    (scene.objects.iter().enumerate())
        .filter(|(_, o)| matches!(o.shape, Shape::Mesh { mesh, .. } if mesh == i))
        .map(|(k, _)| k)
        .collect()
}

/// Bytes a mesh's own arrays take: positions and normals, texture coordinates, triangles.
fn data_bytes(m: &Mesh) -> usize {
    m.positions.len() * 24 * 2 + m.uvs.as_ref().map_or(0, |u| u.len() * 16) + m.triangles.len() * 12
}

/// One mesh file's lines: its figures, skipped triangles, notes and placements.
fn file(scene: &Scene, i: usize, m: &Mesh, (bvh, built): Built, screen: Screen) -> String {
    let placed = placements(scene, i);
    let mut out = format!(
        "  mesh:       {}: {} triangles, {} vertices; {}\n{INDENT}{}{}; {} read in {}; memory {} + hierarchy {} built in {}\n",
        short_name(&m.file.display().to_string()),
        m.triangles.len(),
        m.positions.len(),
        plural(placed.len(), "placement"),
        normals(m.file_normals, m.positions.len()),
        if m.uvs.is_some() {
            ", texture coordinates"
        } else {
            ""
        },
        bytes(m.bytes as usize),
        seconds(m.load_seconds),
        bytes(data_bytes(m)),
        bytes(bvh),
        seconds(built),
    );
    if m.skipped > 0 {
        let _ = writeln!(
            out,
            "{INDENT}{} degenerate triangles skipped (zero area, a repeated index or a non-finite vertex)",
            m.skipped
        );
    }
    let notes: Vec<String> = (m.notes.iter())
        .take(screen.keep(m.notes.len()))
        .map(|n| format!("{INDENT}note: {}", crate::console::printable(n)))
        .collect();
    out += &screen.lines(&notes, m.notes.len(), INDENT, "notes on this file");
    let lines: Vec<String> = (placed.iter())
        .take(screen.keep(placed.len()))
        .map(|&k| placement(scene, k))
        .collect();
    out += &screen.lines(&lines, placed.len(), INDENT, "placements of this file");
    out
}

/// Many mesh files: their totals, the largest few (by triangles), and their notes counted
/// with the first, then how to see each.
fn grouped(scene: &Scene, built: &[Built]) -> String {
    let meshes = &scene.meshes;
    let sum = |f: &dyn Fn(usize, &Mesh) -> usize| -> usize {
        meshes.iter().enumerate().map(|(i, m)| f(i, m)).sum()
    };
    let triangles = sum(&|_, m| m.triangles.len());
    let vertices = sum(&|_, m| m.positions.len());
    let skipped = sum(&|_, m| m.skipped);
    let placed = (scene.objects.iter())
        .filter(|o| matches!(o.shape, Shape::Mesh { .. }))
        .count();
    let read: f64 = meshes.iter().map(|m| m.load_seconds).sum();
    let mut out = format!(
        "  meshes:     {} files: {triangles} triangles, {vertices} vertices, {}; {} read in {}\n{INDENT}memory {} + hierarchies {} built in {}{}\n",
        meshes.len(),
        plural(placed, "placement"),
        bytes(sum(&|_, m| m.bytes as usize)),
        seconds(read),
        bytes(sum(&|_, m| data_bytes(m))),
        bytes(built.iter().map(|b| b.0).sum()),
        seconds(built.iter().map(|b| b.1).sum()),
        match skipped {
            0 => String::new(),
            n => format!("; {n} degenerate triangles skipped"),
        }
    );
    let mut largest: Vec<usize> = (0..meshes.len()).collect();
    largest.sort_by_key(|&i| std::cmp::Reverse(meshes[i].triangles.len()));
    for &i in largest.iter().take(SHOWN - 1) {
        let m = &meshes[i];
        let _ = writeln!(
            out,
            "{INDENT}largest: {}: {} triangles, {}, {}",
            short_name(&m.file.display().to_string()),
            m.triangles.len(),
            plural(placements(scene, i).len(), "placement"),
            plural(m.notes.len(), "note")
        );
    }
    let noted: Vec<&Mesh> = (meshes.iter())
        .filter(|m| !m.notes.is_empty())
        .map(|m| m.as_ref())
        .collect();
    if let Some(first) = noted.first() {
        let _ = writeln!(
            out,
            "{INDENT}notes: {} on {}, the first: {}",
            noted.iter().map(|m| m.notes.len()).sum::<usize>(),
            plural(noted.len(), "file"),
            crate::console::printable(&first.notes[0])
        );
    }
    let _ = writeln!(
        out,
        "{INDENT}… `rayreel check --full` lists each file with its notes and placements"
    );
    out
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
        "{INDENT}objects[{k}]: {} shading, bounds [{}] to [{}]",
        shading.name(),
        triple(lo),
        triple(hi)
    )
}

fn triple(v: glam::DVec3) -> String {
    [v.x, v.y, v.z].map(|x| format!("{x:.4}")).join(", ")
}

/// `1 placement`, `16 placements`.
fn plural(n: usize, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
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
