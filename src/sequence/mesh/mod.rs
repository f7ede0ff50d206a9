//! Reading the triangle meshes `mesh:` objects name: Wavefront OBJ and PLY (ASCII, binary
//! little- and big-endian), polygons fanned into triangles, degenerate triangles dropped and
//! counted, vertex normals from the file or area-weighted from the faces.
//!
//! Both readers are the project's own: every error names the model file and its line (OBJ) or
//! element index (PLY), which the crates we measured (`tobj`, `ply-rs`) do not report, and
//! `ply-rs` builds a map per element (see docs/meshes.md for the measurement). Both read the
//! file as a stream (`Input`), by its grammar, line by line where the format has lines: a file
//! is refused at the first byte that cannot belong to it, not after being read whole, and every
//! array grows only after the memory budget (`crate::budget`) admits it.

mod input;
mod obj;
mod ply;
mod ply_rows;

use crate::budget::{self, OutOfMemory};
use crate::scene::Mesh;
use glam::{DVec2, DVec3};
use input::Input;
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
    /// The file may be fine: the memory the process may take is not enough for it.
    pub out_of_memory: bool,
}

/// A reader's refusal: where in the file (`line 12`, `face 3`), what, and whether memory ran
/// out rather than the file being wrong.
#[derive(Debug)]
pub(crate) struct Fail {
    pub where_: Option<String>,
    pub message: String,
    pub memory: bool,
}

impl Fail {
    pub(crate) fn at(where_: impl Into<String>, message: impl Into<String>) -> Fail {
        Fail {
            where_: Some(where_.into()),
            message: message.into(),
            memory: false,
        }
    }

    pub(crate) fn whole(message: impl Into<String>) -> Fail {
        Fail {
            where_: None,
            message: message.into(),
            memory: false,
        }
    }

    fn in_file(self, file: &Path) -> MeshError {
        MeshError {
            file: file.to_owned(),
            where_: self.where_,
            message: self.message,
            out_of_memory: self.memory,
        }
    }
}

impl From<OutOfMemory> for Fail {
    fn from(e: OutOfMemory) -> Fail {
        Fail {
            where_: None,
            message: e.to_string(),
            memory: true,
        }
    }
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
pub fn load(file: &Path) -> Result<Loaded, MeshError> {
    let started = std::time::Instant::now();
    let ext = file
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    // Opened first: a directory or FIFO named like a model is refused for what it is.
    let mut loaded = open(file)
        .and_then(|mut input| match ext.as_str() {
            "obj" | "ply" => parse(&mut input, file, ext == "ply"),
            _ => Err(Fail::whole(
                "unknown mesh format: the file name must end in .obj or .ply",
            )),
        })
        .map_err(|f| f.in_file(file))?;
    loaded.mesh.load_seconds = started.elapsed().as_secs_f64();
    Ok(loaded)
}

/// `load` for bytes in memory (the fuzz targets): `ply` picks the reader.
pub(crate) fn read_bytes(bytes: &[u8], ply: bool) -> Result<Loaded, MeshError> {
    let name = Path::new(if ply { "bytes.ply" } else { "bytes.obj" });
    parse(&mut Input::new(bytes, bytes.len() as u64), name, ply).map_err(|f| f.in_file(name))
}

/// The file read whole by its reader, its digest and size taken, then `finish`ed.
fn parse<R: std::io::BufRead>(
    input: &mut Input<R>,
    file: &Path,
    ply: bool,
) -> Result<Loaded, Fail> {
    let soup = match ply {
        true => ply::read(input),
        false => obj::read(input),
    }?;
    let (digest, bytes) = input.finish()?;
    let mut loaded = finish(file, soup)?;
    loaded.mesh.digest = digest;
    loaded.mesh.bytes = bytes;
    Ok(loaded)
}

/// The file as a stream, once it is known to be a regular file of at most `MAX_MESH_BYTES`.
fn open(file: &Path) -> Result<Input<std::io::BufReader<std::io::Take<std::fs::File>>>, Fail> {
    use crate::regular::{self, Links, Refused};
    // A FIFO at the name must not hang the load before it can be refused.
    let (f, meta) = regular::open(file, Links::Follow).map_err(|e| {
        Fail::whole(match e {
            Refused::NotRegular(_) => {
                "is not a regular file (a FIFO, device or directory cannot be a mesh)".into()
            }
            Refused::Missing => format!(
                "cannot read: {}",
                std::io::Error::from_raw_os_error(libc::ENOENT)
            ),
            Refused::Io(e) => format!("cannot read: {e}"),
        })
    })?;
    if meta.len() > MAX_MESH_BYTES {
        return Err(Fail::whole(format!(
            "the file is {} bytes; meshes are limited to {} GiB",
            meta.len(),
            MAX_MESH_BYTES >> 30
        )));
    }
    use std::io::Read;
    // A file that grows while it is read stops at the limit all the same.
    let stream = std::io::BufReader::with_capacity(1 << 16, f.take(MAX_MESH_BYTES + 1));
    Ok(Input::new(stream, meta.len()))
}

/// A mesh as `load` gives it: positions are the file's times 2^−`exponent` (exactly), so that
/// a model in any units is traced with the same arithmetic; its placements' scales carry
/// 2^`exponent` back (see `units`).
pub struct Loaded {
    pub mesh: Mesh,
    pub exponent: i32,
}

/// Checks the soup's arrays agree, brings the positions to units f64 keeps (`units`), drops
/// degenerate triangles and fills in normals. The digest and the read's figures are the
/// caller's.
fn finish(file: &Path, soup: Soup) -> Result<Loaded, Fail> {
    let Soup {
        mut positions,
        normals,
        uvs,
        triangles,
        notes,
        has_normal,
    } = soup;
    let n = positions.len();
    // The readers keep one entry per vertex in every array; anything else is a reader's bug,
    // refused here rather than handed to the tracer.
    let lengths = [
        normals.as_ref().map(Vec::len),
        uvs.as_ref().map(Vec::len),
        has_normal.as_ref().map(Vec::len),
    ];
    let in_range = triangles.iter().flatten().all(|&i| (i as usize) < n);
    if lengths.iter().flatten().any(|&l| l != n) || !in_range {
        return Err(Fail::whole(
            "the file's vertex attributes do not line up with its positions",
        ));
    }
    if triangles.len() as u64 > MAX_TRIANGLES {
        return Err(Fail::whole(format!(
            "{} triangles; at most 2^32 are accepted",
            triangles.len()
        )));
    }
    let exponent = units(&mut positions, &triangles);
    let total = triangles.len();
    let mut kept = triangles;
    kept.retain(|t| !degenerate(&positions, t));
    // What the rest takes: normals and their sums, and the hierarchy the tracer will build.
    let later = (n as u64) * 48 + budget::hierarchy_bytes(kept.len() as u64, false);
    budget::admit(later, || {
        format!(
            "its normals and hierarchy ({} triangles, {n} vertices)",
            kept.len()
        )
    })?;
    if kept.is_empty() {
        return Err(Fail::whole(match total {
            0 => "the file has no faces".into(),
            n => format!(
                "all {n} triangles are degenerate (zero area, a repeated index or a non-finite vertex)"
            ),
        }));
    }
    kept.shrink_to_fit();
    let (normals, file_normals) = vertex_normals(&positions, &kept, normals, has_normal);
    let local_box = crate::scene::box_of(&positions, &kept);
    let mesh = Mesh {
        local_box,
        file: file.to_owned(),
        positions,
        normals,
        uvs,
        skipped: total - kept.len(),
        triangles: kept,
        file_normals,
        notes,
        digest: 0,
        bytes: 0,
        load_seconds: 0.0,
    };
    Ok(Loaded { mesh, exponent })
}

/// The file's normal where it gives a usable one (finite, non-zero: `unit`), else the
/// area-weighted normal of the faces around the vertex; and how many came from the file. The
/// faces' normals are summed only when some vertex needs them (a file with every normal, as
/// most scanned and exported models are, skips a pass over every triangle).
fn vertex_normals(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    normals: Option<Vec<DVec3>>,
    has_normal: Option<Vec<bool>>,
) -> (Vec<DVec3>, usize) {
    let Some(mut normals) = normals else {
        return (area_weighted(positions, triangles), 0);
    };
    let mut from_file = 0;
    for (i, v) in normals.iter_mut().enumerate() {
        let given = has_normal.as_ref().is_none_or(|h| h[i]);
        let u = unit(*v);
        // Zero marks a vertex the faces must give: a usable unit normal is never zero.
        *v = if given && u != DVec3::ZERO && u.is_finite() {
            from_file += 1;
            u
        } else {
            DVec3::ZERO
        };
    }
    if from_file < normals.len() {
        let face = area_weighted(positions, triangles);
        for (v, f) in normals.iter_mut().zip(face) {
            if *v == DVec3::ZERO {
                *v = f;
            }
        }
    }
    (normals, from_file)
}

/// Coordinates whose largest magnitude is in [2^−32, 2^32] are kept as they are. Others are
/// multiplied by 2^−k (exactly: scalbn), k the exponent of that largest magnitude M
/// (M = m·2^k, m in [0.5, 1)), over every finite coordinate of every vertex a triangle uses;
/// returns k (0 when kept). Every product, cross product and normalisation of the tracer then
/// stays within f64's normal range, and since scaling by a power of two commutes with every
/// rounding in that range, a model in metres, microns or light years gives the same pixels.
pub(crate) fn units(positions: &mut [DVec3], triangles: &[[u32; 3]]) -> i32 {
    let largest = triangles
        .iter()
        .flatten()
        .map(|&i| positions[i as usize])
        .flat_map(|p| [p.x, p.y, p.z])
        .filter(|c| c.is_finite())
        .fold(0.0f64, |m, c| m.max(c.abs()));
    const LOW: f64 = 1.0 / 4_294_967_296.0;
    const HIGH: f64 = 4_294_967_296.0;
    if largest == 0.0 || (LOW..=HIGH).contains(&largest) {
        return 0;
    }
    let k = libm::ilogb(largest) + 1;
    for p in positions.iter_mut() {
        *p = DVec3::new(
            libm::scalbn(p.x, -k),
            libm::scalbn(p.y, -k),
            libm::scalbn(p.z, -k),
        );
    }
    k
}

/// A mesh made in memory (benchmarks, tests): the same dropping of degenerate triangles and
/// the same vertex normals as a file without normals gets, in the units given.
pub fn from_triangles(name: &str, positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    let soup = Soup {
        positions,
        triangles,
        ..Soup::default()
    };
    let loaded = finish(Path::new(name), soup).unwrap_or_else(|e| panic!("{name}: {}", e.message));
    assert_eq!(
        loaded.exponent, 0,
        "{name}: coordinates out of [2^-32, 2^32]"
    );
    let mut m = loaded.mesh;
    m.digest = fnv1a(name.as_bytes());
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
            let u = unit(n);
            if u == DVec3::ZERO || !u.is_finite() {
                DVec3::Y
            } else {
                u
            }
        })
        .collect()
}

/// Text quoted from a file into a note, cut at 80 characters (`…` where cut): a note stays a
/// line whatever the file holds.
pub(crate) fn quoted(text: &str) -> String {
    match text.char_indices().nth(80) {
        Some((at, _)) => format!("{}…", &text[..at]),
        None => text.to_string(),
    }
}

/// `normalize_or_zero` of `v` first multiplied by 2^−k, k the exponent of its largest
/// |component|: exact, and the same as `normalize_or_zero(v)` wherever v·v neither overflows
/// nor underflows, but a unit vector too where it would (a file normal of 1e-160 lost seven
/// digits to the subnormal square; the fuzzer found it).
fn unit(v: DVec3) -> DVec3 {
    let largest = v.abs().max_element();
    if !(largest > 0.0 && largest.is_finite()) {
        return v.normalize_or_zero();
    }
    let k = libm::ilogb(largest);
    DVec3::new(
        libm::scalbn(v.x, -k),
        libm::scalbn(v.y, -k),
        libm::scalbn(v.z, -k),
    )
    .normalize_or_zero()
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
    fn tiny_and_huge_normals_come_out_unit_and_others_as_they_were() {
        for v in [
            DVec3::new(1e-160, 0.0, 0.0),
            DVec3::new(3e-170, -4e-170, 0.0),
            DVec3::splat(1e300),
        ] {
            assert!((unit(v).length() - 1.0).abs() < 1e-15, "{v}");
        }
        for v in [
            DVec3::new(0.3, -2.0, 7.0),
            DVec3::new(1e-9, 1.0, 1e20),
            DVec3::new(5.0, 1e-170, 0.0),
        ] {
            assert_eq!(unit(v), v.normalize_or_zero(), "{v}");
        }
        assert_eq!(unit(DVec3::ZERO), DVec3::ZERO);
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
