//! Area lights (sphere and rect): each eye sample takes `samples` points on the light, each
//! lit like a point light carrying 1/samples of it. The points continue one (0,2)-sequence
//! through a pixel's samples (point j of sample k is point k·samples + j), XOR-shifted per
//! (frame, pixel, light); a sphere is sampled on the disk through its centre that faces the
//! shading point. Points are placed per lane in f64 from the lane's own surface point, so
//! they do not depend on the packet (see docs/spec/tracer.md, "Area lights").

use super::World;
use super::path::LightSeeds;
use super::shade::{Here, Surface, Tints, shine, towards};
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::scene::Light;
use glam::DVec3;
use std::cell::RefCell;

/// An area light (sphere or rect) of index `index` in the scene's lights, after its ambient
/// term: its m = `samples` points j = 0 … m − 1 in order, each lit as a point light whose
/// term is scaled by 1/m. Each lane's points are computed in f64 from the lane's own surface
/// point and pixel, so they do not depend on the packet. Returns the lanes of `active` it did
/// not reach whole: left out (behind a rect, inside a sphere) or dark at some point.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn light<V: Lanes>(
    world: &World,
    s: &Surface<V>,
    at: &Here<V>,
    (light, index): (&Light, usize),
    active: V::M,
    seeds: Option<LightSeeds>,
    sum: &mut V3<V>,
    rays: &mut u64,
) -> V::M {
    let (i, m) = match *light {
        Light::Sphere {
            intensity, samples, ..
        }
        | Light::Rect {
            intensity, samples, ..
        } => (intensity, samples),
        _ => unreachable!("only area lights come here"),
    };
    let lit = match *light {
        // One-sided: only points in front of the rectangle's plane see it.
        Light::Rect { corner, normal, .. } => {
            let side = (at.point - V3::splat(corner)).dot(V3::splat(normal));
            active.and(side.gt(V::splat(0.0)))
        }
        _ => active,
    };
    let fallback;
    let (seeds, k, discs) = match seeds {
        Some(l) => (l.seeds, l.k, Some(l.discs)),
        None => {
            fallback = [super::sample::light_seed(0, 0); MAX_LANES];
            (&fallback, 0, None)
        }
    };
    let points = AreaPoints::new::<V>(light, index, seeds, at.point, lit);
    let lit = lit.and(V::M::from_bits(points.lanes));
    if !lit.any() {
        return active;
    }
    // Lanes whose cone towards the light meets no opaque object trace no shadow ray.
    // `match`, not `Option::map`: a closure is compiled outside the kernel's
    // `#[target_feature]` function, and lane operations must stay in it.
    #[allow(clippy::manual_map)]
    let seen = match &world.cones {
        Some(o) => Some(super::cone::open(
            o,
            super::cone::ball(light),
            at.point,
            at.object,
            lit,
        )),
        None => None,
    };
    let mut dark = active.andnot(lit);
    let share = Some(V::splat(1.0 / f64::from(m)));
    let tints = Tints::new(s, &i);
    let mut q = [[0.0; MAX_LANES]; 3];
    // The points' coordinates on the light's domain depend only on the lanes' pixels, the
    // sample and the light: made once a sample where the packet keeps them, they serve every
    // surface its paths visit and every station of a mesh; the same values either way.
    let mut table = match discs {
        Some(d) if m <= Discs::MAX_POINTS && keeps() => Some(d.table.borrow_mut()),
        _ => None,
    };
    let kept = match &mut table {
        Some(t) => {
            let at = t.find::<V::F64>(&points, (index, k, m), V::N);
            Some(&t.entries[at].1[..m as usize])
        }
        None => None,
    };
    // Points k·m … k·m + m − 1 of the sequence.
    let mut sequence = super::sample::Points02::at(k * m);
    let mut one = [[0.0; MAX_LANES]; 2];
    for j in 0..m as usize {
        let c = match kept {
            Some(kept) => &kept[j],
            None => {
                points.coords::<V::F64>(sequence.words(), V::N, &mut one);
                sequence.advance();
                &one
            }
        };
        points.place::<V::F64>(c, V::N, &mut q);
        let (l, d) = towards(at.point, V3::load(&q, 0));
        let unlit = shine(world, s, at, (lit, seen), (l, d), &tints, share, sum, rays);
        dark = dark.or(unlit);
    }
    dark
}

/// Whether packets keep their points' coordinates: always, but tests turn it off to check
/// that keeping them changes no byte (the switch changes only how fast other tests run).
#[cfg(not(test))]
#[inline(always)]
fn keeps() -> bool {
    true
}

#[cfg(test)]
pub(super) static KEEP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(true);

#[cfg(test)]
fn keeps() -> bool {
    KEEP.load(std::sync::atomic::Ordering::Relaxed)
}

/// Each point's coordinates on its light's domain for every lane of a packet (`Coords`).
type Coords = [[f64; MAX_LANES]; 2];

/// The coordinates of the area lights' points a packet's sample takes (`AreaPoints::coords`),
/// kept while the sample's paths are traced: the lights' indices and each one's points in
/// order. Cleared for each sample; its buffers stay for the packet's next one.
#[derive(Default)]
pub struct Discs {
    table: RefCell<Table>,
}

#[derive(Default)]
struct Table {
    /// Entries in use: (light index, its points' coordinates); those past it are spare.
    used: usize,
    entries: Vec<(usize, Vec<Coords>)>,
}

impl Discs {
    /// Lights of more points recompute them at each surface: a packet keeping 64 of 32 lanes
    /// holds 32 KiB, about what the cache nearest the core has.
    const MAX_POINTS: u32 = 64;

    /// Forgets the last sample's points.
    pub fn clear(&self) {
        self.table.borrow_mut().used = 0;
    }
}

impl Table {
    /// The entry of light `index` for sample `k` of `m` points a sample, made if the sample
    /// has none yet.
    #[inline(always)]
    fn find<W: Lanes>(
        &mut self,
        points: &AreaPoints,
        (index, k, m): (usize, u32, u32),
        n: usize,
    ) -> usize {
        if let Some(at) = self.entries[..self.used].iter().position(|e| e.0 == index) {
            return at;
        }
        if self.used == self.entries.len() {
            self.entries.push((index, Vec::new()));
        }
        let entry = &mut self.entries[self.used];
        entry.0 = index;
        entry.1.resize(m as usize, [[0.0; MAX_LANES]; 2]);
        let mut sequence = super::sample::Points02::at(k * m);
        for c in entry.1.iter_mut() {
            points.coords::<W>(sequence.words(), n, c);
            sequence.advance();
        }
        self.used += 1;
        self.used - 1
    }
}

/// Per axis, one f64 value per lane.
type Axes = [[f64; MAX_LANES]; 3];

/// Where an area light's points fall for each lane of a packet: per lane its digital shift
/// and, for a sphere, the disk it sees (centre, radius and the basis of the disk's plane).
struct AreaPoints {
    /// Lanes to place points for (bit k for lane k): active, in front of a rect, outside a
    /// sphere.
    lanes: u32,
    /// Each lane's digital shift: sx in the first array, sy in the second.
    shift: [[u32; MAX_LANES]; 2],
    shape: AreaShape,
}

// Built once per light and shading call, on the stack: the sphere's per-lane basis is what it
// needs, and boxing the variant would cost an allocation each time.
#[allow(clippy::large_enum_variant)]
enum AreaShape {
    Rect {
        corner: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
    },
    Sphere {
        center: DVec3,
        radius: f64,
        /// Per lane, e1 and e2 of the disk facing the lane's point (0 on lanes without
        /// points).
        basis: [Axes; 2],
    },
}

impl AreaPoints {
    /// The points of `light` (index `index`) for the lanes of `lit`, whose surface points are
    /// `point` and light states `seeds`. Lanes inside a sphere light get none.
    #[inline(always)]
    fn new<V: Lanes>(
        light: &Light,
        index: usize,
        seeds: &[u64; MAX_LANES],
        point: V3<V>,
        lit: V::M,
    ) -> AreaPoints {
        let mut lanes = lit.bits();
        // Every lane's shift, lit or not: the coordinates a packet keeps (`Discs`) serve lanes
        // that later surfaces light.
        let mut shift = [[0; MAX_LANES]; 2];
        for (k, seed) in seeds.iter().enumerate().take(V::N) {
            (shift[0][k], shift[1][k]) = super::sample::light_shift(*seed, index);
        }
        let shape = match *light {
            Light::Rect {
                corner,
                edge_u,
                edge_v,
                ..
            } => AreaShape::Rect {
                corner,
                edge_u,
                edge_v,
            },
            Light::Sphere { center, radius, .. } => {
                // The surface points widened exactly to f64, whatever the kernel's precision.
                let p = [point.x.array(), point.y.array(), point.z.array()];
                let basis;
                (lanes, basis) = disk_bases::<V::F64>(center, radius, &p, lanes, V::N);
                AreaShape::Sphere {
                    center,
                    radius,
                    basis,
                }
            }
            _ => unreachable!("only area lights have points"),
        };
        AreaPoints {
            lanes,
            shift,
            shape,
        }
    }

    /// Each lane's coordinates on the light's domain of the point of its sequence whose words
    /// (`sobol02` of its index) are `(gx, gy)`, for lanes 0 … lanes − 1: the shifted
    /// fractions (x, y) for a rect, their concentric map (α, β) for a sphere; computed in the
    /// f64 lanes `W`, `W::N` lanes at a time.
    #[inline(always)]
    fn coords<W: Lanes>(&self, (gx, gy): (u32, u32), lanes: usize, out: &mut Coords) {
        use super::sample::unit32;
        for c in (0..lanes).step_by(W::N) {
            // The sequence's coordinates: integer work, lane by lane.
            let x = W::from_fn(|k| unit32(gx ^ self.shift[0][c + k]));
            let y = W::from_fn(|k| unit32(gy ^ self.shift[1][c + k]));
            let (x, y) = match &self.shape {
                AreaShape::Rect { .. } => (x, y),
                AreaShape::Sphere { .. } => super::lens::disc(x, y),
            };
            x.store(&mut out[0][c..]);
            y.store(&mut out[1][c..]);
        }
    }

    /// The points on the light whose coordinates are `coords` (`coords`) into `out`, for lanes
    /// 0 … lanes − 1 (the light's centre or corner on lanes that take no points), computed in
    /// the f64 lanes `W`, `W::N` lanes at a time.
    #[inline(always)]
    fn place<W: Lanes>(&self, coords: &Coords, lanes: usize, out: &mut Axes) {
        for c in (0..lanes).step_by(W::N) {
            let live = W::M::from_bits(self.lanes >> c);
            let (x, y) = (W::load(&coords[0][c..]), W::load(&coords[1][c..]));
            let (p, idle) = match &self.shape {
                AreaShape::Rect {
                    corner,
                    edge_u,
                    edge_v,
                } => {
                    let corner = V3::splat(*corner);
                    let p = (corner + V3::splat(*edge_u) * x) + V3::splat(*edge_v) * y;
                    (p, corner)
                }
                AreaShape::Sphere {
                    center,
                    radius,
                    basis,
                } => {
                    let (e1, e2) = (V3::load(&basis[0], c), V3::load(&basis[1], c));
                    let center = V3::splat(*center);
                    (center + (e1 * x + e2 * y) * W::splat(*radius), center)
                }
            };
            V3::select(live, p, idle).store(out, c);
        }
    }
}

/// The disks facing the points `p` of lanes 0 … n − 1, computed in `W`'s lanes: the lanes of
/// `lanes` outside the sphere, and each one's basis (`disk_basis`).
#[inline(always)]
fn disk_bases<W: Lanes>(
    center: DVec3,
    radius: f64,
    p: &Axes,
    mut lanes: u32,
    n: usize,
) -> (u32, [Axes; 2]) {
    let mut basis = [[[0.0; MAX_LANES]; 3]; 2];
    for c in (0..n).step_by(W::N) {
        let on = W::M::from_bits(lanes >> c);
        let (on, e1, e2) = disk_basis(center, radius, V3::<W>::load(p, c), on);
        let group = W::M::first(W::N).bits() << c;
        lanes = (lanes & !group) | on.bits() << c;
        e1.store(&mut basis[0], c);
        e2.store(&mut basis[1], c);
    }
    (lanes, basis)
}

/// The basis (e1, e2) of the disk through `center` perpendicular to w = normalize(center − p),
/// by Duff et al. 2017, on the lanes of `on` where p is outside the sphere (|center − p| >
/// radius, not NaN); those lanes are returned with the basis.
#[inline(always)]
fn disk_basis<W: Lanes>(center: DVec3, radius: f64, p: V3<W>, on: W::M) -> (W::M, V3<W>, V3<W>) {
    let v = V3::splat(center) - p;
    let d = ((v.x * v.x + v.y * v.y) + v.z * v.z).sqrt();
    let on = on.and(d.gt(W::splat(radius)));
    let one = W::splat(1.0);
    let w = v * (one / d);
    let sign = one.copysign(w.z);
    let a = -one / (sign + w.z);
    let b = w.x * w.y * a;
    let e1 = V3 {
        x: one + sign * w.x * w.x * a,
        y: sign * b,
        z: -sign * w.x,
    };
    let e2 = V3 {
        x: b,
        y: sign + w.y * w.y * a,
        z: -w.y,
    };
    let zero = V3::zero();
    (on, V3::select(on, e1, zero), V3::select(on, e2, zero))
}
