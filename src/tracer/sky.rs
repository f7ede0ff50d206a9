//! What a ray that leaves the scene sees: the flat background colour, or a sky (an
//! equirectangular image filtered by the ray's footprint, or a gradient). The integrator
//! calls `Background::seen` wherever a ray misses (eye rays, reflection and transmission
//! rays); with a flat colour that is the colour itself, splatted once a packet, so such a
//! scene traces exactly the operations (and writes exactly the bytes) it did before skies.
//! The rules, operation by operation, are in docs/spec/texture.md#the-sky.
//!
//! ```yaml
//! render:
//!   background: { image: skies/noon.exr, rotate: 90, intensity: 1 }
//!   background: { gradient: { zenith: [0.2, 0.35, 0.7], horizon: [0.75, 0.8, 0.85], ground: [0.3, 0.28, 0.25] } }
//! ```
//!
//! A sky is evaluated per lane in f64 from the lanes' values widened exactly (as texture
//! lookups are), so a lane's colour is the same for every packet width.

use super::World;
use super::texture::{floor, trilinear};
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::scene::{Image, Level, Sky};
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// The background of a packet's misses: one colour, or the sky.
pub(super) enum Background<'a, V: Lanes> {
    Flat(V3<V>),
    Sky(&'a Sky),
}

impl<'a, V: Lanes> Background<'a, V> {
    #[inline(always)]
    pub(super) fn of(world: &'a World) -> Background<'a, V> {
        match &world.scene.sky {
            None => Background::Flat(V3::splat(world.scene.background)),
            Some(sky) => Background::Sky(sky),
        }
    }

    /// What the lanes of `missed` see along their directions `dir`; `spread` is the rays'
    /// footprint cone spread (radians) when they carry cones. Other lanes get 0.
    #[inline(always)]
    pub(super) fn seen(&self, dir: &V3<V>, missed: V::M, spread: Option<V>) -> V3<V> {
        match self {
            Background::Flat(c) => *c,
            Background::Sky(sky) => lanes(sky, dir, missed, spread),
        }
    }
}

#[inline(always)]
fn lanes<V: Lanes>(sky: &Sky, dir: &V3<V>, missed: V::M, spread: Option<V>) -> V3<V> {
    let mut out = [DVec3::ZERO; MAX_LANES];
    let widths = match spread {
        Some(s) => s.array(),
        None => [0.0; MAX_LANES],
    };
    for (k, o) in out.iter_mut().enumerate().take(V::N) {
        if missed.lane(k) {
            *o = look(sky, dir.lane(k), widths[k]);
        }
    }
    V3::from_fn(|k| out[k])
}

/// The sky seen along direction `d` (not necessarily unit) by a cone `spread` radians wide.
#[inline(never)]
pub fn look(sky: &Sky, d: DVec3, spread: f64) -> DVec3 {
    match sky {
        Sky::Gradient {
            zenith,
            horizon,
            ground,
        } => {
            let s = d.y / d.dot(d).sqrt();
            if !s.is_finite() {
                return *horizon;
            }
            let (a, other) = if s >= 0.0 { (s, zenith) } else { (-s, ground) };
            *horizon * (1.0 - a) + *other * a
        }
        Sky::Image {
            image,
            rotate,
            intensity,
        } => equirect(image, *rotate, d, spread) * *intensity,
    }
}

/// The equirectangular image along `d`: u = 0.5 + atan2(x, −z)/2π (+ rotate/360) runs along
/// the horizon, from −z at the image's centre towards +x to its right as seen from inside;
/// v = 0.5 + atan2(y, √(x² + z²))/π from the nadir (0) to the zenith (1, the top row).
fn equirect(image: &Image, rotate: f64, d: DVec3, spread: f64) -> DVec3 {
    let phi = libm::atan2(d.x, -d.z);
    let rho = (d.x * d.x + d.z * d.z).sqrt();
    let theta = libm::atan2(d.y, rho);
    let u = (phi / TAU + 0.5) + rotate / 360.0;
    let v = theta / PI + 0.5;
    let last = &image.levels[image.levels.len() - 1];
    if !(u.is_finite() && v.is_finite()) {
        return DVec3::from_array(last.texels[0].map(f64::from));
    }
    let l0 = &image.levels[0];
    let density = (f64::from(l0.width) / TAU).max(f64::from(l0.height) / PI);
    let texels = spread.abs() * density;
    trilinear(image, texels, |level| bilinear(level, u, v))
}

/// Bilinear interpolation at (u, v), repeating along u and clamped to the top and bottom rows
/// along v: texel (i, j)'s centre is at u = (i + 0.5)/width, v = 1 − (j + 0.5)/height.
fn bilinear(level: &Level, u: f64, v: f64) -> DVec3 {
    let (w, h) = (f64::from(level.width), f64::from(level.height));
    let x = (u - floor(u)) * w - 0.5;
    let y = (1.0 - v) * h - 0.5;
    let (x0, y0) = (floor(x), floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let i0 = (x0 as i64).rem_euclid(i64::from(level.width)) as u32;
    let i1 = (i0 + 1) % level.width;
    let row = |j: f64| (j as i64).clamp(0, i64::from(level.height) - 1) as u32;
    let (j0, j1) = (row(y0), row(y0 + 1.0));
    let t = |i: u32, j: u32| {
        DVec3::from_array(level.texels[(j * level.width + i) as usize].map(f64::from))
    };
    (t(i0, j0) * (1.0 - fx) + t(i1, j0) * fx) * (1.0 - fy)
        + (t(i0, j1) * (1.0 - fx) + t(i1, j1) * fx) * fy
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    /// A 4×2 image whose texels are their own column and row.
    fn grid() -> Arc<Image> {
        let texels = (0..8)
            .map(|i| [(i % 4) as f32, (i / 4) as f32, 0.0])
            .collect();
        let level0 = Level {
            width: 4,
            height: 2,
            texels,
        };
        Arc::new(Image {
            file: "grid".into(),
            levels: vec![level0],
            digest: 0,
            bytes: 0,
            load_seconds: 0.0,
        })
    }

    #[test]
    fn the_image_centre_lies_ahead_and_its_right_half_to_the_right() {
        let sky = |rotate| Sky::Image {
            image: grid(),
            rotate,
            intensity: 1.0,
        };
        // Looking down −z, slightly up, the centre of column 1.5 … between columns 1 and 2.
        let ahead = look(&sky(0.0), DVec3::new(0.0, 0.0, -1.0), 0.0);
        assert_eq!(ahead.x, 1.5);
        // +x is a quarter turn to the right: u = 0.75, between columns 2 and 3.
        let right = look(&sky(0.0), DVec3::new(1.0, 0.0, 0.0), 0.0);
        assert_eq!(right.x, 2.5);
        // Turned 90° (right-handed about +y), what was ahead is seen towards −x.
        let turned = look(&sky(90.0), DVec3::new(-1.0, 0.0, 0.0), 0.0);
        assert_eq!(turned.x, 1.5);
        // Straight up is the top row, straight down the bottom one, never mixed.
        assert_eq!(look(&sky(0.0), DVec3::Y, 0.0).y, 0.0);
        assert_eq!(look(&sky(0.0), -DVec3::Y, 0.0).y, 1.0);
    }

    #[test]
    fn a_gradient_blends_by_height() {
        let sky = Sky::Gradient {
            zenith: DVec3::new(0.0, 0.0, 1.0),
            horizon: DVec3::ONE,
            ground: DVec3::ZERO,
        };
        assert_eq!(
            look(&sky, DVec3::new(0.0, 5.0, 0.0), 0.0),
            DVec3::new(0.0, 0.0, 1.0)
        );
        assert_eq!(look(&sky, DVec3::new(2.0, 0.0, 0.0), 0.0), DVec3::ONE);
        assert_eq!(look(&sky, DVec3::new(0.0, -1.0, 0.0), 0.0), DVec3::ZERO);
        let down = look(&sky, DVec3::new(1.0, -1.0, 0.0), 0.0).x;
        assert!((down - (1.0 - 0.5f64.sqrt())).abs() < 1e-15);
    }
}
