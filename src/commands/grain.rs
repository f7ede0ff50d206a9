//! `check`'s grain estimate. A moving camera under an open shutter, or an open lens, smears
//! each point over several pixels; each sample of a pixel sees one instant and one point of
//! the lens, so few samples give a dithered, grainy smear instead of a smooth one. This
//! measures the smear in pixels on the frames and compares the most samples a pixel can get
//! with what a smooth smear was measured to need.

use crate::camera::Camera;
use crate::scene::{Scene, Shape};
use crate::sequence::Sequence;
use crate::shutter::Exposure;
use glam::DVec3;

/// Most samples a pixel needs for a smear of a pixel or more to look smooth, from the
/// fly-around measured when this warning was asked for (180° shutter, focus pull, 1280×720,
/// against 256 samples, 2026-11-24): 2–8 adaptive 38.8 dB with 4.1% of pixels off by more than 8 levels, 16
/// uniform 43.9 dB and 1.4%, `final` (4–64 adaptive) 49.2 dB and 0.17%.
pub(crate) const SMOOTH_SAMPLES: u32 = 64;
/// Smears under a pixel look like antialiasing, not grain.
const GRAIN_PIXELS: f64 = 1.0;
/// Frames measured: every frame of a short sequence, this many evenly spaced of a long one.
const PROBED_FRAMES: u64 = 240;
/// Screen points whose smear is measured: the centre and near the four corners.
const PROBES: [(f64, f64); 5] = [
    (0.0, 0.0),
    (-0.9, -0.9),
    (-0.9, 0.9),
    (0.9, -0.9),
    (0.9, 0.9),
];

/// A warning when frames will look grainy, naming the frames, the smear and what to change.
pub(crate) fn warning(seq: &Sequence) -> Option<String> {
    let s = &seq.settings;
    let most = s.adaptive.map_or(s.samples, |a| a.max_samples);
    if most >= SMOOTH_SAMPLES {
        return None;
    }
    let t = &seq.timeline;
    let step = t.frame_count.div_ceil(PROBED_FRAMES).max(1);
    let (mut motion, mut lens) = (0.0_f64, 0.0_f64);
    let mut grainy: Option<(u64, u64)> = None;
    for n in (t.first_frame()..=t.last_frame()).step_by(step as usize) {
        let Ok(e) = Exposure::of_frame(t, s.shutter, n) else {
            continue;
        };
        let m = motion_pixels(&e, s.width, s.height);
        let l = lens_pixels(&e.camera, s.width, &seq.scene);
        (motion, lens) = (motion.max(m), lens.max(l));
        if m.max(l) >= GRAIN_PIXELS {
            grainy = Some(grainy.map_or((n, n), |(first, _)| (first, n)));
        }
    }
    let (first, last) = grainy?;
    let frames = match first == last {
        true => format!("frame {first}"),
        false => format!("frames {first} to {last}"),
    };
    let mut smears = Vec::new();
    if motion >= GRAIN_PIXELS {
        smears.push(format!("the shutter smears up to {motion:.0} pixels"));
    }
    if lens >= GRAIN_PIXELS {
        smears.push(format!("the lens blurs up to {lens:.0} pixels"));
    }
    Some(format!(
        "warning: {frames} may look grainy: {} with at most {most} sample{} a pixel (a smooth blur takes about {SMOOTH_SAMPLES}); render with --quality final, or set render.adaptive.max_samples: {SMOOTH_SAMPLES}",
        smears.join(" and "),
        if most == 1 { "" } else { "s" },
    ))
}

/// How far, in pixels, the points the frame's camera sees at its focus distance move on the
/// screen between the shutter's first and last instants.
fn motion_pixels(e: &Exposure, width: u32, height: u32) -> f64 {
    let (Some(open), Some(close)) = (e.instants.first(), e.instants.last()) else {
        return 0.0;
    };
    let (c, aspect) = (&e.camera, f64::from(height) / f64::from(width));
    PROBES
        .iter()
        .map(|&(x, y)| {
            let seen = c.origin + c.direction(x, y * aspect) * c.focus_distance;
            match (screen(open, seen), screen(close, seen)) {
                (Some(a), Some(b)) => a.distance(b) * 0.5 * f64::from(width),
                _ => f64::INFINITY,
            }
        })
        .fold(0.0, f64::max)
}

/// Where `p` falls on `camera`'s screen (x across [-1, 1] over the width), if in front of it.
fn screen(camera: &Camera, p: DVec3) -> Option<glam::DVec2> {
    let d = p - camera.origin;
    let z = d.dot(camera.forward);
    (z > 0.0).then(|| {
        let scale = 1.0 / (z * camera.tan_half_fov);
        glam::DVec2::new(d.dot(camera.right) * scale, d.dot(camera.up) * scale)
    })
}

/// The widest circle of confusion, in pixels, of the scene's spheres (and of the horizon when
/// the scene has planes or meshes, which reach to infinity or may): a thin lens of aperture A
/// focused at f blurs a point at depth d over A·|d − f|/d on the focal plane.
fn lens_pixels(c: &Camera, width: u32, scene: &Scene) -> f64 {
    if c.lens_radius == 0.0 {
        return 0.0;
    }
    let f = c.focus_distance;
    // Pixels per scene unit on the focal plane, times the aperture.
    let aperture_pixels = 2.0 * c.lens_radius / (f * c.tan_half_fov) * 0.5 * f64::from(width);
    let pixels = |d: f64| aperture_pixels * (d - f).abs() / d;
    // The limit of `pixels` as d grows without bound.
    let horizon = aperture_pixels;
    scene
        .objects
        .iter()
        .map(|o| match &o.shape {
            Shape::Sphere { center, radius } => {
                let d = (*center - c.origin).dot(c.forward);
                // A sphere behind the camera or around it: its nearest visible depth is unknown.
                match d - radius > 0.0 {
                    true => pixels(d - radius).max(pixels(d + radius)),
                    false => 0.0,
                }
            }
            _ => horizon,
        })
        .fold(0.0, f64::max)
}
