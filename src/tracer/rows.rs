//! One pass over one row of a frame, for any lane type: the selected pixels are taken N at a
//! time (adjacent ones, so their rays are coherent), and each packet traces sample k of all
//! its pixels together, for k in order. Every pixel therefore sums exactly the samples it
//! summed one ray at a time, in the same order, and its value cannot depend on the width.

use super::accel::{FromOrigin, Rays};
use super::lanes::{Lanes, Mask};
use super::shade::{self, Eye};
use super::vec3::V3;
use super::{Sampler, Samples, Settings, World, finite, sample};
use crate::camera::{Camera, screen_points};
use glam::{DVec3, Vec3};

/// Everything one pass over a frame needs, shared by its rows.
pub(super) struct Pass<'a> {
    pub world: &'a World,
    pub camera: &'a Camera,
    pub settings: &'a Settings,
    pub frame: u64,
    pub samples: Samples,
    /// Pixels this pass renders: all, or those marked (row-major).
    pub marked: Option<&'a [bool]>,
    /// `Geometry::from_origin` of the camera position.
    pub from_origin: &'a [FromOrigin],
}

/// One row's slice of the frame: 3 floats per pixel, and each pixel's sample spread (the
/// largest channel range) when the pass records it.
pub(super) struct RowOut<'a> {
    pub rgb: &'a mut [f32],
    pub spread: Option<&'a mut [f32]>,
}

#[derive(Debug, Default, Clone, Copy)]
pub(super) struct RowStats {
    pub samples: u64,
    pub rays: u64,
    pub non_finite: u64,
}

impl std::ops::Add for RowStats {
    type Output = RowStats;
    fn add(self, o: RowStats) -> RowStats {
        RowStats {
            samples: self.samples + o.samples,
            rays: self.rays + o.rays,
            non_finite: self.non_finite + o.non_finite,
        }
    }
}

#[inline(always)]
pub(super) fn row<V: Lanes>(pass: &Pass, row: u32, mut out: RowOut) -> RowStats {
    let w = pass.settings.width;
    let mut stats = RowStats::default();
    let mut cols = [0u32; 16];
    let mut n = 0;
    for col in 0..w {
        let index = row as usize * w as usize + col as usize;
        if pass.marked.is_some_and(|m| !m[index]) {
            continue;
        }
        cols[n] = col;
        n += 1;
        if n == V::N {
            packet::<V>(pass, row, &cols[..n], &mut out, &mut stats);
            n = 0;
        }
    }
    if n > 0 {
        packet::<V>(pass, row, &cols[..n], &mut out, &mut stats);
    }
    stats
}

/// Traces every sample of up to N pixels of one row and stores their means. Lane k's sum,
/// range and mean are the scalar ones of its pixel: glam's `DVec3::min`/`max` and
/// `max_element` compare exactly as the lanes' `min`/`max` do.
#[inline(always)]
fn packet<V: Lanes>(pass: &Pass, row: u32, cols: &[u32], out: &mut RowOut, stats: &mut RowStats) {
    let s = pass.settings;
    let last = cols.len() - 1;
    // Lanes past the last pixel repeat it: a valid ray, masked out of every result.
    let col = V::from_fn(|k| f64::from(cols[k.min(last)]));
    let index = |k: usize| u64::from(row) * u64::from(s.width) + u64::from(cols[k.min(last)]);
    let (first, end) = match pass.samples {
        Samples::All(n) => (0, n),
        Samples::More { have, total } => (have, total),
    };
    let range = out.spread.is_some() && end - first > 1;
    let mut sum = V3::<V>::zero();
    let (mut lo, mut hi) = (
        V3::<V>::splat(DVec3::INFINITY),
        V3::<V>::splat(DVec3::NEG_INFINITY),
    );
    for k in first..end {
        let (u, v) = offsets::<V>(pass, &index, k);
        let dir = eye_directions(pass, row, col, u, v);
        let eye = Eye {
            rays: Rays {
                origin: V3::splat(pass.camera.origin),
                dir,
                leaving: V::splat(-1.0),
            },
            active: V::M::first(cols.len()),
            from_origin: Some(pass.from_origin),
        };
        let c = shade::trace_packet(pass.world, &eye, s.max_depth, &mut stats.rays);
        sum = sum + c;
        if range {
            lo = V3 {
                x: lo.x.min(c.x),
                y: lo.y.min(c.y),
                z: lo.z.min(c.z),
            };
            hi = V3 {
                x: hi.x.max(c.x),
                y: hi.y.max(c.y),
                z: hi.z.max(c.z),
            };
        }
    }
    if let Some(spread) = out.spread.as_deref_mut() {
        let d = hi - lo;
        let widest = d.x.max(d.y).max(d.z).array();
        for (lane, &col) in cols.iter().enumerate() {
            spread[col as usize] = if range { widest[lane] as f32 } else { 0.0 };
        }
    }
    let mean = match pass.samples {
        // x / 1 = x exactly: one sample needs no division.
        Samples::All(1) => sum,
        Samples::All(n) => sum / V::splat(f64::from(n)),
        Samples::More { have, total } => {
            // Each pixel folds in the f32 mean it already had.
            let old =
                V3::from_fn(|k| Vec3::from_slice(pixel(out.rgb, cols[k.min(last)])).as_dvec3());
            (old * V::splat(f64::from(have)) + sum) / V::splat(f64::from(total))
        }
    };
    let (x, y, z) = (mean.x.array(), mean.y.array(), mean.z.array());
    for (lane, &col) in cols.iter().enumerate() {
        let m = [x[lane] as f32, y[lane] as f32, z[lane] as f32];
        stats.non_finite += m.iter().filter(|v| !v.is_finite()).count() as u64;
        out.rgb[3 * col as usize..3 * col as usize + 3].copy_from_slice(&finite(m));
    }
    stats.samples += u64::from(end - first) * cols.len() as u64;
}

fn pixel(rgb: &[f32], col: u32) -> &[f32] {
    &rgb[3 * col as usize..3 * col as usize + 3]
}

/// Sub-pixel offsets of sample `k` for each lane's pixel (see `sample`).
#[inline(always)]
fn offsets<V: Lanes>(pass: &Pass, index: &impl Fn(usize) -> u64, k: u32) -> (V, V) {
    let f = pass.frame;
    let pick = |i: usize| match (pass.samples, pass.settings.sampler) {
        (Samples::More { .. }, _) => sample::r2(f, index(i), k),
        (Samples::All(n), Sampler::Stratified) => sample::offset(f, index(i), k, n),
        (Samples::All(_), Sampler::Random) => sample::independent(f, index(i), k),
    };
    if let Samples::All(1) = pass.samples {
        // The talk's image: one ray through the pixel centre, whatever the sampler.
        return (V::splat(0.5), V::splat(0.5));
    }
    let (mut u, mut v) = ([0.0; 16], [0.0; 16]);
    for i in 0..V::N {
        (u[i], v[i]) = pick(i);
    }
    (V::load(&u), V::load(&v))
}

#[inline(always)]
fn eye_directions<V: Lanes>(pass: &Pass, row: u32, col: V, u: V, v: V) -> V3<V> {
    let s = pass.settings;
    let (x, y) = screen_points(V::splat(f64::from(row)), col, u, v, s.width, s.height);
    pass.camera.directions(x, y)
}

/// Distance along each pixel centre's eye ray to the first hit (+inf for background).
#[inline(always)]
pub(super) fn depth<V: Lanes>(pass: &Pass, row: u32, out: &mut [f32]) {
    let w = pass.settings.width as usize;
    let half = V::splat(0.5);
    for first in (0..w).step_by(V::N) {
        let n = V::N.min(w - first);
        let col = V::from_fn(|k| (first + k.min(n - 1)) as f64);
        let rays = Rays {
            origin: V3::splat(pass.camera.origin),
            dir: eye_directions(pass, row, col, half, half),
            leaving: V::splat(-1.0),
        };
        let hit = pass
            .world
            .geometry
            .nearest(&rays, Some(pass.from_origin), V::M::first(n));
        let t = hit.t.array();
        for k in 0..n {
            out[first + k] = if hit.hit.lane(k) {
                t[k] as f32
            } else {
                f32::INFINITY
            };
        }
    }
}
