//! `mesh:` objects: the file resolved against the sequence file's folder or a model library
//! the user named (and kept inside them), read once however often it is placed, and its
//! placement checked.
//!
//! ```yaml
//! - mesh: { file: models/bunny.ply, material: clay, shading: phong, scale: 10, rotate: [0, 30, 0], translate: [0, -1, 0] }
//! ```

use super::*;
use crate::scene::{Mesh, Placement, rotation};
use glam::DMat3;
use std::collections::HashMap;
use std::sync::Arc;

pub(super) struct Meshes {
    folders: Folders,
    loaded: Vec<Arc<Mesh>>,
    /// Per mesh, k: its positions are the file's times 2^−k (`mesh::units`).
    exponents: Vec<i32>,
    by_path: HashMap<PathBuf, usize>,
    warnings: Vec<String>,
}

impl Meshes {
    pub(super) fn new(folders: &Folders) -> Meshes {
        Meshes {
            folders: folders.clone(),
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
        let file = resolve(&self.folders, &field, &m.file, "a mesh")?;
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

/// Where the files a sequence names (meshes, images) are looked for: the sequence file's
/// folder, then each model library the user named (`--assets`, `RAYREEL_ASSETS`), in order.
/// A sequence file names none of them itself, so one received from someone else reads only
/// below its own folder and the libraries its user chose.
#[derive(Debug, Clone, Default)]
pub struct Folders {
    pub(crate) sequence: PathBuf,
    pub(crate) assets: Vec<PathBuf>,
}

impl Folders {
    pub(crate) fn new(sequence: &Path, assets: &[PathBuf]) -> Folders {
        Folders {
            sequence: sequence.to_owned(),
            assets: assets.to_vec(),
        }
    }

    /// Every folder, the sequence's first.
    fn all(&self) -> impl Iterator<Item = &Path> {
        std::iter::once(self.sequence.as_path()).chain(self.assets.iter().map(PathBuf::as_path))
    }
}

/// `file` against `folders`: the first folder that holds it (or the sequence's folder when
/// none does, for the reader to say it is missing). Like `output`, a name may not be absolute,
/// start with `~` or hold `..`, and once symbolic links are followed it must stay below one of
/// the folders. `what` names the kind of file in messages ("a mesh", "a texture").
pub(super) fn resolve(folders: &Folders, field: &str, file: &str, what: &str) -> Check<PathBuf> {
    let p = Path::new(file);
    let climbs = p
        .components()
        .any(|c| matches!(c, std::path::Component::ParentDir));
    if file.is_empty() || p.is_absolute() || climbs || file.starts_with('~') {
        return invalid(
            field,
            format!(
                "{what} file must be a relative path below the sequence file's folder (or a model library given with --assets), without `..` (got `{file}`)"
            ),
        );
    }
    let found = folders
        .all()
        .map(|f| f.join(p))
        .find(|full| std::fs::symlink_metadata(full).is_ok());
    let Some(full) = found else {
        if folders.assets.is_empty() {
            return Ok(folders.sequence.join(p));
        }
        let looked: Vec<String> = folders.all().map(shown_folder).collect();
        return invalid(
            field,
            format!(
                "`{file}` is in none of the folders looked in: {}",
                looked.join(", ")
            ),
        );
    };
    let Ok(real) = std::fs::canonicalize(&full) else {
        return Ok(full);
    };
    let inside = folders
        .all()
        .filter_map(|f| std::fs::canonicalize(shown_path(f)).ok())
        .any(|root| real.starts_with(root));
    if !inside {
        return invalid(
            field,
            format!(
                "`{file}` leads outside the sequence file's folder once symbolic links are followed (to {}); copy the file there, or give the folder it is in with --assets",
                real.display()
            ),
        );
    }
    Ok(full)
}

/// A folder as a path to open: the current directory for the empty path (stdin's folder).
fn shown_path(folder: &Path) -> &Path {
    match folder.as_os_str().is_empty() {
        true => Path::new("."),
        false => folder,
    }
}

/// A folder as messages name it.
fn shown_folder(folder: &Path) -> String {
    crate::console::printable(&shown_path(folder).display().to_string()).into_owned()
}

/// Where `m` puts `mesh`: `scale` along the file's axes, the file's `up` axis turned to +y,
/// `rotate`, then `fit` (a uniform factor making the largest extent `fit` scene units) and
/// `origin` (which point of the bounds `translate` puts in place), all folded into one
/// placement: world = translate′ + (R·U)·(scale′ ∘ p) (docs/spec/mesh.md#placement). For a
/// mesh whose positions were brought to f64's range by 2^−k (`mesh::units`), the scale is
/// the one written times 2^k: the same world points, exactly.
fn placement(path: &str, m: &raw::Mesh, k: i32, mesh: &Mesh) -> Check<Placement> {
    let field = format!("{path}.scale");
    // Any finite factor: what must hold is checked on the placed model below.
    let given = match m.scale {
        None => DVec3::ONE,
        Some(raw::Scale(v)) => finite(&field, v, "a finite number")?,
    };
    if given.abs().min_element() == 0.0 {
        return invalid(
            &field,
            format!("each factor must be non-zero {}", got(num3(given))),
        );
    }
    let mut scale = DVec3::new(
        libm::scalbn(given.x, k),
        libm::scalbn(given.y, k),
        libm::scalbn(given.z, k),
    );
    // With `fit` the scale only sets proportions: the size that must hold is the fitted one,
    // judged below, so a model in 1e-150 units with `scale: 1, fit: 1.5` is 1.5 across.
    // Only a scale whose factors are no longer normal f64 numbers is refused before fitting.
    let least = match m.fit {
        None => MIN_SCALE,
        Some(_) => f64::MIN_POSITIVE,
    };
    if scale.abs().min_element() < least {
        return invalid(&field, too_small(mesh, k, given));
    }
    // Any finite angle: `sin_cos` reduces it exactly.
    let rotate = finite(
        &format!("{path}.rotate"),
        m.rotate.unwrap_or_default(),
        "a finite number of degrees",
    )?;
    let up = up_axis(&format!("{path}.up"), m.up.as_deref())?;
    let rotation = rotation(rotate) * up;
    let mut translate = vector(
        &format!("{path}.translate"),
        m.translate.unwrap_or_default(),
    )?;
    if let Some(fit) = m.fit {
        let fit = in_range(
            &format!("{path}.fit"),
            fit,
            MIN_SCALE,
            MAX_MAGNITUDE,
            "a positive length in [1e-100, 1e100]",
        )?;
        let (lo, hi) = placed_bounds(mesh, scale, rotation, DVec3::ZERO);
        let factor = fit / (hi - lo).max_element();
        scale *= factor;
        let small = scale.abs().min_element();
        if !(small >= MIN_SCALE && scale.abs().max_element() <= MAX_MAGNITUDE) {
            return invalid(
                format!("{path}.fit"),
                format!(
                    "fitting the model to {} scales it by {}, beyond what coordinates can hold",
                    num(fit),
                    num(factor)
                ),
            );
        }
    }
    if let Some(offset) = origin_offset(mesh, scale, rotation, m.origin.unwrap_or_default()) {
        translate -= offset;
    }
    Ok(Placement {
        scale,
        rotation,
        translate,
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
        "{}'s coordinates reach {reach:.2e}, so this scale makes the placed model about {:.2e} across; it must be at least {MIN_SCALE:e} across, as f64 cannot trace a smaller one among coordinates up to ±{MAX_MAGNITUDE:e} {}",
        mesh.file.display(),
        reach * scale.abs().min_element(),
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

/// The rotation turning the file's `up` axis (`y` by default; `z`, `x`, or any of them
/// negated, `+` allowed) to +y, by quarter turns, so it is exact: z → +y is −90° about X
/// (Blender's Z-up, −Y-forward files then face +Z), x → +y is 90° about Z, −y is 180° about X,
/// −z is 90° about X, −x is −90° about Z.
/// What `origin: center|bottom` subtracts from `translate`: the centre of the model's
/// bounds once scaled and rotated, or the centre of their bottom; None for `origin: file`.
pub(super) fn origin_offset(
    mesh: &Mesh,
    scale: DVec3,
    rotation: DMat3,
    origin: raw::Origin,
) -> Option<DVec3> {
    if origin == raw::Origin::File {
        return None;
    }
    let (lo, hi) = placed_bounds(mesh, scale, rotation, DVec3::ZERO);
    let centre = (lo + hi) * 0.5;
    Some(match origin {
        raw::Origin::Bottom => DVec3::new(centre.x, lo.y, centre.z),
        _ => centre,
    })
}

pub(super) fn up_axis(path: &str, up: Option<&str>) -> Check<DMat3> {
    let degrees = match up.map(|u| u.trim_start_matches('+')) {
        None | Some("y") | Some("Y") => [0.0, 0.0, 0.0],
        Some("z") | Some("Z") => [-90.0, 0.0, 0.0],
        Some("x") | Some("X") => [0.0, 0.0, 90.0],
        Some("-y") | Some("-Y") => [180.0, 0.0, 0.0],
        Some("-z") | Some("-Z") => [90.0, 0.0, 0.0],
        Some("-x") | Some("-X") => [0.0, 0.0, -90.0],
        Some(other) => {
            return invalid(
                path,
                format!(
                    "the file's up axis is one of y, z, x, -y, -z, -x (got `{}`)",
                    crate::console::printable(other)
                ),
            );
        }
    };
    Ok(rotation(DVec3::from_array(degrees)))
}

/// The per-axis smallest and largest of translate + R·(scale ∘ p) over the vertices the
/// mesh's triangles use, each point computed as `Placement::point` does.
pub(crate) fn placed_bounds(
    mesh: &Mesh,
    scale: DVec3,
    rotation: DMat3,
    translate: DVec3,
) -> (DVec3, DVec3) {
    let place = Placement {
        scale,
        rotation,
        translate,
    };
    let mut used = vec![false; mesh.positions.len()];
    mesh.triangles
        .iter()
        .flatten()
        .for_each(|&i| used[i as usize] = true);
    let points = mesh.positions.iter().zip(&used).filter(|(_, u)| **u);
    points.fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), (p, _)| {
            let q = place.point(*p);
            (lo.min(q), hi.max(q))
        },
    )
}

/// The smallest factor of a scale, in units of the model's own size (its positions' largest
/// magnitude brought to [0.5, 1) when outside [2^−32, 2^32]): scaled coordinates must stay
/// normal f64 numbers, as spheres' radii do.
const MIN_SCALE: f64 = 1e-100;

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
