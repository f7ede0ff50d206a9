//! The geometry the tracer queries: spheres and planes in flat arrays, and a bounding volume
//! hierarchy over the spheres only when a scene has enough of them to need one. Queries take a
//! packet of rays (any lane type). Every hit is computed by `intersect::sphere_hit` or
//! `plane_hit`; the hierarchy only skips spheres whose (slightly padded) boxes no ray of the
//! packet can enter, so it never changes an image.
//!
//! Ties: spheres are tested before planes; among spheres the lower object index wins an exact
//! tie in t, among planes the earlier one. The hierarchy visits spheres in an order that
//! depends on the packet, and this rule makes the answer independent of that order, so every
//! lane width gives the same hit.

use super::bvh::Bvh;
use super::intersect::{Hit, Ray, plane_hit, sphere_hit};
use super::mesh::{Best, Instance, NO_TRIANGLE};
use crate::lanes::{F64x1, Lanes, MAX_LANES, Mask, V3};
use crate::scene::{Object, Shape, closest_to_origin};
use glam::DVec3;
use std::ops::Range;
use std::sync::Arc;

mod build;
mod four;
pub(crate) mod frustum;
mod single;
mod slabs;
pub(crate) mod walk;
pub(crate) mod wide;

pub(crate) use slabs::Slabs;

/// Below this many spheres a plain loop beats any hierarchy (measured with `rayreel bench`).
pub const BVH_MIN_SPHERES: usize = 12;
const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone)]
pub struct Geometry {
    /// Spheres in hierarchy order, as plain records so the hot loop needs no shape dispatch.
    spheres: Vec<Ball>,
    planes: Vec<Flat>,
    bvh: Vec<Node>,
    /// Placed meshes, tested after spheres and planes.
    meshes: Vec<Instance>,
    /// The hierarchy over the placed meshes' boxes, when there are enough to need one.
    top: Option<wide::Tree>,
}

/// From this many placed meshes a packet walks a hierarchy over them rather than testing
/// each one's box.
pub const TOP_MIN_MESHES: usize = 4;

#[derive(Debug, Clone, Copy)]
struct Ball {
    center: DVec3,
    radius: f64,
    /// radius², as every intersection forms it.
    r2: f64,
    object: u32,
}

#[derive(Debug, Clone, Copy)]
struct Flat {
    point: DVec3,
    normal: DVec3,
    object: u32,
}

#[derive(Debug, Clone, Copy)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first sphere; interior: left child (the right one follows it).
    first: u32,
    /// Spheres in a leaf; 0 for an interior node.
    count: u32,
    /// Interior: the axis the children were split along (left holds the smaller centres).
    axis: u32,
}

/// A packet of rays as the geometry sees them.
#[derive(Clone, Copy)]
pub struct Rays<V: Lanes> {
    pub origin: V3<V>,
    /// Unit length.
    pub dir: V3<V>,
    /// Index of the object each lane starts on, or −1 for eye rays.
    pub leaving: V,
}

/// f = origin − centre and |f|² − r² of one sphere for rays from one shared origin (eye rays
/// of a pinhole camera): computed once a frame with exactly the arithmetic `sphere_hit` uses.
#[derive(Debug, Clone, Copy)]
pub struct FromOrigin {
    f: DVec3,
    c: f64,
}

/// The nearest hit of each lane: `hit` lanes have `t` and `object` (an index, as a float);
/// lanes that hit a mesh also have the triangle (`prim`, else `NO_TRIANGLE`) and the
/// barycentric weights `u`, `v` of its second and third vertex.
#[derive(Clone, Copy)]
pub struct Nearest<V: Lanes> {
    pub hit: V::M,
    pub t: V,
    pub object: V,
    pub u: V,
    pub v: V,
    pub prim: [u32; MAX_LANES],
}

impl Geometry {
    /// The geometry of spheres and planes (a mesh-free scene).
    pub fn new(objects: &[Object]) -> Geometry {
        Geometry::subset(objects, &[], |_| true)
    }

    /// The geometry of the objects `keep` accepts, under their indices in `objects`; `bvhs`
    /// holds the hierarchy of each of the scene's meshes.
    pub fn subset(objects: &[Object], bvhs: &[Arc<Bvh>], keep: impl Fn(usize) -> bool) -> Geometry {
        let mut spheres = Vec::new();
        let mut planes = Vec::new();
        let mut meshes = Vec::new();
        for (i, o) in objects.iter().enumerate().filter(|(i, _)| keep(*i)) {
            let object = i as u32;
            match o.shape {
                Shape::Sphere { center, radius } => spheres.push(Ball {
                    center,
                    radius,
                    r2: radius * radius,
                    object,
                }),
                Shape::Plane { point, normal, .. } => planes.push(Flat {
                    point,
                    normal,
                    object,
                }),
                Shape::Mesh { mesh, place, .. } => {
                    meshes.push(Instance::new(i, bvhs[mesh].clone(), &place))
                }
            }
        }
        let mut bvh = Vec::new();
        if spheres.len() >= BVH_MIN_SPHERES {
            bvh.push(Node {
                min: DVec3::ZERO,
                max: DVec3::ZERO,
                first: 0,
                count: 0,
                axis: 0,
            });
            let n = spheres.len();
            build::build(&mut bvh, &mut spheres, 0, 0, n);
        }
        let top = (meshes.len() >= TOP_MIN_MESHES).then(|| top_level(&meshes));
        Geometry {
            spheres,
            planes,
            bvh,
            meshes,
            top,
        }
    }

    /// This geometry moved by −`by` (camera-relative coordinates for f32), each box widened
    /// by `pad` times its largest coordinate and extent (boxes that stay conservative once
    /// rounded to f32). The hierarchy keeps its shape: translation changes no split.
    pub fn shifted(&self, by: DVec3, pad: f64) -> Geometry {
        let spheres = self
            .spheres
            .iter()
            .map(|b| Ball {
                center: b.center - by,
                ..*b
            })
            .collect();
        let planes = self
            .planes
            .iter()
            .map(|p| Flat {
                point: closest_to_origin(p.point - by, p.normal),
                ..*p
            })
            .collect();
        let bvh = self
            .bvh
            .iter()
            .map(|n| {
                let (min, max) = (n.min - by, n.max - by);
                let reach = min.abs().max(max.abs()).max_element() + (max - min).max_element();
                Node {
                    min: min - pad * reach,
                    max: max + pad * reach,
                    ..*n
                }
            })
            .collect();
        Geometry {
            spheres,
            planes,
            bvh,
            meshes: self.meshes.iter().map(|m| m.shifted(by, pad)).collect(),
            top: self.top.as_ref().map(|t| t.shifted(by, pad)),
        }
    }

    /// Whether a hierarchy was built (reported by `rayreel bench`).
    pub fn has_bvh(&self) -> bool {
        !self.bvh.is_empty()
    }

    /// One ray's nearest hit (the one-lane packet).
    pub fn nearest_one(&self, ray: &Ray) -> Option<Hit> {
        let n = self.nearest(&one_ray(ray), None, true);
        n.hit.then_some(Hit {
            t: n.t.0,
            object: n.object.0 as usize,
        })
    }

    /// Whether anything lies on one ray strictly before `max_t`.
    pub fn occluded_one(&self, ray: &Ray, max_t: f64) -> bool {
        self.occluded(&one_ray(ray), F64x1(max_t), true)
    }

    /// Per-sphere constants for rays starting at `origin`, in the order `nearest` wants them.
    pub fn from_origin(&self, origin: DVec3) -> Vec<FromOrigin> {
        self.spheres
            .iter()
            .map(|b| {
                let f = origin - b.center;
                FromOrigin {
                    f,
                    c: f.dot(f) - b.r2,
                }
            })
            .collect()
    }

    /// The nearest hit with t > 0 of each `active` lane. `eye` holds `from_origin` of the
    /// packet's shared origin when it has one (then no lane is leaving a surface).
    #[inline(always)]
    pub fn nearest<V: Lanes>(
        &self,
        rays: &Rays<V>,
        eye: Option<&[FromOrigin]>,
        active: V::M,
    ) -> Nearest<V> {
        let mut search = NearestSearch {
            geometry: self,
            rays,
            eye,
            active,
            t: V::splat(f64::INFINITY),
            object: V::splat(-1.0),
        };
        if self.bvh.is_empty() {
            search.leaf(0..self.spheres.len(), active);
        } else {
            self.walk(rays, &mut search);
        }
        let (mut t, mut object) = (search.t, search.object);
        for p in &self.planes {
            let (hit, tp) = plane(p, rays, active);
            let better = hit.and(tp.lt(t));
            t = V::select(better, tp, t);
            object = V::select(better, V::splat(f64::from(p.object)), object);
        }
        if self.meshes.is_empty() {
            return Nearest {
                hit: active.and(t.lt(V::splat(f64::INFINITY))),
                t,
                object,
                u: V::splat(0.0),
                v: V::splat(0.0),
                prim: [NO_TRIANGLE; MAX_LANES],
            };
        }
        // The mesh walks out of line, on a copy of the rays. A walk is large: inlined in each
        // integrator, the walks made the packet function half walk, and its compile time
        // (superlinear in a function's size) most of a build's. The copy keeps the caller's
        // rays from escaping, so that they stay in registers (else the talk's eye rays cost a
        // memcpy a packet, though it has no mesh).
        let rays = *rays;
        V::outlined(
            #[inline(always)]
            move || self.mesh_nearest(&rays, active, (t, object)),
        )
    }

    /// `nearest` in the meshes, given the nearest hits `t` on `object` among the other shapes.
    #[inline(always)]
    fn mesh_nearest<V: Lanes>(
        &self,
        rays: &Rays<V>,
        active: V::M,
        (t, object): (V, V),
    ) -> Nearest<V> {
        let mut best = Best {
            t,
            object,
            u: V::splat(0.0),
            v: V::splat(0.0),
            prim: [NO_TRIANGLE; MAX_LANES],
        };
        if let Some(top) = &self.top {
            let mut visit = TopNearest {
                meshes: &self.meshes,
                order: &top.order,
                rays,
                best: &mut best,
            };
            walk::walk(top, rays, active, &mut visit);
        } else {
            let slabs = Slabs::new(rays, active);
            for m in &self.meshes {
                let enter = m.entered(&slabs, best.t, active);
                if enter.any() {
                    m.nearest(rays, enter, &mut best);
                }
            }
        }
        Nearest {
            hit: active.and(best.t.lt(V::splat(f64::INFINITY))),
            t: best.t,
            object: best.object,
            u: best.u,
            v: best.v,
            prim: best.prim,
        }
    }

    /// The lanes of `open` blocked by a mesh before `max_t`.
    #[inline(always)]
    fn mesh_blocked<V: Lanes>(&self, rays: &Rays<V>, max_t: V, open: V::M) -> V::M {
        if let Some(top) = &self.top {
            let mut visit = TopAny {
                meshes: &self.meshes,
                order: &top.order,
                rays,
                max_t,
                blocked: V::M::none_set(),
            };
            walk::walk(top, rays, open, &mut visit);
            return visit.blocked;
        }
        let slabs = Slabs::new(rays, open);
        let mut blocked = V::M::none_set();
        for m in &self.meshes {
            let enter = m.entered(&slabs, max_t, open.andnot(blocked));
            if enter.any() {
                blocked = blocked.or(m.blocked(rays, max_t, enter));
            }
        }
        blocked
    }

    /// The `active` lanes with something on their ray strictly before `max_t`.
    #[inline(always)]
    pub fn occluded<V: Lanes>(&self, rays: &Rays<V>, max_t: V, active: V::M) -> V::M {
        V::outlined(
            #[inline(always)]
            || self.find_blocked(rays, max_t, active),
        )
    }

    #[inline(always)]
    fn find_blocked<V: Lanes>(&self, rays: &Rays<V>, max_t: V, active: V::M) -> V::M {
        let mut blocked = V::M::none_set();
        for p in &self.planes {
            let (hit, t) = plane(p, rays, active.andnot(blocked));
            blocked = blocked.or(hit.and(t.lt(max_t)));
        }
        let mut search = AnySearch {
            geometry: self,
            rays,
            max_t,
            open: active.andnot(blocked),
        };
        if !search.open.any() {
            return blocked;
        }
        if self.bvh.is_empty() {
            search.leaf(0..self.spheres.len(), search.open);
        } else {
            self.walk(rays, &mut search);
        }
        if !self.meshes.is_empty() && search.open.any() {
            // Out of line on a copy of the rays, as in `nearest`: inlined, the mesh walk's
            // code changed how the spheres' tests above were compiled (the talk's shadow
            // rays took 0.7% more instructions when a mesh leaf grew).
            let (rays, open) = (*rays, search.open);
            let blocked = V::outlined(
                #[inline(always)]
                move || self.mesh_blocked(&rays, max_t, open),
            );
            search.open = search.open.andnot(blocked);
        }
        active.andnot(search.open)
    }

    /// Whether any mesh is placed.
    pub fn has_meshes(&self) -> bool {
        !self.meshes.is_empty()
    }

    #[inline(always)]
    fn sphere<V: Lanes>(
        &self,
        i: usize,
        eye: Option<&[FromOrigin]>,
        rays: &Rays<V>,
        active: V::M,
    ) -> (V::M, V) {
        let b = &self.spheres[i];
        let r2 = V::splat(b.r2);
        match eye {
            Some(eye) => {
                let e = eye[i];
                let none = V::M::none_set();
                sphere_hit(
                    V3::splat(e.f),
                    Some(V::splat(e.c)),
                    r2,
                    rays.dir,
                    none,
                    active,
                )
            }
            None => {
                let own = rays.leaving.eq(V::splat(f64::from(b.object)));
                let f = rays.origin - V3::splat(b.center);
                sphere_hit(f, None, r2, rays.dir, own, active)
            }
        }
    }

    /// Visits the leaves whose boxes a ray of the search's lanes enters before its limit,
    /// nearer child first (as the first searching lane sees them).
    #[inline(always)]
    fn walk<V: Lanes, S: Search<V>>(&self, rays: &Rays<V>, search: &mut S) {
        let slabs = Slabs::new(rays, search.lanes());
        // Children are ordered by the first searching lane's direction (a heuristic only).
        let lead = search.lanes().bits().trailing_zeros() as usize;
        let backwards = [
            rays.dir.x.lane(lead) < 0.0,
            rays.dir.y.lane(lead) < 0.0,
            rays.dir.z.lane(lead) < 0.0,
        ];
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 && search.lanes().any() {
            top -= 1;
            let node = &self.bvh[stack[top] as usize];
            let enter = slabs.entry(node, search.limit()).and(search.lanes());
            if !enter.any() {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                search.leaf(first..first + node.count as usize, enter);
                continue;
            }
            // Push the farther child first so the nearer one is visited first.
            let (near, far) = if backwards[node.axis as usize] {
                (node.first + 1, node.first)
            } else {
                (node.first, node.first + 1)
            };
            stack[top] = far;
            stack[top + 1] = near;
            top += 2;
        }
    }
}

/// What a walk through the hierarchy looks for: the lanes still searching, how far along
/// their rays a box must start to matter, and what to do in a leaf.
trait Search<V: Lanes> {
    fn lanes(&self) -> V::M;
    fn limit(&self) -> V;
    fn leaf(&mut self, spheres: Range<usize>, enter: V::M);
}

/// The nearest sphere hit so far of each lane.
struct NearestSearch<'a, V: Lanes> {
    geometry: &'a Geometry,
    rays: &'a Rays<V>,
    eye: Option<&'a [FromOrigin]>,
    active: V::M,
    t: V,
    object: V,
}

impl<V: Lanes> Search<V> for NearestSearch<'_, V> {
    #[inline(always)]
    fn lanes(&self) -> V::M {
        self.active
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.t
    }

    #[inline(always)]
    fn leaf(&mut self, spheres: Range<usize>, enter: V::M) {
        for i in spheres {
            let (hit, t) = self.geometry.sphere(i, self.eye, self.rays, enter);
            if hit.any() {
                let object = V::splat(f64::from(self.geometry.spheres[i].object));
                let tie = t.eq(self.t).and(object.lt(self.object));
                let better = hit.and(t.lt(self.t).or(tie));
                self.t = V::select(better, t, self.t);
                self.object = V::select(better, object, self.object);
            }
        }
    }
}

/// Whether anything blocks each lane before `max_t`; lanes leave `open` once blocked.
struct AnySearch<'a, V: Lanes> {
    geometry: &'a Geometry,
    rays: &'a Rays<V>,
    max_t: V,
    open: V::M,
}

impl<V: Lanes> Search<V> for AnySearch<'_, V> {
    #[inline(always)]
    fn lanes(&self) -> V::M {
        self.open
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.max_t
    }

    #[inline(always)]
    fn leaf(&mut self, spheres: Range<usize>, enter: V::M) {
        let mut open = enter.and(self.open);
        for i in spheres {
            if !open.any() {
                break;
            }
            let (hit, t) = self.geometry.sphere(i, None, self.rays, open);
            let blocked = hit.and(t.lt(self.max_t));
            open = open.andnot(blocked);
            self.open = self.open.andnot(blocked);
        }
    }
}

/// The hierarchy over placed meshes: each leaf item a placement, under its placed box.
fn top_level(meshes: &[Instance]) -> wide::Tree {
    let prims = meshes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let (lo, hi) = m.placed_box();
            wide::Prim::new(lo, hi, i as u32)
        })
        .collect();
    wide::Tree::build(prims)
}

/// The top level's leaves for nearest hits: each placement whose box a lane enters walks its
/// own hierarchy.
struct TopNearest<'a, V: Lanes> {
    meshes: &'a [Instance],
    order: &'a [u32],
    rays: &'a Rays<V>,
    best: &'a mut Best<V>,
}

impl<V: Lanes> walk::Visit<V> for TopNearest<'_, V> {
    #[inline(always)]
    fn open(&self, lanes: V::M) -> V::M {
        lanes
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.best.t
    }

    #[inline(always)]
    fn leaf(&mut self, slabs: &Slabs<V>, first: usize, count: usize, enter: V::M) {
        for &i in &self.order[first..first + count] {
            let m = &self.meshes[i as usize];
            let lanes = m.entered(slabs, self.best.t, enter);
            if lanes.any() {
                m.nearest(self.rays, lanes, self.best);
            }
        }
    }
}

/// The top level's leaves for shadow rays: lanes stop at the first placement that blocks them.
struct TopAny<'a, V: Lanes> {
    meshes: &'a [Instance],
    order: &'a [u32],
    rays: &'a Rays<V>,
    max_t: V,
    blocked: V::M,
}

impl<V: Lanes> walk::Visit<V> for TopAny<'_, V> {
    #[inline(always)]
    fn open(&self, lanes: V::M) -> V::M {
        lanes.andnot(self.blocked)
    }

    #[inline(always)]
    fn limit(&self) -> V {
        self.max_t
    }

    #[inline(always)]
    fn leaf(&mut self, slabs: &Slabs<V>, first: usize, count: usize, enter: V::M) {
        for &i in &self.order[first..first + count] {
            let m = &self.meshes[i as usize];
            let lanes = m.entered(slabs, self.max_t, enter.andnot(self.blocked));
            if lanes.any() {
                self.blocked = self.blocked.or(m.blocked(self.rays, self.max_t, lanes));
            }
        }
    }
}

fn one_ray(ray: &Ray) -> Rays<F64x1> {
    Rays {
        origin: V3::splat(ray.origin),
        dir: V3::splat(ray.dir),
        leaving: F64x1(ray.leaving.map_or(-1.0, |o| o as f64)),
    }
}

#[inline(always)]
fn plane<V: Lanes>(p: &Flat, rays: &Rays<V>, active: V::M) -> (V::M, V) {
    let own = rays.leaving.eq(V::splat(f64::from(p.object)));
    plane_hit(
        V3::splat(p.point),
        V3::splat(p.normal),
        rays.origin,
        rays.dir,
        own,
        active,
    )
}

#[cfg(test)]
mod tests;
