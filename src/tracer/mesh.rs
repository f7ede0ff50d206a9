//! Placed meshes: each `mesh:` object is an instance of its file's hierarchy (`bvh`), with
//! the world → mesh map of its placement. A packet is taken into the mesh's coordinates as
//! o' = A·(o − T), d' = A·d (A = (1/s) ∘ Rᵀ, not renormalised, so t means the same in both),
//! and walks the hierarchy there; a mesh used many times is stored once.
//!
//! Ties: a mesh hit replaces the nearest so far only when strictly nearer, or at an equal t
//! when that one is a mesh hit too with a greater (object, triangle) index pair; spheres and
//! planes, tested first, keep an equal t. So the result never depends on the order the
//! hierarchy happens to visit triangles in, and every lane width finds the same hit.

use super::accel::walk::{Visit, walk};
use super::accel::wide::Tree;
use super::accel::{Rays, Slabs};
use super::bvh::{Bvh, Tri, Tri32};
use super::triangle::{barycentrics, triangle_hit};
use crate::lanes::{Lanes, MAX_LANES, Mask, V3, single};
use crate::scene::Placement;
use glam::{DMat3, DVec3};
use std::sync::Arc;

/// Marks a lane whose nearest hit is not a mesh triangle.
pub const NO_TRIANGLE: u32 = u32::MAX;

#[derive(Debug, Clone)]
pub struct Instance {
    pub object: u32,
    bvh: Arc<Bvh>,
    to_local: DMat3,
    translate: DVec3,
    /// The placed root box, padded: a packet that misses it skips the mesh.
    min: DVec3,
    max: DVec3,
}

/// The nearest hit of each lane so far, with the triangle (per lane) and its barycentrics.
#[derive(Clone, Copy)]
pub struct Best<V: Lanes> {
    pub t: V,
    pub object: V,
    pub u: V,
    pub v: V,
    pub prim: [u32; MAX_LANES],
}

impl Instance {
    pub fn new(object: usize, bvh: Arc<Bvh>, place: &Placement) -> Instance {
        let (lo, hi) = bvh.bounds();
        let (min, max) = place.placed_box(lo, hi);
        let reach = min.abs().max(max.abs()).max_element() + (max - min).max_element();
        let pad = reach / (1 << 20) as f64;
        Instance {
            object: object as u32,
            bvh,
            to_local: place.to_local(),
            translate: place.translate,
            min: min - pad,
            max: max + pad,
        }
    }

    /// This instance with the world moved by −`by` (f32's camera-relative coordinates), its
    /// box widened by `pad` times its reach.
    pub fn shifted(&self, by: DVec3, pad: f64) -> Instance {
        let (min, max) = (self.min - by, self.max - by);
        let reach = min.abs().max(max.abs()).max_element() + (max - min).max_element();
        Instance {
            translate: self.translate - by,
            min: min - pad * reach,
            max: max + pad * reach,
            bvh: self.bvh.clone(),
            ..*self
        }
    }

    /// The packet in mesh coordinates: A·(o − T) and A·d, each row ((a·x + b·y) + c·z).
    #[inline(always)]
    fn local<V: Lanes>(&self, rays: &Rays<V>) -> Rays<V> {
        Rays {
            origin: apply(&self.to_local, rays.origin - V3::splat(self.translate)),
            dir: apply(&self.to_local, rays.dir),
            leaving: rays.leaving,
        }
    }

    /// Where each lane's triangle tests start, and how far along its ray that is: in f32
    /// frames a ray from outside the box twice the size of the mesh's, about its centre c,
    /// starts at the point of its line nearest c (t₀ = (c − o′)·d′ / d′·d′ when positive),
    /// so the edge functions' rounding, which grows with the square of the distance from
    /// the origin to a triangle, stays that of a ray from near the mesh (docs/spec/mesh.md).
    /// Every triangle of the placement is tested from the same point: still watertight.
    #[inline(always)]
    fn start<V: Lanes>(&self, local: &Rays<V>) -> (V3<V>, Option<V>) {
        if !single::<V>() {
            return (local.origin, None);
        }
        let (o, d) = (local.origin, local.dir);
        let g = V3::splat(self.bvh.centre) - o;
        let e = V3::splat(self.bvh.extent);
        let one = V::splat(1.0);
        let outside =
            g.x.copysign(one)
                .gt(e.x)
                .or(g.y.copysign(one).gt(e.y))
                .or(g.z.copysign(one).gt(e.z));
        let q = g.dot(d) / d.dot(d);
        let t0 = V::select(outside.and(q.gt(V::splat(0.0))), q, V::splat(0.0));
        (o + d * t0, Some(t0))
    }

    /// The placed box (padded), in the world.
    pub fn placed_box(&self) -> (DVec3, DVec3) {
        (self.min, self.max)
    }

    /// The lanes of `active` whose ray enters this mesh's placed box before `limit`.
    #[inline(always)]
    pub(super) fn entered<V: Lanes>(&self, world: &Slabs<V>, limit: V, active: V::M) -> V::M {
        world.enters(self.min, self.max, limit).and(active)
    }

    /// Updates `best` with this mesh's nearest hits on the `active` lanes.
    #[inline(always)]
    pub fn nearest<V: Lanes>(&self, rays: &Rays<V>, active: V::M, best: &mut Best<V>) {
        let local = self.local(rays);
        let from = self.start(&local);
        let object = self.object;
        let tree = &self.bvh.tree;
        // The triangles in the lanes' precision.
        match single::<V>() {
            true => nearest_in(tree, &local, from, self.bvh.tris32(), object, active, best),
            false => nearest_in(tree, &local, from, self.bvh.tris(), object, active, best),
        }
    }

    /// The lanes of `open` whose ray meets a triangle strictly before `max_t`.
    #[inline(always)]
    pub fn blocked<V: Lanes>(&self, rays: &Rays<V>, max_t: V, open: V::M) -> V::M {
        let local = self.local(rays);
        let from = self.start(&local);
        let tree = &self.bvh.tree;
        match single::<V>() {
            true => blocked_in(tree, &local, from, self.bvh.tris32(), max_t, open),
            false => blocked_in(tree, &local, from, self.bvh.tris(), max_t, open),
        }
    }
}

/// `Instance::nearest` in the tree, with the triangles `tris` of one precision.
#[inline(always)]
fn nearest_in<V: Lanes, T: Stored>(
    tree: &Tree,
    rays: &Rays<V>,
    from: (V3<V>, Option<V>),
    tris: &[T],
    object: u32,
    active: V::M,
    best: &mut Best<V>,
) {
    let mut visit = NearestVisit {
        rays,
        from,
        tris,
        object,
        best,
    };
    walk(tree, rays, active, &mut visit);
}

/// `Instance::blocked` in the tree, with the triangles `tris` of one precision.
#[inline(always)]
fn blocked_in<V: Lanes, T: Stored>(
    tree: &Tree,
    rays: &Rays<V>,
    from: (V3<V>, Option<V>),
    tris: &[T],
    max_t: V,
    open: V::M,
) -> V::M {
    let mut visit = AnyVisit {
        rays,
        from,
        tris,
        max_t,
        blocked: V::M::none_set(),
    };
    walk(tree, rays, open, &mut visit);
    visit.blocked
}

/// A stored triangle, in either precision: its vertices and normal as lanes, and its index.
pub(super) trait Stored: Copy {
    fn lanes<V: Lanes>(&self) -> ([V3<V>; 3], V3<V>);
    fn id(&self) -> u32;
}

impl Stored for Tri {
    #[inline(always)]
    fn lanes<V: Lanes>(&self) -> ([V3<V>; 3], V3<V>) {
        // Written out: a closure (`map`) is compiled outside the kernel's target feature.
        let v = &self.v;
        (
            [V3::splat(v[0]), V3::splat(v[1]), V3::splat(v[2])],
            V3::splat(self.n),
        )
    }
    #[inline(always)]
    fn id(&self) -> u32 {
        self.id
    }
}

impl Stored for Tri32 {
    #[inline(always)]
    fn lanes<V: Lanes>(&self) -> ([V3<V>; 3], V3<V>) {
        let v = &self.v;
        (
            [splat32(v[0]), splat32(v[1]), splat32(v[2])],
            splat32(self.n),
        )
    }
    #[inline(always)]
    fn id(&self) -> u32 {
        self.id
    }
}

/// Lanes of an f32 vector (exact in either precision).
#[inline(always)]
fn splat32<V: Lanes>(a: [f32; 3]) -> V3<V> {
    V3 {
        x: V::splat(f64::from(a[0])),
        y: V::splat(f64::from(a[1])),
        z: V::splat(f64::from(a[2])),
    }
}

/// A matrix times lanes of vectors, each row as ((a·x + b·y) + c·z).
#[inline(always)]
fn apply<V: Lanes>(m: &DMat3, v: V3<V>) -> V3<V> {
    let r = m.transpose();
    V3 {
        x: row(r.x_axis, v),
        y: row(r.y_axis, v),
        z: row(r.z_axis, v),
    }
}

#[inline(always)]
fn row<V: Lanes>(r: DVec3, v: V3<V>) -> V {
    V::splat(r.x) * v.x + V::splat(r.y) * v.y + V::splat(r.z) * v.z
}

struct NearestVisit<'a, V: Lanes, T: Stored> {
    rays: &'a Rays<V>,
    tris: &'a [T],
    /// Where the triangle tests start (`Instance::start`).
    from: (V3<V>, Option<V>),
    object: u32,
    best: &'a mut Best<V>,
}

impl<V: Lanes, T: Stored> Visit<V> for NearestVisit<'_, V, T> {
    #[inline(always)]
    fn open(&self, lanes: V::M) -> V::M {
        lanes
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.best.t
    }

    #[inline(always)]
    fn leaf(&mut self, _: &Slabs<V>, first: usize, count: usize, enter: V::M) {
        let tris = &self.tris[first..first + count];
        let (dir, from, object) = (self.rays.dir, self.from, self.object);
        let Some(i) = one_half::<V>(enter) else {
            return nearest_leaf(tris, object, dir, from, enter, self.best);
        };
        let best = &mut *self.best;
        let n = V::N / 2;
        let mut half = Best {
            t: best.t.half(i),
            object: best.object.half(i),
            u: best.u.half(i),
            v: best.v.half(i),
            prim: [NO_TRIANGLE; MAX_LANES],
        };
        half.prim[..n].copy_from_slice(&best.prim[i * n..i * n + n]);
        let enter = <V::Half as Lanes>::M::from_bits(enter.bits() >> (i * n));
        nearest_leaf(
            tris,
            object,
            halves(dir, i),
            half_from(from, i),
            enter,
            &mut half,
        );
        best.t = best.t.with_half(i, half.t);
        best.object = best.object.with_half(i, half.object);
        best.u = best.u.with_half(i, half.u);
        best.v = best.v.with_half(i, half.v);
        best.prim[i * n..i * n + n].copy_from_slice(&half.prim[..n]);
    }

    #[inline(always)]
    fn fetch(&self, first: usize, count: usize) {
        crate::lanes::fetch(&self.tris[first..first + count]);
    }

    /// `leaf` for lane `k` alone, in `V::One`: the same operations on the same values.
    #[inline(always)]
    fn leaf_one(&mut self, _: &Slabs<V>, first: usize, count: usize, k: usize) {
        let ray = Lone::of(self.rays, &self.from, k);
        let lane = V::M::from_bits(1 << k);
        let best = &mut *self.best;
        for tri in &self.tris[first..first + count] {
            let (hit, t, w) = ray.hit(tri);
            if !hit {
                continue;
            }
            let now = lane_of(best.t, k);
            if t.lt(now) || (t.eq(now) && ties_won(lane, self.object, tri.id(), best).any()) {
                let (u, v) = barycentrics(w);
                best.t = V::select(lane, V::splat(t.lane(0)), best.t);
                best.object = V::select(lane, V::splat(f64::from(self.object)), best.object);
                best.u = V::select(lane, V::splat(u.lane(0)), best.u);
                best.v = V::select(lane, V::splat(v.lane(0)), best.v);
                best.prim[k] = tri.id();
            }
        }
    }
}

struct AnyVisit<'a, V: Lanes, T: Stored> {
    rays: &'a Rays<V>,
    tris: &'a [T],
    from: (V3<V>, Option<V>),
    max_t: V,
    blocked: V::M,
}

impl<V: Lanes, T: Stored> Visit<V> for AnyVisit<'_, V, T> {
    #[inline(always)]
    fn open(&self, lanes: V::M) -> V::M {
        lanes.andnot(self.blocked)
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.max_t
    }

    #[inline(always)]
    fn leaf(&mut self, _: &Slabs<V>, first: usize, count: usize, enter: V::M) {
        let tris = &self.tris[first..first + count];
        let (dir, from) = (self.rays.dir, self.from);
        let Some(i) = one_half::<V>(enter) else {
            let blocked = blocked_leaf(tris, dir, from, self.max_t, enter);
            self.blocked = self.blocked.or(blocked);
            return;
        };
        let n = V::N / 2;
        let enter = <V::Half as Lanes>::M::from_bits(enter.bits() >> (i * n));
        let max_t = self.max_t.half(i);
        let blocked = blocked_leaf(tris, halves(dir, i), half_from(from, i), max_t, enter);
        self.blocked = self.blocked.or(V::M::from_bits(blocked.bits() << (i * n)));
    }

    #[inline(always)]
    fn fetch(&self, first: usize, count: usize) {
        crate::lanes::fetch(&self.tris[first..first + count]);
    }

    /// `leaf` for lane `k` alone, in `V::One`.
    #[inline(always)]
    fn leaf_one(&mut self, _: &Slabs<V>, first: usize, count: usize, k: usize) {
        let ray = Lone::of(self.rays, &self.from, k);
        let max_t = lane_of(self.max_t, k);
        for tri in &self.tris[first..first + count] {
            let (hit, t, _) = ray.hit(tri);
            if hit && t.lt(max_t) {
                self.blocked = self.blocked.or(V::M::from_bits(1 << k));
                return;
            }
        }
    }
}

/// One lane of a packet in mesh coordinates, as one lane of its precision: where its
/// triangle tests start (and how far along the ray that is) and its direction.
struct Lone<W: Lanes> {
    from: V3<W>,
    skipped: Option<W>,
    dir: V3<W>,
}

impl<W: Lanes<M = bool>> Lone<W> {
    #[inline(always)]
    fn of<V: Lanes<One = W>>(rays: &Rays<V>, from: &(V3<V>, Option<V>), k: usize) -> Lone<W> {
        Lone {
            from: v3_of(from.0, k),
            skipped: from.1.map(|t| lane_of(t, k)),
            dir: v3_of(rays.dir, k),
        }
    }

    /// `triangle_hit` of one stored triangle for this ray.
    #[inline(always)]
    fn hit<T: Stored>(&self, tri: &T) -> (bool, W, [W; 3]) {
        let (v, n) = tri.lanes::<W>();
        triangle_hit(v, n, self.from, self.dir, self.skipped, true)
    }
}

/// Lane `k` of the vectors `v` as one lane of their precision (exactly).
#[inline(always)]
fn v3_of<V: Lanes>(v: V3<V>, k: usize) -> V3<V::One> {
    V3 {
        x: lane_of(v.x, k),
        y: lane_of(v.y, k),
        z: lane_of(v.z, k),
    }
}

/// Lane `k` of `v` as one lane of its precision (exactly).
#[inline(always)]
fn lane_of<V: Lanes>(v: V, k: usize) -> V::One {
    if single::<V>() {
        let mut a = [0f32; MAX_LANES];
        v.store_f32(&mut a);
        V::One::splat(f64::from(a[k]))
    } else {
        V::One::splat(v.lane(k))
    }
}

/// `triangle_hit` of one stored triangle for lanes in mesh coordinates.
#[inline(always)]
fn hit<V: Lanes, T: Stored>(
    tri: &T,
    dir: V3<V>,
    (from, skipped): (V3<V>, Option<V>),
    enter: V::M,
) -> (V::M, V, [V; 3]) {
    let (v, n) = tri.lanes();
    triangle_hit(v, n, from, dir, skipped, enter)
}

/// The nearest hits among `tris` (of mesh `object`) of the lanes `enter`, into `best`.
#[inline(always)]
fn nearest_leaf<V: Lanes, T: Stored>(
    tris: &[T],
    object: u32,
    dir: V3<V>,
    from: (V3<V>, Option<V>),
    enter: V::M,
    best: &mut Best<V>,
) {
    for tri in tris {
        let (hit, t, w) = hit(tri, dir, from, enter);
        if !hit.any() {
            continue;
        }
        let mut better = hit.and(t.lt(best.t));
        let tie = hit.and(t.eq(best.t));
        if tie.any() {
            better = better.or(ties_won(tie, object, tri.id(), best));
        }
        if better.any() {
            let (u, v) = barycentrics(w);
            best.t = V::select(better, t, best.t);
            best.object = V::select(better, V::splat(f64::from(object)), best.object);
            best.u = V::select(better, u, best.u);
            best.v = V::select(better, v, best.v);
            let mut bits = better.bits();
            while bits != 0 {
                best.prim[bits.trailing_zeros() as usize] = tri.id();
                bits &= bits - 1;
            }
        }
    }
}

/// The lanes of `enter` that meet one of `tris` strictly before `max_t`.
#[inline(always)]
fn blocked_leaf<V: Lanes, T: Stored>(
    tris: &[T],
    dir: V3<V>,
    from: (V3<V>, Option<V>),
    max_t: V,
    enter: V::M,
) -> V::M {
    let (mut enter, mut blocked) = (enter, V::M::none_set());
    for tri in tris {
        let (hit, t, _) = hit(tri, dir, from, enter);
        let b = hit.and(t.lt(max_t));
        blocked = blocked.or(b);
        enter = enter.andnot(b);
        if !enter.any() {
            break;
        }
    }
    blocked
}

/// The half of a pair of registers that holds every lane of `lanes`, if one does: a leaf
/// entered by those lanes alone is tested in that half (the same operations on the same
/// values, lane by lane), half the work. (Terrains and small meshes: a leaf is entered by a
/// few neighbouring rays of a packet.)
#[inline(always)]
fn one_half<V: Lanes>(lanes: V::M) -> Option<usize> {
    if !V::HALVES {
        return None;
    }
    let (bits, n) = (lanes.bits(), V::N / 2);
    match (bits & ((1 << n) - 1) == 0, bits >> n == 0) {
        (false, true) => Some(0),
        (true, false) => Some(1),
        _ => None,
    }
}

/// Half `i` of each component.
#[inline(always)]
fn halves<V: Lanes>(v: V3<V>, i: usize) -> V3<V::Half> {
    V3 {
        x: v.x.half(i),
        y: v.y.half(i),
        z: v.z.half(i),
    }
}

/// Half `i` of where the triangle tests start.
#[inline(always)]
fn half_from<V: Lanes>(
    (from, skipped): (V3<V>, Option<V>),
    i: usize,
) -> (V3<V::Half>, Option<V::Half>) {
    // Not `Option::map`: its closure may be compiled outside the kernel's target feature.
    #[allow(clippy::manual_map)]
    let skipped = match skipped {
        Some(t) => Some(t.half(i)),
        None => None,
    };
    (halves(from, i), skipped)
}

/// The lanes of `tie` (same t as the best so far) where triangle `id` of `object` comes first:
/// the best so far is a mesh triangle with a greater (object, triangle) pair.
#[inline(always)]
fn ties_won<V: Lanes>(tie: V::M, object: u32, id: u32, best: &Best<V>) -> V::M {
    let objects = best.object.array();
    let mut won = 0u32;
    let mut bits = tie.bits();
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let (o, p) = (objects[k] as u32, best.prim[k]);
        if p != NO_TRIANGLE && (object < o || (object == o && id < p)) {
            won |= 1 << k;
        }
    }
    V::M::from_bits(won)
}

#[cfg(test)]
mod tests;
