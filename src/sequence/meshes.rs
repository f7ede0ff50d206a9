//! `mesh:` objects: the file resolved against the sequence file's folder (and kept inside
//! it), read once however often it is placed, and its placement checked.
//!
//! ```yaml
//! - mesh: { file: models/bunny.ply, material: clay, shading: phong, scale: 10, rotate: [0, 30, 0], translate: [0, -1, 0] }
//! ```

use super::*;
use crate::scene::{Mesh, Placement};
use glam::DMat3;
use std::collections::HashMap;
use std::sync::Arc;

pub(super) struct Meshes {
    base: PathBuf,
    loaded: Vec<Arc<Mesh>>,
    /// Per mesh, k: its positions are the file's times 2^−k (`mesh::units`).
    exponents: Vec<i32>,
    by_path: HashMap<PathBuf, usize>,
    warnings: Vec<String>,
}

impl Meshes {
    pub(super) fn new(base: &Path) -> Meshes {
        Meshes {
            base: base.to_owned(),
            loaded: Vec::new(),
            exponents: Vec::new(),
            by_path: HashMap::new(),
            warnings: Vec::new(),
        }
    }

    /// The meshes in order of first use, and a warning per file that lost triangles.
    pub(super) fn finish(self) -> (Vec<Arc<Mesh>>, Vec<String>) {
        (self.loaded, self.warnings)
    }

    /// Whether the mesh `shape` places has texture coordinates.
    pub(super) fn has_uvs(&self, shape: &Shape) -> bool {
        matches!(shape, Shape::Mesh { mesh, .. } if self.loaded[*mesh].uvs.is_some())
    }

    /// Reads (or reuses) the file of `m` and checks its placement.
    pub(super) fn place(&mut self, path: &str, m: &raw::Mesh) -> Check<Shape> {
        let field = format!("{path}.file");
        let file = resolve(&self.base, &field, &m.file, "a mesh")?;
        let key = std::fs::canonicalize(&file).unwrap_or_else(|_| file.clone());
        let index = match self.by_path.get(&key) {
            Some(&i) => i,
            None => {
                let super::mesh::Loaded { mesh, exponent } =
                    super::mesh::load(&file).or_else(|e| match e.out_of_memory {
                        true => no_memory(&field, e.to_string()),
                        false => invalid(&field, e.to_string()),
                    })?;
                if mesh.skipped > 0 {
                    self.warnings.push(format!(
                        "{field}: {} of {} triangles of {} are degenerate (zero area, a repeated index or a non-finite vertex) and were skipped",
                        mesh.skipped,
                        mesh.skipped + mesh.triangles.len(),
                        m.file
                    ));
                }
                self.loaded.push(Arc::new(mesh));
                self.exponents.push(exponent);
                self.by_path.insert(key, self.loaded.len() - 1);
                self.loaded.len() - 1
            }
        };
        let place = placement(path, m, self.exponents[index], &self.loaded[index])?;
        check_reach(path, &place, &self.loaded[index])?;
        Ok(Shape::Mesh {
            mesh: index,
            place,
            shading: m.shading.unwrap_or_default(),
        })
    }
}

/// `file` against the sequence file's folder `base`; like `output`, a sequence file may only
/// reach below its own folder (no absolute path, no `..`, no link leading out). `what` names
/// the kind of file in messages ("a mesh", "a texture").
pub(super) fn resolve(base: &Path, field: &str, file: &str, what: &str) -> Check<PathBuf> {
    let p = Path::new(file);
    let climbs = p
        .components()
        .any(|c| matches!(c, std::path::Component::ParentDir));
    if file.is_empty() || p.is_absolute() || climbs || file.starts_with('~') {
        return invalid(
            field,
            format!(
                "{what} file must be a relative path below the sequence file's folder, without `..` (got `{file}`); copy or link it there"
            ),
        );
    }
    let full = base.join(p);
    let canonical_base = std::fs::canonicalize(if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    });
    if let (Ok(b), Ok(real)) = (canonical_base, std::fs::canonicalize(&full))
        && !real.starts_with(&b)
    {
        return invalid(
            field,
            format!(
                "`{file}` leads outside the sequence file's folder once symbolic links are followed (to {}); copy the file there",
                real.display()
            ),
        );
    }
    Ok(full)
}

/// The placement as written, its scale times 2^k for a mesh whose positions were brought to
/// f64's range by 2^−k (`mesh::units`): the same world points, exactly.
fn placement(path: &str, m: &raw::Mesh, k: i32, mesh: &Mesh) -> Check<Placement> {
    let field = format!("{path}.scale");
    // Any finite factor: what must hold is checked on the placed model below.
    let scale = match m.scale {
        None => DVec3::ONE,
        Some(raw::Scale(v)) => finite(&field, v, "a finite number")?,
    };
    if scale.abs().min_element() == 0.0 {
        return invalid(
            &field,
            format!("each factor must be non-zero {}", got(num3(scale))),
        );
    }
    let placed = DVec3::new(
        libm::scalbn(scale.x, k),
        libm::scalbn(scale.y, k),
        libm::scalbn(scale.z, k),
    );
    if placed.abs().min_element() < MIN_SCALE {
        return invalid(&field, too_small(mesh, k, scale));
    }
    // Any finite angle: `sin_cos` reduces it exactly.
    let rotate = finite(
        &format!("{path}.rotate"),
        m.rotate.unwrap_or_default(),
        "a finite number of degrees",
    )?;
    Ok(Placement {
        scale: placed,
        rotation: rotation(rotate),
        translate: vector(
            &format!("{path}.translate"),
            m.translate.unwrap_or_default(),
        )?,
    })
}

/// Why a scale is refused: under 1e-100, or for a file in other units, a placed model under
/// 1e-100 times the size of one in units of about 1.
fn too_small(mesh: &Mesh, k: i32, scale: DVec3) -> String {
    if k == 0 {
        return format!(
            "each factor must be non-zero, at least {MIN_SCALE:e} in size {}",
            got(num3(scale))
        );
    }
    let (lo, hi) = mesh.bounds();
    let reach = libm::scalbn(lo.abs().max(hi.abs()).max_element(), k);
    format!(
        "{}'s coordinates reach {}, so this scale makes the placed model about {} across; it must be at least {MIN_SCALE:e} across, as f64 cannot trace a smaller one among coordinates up to ±{MAX_MAGNITUDE:e} {}",
        mesh.file.display(),
        approx(reach),
        approx(reach * scale.abs().min_element()),
        got(num3(scale))
    )
}

/// Each of three numbers finite (`what` says what they must be).
fn finite(field: &str, v: raw::V3, what: &str) -> Check<DVec3> {
    for (i, a) in v.iter().enumerate() {
        if !a.is_finite() {
            return invalid(
                format!("{field}[{i}]"),
                format!("must be {what} {}", got_num(*a)),
            );
        }
    }
    Ok(DVec3::from(v))
}

/// The smallest factor of a scale, in units of the model's own size (its positions' largest
/// magnitude brought to [0.5, 1) when outside [2^−32, 2^32]): scaled coordinates must stay
/// normal f64 numbers, as spheres' radii do.
const MIN_SCALE: f64 = 1e-100;

/// Rz · Ry · Rx for angles in degrees, right-handed (counter-clockwise seen from the positive
/// axis). Whole multiples of 90° use exact 0 and ±1, so axis-aligned models stay aligned.
pub fn rotation(degrees: DVec3) -> DMat3 {
    let (sx, cx) = sin_cos(degrees.x);
    let (sy, cy) = sin_cos(degrees.y);
    let (sz, cz) = sin_cos(degrees.z);
    let rx = DMat3::from_cols(
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, cx, sx),
        DVec3::new(0.0, -sx, cx),
    );
    let ry = DMat3::from_cols(
        DVec3::new(cy, 0.0, -sy),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(sy, 0.0, cy),
    );
    let rz = DMat3::from_cols(
        DVec3::new(cz, sz, 0.0),
        DVec3::new(-sz, cz, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    );
    rz * (ry * rx)
}

/// sin and cos of an angle in degrees: exact at whole multiples of 90°, else libm's of the
/// angle (reduced to (−360, 360) by `%`) times π/180.
fn sin_cos(degrees: f64) -> (f64, f64) {
    let d = degrees % 360.0;
    if d % 90.0 == 0.0 {
        let quarter = ((d / 90.0) as i64).rem_euclid(4);
        return [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][quarter as usize];
    }
    let r = d.to_radians();
    (libm::sin(r), libm::cos(r))
}

/// The placed model must stay within the coordinates every other object may have.
fn check_reach(path: &str, place: &Placement, mesh: &Mesh) -> Check<()> {
    let (lo, hi) = mesh.bounds();
    let far = place.translate.abs().max_element()
        + (place.scale.abs().max_element() * lo.abs().max(hi.abs()).max_element()) * 3f64.sqrt();
    if far.is_nan() || far > MAX_MAGNITUDE {
        return invalid(
            path,
            format!(
                "the model placed by its scale and translate reaches {} from the origin; coordinates are limited to ±{MAX_MAGNITUDE:e}",
                num(far)
            ),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_are_right_handed_and_exact_at_quarter_turns() {
        // 90° about Y takes +Z to +X; 90° about X takes +Y to +Z; about Z takes +X to +Y.
        assert_eq!(rotation(DVec3::new(0.0, 90.0, 0.0)) * DVec3::Z, DVec3::X);
        assert_eq!(rotation(DVec3::new(90.0, 0.0, 0.0)) * DVec3::Y, DVec3::Z);
        assert_eq!(rotation(DVec3::new(0.0, 0.0, 90.0)) * DVec3::X, DVec3::Y);
        // X first, then Y: +Y → +Z (about X) → +X (about Y).
        assert_eq!(rotation(DVec3::new(90.0, 90.0, 0.0)) * DVec3::Y, DVec3::X);
        let r = rotation(DVec3::new(0.0, 30.0, 0.0)) * DVec3::Z;
        assert!((r - DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0)).length() < 1e-15);
    }
}
