//! Placed meshes: each `mesh:` object is an instance of its file's hierarchy (`bvh`), with
//! the world → mesh map of its placement. A packet is taken into the mesh's coordinates as
//! o' = A·(o − T), d' = A·d (A = (1/s) ∘ Rᵀ, not renormalised, so t means the same in both),
//! and walks the hierarchy there; a mesh used many times is stored once.
//!
//! Ties: a mesh hit replaces the nearest so far only when strictly nearer, or at an equal t
//! when that one is a mesh hit too with a greater (object, triangle) index pair; spheres and
//! planes, tested first, keep an equal t. So the result never depends on the order the
//! hierarchy happens to visit triangles in, and every lane width finds the same hit.

use super::accel::{Rays, Slabs};
use super::bvh::{Bvh, Node, Tri};
use super::triangle::{barycentrics, triangle_hit};
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
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

    /// The lanes of `active` whose ray enters this mesh's placed box before `limit`.
    #[inline(always)]
    pub(super) fn entered<V: Lanes>(&self, world: &Slabs<V>, limit: V, active: V::M) -> V::M {
        world.enters(self.min, self.max, limit).and(active)
    }

    /// Updates `best` with this mesh's nearest hits on the `active` lanes.
    #[inline(always)]
    pub fn nearest<V: Lanes>(&self, rays: &Rays<V>, active: V::M, best: &mut Best<V>) {
        let local = self.local(rays);
        let mut visit = NearestVisit {
            rays: &local,
            object: self.object,
            best,
        };
        self.walk(&local, active, &mut visit);
    }

    /// The lanes of `open` whose ray meets a triangle strictly before `max_t`.
    #[inline(always)]
    pub fn blocked<V: Lanes>(&self, rays: &Rays<V>, max_t: V, open: V::M) -> V::M {
        let local = self.local(rays);
        let mut visit = AnyVisit {
            rays: &local,
            max_t,
            blocked: V::M::none_set(),
        };
        self.walk(&local, open, &mut visit);
        visit.blocked
    }

    /// Visits the leaves whose boxes a lane of `lanes` enters before its limit, nearer child
    /// first (as the first lane sees them).
    #[inline(always)]
    fn walk<V: Lanes, S: Visit<V>>(&self, rays: &Rays<V>, lanes: V::M, visit: &mut S) {
        let slabs = Slabs::new(rays, lanes);
        let lead = lanes.bits().trailing_zeros() as usize;
        let backwards = [
            rays.dir.x.lane(lead) < 0.0,
            rays.dir.y.lane(lead) < 0.0,
            rays.dir.z.lane(lead) < 0.0,
        ];
        let nodes: &[Node] = &self.bvh.nodes;
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let at = stack[top];
            let node = &nodes[at as usize];
            let open = visit.open(lanes);
            let enter = slabs.enters(node.min, node.max, visit.limit()).and(open);
            if !enter.any() {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                visit.leaf(&self.bvh.tris[first..first + node.count as usize], enter);
                continue;
            }
            let (near, far) = if backwards[node.axis as usize] {
                (node.first, at + 1)
            } else {
                (at + 1, node.first)
            };
            stack[top] = far;
            stack[top + 1] = near;
            top += 2;
        }
    }
}

/// The deepest walk: the hierarchy is at most `bvh::MAX_DEPTH` levels deep.
const STACK: usize = super::bvh::MAX_DEPTH + 2;

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

/// What a walk does at a leaf, and which lanes still search and how far.
trait Visit<V: Lanes> {
    fn open(&self, lanes: V::M) -> V::M;
    fn limit(&self) -> V;
    fn leaf(&mut self, tris: &[Tri], enter: V::M);
}

struct NearestVisit<'a, V: Lanes> {
    rays: &'a Rays<V>,
    object: u32,
    best: &'a mut Best<V>,
}

impl<V: Lanes> Visit<V> for NearestVisit<'_, V> {
    #[inline(always)]
    fn open(&self, lanes: V::M) -> V::M {
        lanes
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.best.t
    }

    #[inline(always)]
    fn leaf(&mut self, tris: &[Tri], enter: V::M) {
        let best = &mut *self.best;
        for tri in tris {
            let (hit, t, w) = hit(tri, self.rays, enter);
            if !hit.any() {
                continue;
            }
            let mut better = hit.and(t.lt(best.t));
            let tie = hit.and(t.eq(best.t));
            if tie.any() {
                better = better.or(ties_won(tie, self.object, tri.id, best));
            }
            if better.any() {
                let (u, v) = barycentrics(w);
                best.t = V::select(better, t, best.t);
                best.object = V::select(better, V::splat(f64::from(self.object)), best.object);
                best.u = V::select(better, u, best.u);
                best.v = V::select(better, v, best.v);
                let mut bits = better.bits();
                while bits != 0 {
                    best.prim[bits.trailing_zeros() as usize] = tri.id;
                    bits &= bits - 1;
                }
            }
        }
    }
}

struct AnyVisit<'a, V: Lanes> {
    rays: &'a Rays<V>,
    max_t: V,
    blocked: V::M,
}

impl<V: Lanes> Visit<V> for AnyVisit<'_, V> {
    #[inline(always)]
    fn open(&self, lanes: V::M) -> V::M {
        lanes.andnot(self.blocked)
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.max_t
    }

    #[inline(always)]
    fn leaf(&mut self, tris: &[Tri], enter: V::M) {
        let mut enter = enter;
        for tri in tris {
            let (hit, t, _) = hit(tri, self.rays, enter);
            let b = hit.and(t.lt(self.max_t));
            self.blocked = self.blocked.or(b);
            enter = enter.andnot(b);
            if !enter.any() {
                break;
            }
        }
    }
}

/// `triangle_hit` of one stored triangle for the packet in mesh coordinates.
#[inline(always)]
fn hit<V: Lanes>(tri: &Tri, rays: &Rays<V>, enter: V::M) -> (V::M, V, [V; 3]) {
    let v = [
        V3::splat(tri.v[0]),
        V3::splat(tri.v[1]),
        V3::splat(tri.v[2]),
    ];
    triangle_hit(v, V3::splat(tri.n), rays.origin, rays.dir, enter)
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
