//! Compositing passes (AOVs): what the first surface of each pixel centre's eye ray is, beside
//! the colour. A pass of its own, one ray per pixel through the one-lane (scalar f64) code on
//! the f64 world, so it neither touches the colour kernels nor depends on the lane width, the
//! precision or the thread count; a frame without passes never comes here.
//!
//! ```yaml
//! render:
//!   aov: [normal, albedo, id, motion, position]   # extra EXR channels; none by default
//! ```
//! The rules, operation by operation, are in docs/spec/output.md (*Compositing passes*).

use super::accel::Rays;
use super::texture::Cone;
use super::{Settings, World, shade};
use crate::camera::{Camera, screen_point};
pub use crate::frame::Passes;
use crate::lanes::{F64x1, MAX_LANES, V3};
use crate::scene::{Object, Scene, Shape, turned};
use crate::settings::Aov;
use crate::shutter::Next;
use crate::timeline::motion::{Posed, Thing};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Rows whose records are computed together before they go to the channels.
const BAND_ROWS: usize = 64;

/// What one pixel's passes hold: normal, albedo, id, motion (u, v), position.
type Record = [f32; 12];

/// A pixel whose eye ray hits nothing: zeros, and id −1.
const MISS: Record = [0., 0., 0., 0., 0., 0., -1., 0., 0., 0., 0., 0.];

/// The channels of each pass and where they sit in a `Record`.
fn layout(aov: Aov) -> &'static [(&'static str, usize)] {
    match aov {
        Aov::Normal => &[("N.X", 0), ("N.Y", 1), ("N.Z", 2)],
        Aov::Albedo => &[("albedo.R", 3), ("albedo.G", 4), ("albedo.B", 5)],
        Aov::Id => &[("objectId", 6)],
        Aov::Motion => &[("forward.u", 7), ("forward.v", 8)],
        Aov::Position => &[("P.X", 9), ("P.Y", 10), ("P.Z", 11)],
    }
}

/// The passes `settings.aov` asks for, seen from `camera` (the frame's, at its time; its lens
/// is ignored) in `world` (posed at that time), with motion towards `next` (the camera and
/// the moving things one frame later; without it, motion is 0). `None` when no pass is asked
/// for or `stop` was set.
pub fn render(
    world: &World,
    camera: &Camera,
    next: Option<&Next>,
    settings: &Settings,
    stop: &AtomicBool,
) -> Option<Passes> {
    if settings.aov.is_empty() {
        return None;
    }
    let (w, h) = (settings.width, settings.height);
    let pixels = w as usize * h as usize;
    let mut channels: Vec<(&'static str, usize, Vec<f32>)> = (settings.aov.iter())
        .flat_map(layout)
        .map(|&(name, at)| (name, at, vec![0.0; pixels]))
        .collect();
    // Each object's pose one frame later, where it moves.
    let mut later: Vec<Option<Object>> = vec![None; world.scene.objects.len()];
    for (thing, posed) in next.map_or(&[][..], |n| &n.poses[..]) {
        if let (Thing::Object(i), Posed::Object(o)) = (thing, posed) {
            later[*i] = Some(*o);
        }
    }
    let next = next.map(|n| (&n.camera, &later[..]));
    // A band of rows at a time, so the records in flight stay small beside the channels.
    let band = BAND_ROWS * w as usize;
    for first in (0..pixels).step_by(band) {
        if stop.load(Ordering::Relaxed) {
            return None;
        }
        let records: Vec<Record> = (first..pixels.min(first + band))
            .into_par_iter()
            .map(|i| {
                let at = ((i / w as usize) as u32, (i % w as usize) as u32);
                pixel(world, (camera, next), (w, h), at)
            })
            .collect();
        for (_, at, values) in &mut channels {
            for (v, r) in values[first..].iter_mut().zip(&records) {
                *v = r[*at];
            }
        }
    }
    let channels = (channels.into_iter())
        .map(|(name, _, values)| (name, values))
        .collect();
    Some(Passes {
        channels,
        objects: objects(&world.scene),
    })
}

/// The camera one frame later, and each object's pose then where it moves (by index).
type Later<'a> = (&'a Camera, &'a [Option<Object>]);

/// The passes of pixel (row, col): its centre's pinhole eye ray and that ray's nearest hit.
fn pixel(
    world: &World,
    (camera, next): (&Camera, Option<Later>),
    (w, h): (u32, u32),
    (row, col): (u32, u32),
) -> Record {
    let (x, y) = screen_point(row, col, 0.5, 0.5, w, h);
    let dir = camera.direction(x, y);
    let ray = Rays {
        origin: V3::<F64x1>::splat(camera.origin),
        dir: V3::splat(dir),
        leaving: F64x1(-1.0),
    };
    let hit = world.geometry.nearest(&ray, None, true);
    if !hit.hit {
        return MISS;
    }
    // The eye cone of one sample a pixel (`rows::packet`), so textures filter as there.
    let width = world.textured.then(|| {
        let spread = match world.point_sampled {
            true => 0.0,
            false => 2.0 * camera.tan_half_fov / f64::from(w),
        };
        Cone::<F64x1>::eye(spread).at(hit.t)
    });
    // A checker reads the pixel's average, as the frame's eye hits do.
    let pixel = world.checkered().then(|| {
        let at = (F64x1(f64::from(row)), F64x1(f64::from(col)));
        super::rows::pixel_rays((w, h), at, &[camera; MAX_LANES], None)
    });
    let width = width.map(|c| (c, pixel.as_ref()));
    let (n, albedo) = shade::first_surface(world, &ray, &hit, width);
    let p = (ray.origin + ray.dir * hit.t).lane(0);
    let [u, v] = match next {
        Some((next, later)) => {
            let k = hit.object.0 as usize;
            // An object that holds still keeps P exactly (the carry would round).
            let now = &world.scene.objects[k];
            let q = match &later[k] {
                Some(then) if then != now => carried(p, now, then),
                _ => p,
            };
            motion((p, q), camera, next, (w, h))
        }
        None => [0.0; 2],
    };
    let f = |v: DVec3| v.to_array().map(|c| c as f32);
    let ([nx, ny, nz], [ar, ag, ab], [px, py, pz]) = (f(n), f(albedo), f(p));
    [
        nx,
        ny,
        nz,
        ar,
        ag,
        ab,
        hit.object.0 as f32,
        u,
        v,
        px,
        py,
        pz,
    ]
}

/// Where the surface point p of object `now` is when the object is posed `then`: the same
/// point of the object. A sphere's follows its centre and scales with its radius; a mesh's
/// keeps its local coordinates; a plane's turns with the normal (the shortest turn) about the
/// plane's point and follows the point.
fn carried(p: DVec3, now: &Object, then: &Object) -> DVec3 {
    match (now.shape, then.shape) {
        (
            Shape::Sphere {
                center: c0,
                radius: r0,
            },
            Shape::Sphere {
                center: c1,
                radius: r1,
            },
        ) => c1 + (p - c0) * (r1 / r0),
        (Shape::Mesh { place: a, .. }, Shape::Mesh { place: b, .. }) => {
            b.point(a.to_local() * (p - a.translate))
        }
        (
            Shape::Plane {
                point: a,
                normal: na,
                ..
            },
            Shape::Plane {
                point: b,
                normal: nb,
                ..
            },
        ) => b + turned(p - a, na, nb),
        _ => p,
    }
}

/// Where `q` (p one frame later) is in the image of `next` minus where p is in the image of
/// `now`, in pixels: u to the right, v up (Nuke's `forward` vectors). 0 when either is not in
/// front of its camera.
fn motion((p, q): (DVec3, DVec3), now: &Camera, next: &Camera, size: (u32, u32)) -> [f32; 2] {
    match (project(p, now, size), project(q, next, size)) {
        (Some((c0, r0)), Some((c1, r1))) => {
            let (u, v) = ((c1 - c0) as f32, (r0 - r1) as f32);
            match u.is_finite() && v.is_finite() {
                true => [u, v],
                false => [0.0; 2],
            }
        }
        _ => [0.0; 2],
    }
}

/// The image position of `p` seen by `camera`, in pixels from the top left corner (column,
/// row; pixel (i, j)'s centre is at (j + ½, i + ½)), when `p` is in front of it.
fn project(p: DVec3, camera: &Camera, (w, h): (u32, u32)) -> Option<(f64, f64)> {
    let v = p - camera.origin;
    let z = v.dot(camera.forward);
    // Not in front (or NaN): no position in the image.
    if z.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let s = z * camera.tan_half_fov;
    let (x, y) = (v.dot(camera.right) / s, v.dot(camera.up) / s);
    let half = 0.5 * f64::from(w);
    Some(((x + 1.0) * half, 0.5 * f64::from(h) - y * half))
}

/// The id table: one line per object, `ID sphere`, `ID plane` or `ID mesh FILE` (the file
/// name alone, each character that is not printable ASCII as `?`: EXR text is bytes).
pub fn objects(scene: &Scene) -> String {
    let kind = |shape: &Shape| match *shape {
        Shape::Sphere { .. } => "sphere".to_string(),
        Shape::Plane { .. } => "plane".to_string(),
        Shape::Mesh { mesh, .. } => {
            let file = &scene.meshes[mesh].file;
            let name = file.file_name().unwrap_or(file.as_os_str());
            let name: String = (name.to_string_lossy().chars())
                .map(|c| match c {
                    ' '..='~' => c,
                    _ => '?',
                })
                .collect();
            format!("mesh {name}")
        }
    };
    (scene.objects.iter().enumerate())
        .map(|(i, o)| format!("{i} {}", kind(&o.shape)))
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pose;

    fn camera(x: f64) -> Camera {
        Camera::new(&Pose {
            position: DVec3::new(x, 0.0, 1.0),
            look_at: DVec3::new(x, 0.0, 0.0),
            up: DVec3::Y,
            fov: 90.0,
        })
        .unwrap()
    }

    #[test]
    fn pixel_centres_project_to_themselves() {
        let c = camera(0.0);
        let (w, h) = (8, 6);
        for (row, col) in [(0, 0), (2, 5), (5, 7)] {
            let (x, y) = screen_point(row, col, 0.5, 0.5, w, h);
            let p = c.origin + c.direction(x, y) * 3.0;
            let (cx, cy) = project(p, &c, (w, h)).unwrap();
            assert!((cx - (f64::from(col) + 0.5)).abs() < 1e-12, "{cx}");
            assert!((cy - (f64::from(row) + 0.5)).abs() < 1e-12, "{cy}");
        }
    }

    #[test]
    fn a_camera_moving_right_moves_the_picture_left() {
        // fov 90 at distance 1: the image's half width of 4 pixels spans 1 unit.
        let p = DVec3::new(0.0, 0.0, 0.0);
        assert_eq!(
            motion((p, p), &camera(0.0), &camera(0.0), (8, 6)),
            [0.0, 0.0]
        );
        let [u, v] = motion((p, p), &camera(0.0), &camera(0.25), (8, 6));
        assert!((u + 1.0).abs() < 1e-6 && v == 0.0, "{u} {v}");
        // The point moving right by as much, seen from a still camera, moves right.
        let q = DVec3::new(0.25, 0.0, 0.0);
        let [u, v] = motion((p, q), &camera(0.0), &camera(0.0), (8, 6));
        assert!((u - 1.0).abs() < 1e-6 && v == 0.0, "{u} {v}");
        // Both moving together: no motion on screen.
        let [u, v] = motion((p, q), &camera(0.0), &camera(0.25), (8, 6));
        assert!(u.abs() < 1e-6 && v == 0.0, "{u} {v}");
        // A quarter turn of the plane y = 0 to x = 0 about the origin takes +x to −y.
        let t = turned(DVec3::X, DVec3::Y, DVec3::X);
        assert!((t - DVec3::NEG_Y).length() < 1e-15, "{t}");
        assert_eq!(turned(DVec3::Z, DVec3::Y, DVec3::Y), DVec3::Z);
        // Behind the next camera: no motion.
        assert_eq!(
            motion(
                (DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.0, 0.0, 2.0)),
                &camera(0.0),
                &camera(0.0),
                (8, 6)
            ),
            [0.0, 0.0]
        );
    }
}
