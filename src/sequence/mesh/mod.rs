//! Reading the triangle meshes `mesh:` objects name: Wavefront OBJ and PLY (ASCII, binary
//! little- and big-endian), polygons fanned into triangles, degenerate triangles dropped and
//! counted, vertex normals from the file or area-weighted from the faces.
//!
//! Both readers are the project's own: every error names the model file and its line (OBJ) or
//! element index (PLY), which the crates we measured (`tobj`, `ply-rs`) do not report, and
//! `ply-rs` builds a map per element (see docs/meshes.md for the measurement).

mod obj;
mod ply;

use crate::scene::Mesh;
use glam::{DVec2, DVec3};
use std::path::{Path, PathBuf};

/// Largest mesh file read, in bytes.
pub const MAX_MESH_BYTES: u64 = 16 << 30;
/// Largest number of triangles a mesh may have after fanning.
pub const MAX_TRIANGLES: u64 = 1 << 32;

/// What is wrong with a mesh file: `where_` is `line 12` (OBJ) or `face 3` (PLY), when known.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {message}", file.display(), where_.as_ref().map(|w| format!(": {w}")).unwrap_or_default())]
pub struct MeshError {
    pub file: PathBuf,
    pub where_: Option<String>,
    pub message: String,
}

/// What a reader gives back: positions and optional per-corner attributes, polygons as index
/// lists into `vertices`.
#[derive(Default)]
pub(crate) struct Soup {
    pub positions: Vec<DVec3>,
    /// Per vertex, when the file has them (NaN-free not guaranteed).
    pub normals: Option<Vec<DVec3>>,
    pub uvs: Option<Vec<DVec2>>,
    pub triangles: Vec<[u32; 3]>,
    pub notes: Vec<String>,
    /// Vertices whose normal came from the file (OBJ corners may lack one).
    pub has_normal: Option<Vec<bool>>,
}

/// Reads the mesh at `file` (already resolved against the sequence file's folder).
pub fn load(file: &Path) -> Result<Mesh, MeshError> {
    let started = std::time::Instant::now();
    let bytes = read(file)?;
    let fail = |where_: Option<String>, message: String| MeshError {
        file: file.to_owned(),
        where_,
        message,
    };
    let ext = file
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let soup = match ext.as_str() {
        "obj" => obj::read(&bytes).map_err(|(line, m)| fail(Some(format!("line {line}")), m))?,
        "ply" => ply::read(&bytes).map_err(|(w, m)| fail(w, m))?,
        _ => {
            return Err(fail(
                None,
                "unknown mesh format: the file name must end in .obj or .ply".into(),
            ));
        }
    };
    finish(file, soup, &bytes, started).map_err(|m| fail(None, m))
}

fn read(file: &Path) -> Result<Vec<u8>, MeshError> {
    use crate::regular::{self, Links, Refused};
    let fail = |message: String| MeshError {
        file: file.to_owned(),
        where_: None,
        message,
    };
    // A FIFO at the name must not hang the load before it can be refused.
    let (f, meta) = regular::open(file, Links::Follow).map_err(|e| match e {
        Refused::NotRegular(_) => {
            fail("is not a regular file (a FIFO, device or directory cannot be a mesh)".into())
        }
        Refused::Missing => fail(format!(
            "cannot read: {}",
            std::io::Error::from_raw_os_error(libc::ENOENT)
        )),
        Refused::Io(e) => fail(format!("cannot read: {e}")),
    })?;
    if meta.len() > MAX_MESH_BYTES {
        return Err(fail(format!(
            "the file is {} bytes; meshes are limited to {} GiB",
            meta.len(),
            MAX_MESH_BYTES >> 30
        )));
    }
    regular::read_at_most(&f, meta.len(), MAX_MESH_BYTES + 1)
        .map_err(|e| fail(format!("cannot read: {e}")))
}

/// Drops degenerate triangles, fills in normals, and hashes the content.
fn finish(
    file: &Path,
    soup: Soup,
    bytes: &[u8],
    started: std::time::Instant,
) -> Result<Mesh, String> {
    let Soup {
        positions,
        normals,
        uvs,
        triangles,
        notes,
        has_normal,
    } = soup;
    if triangles.len() as u64 > MAX_TRIANGLES {
        return Err(format!(
            "{} triangles; at most 2^32 are accepted",
            triangles.len()
        ));
    }
    let total = triangles.len();
    let kept: Vec<[u32; 3]> = triangles
        .into_iter()
        .filter(|t| !degenerate(&positions, t))
        .collect();
    if kept.is_empty() {
        return Err(match total {
            0 => "the file has no faces".into(),
            n => format!(
                "all {n} triangles are degenerate (zero area, a repeated index or a non-finite vertex)"
            ),
        });
    }
    let face = area_weighted(&positions, &kept);
    let mut file_normals = 0;
    let normals = match normals {
        Some(n) => n
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let from_file = has_normal.as_ref().is_none_or(|h| h[i]);
                let u = v.normalize_or_zero();
                if from_file && u != DVec3::ZERO && u.is_finite() {
                    file_normals += 1;
                    u
                } else {
                    face[i]
                }
            })
            .collect(),
        None => face,
    };
    Ok(Mesh {
        file: file.to_owned(),
        positions,
        normals,
        uvs,
        skipped: total - kept.len(),
        triangles: kept,
        file_normals,
        notes,
        digest: fnv1a(bytes),
        bytes: bytes.len() as u64,
        load_seconds: started.elapsed().as_secs_f64(),
    })
}

/// A mesh made in memory (benchmarks, tests): the same dropping of degenerate triangles and
/// the same vertex normals as a file without normals gets.
pub fn from_triangles(name: &str, positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    let soup = Soup {
        positions,
        triangles,
        ..Soup::default()
    };
    let digest = fnv1a(name.as_bytes());
    let mut m = finish(Path::new(name), soup, &[], std::time::Instant::now())
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    m.digest = digest;
    m
}

/// Zero area (the edge cross product is exactly zero), a repeated index, or a vertex that is
/// not finite.
fn degenerate(p: &[DVec3], t: &[u32; 3]) -> bool {
    let [a, b, c] = t.map(|i| p[i as usize]);
    t[0] == t[1]
        || t[1] == t[2]
        || t[0] == t[2]
        || !(a.is_finite() && b.is_finite() && c.is_finite())
        || (b - a).cross(c - a) == DVec3::ZERO
}

/// Per vertex: the normalised sum of (b − a) × (c − a) over the triangles around it (each
/// face normal weighted by twice its area), in triangle order; (0, 1, 0) where that is zero.
fn area_weighted(p: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut sum = vec![DVec3::ZERO; p.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| p[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            sum[i as usize] += n;
        }
    }
    sum.into_iter()
        .map(|n| {
            let u = n.normalize_or_zero();
            if u == DVec3::ZERO || !u.is_finite() {
                DVec3::Y
            } else {
                u
            }
        })
        .collect()
}

/// FNV-1a, 64 bits.
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_on(0xcbf2_9ce4_8422_2325, bytes)
}

/// Continues the FNV-1a hash `h` of some bytes over `bytes`: the hash of their concatenation.
pub(crate) fn fnv1a_on(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Fans polygon `corners` (vertex indices) into triangles (0, i, i+1).
pub(crate) fn fan(corners: &[u32], out: &mut Vec<[u32; 3]>) {
    for i in 1..corners.len().saturating_sub(1) {
        out.push([corners[0], corners[i], corners[i + 1]]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fans_polygons_from_the_first_corner() {
        let mut t = Vec::new();
        fan(&[0, 1, 2, 3, 4], &mut t);
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn degenerate_triangles_are_recognised() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, 2.0 * DVec3::X, DVec3::NAN];
        assert!(!degenerate(&p, &[0, 1, 2]));
        assert!(degenerate(&p, &[0, 1, 3]));
        assert!(degenerate(&p, &[0, 1, 1]));
        assert!(degenerate(&p, &[0, 1, 4]));
    }
}
