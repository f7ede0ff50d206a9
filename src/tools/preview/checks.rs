//! Frames where the camera is inside a sphere, behind a plane or rolling over: drawn red on
//! the path plot and reported as warnings by `preview`, `check` and `render`.

use super::*;
use crate::shutter::Exposure;
use crate::tracer::precision::Unresolved;

/// Checks every sampled frame: inside a sphere, behind a plane (the side its normal points
/// away from), or a camera that cannot be built or rolls over since the previous frame.
pub(super) fn problems(seq: &Sequence, samples: &[(u64, Pose)]) -> (Vec<bool>, Vec<String>) {
    let mut bad = vec![false; samples.len()];
    let mut warnings = Vec::new();
    let positions: Vec<DVec3> = samples.iter().map(|(_, p)| p.position).collect();
    let frames: Vec<u64> = samples.iter().map(|(n, _)| *n).collect();
    for (what, flags) in inside_objects(seq, &positions) {
        report(&flags, &frames, &what, &mut bad, &mut warnings);
    }
    let rolls = roll_flags(samples);
    let what = "the camera cannot be built or rolls over by more than 60° from the previous frame";
    report(&rolls, &frames, what, &mut bad, &mut warnings);
    (bad, warnings)
}

/// Distance tests `inside_warnings` may spend: the frames it samples shrink as objects grow.
pub(super) const INSIDE_BUDGET: u64 = 20_000_000;

/// `frames 9-11: the camera is inside objects[0] (sphere)` for every run of frames where the
/// camera is inside a sphere or behind a plane; `check` and `render` print these. Long
/// timelines are sampled (every frame up to 100 000, fewer in scenes of many objects).
pub fn inside_warnings(seq: &Sequence) -> Vec<String> {
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
    let n = (INSIDE_BUDGET / objects).clamp(100, MAX_PATH_SAMPLES);
    let frames = evenly_spaced(t.frame_count, n).into_iter();
    frames.map(|f| f + t.first_frame()).collect()
}

/// `frames 0-40: f32 places objects[3] (sphere) only to 6.1 pixels (limit 4), so it is traced
/// in f64` for every run of frames f32 cannot resolve (see `tracer::precision`), when the
/// settings ask for f32; sampled like `inside_warnings`. The pixels are the run's worst.
pub fn precision_warnings(seq: &Sequence) -> Vec<String> {
    use crate::tracer::{Precision, precision::f32_limit};
    if seq.settings.precision != Precision::F32 {
        return Vec::new();
    }
    let t = &seq.timeline;
    let limits = checked_frames(seq).into_iter().map(|n| {
        let camera = Exposure::of_frame(t, None, n).ok().map(|e| e.camera);
        (
            n,
            camera.and_then(|c| f32_limit(&seq.scene, &c, &seq.settings)),
        )
    });
    let mut runs: Vec<(u64, u64, Unresolved)> = Vec::new();
    for (n, limit) in limits {
        match (runs.last_mut(), limit) {
            (Some((_, last, worst)), Some(u)) if worst.what == u.what => {
                *last = n;
                worst.pixels = worst.pixels.max(u.pixels);
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
pub(super) fn inside_objects(seq: &Sequence, positions: &[DVec3]) -> Vec<(String, Vec<bool>)> {
    let mut reach = Bounds::EMPTY;
    for &p in positions {
        reach.add(p);
    }
    let mut out = Vec::new();
    for (i, o) in seq.scene.objects.iter().enumerate() {
        // A camera in or behind glass looks through it (a slab's two planes always have the
        // camera behind one of them).
        if seq.scene.materials[o.material].transparent() {
            continue;
        }
        let (flags, what): (Vec<bool>, _) = match o.shape {
            // A sphere whose box misses every position's box cannot hold one.
            Shape::Sphere { center, radius } if !reach.grown(radius).contains(center) => continue,
            Shape::Sphere { center, radius } => (
                positions
                    .iter()
                    .map(|p| p.distance(center) < radius)
                    .collect(),
                format!("the camera is inside objects[{i}] (sphere)"),
            ),
            Shape::Plane { point, normal } => (
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
pub(super) fn report(
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

/// The load-time roll check (`sequence::check_every_frame`) repeated on the samples, so a
/// sequence built in code is flagged too.
pub(super) fn roll_flags(samples: &[(u64, Pose)]) -> Vec<bool> {
    let limit = crate::sequence::MAX_ROLL_PER_FRAME_DEGREES
        .to_radians()
        .cos();
    let mut previous: Option<DVec3> = None;
    let mut flags = Vec::with_capacity(samples.len());
    for (_, pose) in samples {
        let flag = match Camera::new(pose) {
            Ok(c) => {
                let rolled = previous.is_some_and(|r| r.dot(c.right) < limit);
                previous = Some(c.right);
                rolled
            }
            Err(_) => true,
        };
        flags.push(flag);
    }
    flags
}

/// Spheres much larger than everything the camera does and looks at.
pub(super) fn huge_spheres(seq: &Sequence, samples: &[(u64, Pose)]) -> Vec<bool> {
    let mut reach = Bounds::EMPTY;
    for (_, p) in samples {
        reach.add(p.position);
        reach.add(p.look_at);
    }
    let size = reach.size().length().max(f64::MIN_POSITIVE);
    let huge = |o: &crate::scene::Object| match o.shape {
        Shape::Sphere { radius, .. } => radius > HUGE_SPHERE * size,
        Shape::Plane { .. } | Shape::Mesh { .. } => false,
    };
    seq.scene.objects.iter().map(huge).collect()
}
