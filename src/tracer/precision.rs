//! When f32 is not enough. In f32 every coordinate relative to the camera carries a rounding
//! error of up to u = 2^-24 of its size, so a surface whose points lie up to R from the camera
//! (a sphere: |c − camera| + r; a plane, anchored nearest the camera: its distance) is only
//! known to about u·R. Measured on the talk's scene with its floor sphere grown (README,
//! "Precision"), the image error follows that error in pixels at the subject distance D (the
//! camera's focus distance): E = u·R·H / (2·D·tan(fov/2)), H the image height. A frame whose
//! worst object has E above `MAX_ERROR_PIXELS`, or holds a size f32 cannot square (above 2^60
//! or, for a radius, below 2^-60), is traced in f64 instead: the same bytes an f64 render gives.

use super::Settings;
use crate::camera::Camera;
use crate::scene::{Scene, Shape};

/// The largest surface error, in pixels, an f32 frame may have: measured, 1 pixel costs the
/// talk's image about 55 dB of PSNR and 10 pixels about 43.
pub const MAX_ERROR_PIXELS: f64 = 4.0;

/// f32's unit roundoff.
const U: f64 = 1.0 / 16_777_216.0;

/// Sizes beyond which squares leave f32's normal range (2^±126 with room for sums).
const LARGEST: f64 = 1_152_921_504_606_846_976.0; // 2^60
const SMALLEST: f64 = 1.0 / LARGEST;

/// What f32 cannot resolve in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Unresolved {
    /// `objects[3] (sphere)` or `lights[0] (point)`.
    pub what: String,
    /// Its surface error in pixels, infinite when a size is out of f32's range.
    pub pixels: f64,
}

impl std::fmt::Display for Unresolved {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        if self.pixels.is_finite() {
            write!(
                f,
                "f32 places {} only to {:.1} pixels (limit {MAX_ERROR_PIXELS}), so it is traced in f64",
                self.what, self.pixels
            )
        } else {
            write!(
                f,
                "{} has a size f32 cannot square (beyond 2^60 or below 2^-60 relative to the camera), so it is traced in f64",
                self.what
            )
        }
    }
}

/// Whether f32 resolves the frame `camera` sees of `scene` at `settings`' height; if not,
/// the object (or light) that decides it.
pub fn f32_limit(scene: &Scene, camera: &Camera, settings: &Settings) -> Option<Unresolved> {
    let per_length =
        f64::from(settings.height) / (2.0 * camera.focus_distance * camera.tan_half_fov);
    let mut worst: Option<Unresolved> = None;
    let mut note = |what: String, pixels: f64| {
        if pixels > MAX_ERROR_PIXELS && worst.as_ref().is_none_or(|w| pixels > w.pixels) {
            worst = Some(Unresolved { what, pixels });
        }
    };
    for (i, o) in scene.objects.iter().enumerate() {
        let (reach, kind, radius) = match o.shape {
            Shape::Sphere { center, radius } => {
                ((center - camera.origin).length() + radius, "sphere", radius)
            }
            Shape::Plane { point, normal, .. } => {
                ((point - camera.origin).dot(normal).abs(), "plane", 1.0)
            }
            // A mesh: its farthest box corner; its smallest scale factor must square in f32.
            Shape::Mesh { mesh, place, .. } => {
                let (lo, hi) = scene.mesh_bounds(mesh, &place);
                let far = (lo - camera.origin).abs().max((hi - camera.origin).abs());
                (far.length(), "mesh", place.scale.abs().min_element())
            }
        };
        let pixels = match reach <= LARGEST && radius >= SMALLEST {
            true => U * reach * per_length,
            false => f64::INFINITY,
        };
        note(format!("objects[{i}] ({kind})"), pixels);
    }
    for (i, l) in scene.lights.iter().enumerate() {
        if let Some(p) = l.position()
            && (p - camera.origin).length() > LARGEST
        {
            note(format!("lights[{i}]"), f64::INFINITY);
        }
    }
    worst
}
