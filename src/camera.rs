//! The camera: `world_from_camera`, primary rays, and a thin lens for depth of field.
//!
//! Pixel (row i from the top, column j from the left) of a W×H image looks through the screen
//! point x = −1 + 2(j+u)/W, y = (1 − 2(i+v)/H)·H/W, with (u, v) = (0.5, 0.5) at the pixel
//! centre, along normalize(forward + x·tan(fov/2)·right + y·tan(fov/2)·up). With the camera at
//! (0,0,1) looking at the origin and fov 90 that is exactly the talk's screen on the plane z = 0.

use crate::lanes::{F64x1, Lanes, V3};
use glam::{DMat4, DVec3};

/// Where the camera is and where it looks, as the sequence file and the timeline give it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub position: DVec3,
    pub look_at: DVec3,
    pub up: DVec3,
    /// Horizontal field of view in degrees, in (0, 180).
    pub fov: f64,
}

/// Why a pose cannot be turned into a camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Degenerate {
    #[error("the camera position equals its look_at, so it has no view direction")]
    NoViewDirection,
    #[error("up is parallel to the view direction, so the camera's roll is undefined")]
    UpParallel,
    #[error("fov must be in (0, 180) degrees")]
    Fov,
    #[error(
        "the view swings past up since the previous frame, so the camera rolls over (its picture turns more than 60° about the view axis); move the path or look_at away from the up axis, or change up"
    )]
    Flip,
}

/// A thin lens: its aperture (diameter) and the distance from the camera to the plane in
/// focus, both in scene units. Aperture 0 is a pinhole, for which the focus does not matter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lens {
    pub(crate) aperture: f64,
    pub(crate) focus_distance: f64,
}

/// An orthonormal camera frame, ready to make rays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub origin: DVec3,
    pub forward: DVec3,
    pub(crate) right: DVec3,
    pub(crate) up: DVec3,
    pub(crate) tan_half_fov: f64,
    /// Half the aperture (0: a pinhole) and the focus distance along `forward`.
    pub(crate) lens_radius: f64,
    pub(crate) focus_distance: f64,
}

/// Below this sine of the angle between up and the view direction the roll is numerically
/// meaningless (a 0.0006° tilt), so such a pose is rejected rather than rendered spinning.
const MIN_UP_SINE: f64 = 1e-5;

impl Camera {
    pub fn new(pose: &Pose) -> Result<Camera, Degenerate> {
        if !(pose.fov > 0.0 && pose.fov < 180.0) {
            return Err(Degenerate::Fov);
        }
        let view = pose.look_at - pose.position;
        let length = view.length();
        if !(length > 0.0 && length.is_finite()) {
            return Err(Degenerate::NoViewDirection);
        }
        let forward = view / length;
        let up_length = pose.up.length();
        let up_perp = pose.up - pose.up.dot(forward) * forward;
        let rolls = up_perp.length() > MIN_UP_SINE * up_length;
        if !rolls {
            return Err(Degenerate::UpParallel);
        }
        let up = up_perp.normalize();
        Ok(Camera {
            origin: pose.position,
            forward,
            right: forward.cross(up),
            up,
            // libm, not the platform's: the same bits on every machine.
            tan_half_fov: libm::tan(pose.fov.to_radians() * 0.5),
            lens_radius: 0.0,
            focus_distance: length,
        })
    }

    /// This camera seen through `lens`.
    pub(crate) fn with_lens(self, lens: Lens) -> Camera {
        Camera {
            lens_radius: 0.5 * lens.aperture,
            focus_distance: lens.focus_distance,
            ..self
        }
    }

    /// 3×3 rotation (columns right, up, −forward) and translation to world space.
    pub fn world_from_camera(&self) -> (glam::DMat3, DVec3) {
        (
            glam::DMat3::from_cols(self.right, self.up, -self.forward),
            self.origin,
        )
    }

    /// Unit direction through screen point (x, y) as defined in the module doc.
    #[inline]
    pub fn direction(&self, x: f64, y: f64) -> DVec3 {
        self.directions(F64x1(x), F64x1(y)).lane(0)
    }

    /// `direction` for N screen points at once, lane by lane the same arithmetic.
    #[inline(always)]
    pub(crate) fn directions<V: Lanes>(&self, x: V, y: V) -> V3<V> {
        let s = V::splat(self.tan_half_fov);
        let (x, y) = (x * s, y * s);
        (V3::splat(self.forward) + V3::splat(self.right) * x + V3::splat(self.up) * y).normalize()
    }

    /// OpenEXR's `worldToCamera` and `worldToNDC` for a width×height image, row-major for row
    /// vectors (p′ = p·M, translation in the last row). Camera space is OpenEXR's (RenderMan's):
    /// left-handed, x right, y up, z along the view; NDC has (0, 0) at the top left corner of
    /// the image and (1, 1) at the bottom right, after dividing by w = camera z.
    pub(crate) fn exr_matrices(&self, width: u32, height: u32) -> [DMat4; 2] {
        let (r, u, f, o) = (self.right, self.up, self.forward, self.origin);
        let world_to_camera = DMat4::from_cols_array_2d(&[
            [r.x, u.x, f.x, 0.0],
            [r.y, u.y, f.y, 0.0],
            [r.z, u.z, f.z, 0.0],
            [-o.dot(r), -o.dot(u), -o.dot(f), 1.0],
        ]);
        let (s, aspect) = (self.tan_half_fov, f64::from(width) / f64::from(height));
        let camera_to_ndc = DMat4::from_cols_array_2d(&[
            [0.5 / s, 0.0, 0.0, 0.0],
            [0.0, -0.5 * aspect / s, 0.0, 0.0],
            [0.5, 0.5, 0.0, 1.0],
            [0.0, 0.0, 1.0, 0.0],
        ]);
        // Rows stored as glam columns: the product of row-vector matrices A·B is B·A here.
        [world_to_camera, camera_to_ndc * world_to_camera]
    }
}

/// Screen coordinates of the point (u, v) ∈ [0,1)² inside pixel (row, col) of a width×height image.
#[inline]
pub fn screen_point(row: u32, col: u32, u: f64, v: f64, width: u32, height: u32) -> (f64, f64) {
    let (x, y) = screen_points(
        F64x1(f64::from(row)),
        F64x1(f64::from(col)),
        F64x1(u),
        F64x1(v),
        width,
        height,
    );
    (x.0, y.0)
}

/// `screen_point` for N points at once (rows, columns and offsets per lane).
#[inline(always)]
pub(crate) fn screen_points<V: Lanes>(
    row: V,
    col: V,
    u: V,
    v: V,
    width: u32,
    height: u32,
) -> (V, V) {
    let w = V::splat(f64::from(width));
    let h = V::splat(f64::from(height));
    let (one, two) = (V::splat(1.0), V::splat(2.0));
    let x = -one + two * (col + u) / w;
    let y = (one - two * (row + v) / h) * h / w;
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn talk_pose() -> Pose {
        Pose {
            position: DVec3::new(0.0, 0.0, 1.0),
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov: 90.0,
        }
    }

    #[test]
    fn talk_camera_looks_through_the_z0_screen() {
        let cam = Camera::new(&talk_pose()).unwrap();
        let (x, y) = screen_point(0, 0, 0.5, 0.5, 4, 2);
        assert_eq!((x, y), (-0.75, 0.25));
        let d = cam.direction(x, y);
        let want = (DVec3::new(x, y, 0.0) - DVec3::new(0.0, 0.0, 1.0)).normalize();
        assert!((d - want).length() < 1e-15, "{d} vs {want}");
        assert_eq!(cam.right, DVec3::X);
    }

    /// A point projected through worldToNDC lands where the pixel whose eye ray passes
    /// through it is; worldToCamera puts the camera at the origin looking along +z.
    #[test]
    fn exr_matrices_follow_the_pixels() {
        let pose = Pose {
            position: DVec3::new(1.0, 2.0, 3.0),
            look_at: DVec3::new(-1.0, 0.5, -2.0),
            up: DVec3::new(0.1, 1.0, 0.0),
            fov: 70.0,
        };
        let cam = Camera::new(&pose).unwrap();
        let [to_camera, to_ndc] = cam.exr_matrices(64, 36);
        let row = |m: DMat4, p: DVec3| m.mul_vec4(p.extend(1.0));
        let c = row(to_camera, pose.position);
        assert!(c.truncate().length() < 1e-12);
        let ahead = row(to_camera, pose.position + cam.forward * 5.0);
        assert!((ahead.truncate() - DVec3::new(0.0, 0.0, 5.0)).length() < 1e-12);
        for (i, j) in [(0u32, 0u32), (10, 50), (35, 63)] {
            let (x, y) = screen_point(i, j, 0.5, 0.5, 64, 36);
            let p = pose.position + cam.direction(x, y) * 7.0;
            let n = row(to_ndc, p);
            let (nx, ny) = (n.x / n.w, n.y / n.w);
            assert!((nx - (f64::from(j) + 0.5) / 64.0).abs() < 1e-12, "{nx}");
            assert!((ny - (f64::from(i) + 0.5) / 36.0).abs() < 1e-12, "{ny}");
        }
    }

    #[test]
    fn degenerate_poses_are_errors_not_nans() {
        let mut p = talk_pose();
        p.look_at = p.position;
        assert_eq!(Camera::new(&p), Err(Degenerate::NoViewDirection));
        let mut p = talk_pose();
        p.up = DVec3::new(0.0, 0.0, -3.0);
        assert_eq!(Camera::new(&p), Err(Degenerate::UpParallel));
        let mut p = talk_pose();
        p.fov = 180.0;
        assert_eq!(Camera::new(&p), Err(Degenerate::Fov));
    }
}
