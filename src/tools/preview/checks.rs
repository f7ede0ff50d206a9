//! Frames where the camera is inside a sphere, behind a plane or rolling over: drawn red on
//! the path plot and reported as warnings by `preview` (the inside tests are the ones `check`
//! and `render` warn with, from `crate::warnings`).

use super::*;
use crate::warnings::{inside_objects, report};

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
    let rolls = roll_flags(&seq.timeline, samples);
    let what =
        "the camera cannot be built or its picture rolls by more than 60° since the previous frame";
    report(&rolls, &frames, what, &mut bad, &mut warnings);
    (bad, warnings)
}

/// The load-time roll check (`sequence::check_every_frame`: a roll of the picture about the
/// view axis, not a fast pan) repeated on the samples, so a sequence built in code is flagged
/// too.
pub(super) fn roll_flags(t: &Timeline, samples: &[(u64, Pose)]) -> Vec<bool> {
    let mut previous: Option<(f64, Camera)> = None;
    let mut flags = Vec::with_capacity(samples.len());
    for &(n, pose) in samples {
        let flag = match Camera::new(&pose) {
            Ok(c) => {
                let now = (t.time_of(n), c);
                let rolled =
                    previous.is_some_and(|before| crate::sequence::rolls_over(t, before, now));
                previous = Some(now);
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
