//! The integrator: follows a packet of eye rays along mirror paths (or, when some material
//! transmits or reflects by angle, through `glass::trace_tree`'s trees), summing what
//! `shade` finds at each surface: i0 + r0·i1 + r0·r1·i2 + … over at most `max_depth` surfaces.
//! Eye rays carry their footprint cones when the scene has textures (`texture`) and their
//! pixels' light seeds when it has area lights (`area`).

use super::World;
use super::accel::{FromOrigin, Nearest, Rays};
use super::area::Discs;
use super::intersect::Ray;
use super::shade::{NEGLIGIBLE_WEIGHT, shade_hit};
use super::sky::Background;
use super::texture::{self, Cone, PixelRays};
use crate::lanes::{F64x1, Lanes, MAX_LANES, Mask, V3};
use crate::scene::Shape;
use glam::DVec3;

/// A packet of eye rays: `active` lanes carry a ray; `from_origin` is set when they all start
/// at one point (a pinhole camera), so per-sphere constants are computed once a frame.
pub struct Eye<'a, V: Lanes> {
    pub rays: Rays<V>,
    pub active: V::M,
    pub from_origin: Option<&'a [FromOrigin]>,
    /// Eye rays that miss add nothing (a transparent background, for alpha); reflection rays
    /// that miss still see the background.
    pub transparent: bool,
    /// The eye rays' footprint spread (radians) when the scene has textures (`texture::Cone`).
    pub footprint: Option<f64>,
    /// Each lane's pixel, where the scene has a checker and filters textures: a checker at
    /// the eye rays' first hits is averaged over it (`texture::PixelRays`).
    pub pixel: Option<&'a PixelRays<V>>,
    /// Which points each lane takes on area lights: set only when the scene has some (None
    /// stands for pixel 0 of frame 0, sample 0, in every lane).
    pub lights: Option<LightSeeds<'a>>,
}

/// Each lane's pixel light state (`sample::light_seed`) and the index k of the eye sample the
/// packet traces: area lights take points k·m … k·m + m − 1 of each lane's sequence. Every
/// surface of the sample's path or tree uses them.
#[derive(Clone, Copy)]
pub struct LightSeeds<'a> {
    pub seeds: &'a [u64; MAX_LANES],
    pub k: u32,
    /// The points' coordinates this sample's paths share (`area::Discs`, cleared for it).
    pub discs: &'a Discs,
}

/// Follows one eye ray through at most `max_depth` surfaces; returns its colour (the one-lane
/// packet, for tests and tools).
pub fn trace(world: &World, eye: Ray, max_depth: u32) -> DVec3 {
    let eye = Eye {
        rays: Rays {
            origin: V3::<F64x1>::splat(eye.origin),
            dir: V3::splat(eye.dir),
            leaving: F64x1(eye.leaving.map_or(-1.0, |o| o as f64)),
        },
        active: true,
        from_origin: None,
        transparent: false,
        footprint: world.textured.then_some(0.0),
        pixel: None,
        lights: None,
    };
    trace_packet(world, &eye, max_depth, &mut 0).0.lane(0)
}

/// Follows each lane's eye ray through at most `max_depth` surfaces; returns its colour and
/// the lanes whose eye ray hit something, and adds the rays cast (eye, reflection and shadow
/// rays) to `rays`.
#[inline(always)]
pub fn trace_packet<V: Lanes>(
    world: &World,
    eye: &Eye<V>,
    max_depth: u32,
    rays: &mut u64,
) -> (V3<V>, V::M) {
    // The pair, not `Traced`, out of the outlined call: its other fields are then dead.
    V::outlined(
        #[inline(always)]
        || {
            let t = follow::<V, false>(world, eye, max_depth, rays);
            (t.color, t.covered)
        },
    )
}

/// `trace_packet` that also says which lanes' samples are smooth on the object their eye
/// ray hit (docs/spec/tracer.md, *Smooth pixels*), for worlds that `tracks_smooth`.
#[inline(always)]
pub(super) fn trace_smooth<V: Lanes>(
    world: &World,
    eye: &Eye<V>,
    max_depth: u32,
    rays: &mut u64,
) -> Traced<V> {
    V::outlined(
        #[inline(always)]
        || follow::<V, true>(world, eye, max_depth, rays),
    )
}

/// What a packet's paths found: each lane's colour, the lanes whose eye ray hit something,
/// and (only when asked for) the lanes smooth on `object`, their eye rays' first objects.
pub(super) struct Traced<V: Lanes> {
    pub color: V3<V>,
    pub covered: V::M,
    pub smooth: V::M,
    pub object: V,
}

/// The paths of a packet; with `SMOOTH`, also which lanes are smooth (a separate copy of the
/// walk, so frames that do not ask pay nothing for it).
#[inline(always)]
fn follow<V: Lanes, const SMOOTH: bool>(
    world: &World,
    eye: &Eye<V>,
    max_depth: u32,
    rays: &mut u64,
) -> Traced<V> {
    if world.branches {
        // Out of line: inlined here, the tree doubled the packet function, and its compile
        // time (superlinear in a function's size) with it; a call per packet costs nothing.
        let (color, covered) = V::outlined(
            #[inline(always)]
            || super::glass::trace_tree(world, eye, max_depth, rays),
        );
        // Trees make no pixel smooth.
        let (smooth, object) = (V::M::none_set(), V::splat(-1.0));
        return Traced {
            color,
            covered,
            smooth,
            object,
        };
    }
    let background = Background::of(world);
    let mut ray = eye.rays;
    let mut active = eye.active;
    let mut color = V3::zero();
    let mut weight = V::splat(1.0);
    let mut covered = V::M::none_set();
    let (mut smooth, mut object) = (V::M::none_set(), V::splat(-1.0));
    // `match`, not `Option::map`: a closure is compiled outside the kernel's
    // `#[target_feature]` function, and lane operations must stay in it.
    #[allow(clippy::manual_map)]
    let mut cone = match eye.footprint {
        Some(spread) => Some(Cone::<V>::eye(spread)),
        None => None,
    };
    for depth in 0..max_depth {
        *rays += active.count();
        let from_origin = if depth == 0 { eye.from_origin } else { None };
        let hit = world.geometry.nearest(&ray, from_origin, active);
        let missed = active.andnot(hit.hit);
        if missed.any() && !(depth == 0 && eye.transparent) {
            // `match`, not `Option::map`, as for `cone` above.
            #[allow(clippy::manual_map)]
            let spread = match &cone {
                Some(c) => Some(c.spread),
                None => None,
            };
            let seen = background.seen(&ray.dir, missed, spread);
            color = V3::select(missed, color + seen * weight, color);
        }
        if SMOOTH && depth == 1 {
            // Clause 4: the reflection leaves into a constant background.
            smooth = match world.scene.sky {
                None => smooth.andnot(hit.hit),
                Some(_) => smooth.andnot(active),
            };
        }
        active = hit.hit;
        if depth == 0 {
            covered = hit.hit;
            object = hit.object;
        }
        if !active.any() {
            break;
        }
        let pixel = if depth == 0 { eye.pixel } else { None };
        #[allow(clippy::manual_map)]
        let width = match &cone {
            Some(c) => Some((c.at(hit.t), pixel)),
            None => None,
        };
        let at = shade_hit(world, &ray, &hit, eye.lights, rays, width);
        if SMOOTH && depth == 0 {
            smooth = smooth_hits(world, &hit, at.surface.meaned).andnot(at.dark);
        }
        color = V3::select(active, color + at.local * weight, color);
        weight = weight * at.surface.reflection;
        active = active.andnot(weight.lt(V::splat(NEGLIGIBLE_WEIGHT)));
        if !active.any() || depth + 1 == max_depth {
            break;
        }
        ray = at.reflected(&ray, &hit);
        if let Some(c) = &cone {
            let bend = texture::curvature(world, hit.object);
            cone = Some(c.leaving(hit.t, bend, at.entering));
        }
    }
    Traced {
        color,
        covered,
        smooth,
        object,
    }
}

/// The lanes of `hit` on a sphere or a plane whose every texture took its pixel's mean
/// (`meaned`, bit k for lane k): clauses 1 and 2 of *Smooth pixels*.
#[inline(always)]
fn smooth_hits<V: Lanes>(world: &World, hit: &Nearest<V>, meaned: u32) -> V::M {
    let (objects, ids) = (&world.scene.objects, hit.object.array());
    let lanes = hit.hit.bits() & meaned;
    let bits = (0..V::N)
        .filter(|&k| lanes >> k & 1 == 1)
        .filter(|&k| !matches!(objects[ids[k] as usize].shape, Shape::Mesh { .. }))
        .fold(0u32, |b, k| b | 1 << k);
    V::M::from_bits(bits)
}
