//! The core tracer: `render(scene, camera, settings) → Frame`, one eye ray through each pixel
//! centre, rows spread over the rayon pool. Every pixel depends only on the scene, the camera
//! and its own coordinates, so a frame is byte-identical whatever the thread count.

pub mod intersect;
pub mod shade;

use crate::camera::{Camera, screen_point};
use crate::frame::Frame;
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// What decides a frame besides the scene and the camera.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Surfaces one path may visit: 1 = no reflections.
    pub max_depth: u32,
    /// Also record the eye-ray distance to the first hit.
    pub depth: bool,
}

pub fn render(scene: &Scene, camera: &Camera, settings: &Settings) -> Frame {
    let (w, h) = (settings.width, settings.height);
    let row_len = 3 * w as usize;
    let mut rgb = vec![0f32; row_len * h as usize];
    let mut depth = settings.depth.then(|| vec![0f32; (w * h) as usize]);
    let non_finite = AtomicU64::new(0);
    let trace_row = |row: u32, rgb_row: &mut [f32], mut depth_row: Option<&mut [f32]>| {
        let mut bad = 0;
        for col in 0..w {
            let (x, y) = screen_point(row, col, 0.5, 0.5, w, h);
            let eye = intersect::Ray {
                origin: camera.origin,
                dir: camera.direction(x, y),
                leaving: None,
            };
            let sample = shade::trace(scene, eye, settings.max_depth);
            let c = col as usize;
            let color = sample.color.as_vec3().to_array();
            bad += color.iter().filter(|v| !v.is_finite()).count() as u64;
            rgb_row[3 * c..3 * c + 3].copy_from_slice(&finite(color));
            if let Some(d) = depth_row.as_deref_mut() {
                d[c] = sample.depth as f32;
            }
        }
        if bad > 0 {
            non_finite.fetch_add(bad, Ordering::Relaxed);
        }
    };
    match depth.as_mut() {
        Some(depth) => rgb
            .par_chunks_mut(row_len)
            .zip(depth.par_chunks_mut(w as usize))
            .enumerate()
            .for_each(|(row, (c, d))| trace_row(row as u32, c, Some(d))),
        None => rgb
            .par_chunks_mut(row_len)
            .enumerate()
            .for_each(|(row, c)| trace_row(row as u32, c, None)),
    }
    Frame {
        width: w,
        height: h,
        rgb,
        depth,
        non_finite: non_finite.into_inner(),
    }
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
