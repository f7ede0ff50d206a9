//! What a valid sequence still deserves a warning for, in one line each: keys the film never
//! shows (found by `sequence::load`), runs of frames with the camera inside an object or behind
//! a plane, and runs of f32 frames traced in f64 because f32 cannot resolve them. `check`,
//! `render` and `camera` print these; `preview` draws the same inside tests in red. Long
//! timelines are sampled (every frame up to `MAX_SAMPLED_FRAMES`, fewer in scenes of many
//! objects).

use crate::camera::Camera;
use crate::console::printable;
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
    all.extend(framing_warnings(seq));
    all.extend(precision_warnings(seq));
    all
}

/// Frames the framing checks look at, evenly spaced: a model seen at all is seen on many.
const FRAMING_FRAMES: u64 = 2000;

/// For each mesh: `the camera starts inside the bounds of objects[2] (statue, models/venus.ply,
/// 52.3 units across): …` when the first frame's camera is inside its placed box, and
/// `objects[2] (…) is never in view: …` when no frame's view (sampled, at most 2000) reaches
/// its box. A model scaled so the camera sits inside it, or placed where the camera never
/// looks, is the usual first mistake with an imported model.
pub(crate) fn framing_warnings(seq: &Sequence) -> Vec<String> {
    let t = &seq.timeline;
    let frames: Vec<u64> = evenly_spaced(t.frame_count, FRAMING_FRAMES)
        .into_iter()
        .map(|f| f + t.first_frame())
        .collect();
    let cameras: Vec<Camera> = frames
        .iter()
        .filter_map(|&n| Camera::new(&t.pose_of(n)).ok())
        .collect();
    let aspect = f64::from(seq.settings.height) / f64::from(seq.settings.width);
    let start = t.pose_of(t.first_frame()).position;
    let mut out = Vec::new();
    let mut unseen = Vec::new();
    for (i, o) in seq.scene.objects.iter().enumerate() {
        let Shape::Mesh { mesh, place, .. } = o.shape else {
            continue;
        };
        let (lo, hi) = seq.scene.mesh_bounds(mesh, &place);
        let across = (hi - lo).max_element();
        let what = format!(
            "objects[{i}] ({}{}, {} units across)",
            seq.object_names[i]
                .as_deref()
                .map(|n| format!("{}, ", printable(n)))
                .unwrap_or_default(),
            printable(&seq.scene.meshes[mesh].file.display().to_string()),
            crate::console::num(round3(across))
        );
        if start.cmpge(lo).all() && start.cmple(hi).all() {
            out.push(format!(
                "the camera starts inside the bounds of {what}: is the model scaled for this scene? (`fit:` gives its size in scene units)"
            ));
        }
        if !cameras.iter().any(|c| may_see(c, aspect, lo, hi)) {
            unseen.push(what);
        }
    }
    out.extend(never_in_view(unseen));
    out
}

/// Meshes past this many that are never in view are counted in one warning, not named each
/// in one of their own (a forest of placements half behind the camera made thousands of lines).
const UNSEEN_NAMED: usize = 3;

/// The warnings for the meshes `unseen` (each as `objects[i] (…)`): one each, or one for all
/// that names the first few and counts the rest.
fn never_in_view(unseen: Vec<String>) -> Vec<String> {
    let why = "no frame's camera looks towards its bounds; aim a key at it with `look_at: { object: NAME }` or check its translate";
    if unseen.len() <= UNSEEN_NAMED {
        return (unseen.into_iter())
            .map(|what| format!("{what} is never in view: {why}"))
            .collect();
    }
    let rest = unseen.len() - UNSEEN_NAMED;
    vec![format!(
        "{} meshes are never in view ({} and {rest} more): {why}",
        unseen.len(),
        unseen[..UNSEEN_NAMED].join(", ")
    )]
}

/// `v` to 3 significant digits, for sizes in messages.
fn round3(v: f64) -> f64 {
    if !(v.is_finite() && v > 0.0) {
        return v;
    }
    let scale = 10f64.powi(2 - v.log10().floor() as i32);
    (v * scale).round() / scale
}

/// Whether the box [lo, hi] may show in the view of `camera` (horizontal half-angle tangent
/// `tan_half_fov`, vertical times `aspect` = height / width): false only when all eight
/// corners lie outside one of the view's four side planes, or behind the camera.
fn may_see(camera: &Camera, aspect: f64, lo: DVec3, hi: DVec3) -> bool {
    let (tx, ty) = (camera.tan_half_fov, camera.tan_half_fov * aspect);
    let corners = (0..8).map(|k| {
        let c = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let d = c - camera.origin;
        (d.dot(camera.right), d.dot(camera.up), d.dot(camera.forward))
    });
    let corners: Vec<(f64, f64, f64)> = corners.collect();
    let all = |f: &dyn Fn(&(f64, f64, f64)) -> bool| corners.iter().all(f);
    !(all(&|c| c.2 <= 0.0)
        || all(&|c| c.0 > tx * c.2)
        || all(&|c| c.0 < -tx * c.2)
        || all(&|c| c.1 > ty * c.2)
        || all(&|c| c.1 < -ty * c.2))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn many_unseen_meshes_make_one_warning() {
        let named = |n: usize| (0..n).map(|i| format!("objects[{i}] (m.ply)")).collect();
        let few = never_in_view(named(3));
        assert_eq!(few.len(), 3);
        assert!(few[2].starts_with("objects[2] (m.ply) is never in view: no frame's camera"));
        let many = never_in_view(named(2600));
        assert_eq!(many.len(), 1);
        assert!(
            many[0].starts_with("2600 meshes are never in view (objects[0] (m.ply), objects[1] (m.ply), objects[2] (m.ply) and 2597 more): no frame's camera"),
            "{}",
            many[0]
        );
    }
}
