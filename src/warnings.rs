//! What a valid sequence still deserves a warning for, in one line each: keys the film never
//! shows (found by `sequence::load`), runs of frames with the camera inside an object or behind
//! a plane, and runs of f32 frames traced in f64 because f32 cannot resolve them. `check`,
//! `render` and `camera` print these; `preview` draws the same inside tests in red. Long
//! timelines are sampled (every frame up to `MAX_SAMPLED_FRAMES`, fewer in scenes of many
//! objects).

use crate::frameset::evenly_spaced;
use crate::scene::Shape;
use crate::sequence::Sequence;
use crate::settings::Precision;
use crate::shutter::Exposure;
use crate::tracer::precision::{Unresolved, f32_limit};
use glam::DVec3;

/// The most frames a check looks at: above this the timeline is sampled evenly, which a smooth
/// path loses nothing to (the path plot samples as many).
pub(crate) const MAX_SAMPLED_FRAMES: u64 = 100_000;

/// Every warning of `seq`, in the order they are printed.
pub(crate) fn for_sequence(seq: &Sequence) -> Vec<String> {
    let mut all = seq.warnings.clone();
    all.extend(inside_warnings(seq));
    all.extend(precision_warnings(seq));
    all
}

/// Distance tests `inside_warnings` may spend: the frames it samples shrink as objects grow.
const INSIDE_BUDGET: u64 = 20_000_000;

/// `frames 9-11: the camera is inside objects[0] (sphere)` for every run of frames where the
/// camera is inside a sphere or behind a plane; `check` and `render` print these. Long
/// timelines are sampled (every frame up to 100 000, fewer in scenes of many objects).
pub(crate) fn inside_warnings(seq: &Sequence) -> Vec<String> {
    let t = &seq.timeline;
    let frames = checked_frames(seq);
    let positions: Vec<DVec3> = frames.iter().map(|&f| t.pose_of(f).position).collect();
    let mut bad = vec![false; frames.len()];
    let mut warnings = Vec::new();
    for (what, flags) in inside_objects(seq, &positions) {
        report(&flags, &frames, &what, &mut bad, &mut warnings);
    }
    warnings
}

/// The frames the warnings look at: every frame up to 100 000, fewer in scenes of many
/// objects (at most `INSIDE_BUDGET` object tests).
fn checked_frames(seq: &Sequence) -> Vec<u64> {
    let t = &seq.timeline;
    let objects = seq.scene.objects.len().max(1) as u64;
    let n = (INSIDE_BUDGET / objects).clamp(100, MAX_SAMPLED_FRAMES);
    let frames = evenly_spaced(t.frame_count, n).into_iter();
    frames.map(|f| f + t.first_frame()).collect()
}

/// `frames 0-40: f32 places objects[3] (sphere) only to 6.1 pixels (limit 4), so it is traced
/// in f64` for every run of frames f32 cannot resolve (see `tracer::precision`), when the
/// settings ask for f32; sampled like `inside_warnings`. The pixels are the run's worst.
pub(crate) fn precision_warnings(seq: &Sequence) -> Vec<String> {
    if seq.settings.precision != Precision::F32 {
        return Vec::new();
    }
    let t = &seq.timeline;
    let limits = checked_frames(seq).into_iter().map(|n| {
        let exposure = Exposure::of_frame(t, seq.settings.shutter, n).ok();
        (
            n,
            exposure.and_then(|e| f32_limit(&seq.scene, &e, &seq.settings)),
        )
    });
    let mut runs: Vec<(u64, u64, Unresolved)> = Vec::new();
    for (n, limit) in limits {
        match (runs.last_mut(), limit) {
            (Some((_, last, worst)), Some(u)) if worst.what == u.what => {
                *last = n;
                if u.excess() > worst.excess() {
                    *worst = u;
                }
            }
            (_, Some(u)) => runs.push((n, n, u)),
            (_, None) => {}
        }
    }
    runs.into_iter()
        .map(|(a, b, u)| match a == b {
            true => format!("frame {a}: {u}"),
            false => format!("frames {a}-{b}: {u}"),
        })
        .collect()
}

/// Per object the camera enters: what to call it and, per position, whether it is inside.
pub(crate) fn inside_objects(seq: &Sequence, positions: &[DVec3]) -> Vec<(String, Vec<bool>)> {
    // The box of the positions: a sphere whose box misses it cannot hold one.
    let low = positions.iter().fold(DVec3::INFINITY, |b, &p| b.min(p));
    let high = positions.iter().fold(DVec3::NEG_INFINITY, |b, &p| b.max(p));
    let near = |c: DVec3, r: f64| {
        let r = DVec3::splat(r);
        c.cmpge(low - r).all() && c.cmple(high + r).all()
    };
    let mut out = Vec::new();
    for (i, o) in seq.scene.objects.iter().enumerate() {
        // A camera in or behind glass looks through it (a slab's two planes always have the
        // camera behind one of them).
        if seq.scene.materials[o.material].transparent() {
            continue;
        }
        let (flags, what): (Vec<bool>, _) = match o.shape {
            Shape::Sphere { center, radius } if !near(center, radius) => continue,
            Shape::Sphere { center, radius } => (
                positions
                    .iter()
                    .map(|p| p.distance(center) < radius)
                    .collect(),
                format!("the camera is inside objects[{i}] (sphere)"),
            ),
            Shape::Plane { point, normal, .. } => (
                positions
                    .iter()
                    .map(|&p| (p - point).dot(normal) < 0.0)
                    .collect(),
                format!("the camera is behind objects[{i}] (plane), against its normal"),
            ),
            // A mesh need not be closed: being inside its box says nothing.
            Shape::Mesh { .. } => continue,
        };
        if flags.contains(&true) {
            out.push((what, flags));
        }
    }
    out
}

/// Turns per-sample flags into one warning per run of consecutive flagged samples.
pub(crate) fn report(
    flags: &[bool],
    frames: &[u64],
    what: &str,
    bad: &mut [bool],
    warnings: &mut Vec<String>,
) {
    let mut i = 0;
    while i < flags.len() {
        if !flags[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < flags.len() && flags[i] {
            bad[i] = true;
            i += 1;
        }
        let (a, b) = (frames[start], frames[i - 1]);
        let frames = if a == b {
            format!("frame {a}")
        } else {
            format!("frames {a}-{b}")
        };
        warnings.push(format!("{frames}: {what}"));
    }
}
