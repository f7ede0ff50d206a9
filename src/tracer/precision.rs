//! When f32 is not enough. In f32 every coordinate relative to a ray's origin carries a
//! rounding error of up to u = 2^-24 of its size, so a surface whose points lie up to R from
//! the rays' origins (a sphere: |c − camera| + r; a plane, anchored nearest the camera: its
//! distance; each plus how far the lens and the shutter's instants move the origins from the
//! camera) is only known to about u·R. Measured on the talk's scene with its floor sphere
//! grown (docs/quality.md), the image error follows that error in pixels at the subject
//! distance D (the camera's focus distance): E = u·R·H / (2·D·tan(fov/2)), H the image
//! height. A sphere's normal is off by about u·R/r besides, which no pixel count shows: a
//! small sphere far away (a telephoto shot) shades wrongly at any image size. A frame whose
//! worst object has E above `MAX_ERROR_PIXELS`, a normal error above `MAX_NORMAL_ERROR`, or
//! holds a size f32 cannot square (above 2^60 or, for a radius, below 2^-60), is traced in
//! f64 instead: the same bytes an f64 render gives.

use super::Settings;
use crate::scene::{Scene, Shape};
use crate::shutter::Exposure;

/// The largest surface error, in pixels, an f32 frame may have: measured, 1 pixel costs the
/// talk's image about 55 dB of PSNR and 10 pixels about 43.
pub const MAX_ERROR_PIXELS: f64 = 4.0;

/// f32's unit roundoff.
const U: f64 = 1.0 / 16_777_216.0;

/// Sizes beyond which squares leave f32's normal range (2^±126 with room for sums).
const LARGEST: f64 = 1_152_921_504_606_846_976.0; // 2^60
const SMALLEST: f64 = 1.0 / LARGEST;

/// The largest error of a sphere's normal, in radians, an f32 frame may have. A normal is
/// (p − c)/r with p and c each known to u·R, so it is off by up to about u·R/r: a sphere small
/// against its distance (a telephoto shot, or rays leaving a wide lens) shades wrongly long
/// before its outline moves. Measured on `tests/hostile.rs`'s telephoto scene at 200×112:
/// 2⁻⁶ leaves 0.5% of pixels more than 2 levels off, 2⁻⁹ 0.01%, 2⁻¹² none.
pub const MAX_NORMAL_ERROR: f64 = 1.0 / 1024.0;

/// What f32 cannot resolve in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Unresolved {
    /// `objects[3] (sphere)` or `lights[0] (point)`.
    pub what: String,
    pub why: Why,
}

/// Which of the limits an object passes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Why {
    /// Its surface error in pixels, above `MAX_ERROR_PIXELS`.
    Pixels(f64),
    /// Its normal's error in radians, above `MAX_NORMAL_ERROR`.
    Normal(f64),
    /// A size beyond f32's squares.
    Size,
}

impl Unresolved {
    /// How far past its limit: what decides which object a warning names.
    pub fn excess(&self) -> f64 {
        match self.why {
            Why::Pixels(p) => p / MAX_ERROR_PIXELS,
            Why::Normal(n) => n / MAX_NORMAL_ERROR,
            Why::Size => f64::INFINITY,
        }
    }
}

impl std::fmt::Display for Unresolved {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let what = &self.what;
        match self.why {
            Why::Pixels(p) => write!(
                f,
                "f32 places {what} only to {p:.1} pixels (limit {MAX_ERROR_PIXELS}), so it is traced in f64"
            ),
            Why::Normal(n) => write!(
                f,
                "f32 knows the normals of {what} only to {n:.2e} rad (limit 2^-10 = {MAX_NORMAL_ERROR:.2e}: it is small against its distance from the rays' origins), so it is traced in f64"
            ),
            Why::Size => write!(
                f,
                "{what} has a size f32 cannot square (beyond 2^60 or below 2^-60 relative to the camera), so it is traced in f64"
            ),
        }
    }
}

/// How far from the frame's camera position o the rays of `exposure` may leave: the lens
/// radius plus the farthest shutter instant's camera. Every reach grows by it, since a ray's
/// origin, not o, is where its coordinates are measured from.
fn spread(exposure: &Exposure) -> f64 {
    let c = &exposure.camera;
    let moved = exposure
        .instants
        .iter()
        .map(|i| (i.origin - c.origin).length());
    c.lens_radius + moved.fold(0.0, f64::max)
}

/// Whether f32 resolves the frame `exposure` sees of `scene` at `settings`' height; if not,
/// the object (or light) that decides it (the one furthest past its limit).
pub fn f32_limit(scene: &Scene, exposure: &Exposure, settings: &Settings) -> Option<Unresolved> {
    let camera = &exposure.camera;
    let per_length =
        f64::from(settings.height) / (2.0 * camera.focus_distance * camera.tan_half_fov);
    let a = spread(exposure);
    let mut worst: Option<Unresolved> = None;
    let mut note = |what: String, why: Why| {
        let u = Unresolved { what, why };
        if u.excess() > 1.0 && worst.as_ref().is_none_or(|w| u.excess() > w.excess()) {
            worst = Some(u);
        }
    };
    for (i, o) in scene.objects.iter().enumerate() {
        let (reach, kind, radius) = match o.shape {
            Shape::Sphere { center, radius } => (
                (center - camera.origin).length() + radius + a,
                "sphere",
                radius,
            ),
            Shape::Plane { point, normal, .. } => {
                ((point - camera.origin).dot(normal).abs() + a, "plane", 1.0)
            }
            // A mesh: its farthest box corner; its smallest scale factor must square in f32.
            Shape::Mesh { mesh, place, .. } => {
                let (lo, hi) = scene.mesh_bounds(mesh, &place);
                let far = (lo - camera.origin).abs().max((hi - camera.origin).abs());
                (far.length() + a, "mesh", place.scale.abs().min_element())
            }
        };
        let what = format!("objects[{i}] ({kind})");
        if !(reach <= LARGEST && radius >= SMALLEST) {
            note(what, Why::Size);
            continue;
        }
        note(what.clone(), Why::Pixels(U * reach * per_length));
        if kind == "sphere" {
            note(what, Why::Normal(U * reach / radius));
        }
    }
    for (i, l) in scene.lights.iter().enumerate() {
        if let Some(p) = l.position()
            && (p - camera.origin).length() + a > LARGEST
        {
            note(format!("lights[{i}]"), Why::Size);
        }
    }
    worst
}
