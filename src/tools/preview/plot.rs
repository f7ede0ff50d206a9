//! What the path plot shows, computed once from the sequence: the sampled camera path, its
//! problems, keyframes, targets and the box both panels are fitted to.

use super::*;

/// Above this many frames the path is drawn from evenly spaced samples: a smooth path loses
/// nothing visible, and the plot stays fast for timelines of millions of frames.
pub(super) const MAX_PATH_SAMPLES: u64 = crate::warnings::MAX_SAMPLED_FRAMES;

/// A sphere this many times larger than the whole camera motion and view (a floor of radius
/// 9000, a sky dome) is scenery: its silhouette would fill both panels, so it is drawn like a
/// plane and left out of the fit.
pub(super) const HUGE_SPHERE: f64 = 10.0;

/// Look-at targets and lights farther out than this fraction of the scene's size (beyond the
/// box of path and objects) would shrink the scene to a speck (a sun at 1e5); they are drawn
/// at the panel edge with their coordinates instead of being fitted.
pub(super) const EXTRA_REACH: f64 = 0.5;

/// Points along each moving object's or light's path: enough for a smooth curve, few enough
/// that a thousand moving things draw in a moment.
pub(super) const THING_SAMPLES: u64 = 256;

/// Moving things whose paths are drawn (the first in the file); `check` counts the rest.
pub(super) const MAX_THINGS: usize = 64;

/// View-direction ticks drawn along the path.
pub(super) const TICKS: u64 = 12;

/// Everything the path plot draws, computed once from the sequence.
pub(super) struct Plot {
    /// (frame, pose) for every frame, or evenly spaced samples of very long timelines.
    pub(super) samples: Vec<(u64, Pose)>,
    /// Per sample: the camera is inside an object or rolls over there.
    pub(super) bad: Vec<bool>,
    pub(super) warnings: Vec<String>,
    /// Keyframe (position, look_at), numbered by index.
    pub(super) keys: Vec<(DVec3, DVec3)>,
    /// Distinct look-at targets of the keyframes, or the orbit's.
    pub(super) targets: Vec<DVec3>,
    /// Per object: a sphere too big to draw as a disc.
    pub(super) huge: Vec<bool>,
    /// Each moving object or light that has a place (`anchor`), and that place at evenly
    /// spaced frames from first to last.
    pub(super) moving: Vec<(Thing, Vec<DVec3>)>,
    /// The box the panels are fitted to.
    pub(super) fit: Bounds,
}

impl Plot {
    pub(super) fn new(seq: &Sequence) -> Plot {
        let t = &seq.timeline;
        let samples: Vec<(u64, Pose)> = evenly_spaced(t.frame_count, MAX_PATH_SAMPLES)
            .into_iter()
            .map(|n| n + t.first_frame())
            .map(|n| (n, t.pose_of(n)))
            .collect();
        let (bad, warnings) = problems(seq, &samples);
        let (keys, targets) = keys_and_targets(t);
        let huge = huge_spheres(seq, &samples);
        let moving = moving_paths(seq);
        let mut plot = Plot {
            samples,
            bad,
            warnings,
            keys,
            targets,
            huge,
            moving,
            fit: Bounds::EMPTY,
        };
        plot.fit = fit(seq, &plot);
        plot
    }
}

pub(super) fn keys_and_targets(t: &Timeline) -> (Vec<(DVec3, DVec3)>, Vec<DVec3>) {
    match &t.path {
        TimelinePath::Orbit(o) => (Vec::new(), vec![o.look_at]),
        TimelinePath::Keys(keyed) => {
            let keys = &keyed.keys;
            let mut targets: Vec<DVec3> = Vec::new();
            for k in keys {
                if !targets.contains(&k.pose.look_at) {
                    targets.push(k.pose.look_at);
                }
            }
            let keyed = keys.iter().map(|k| (k.pose.position, k.pose.look_at));
            (keyed.collect(), targets)
        }
    }
}

/// The paths of moving things (the first `MAX_THINGS`), each at `THING_SAMPLES` frames.
pub(super) fn moving_paths(seq: &Sequence) -> Vec<(Thing, Vec<DVec3>)> {
    let t = &seq.timeline;
    let frames = evenly_spaced(t.frame_count, THING_SAMPLES);
    let rigs = t.motion.iter().take(MAX_THINGS);
    rigs.filter_map(|rig| {
        let at = |n: &u64| anchor(seq, rig.at(t.time_of(n + t.first_frame())));
        let path: Option<Vec<DVec3>> = frames.iter().map(at).collect();
        path.map(|p| (rig.thing, p))
    })
    .collect()
}

/// Where a thing is: a sphere's centre, a mesh's placed bounds' centre, a plane's point, a
/// light's position (a rect's corner); None for a directional or ambient light.
fn anchor(seq: &Sequence, posed: Posed) -> Option<DVec3> {
    match posed {
        Posed::Object(o) => Some(match o.shape {
            Shape::Sphere { center, .. } => center,
            Shape::Plane { point, .. } => point,
            Shape::Mesh { mesh, place, .. } => {
                let (lo, hi) = seq.scene.mesh_bounds(mesh, &place);
                (lo + hi) * 0.5
            }
        }),
        Posed::Light(l) => l.position(),
    }
}

/// Point and spot lights: (index in `lights`, position).
pub(super) fn positioned_lights(seq: &Sequence) -> Vec<(usize, DVec3)> {
    let lights = seq.scene.lights.iter().enumerate();
    lights
        .filter_map(|(i, l)| l.position().map(|p| (i, p)))
        .collect()
}

/// The box both panels show: the camera path, the keyframes (the last may lie beyond the last
/// frame) and the ordinary spheres, plus look-at targets and lights not far outside them.
pub(super) fn fit(seq: &Sequence, plot: &Plot) -> Bounds {
    let mut core = Bounds::EMPTY;
    let keys = plot.keys.iter().map(|k| k.0);
    for p in plot.samples.iter().map(|(_, p)| p.position).chain(keys) {
        core.add(p);
    }
    // Planes' points slide along their plane, anywhere: only spheres' and meshes' paths are
    // fitted (moving lights are fitted below, as still ones are, when near).
    for (thing, path) in &plot.moving {
        if let Thing::Object(i) = thing
            && !matches!(seq.scene.objects[*i].shape, Shape::Plane { .. })
        {
            path.iter().for_each(|&p| core.add(p));
        }
    }

    for (o, &huge) in seq.scene.objects.iter().zip(&plot.huge) {
        if let (Shape::Sphere { center, radius }, false) = (o.shape, huge) {
            core.add(center - DVec3::splat(radius));
            core.add(center + DVec3::splat(radius));
        }
        if let Shape::Mesh { mesh, place, .. } = o.shape {
            let (lo, hi) = seq.scene.mesh_bounds(mesh, &place);
            core.add(lo);
            core.add(hi);
        }
    }
    // A still camera with nothing around it still needs a size: its distance to the target.
    let first = plot.samples[0].1;
    let floor = first.position.distance(first.look_at).max(1e-300);
    let size = core.size().max_element().max(floor);
    let near = core.grown(EXTRA_REACH * size);
    let mut all = core;
    let lights = positioned_lights(seq).into_iter().map(|(_, p)| p);
    let moving_lights = plot
        .moving
        .iter()
        .filter(|(thing, _)| matches!(thing, Thing::Light(_)))
        .flat_map(|(_, path)| path.iter().copied());
    let extra = plot.targets.iter().copied().chain(lights);
    for p in extra.chain(moving_lights) {
        if near.contains(p) {
            all.add(p);
        }
    }
    // No axis may be flat, or a panel's scale would be infinite.
    let min = 0.1 * all.size().max_element().max(floor);
    all.at_least(min)
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Bounds {
    pub(super) min: DVec3,
    pub(super) max: DVec3,
}

impl Bounds {
    pub(super) const EMPTY: Bounds = Bounds {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    pub(super) fn add(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub(super) fn size(&self) -> DVec3 {
        (self.max - self.min).max(DVec3::ZERO)
    }

    pub(super) fn grown(&self, by: f64) -> Bounds {
        Bounds {
            min: self.min - DVec3::splat(by),
            max: self.max + DVec3::splat(by),
        }
    }

    pub(super) fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Widens every axis shorter than `min` around its middle.
    pub(super) fn at_least(&self, min: f64) -> Bounds {
        let mid = (self.min + self.max) / 2.0;
        let half = self.size().max(DVec3::splat(min)) / 2.0;
        Bounds {
            min: mid - half,
            max: mid + half,
        }
    }
}
