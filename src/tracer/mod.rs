//! The core tracer: `render(scene, camera, settings, frame) → Frame`. Pixels are sampled at
//! their centre (1 sample), on a jittered grid, or adaptively; rows spread over the rayon pool.
//! Every pixel depends only on the scene, the camera, the frame number and its own coordinates,
//! so a frame is byte-identical whatever the thread count or order of work.

pub mod accel;
pub mod intersect;
pub mod sample;
pub mod shade;

use crate::camera::{Camera, screen_point};
use crate::frame::Frame;
use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// What decides a frame besides the scene and the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Surfaces one path may visit: 1 = no reflections.
    pub max_depth: u32,
    /// Also record the eye-ray distance to the first hit.
    pub depth: bool,
    /// Eye rays per pixel (uniform sampling), or the first pass of adaptive sampling.
    pub samples: u32,
    pub adaptive: Option<Adaptive>,
    pub sampler: Sampler,
}

/// Adaptive sampling: every pixel gets `samples`; pixels whose samples disagree, or whose
/// neighbours differ, by more than `threshold` are rendered again with `max_samples`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive {
    pub threshold: f32,
    pub max_samples: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampler {
    /// Jittered n×n grid, or R2 low-discrepancy for other counts.
    Stratified,
    /// Independent uniform positions, kept to measure what stratification buys.
    Random,
}

/// A scene ready to trace: the validated data and the geometry built from it once.
#[derive(Debug, Clone)]
pub struct World {
    pub scene: Scene,
    pub geometry: accel::Geometry,
}

impl World {
    pub fn new(scene: Scene) -> World {
        let geometry = accel::Geometry::new(&scene.objects);
        World { scene, geometry }
    }
}

pub fn render(world: &World, camera: &Camera, settings: &Settings, frame: u64) -> Frame {
    render_or_stop(world, camera, settings, frame, &AtomicBool::new(false)).expect("never stopped")
}

/// `render`, given up (`None`) as soon as `stop` is set: it is checked before each row, each
/// pixel and each sample, so even a frame of hours stops within milliseconds.
pub fn render_or_stop(
    world: &World,
    camera: &Camera,
    settings: &Settings,
    frame: u64,
    stop: &AtomicBool,
) -> Option<Frame> {
    let tracer = PixelTracer {
        world,
        camera,
        settings,
        frame,
        stop,
    };
    let (w, h) = (settings.width as usize, settings.height as usize);
    let mut rgb = vec![0f32; 3 * w * h];
    let mut spread = vec![
        0f32;
        if settings.adaptive.is_some() {
            w * h
        } else {
            0
        }
    ];
    let non_finite = AtomicU64::new(0);
    let rays = AtomicU64::new(0);
    let all = Samples::All(settings.samples);
    let mut samples = tracer.pass(&mut rgb, &mut spread, all, |_| true, &non_finite, &rays);
    if let Some(a) = settings.adaptive {
        let marked = mark(&rgb, &spread, w, h, a.threshold);
        let more = Samples::More {
            have: settings.samples,
            total: a.max_samples,
        };
        samples += tracer.pass(&mut rgb, &mut [], more, |i| marked[i], &non_finite, &rays);
    }
    let depth = settings.depth.then(|| tracer.depth());
    if stop.load(Ordering::Relaxed) {
        return None;
    }
    Some(Frame {
        width: settings.width,
        height: settings.height,
        rgb,
        depth,
        non_finite: non_finite.into_inner(),
        samples,
        rays: rays.into_inner(),
    })
}

/// Which samples a pass traces for each selected pixel.
#[derive(Clone, Copy)]
enum Samples {
    /// `n` samples from scratch, in the settings' pattern.
    All(u32),
    /// Extends a pixel that has `have` samples to `total` with R2 samples `have..total`,
    /// which are uniform over the pixel like the first ones, so the mean stays unbiased.
    More { have: u32, total: u32 },
}

struct PixelTracer<'a> {
    world: &'a World,
    camera: &'a Camera,
    settings: &'a Settings,
    frame: u64,
    stop: &'a AtomicBool,
}

impl PixelTracer<'_> {
    /// Renders the pixels `select` picks, rows in parallel; fills `spread` (when not empty)
    /// with each pixel's largest channel range. Returns the number of samples traced.
    fn pass(
        &self,
        rgb: &mut [f32],
        spread: &mut [f32],
        samples: Samples,
        select: impl Fn(usize) -> bool + Sync,
        non_finite: &AtomicU64,
        rays: &AtomicU64,
    ) -> u64 {
        let w = self.settings.width as usize;
        let traced = AtomicU64::new(0);
        let mut spreads: Vec<Option<&mut [f32]>> = if spread.is_empty() {
            (0..self.settings.height).map(|_| None).collect()
        } else {
            spread.chunks_mut(w).map(Some).collect()
        };
        rgb.par_chunks_mut(3 * w)
            .zip(spreads.par_iter_mut())
            .enumerate()
            .for_each(|(row, (rgb_row, spread_row))| {
                let (mut n, mut bad, mut cast) = (0, 0, 0);
                let go_on = || !self.stop.load(Ordering::Relaxed);
                for col in (0..w)
                    .filter(|col| select(row * w + col))
                    .take_while(|_| go_on())
                {
                    let px = &mut rgb_row[3 * col..3 * col + 3];
                    let (sum, range, count) =
                        self.pixel(row as u32, col as u32, samples, &mut cast);
                    let mean = match samples {
                        Samples::All(n) => sum / f64::from(n),
                        Samples::More { have, total } => {
                            (glam::Vec3::from_slice(px).as_dvec3() * f64::from(have) + sum)
                                / f64::from(total)
                        }
                    };
                    let mean = mean.as_vec3().to_array();
                    bad += mean.iter().filter(|v| !v.is_finite()).count() as u64;
                    px.copy_from_slice(&finite(mean));
                    if let Some(s) = spread_row.as_deref_mut() {
                        s[col] = range;
                    }
                    n += u64::from(count);
                }
                traced.fetch_add(n, Ordering::Relaxed);
                rays.fetch_add(cast, Ordering::Relaxed);
                if bad > 0 {
                    non_finite.fetch_add(bad, Ordering::Relaxed);
                }
            });
        traced.into_inner()
    }

    /// Sum of the pixel's samples, their largest per-channel range, and how many there were.
    #[inline]
    fn pixel(&self, row: u32, col: u32, samples: Samples, rays: &mut u64) -> (DVec3, f32, u32) {
        let s = self.settings;
        let index = u64::from(row) * u64::from(s.width) + u64::from(col);
        if let Samples::All(1) = samples {
            // The talk's image: one ray through the pixel centre, nothing to spread.
            let c =
                shade::trace_counted(self.world, self.eye(row, col, 0.5, 0.5), s.max_depth, rays);
            return (c, 0.0, 1);
        }
        let (first, end) = match samples {
            Samples::All(n) => (0, n),
            Samples::More { have, total } => (have, total),
        };
        let (mut sum, mut lo, mut hi) = (DVec3::ZERO, DVec3::INFINITY, DVec3::NEG_INFINITY);
        for k in (first..end).take_while(|_| !self.stop.load(Ordering::Relaxed)) {
            let (u, v) = match (samples, s.sampler) {
                (Samples::More { .. }, _) => sample::r2(self.frame, index, k),
                (Samples::All(n), Sampler::Stratified) => sample::offset(self.frame, index, k, n),
                (Samples::All(_), Sampler::Random) => sample::independent(self.frame, index, k),
            };
            let c = shade::trace_counted(self.world, self.eye(row, col, u, v), s.max_depth, rays);
            sum += c;
            lo = lo.min(c);
            hi = hi.max(c);
        }
        (sum, (hi - lo).max_element() as f32, end - first)
    }

    #[inline]
    fn eye(&self, row: u32, col: u32, u: f64, v: f64) -> intersect::Ray {
        let (x, y) = screen_point(row, col, u, v, self.settings.width, self.settings.height);
        intersect::Ray {
            origin: self.camera.origin,
            dir: self.camera.direction(x, y),
            leaving: None,
        }
    }

    /// Distance along each pixel's centre ray to the first hit (+inf for background).
    fn depth(&self) -> Vec<f32> {
        let w = self.settings.width as usize;
        let mut depth = vec![0f32; w * self.settings.height as usize];
        depth.par_chunks_mut(w).enumerate().for_each(|(row, d)| {
            for (col, z) in d.iter_mut().enumerate() {
                let ray = self.eye(row as u32, col as u32, 0.5, 0.5);
                *z = self
                    .world
                    .geometry
                    .nearest(&ray)
                    .map_or(f32::INFINITY, |h| h.t as f32);
            }
        });
        depth
    }
}

/// Pixels that need more samples: their own samples disagree, or they stand out from their
/// neighbours along a row or column (a second difference, so smooth shading gradients, which
/// antialiasing cannot improve, are left alone while edges and thin features are caught).
fn mark(rgb: &[f32], spread: &[f32], w: usize, h: usize, threshold: f32) -> Vec<bool> {
    let bumps = |a: usize, i: usize, b: usize| {
        (0..3).any(|c| {
            (2.0 * rgb[3 * i + c] - rgb[3 * a + c] - rgb[3 * b + c]).abs() > 2.0 * threshold
        })
    };
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (row, col) = (i / w, i % w);
            spread[i] > threshold
                || (col > 0 && col + 1 < w && bumps(i - 1, i, i + 1))
                || (row > 0 && row + 1 < h && bumps(i - w, i, i + w))
        })
        .collect()
}

/// The last guard before a pixel: a numerical surprise, or a colour beyond f32, never writes
/// NaN or Inf (`Frame::non_finite` counts how often it had to step in).
#[inline]
fn finite(c: [f32; 3]) -> [f32; 3] {
    c.map(|v| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-f32::MAX, f32::MAX)
        }
    })
}
