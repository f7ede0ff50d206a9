//! The geometry the tracer queries: spheres and planes in flat arrays, and a bounding volume
//! hierarchy over the spheres only when a scene has enough of them to need one. Every hit is
//! computed by the same `intersect` as the plain loop; the hierarchy only skips spheres whose
//! (slightly padded) boxes the ray cannot enter, so it never changes an image.

use super::intersect::{Hit, Ray, intersect};
use crate::scene::{Object, Shape};
use glam::DVec3;

/// Below this many spheres a plain loop beats any hierarchy (measured with `rayreel bench`).
pub const BVH_MIN_SPHERES: usize = 12;
const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone)]
pub struct Geometry {
    /// Spheres in hierarchy order, as plain records so the hot loop needs no shape dispatch.
    spheres: Vec<Ball>,
    planes: Vec<(Shape, u32)>,
    bvh: Vec<Node>,
}

#[derive(Debug, Clone, Copy)]
struct Ball {
    center: DVec3,
    radius: f64,
    /// radius², for the cheap miss test.
    r2: f64,
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
}

impl Geometry {
    pub fn new(objects: &[Object]) -> Geometry {
        let mut spheres = Vec::new();
        let mut planes = Vec::new();
        for (i, o) in objects.iter().enumerate() {
            match o.shape {
                Shape::Sphere { center, radius } => spheres.push(Ball {
                    center,
                    radius,
                    r2: radius * radius,
                    object: i as u32,
                }),
                Shape::Plane { .. } => planes.push((o.shape, i as u32)),
            }
        }
        let mut bvh = Vec::new();
        if spheres.len() >= BVH_MIN_SPHERES {
            bvh.push(Node {
                min: DVec3::ZERO,
                max: DVec3::ZERO,
                first: 0,
                count: 0,
            });
            let n = spheres.len();
            build(&mut bvh, &mut spheres, 0, 0, n);
        }
        Geometry {
            spheres,
            planes,
            bvh,
        }
    }

    /// Whether a hierarchy was built (reported by `rayreel bench`).
    pub fn has_bvh(&self) -> bool {
        !self.bvh.is_empty()
    }

    pub fn nearest(&self, ray: &Ray) -> Option<Hit> {
        let mut best = Hit {
            t: f64::INFINITY,
            object: usize::MAX,
        };
        if self.bvh.is_empty() {
            closest_ball(&self.spheres, ray, &mut best);
        } else {
            self.walk(ray, &mut |range, _| {
                closest_ball(&self.spheres[range], ray, &mut best);
                best.t
            });
        }
        closest(&self.planes, ray, &mut best);
        (best.t < f64::INFINITY).then_some(best)
    }

    /// Whether anything lies on `ray` strictly before `max_t`.
    pub fn occluded(&self, ray: &Ray, max_t: f64) -> bool {
        if blocked(&self.planes, ray, max_t) {
            return true;
        }
        if self.bvh.is_empty() {
            return blocked_ball(&self.spheres, ray, max_t);
        }
        let mut found = false;
        self.walk(ray, &mut |range, _| {
            found = blocked_ball(&self.spheres[range], ray, max_t);
            // A hit ends the walk: nothing can be nearer than "before max_t" matters.
            if found { f64::NEG_INFINITY } else { max_t }
        });
        found
    }

    /// Visits the leaves whose boxes the ray enters before the limit `visit` returns (the
    /// nearest hit so far), nearer child first.
    fn walk(&self, ray: &Ray, visit: &mut dyn FnMut(std::ops::Range<usize>, f64) -> f64) {
        let inv = DVec3::ONE / ray.dir;
        let mut limit = f64::INFINITY;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.bvh[stack[top] as usize];
            if entry(node, ray.origin, inv, limit).is_none() {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                limit = visit(first..first + node.count as usize, limit);
                if limit == f64::NEG_INFINITY {
                    return;
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let tl = entry(&self.bvh[l as usize], ray.origin, inv, limit);
            let tr = entry(&self.bvh[r as usize], ray.origin, inv, limit);
            // Push the farther child first so the nearer one is visited first.
            let order = match (tl, tr) {
                (Some(a), Some(b)) if a <= b => [Some(r), Some(l)],
                (Some(_), Some(_)) => [Some(l), Some(r)],
                (Some(_), None) => [None, Some(l)],
                (None, Some(_)) => [None, Some(r)],
                (None, None) => [None, None],
            };
            for child in order.into_iter().flatten() {
                stack[top] = child;
                top += 1;
            }
        }
    }
}

/// Lowers `best` to the nearest hit among `shapes`.
#[inline]
fn closest(shapes: &[(Shape, u32)], ray: &Ray, best: &mut Hit) {
    for (shape, object) in shapes {
        let own = ray.leaving == Some(*object as usize);
        if let Some(t) = intersect(shape, ray, own)
            && t < best.t
        {
            *best = Hit {
                t,
                object: *object as usize,
            };
        }
    }
}

/// Most rays miss most spheres: the squared distance from the centre to the line (the first
/// half of `sphere_roots`, the same arithmetic) rejects them before any root or division.
#[inline(always)]
fn hit_ball(b: &Ball, ray: &Ray) -> Option<f64> {
    let f = ray.origin - b.center;
    let along = f.dot(ray.dir);
    let perp = f - along * ray.dir;
    let disc = b.r2 - perp.dot(perp);
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let shape = Shape::Sphere {
        center: b.center,
        radius: b.radius,
    };
    intersect(&shape, ray, ray.leaving == Some(b.object as usize))
}

#[inline]
fn closest_ball(balls: &[Ball], ray: &Ray, best: &mut Hit) {
    for b in balls {
        if let Some(t) = hit_ball(b, ray)
            && t < best.t
        {
            *best = Hit {
                t,
                object: b.object as usize,
            };
        }
    }
}

#[inline]
fn blocked_ball(balls: &[Ball], ray: &Ray, max_t: f64) -> bool {
    balls
        .iter()
        .any(|b| hit_ball(b, ray).is_some_and(|t| t < max_t))
}

/// Whether any of `shapes` lies on the ray before `max_t`.
#[inline]
fn blocked(shapes: &[(Shape, u32)], ray: &Ray, max_t: f64) -> bool {
    for (shape, object) in shapes {
        let own = ray.leaving == Some(*object as usize);
        if intersect(shape, ray, own).is_some_and(|t| t < max_t) {
            return true;
        }
    }
    false
}

/// Where the ray enters the node's box, if before `limit`.
#[inline]
fn entry(node: &Node, origin: DVec3, inv: DVec3, limit: f64) -> Option<f64> {
    let t0 = (node.min - origin) * inv;
    let t1 = (node.max - origin) * inv;
    // min/max skip the NaN of 0 · inf (a ray along a box face), keeping the test conservative.
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(limit);
    (near <= far).then_some(near)
}

fn bounds(b: &Ball) -> (DVec3, DVec3) {
    // Padding keeps the box conservative against rounding in the hit computation.
    let pad = b.radius + 1e-9 * (b.radius + b.center.abs().max_element());
    (b.center - pad, b.center + pad)
}

/// Builds node `at` over `spheres[lo..hi]`, split where the surface area heuristic (binned
/// along the widest centroid axis) says rays will test the fewest spheres.
fn build(nodes: &mut Vec<Node>, spheres: &mut [Ball], at: usize, lo: usize, hi: usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut cmin, mut cmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for b in &spheres[lo..hi] {
        let (a, z) = bounds(b);
        (min, max) = (min.min(a), max.max(z));
        (cmin, cmax) = (cmin.min(b.center), cmax.max(b.center));
    }
    let leaf = Node {
        min,
        max,
        first: lo as u32,
        count: (hi - lo) as u32,
    };
    if hi - lo <= LEAF_SIZE {
        nodes[at] = leaf;
        return;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = match sah_split(
        &mut spheres[lo..hi],
        axis,
        cmin[axis],
        extent[axis],
        area(min, max),
    ) {
        Some(m) => lo + m,
        None if hi - lo <= 4 * LEAF_SIZE => {
            nodes[at] = leaf;
            return;
        }
        None => {
            // Coincident centres or no better split: halve by rank to keep depth bounded.
            let mid = (lo + hi) / 2;
            spheres[lo..hi].select_nth_unstable_by(mid - lo, |a, b| {
                a.center[axis]
                    .total_cmp(&b.center[axis])
                    .then(a.object.cmp(&b.object))
            });
            mid
        }
    };
    let left = nodes.len();
    nodes.push(leaf);
    nodes.push(leaf);
    nodes[at] = Node {
        min,
        max,
        first: left as u32,
        count: 0,
    };
    build(nodes, spheres, left, lo, mid);
    build(nodes, spheres, left + 1, mid, hi);
}

fn area(min: DVec3, max: DVec3) -> f64 {
    let d = (max - min).max(DVec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// Partitions `spheres` at the cheapest of 16 bin boundaries; None when no split beats a leaf.
fn sah_split(
    spheres: &mut [Ball],
    axis: usize,
    start: f64,
    extent: f64,
    parent_area: f64,
) -> Option<usize> {
    const BINS: usize = 16;
    if extent <= 0.0 || parent_area <= 0.0 {
        return None;
    }
    let bin = |b: &Ball| (((b.center[axis] - start) / extent * BINS as f64) as usize).min(BINS - 1);
    let mut boxes = [(DVec3::INFINITY, DVec3::NEG_INFINITY, 0usize); BINS];
    for b in spheres.iter() {
        let (lo, hi) = bounds(b);
        let e = &mut boxes[bin(b)];
        *e = (e.0.min(lo), e.1.max(hi), e.2 + 1);
    }
    // Cost of splitting after bin i: area-weighted sphere counts on both sides.
    let sweep = |order: &mut dyn Iterator<Item = usize>| -> Vec<(f64, usize)> {
        let (mut lo, mut hi, mut n) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0);
        order
            .map(|i| {
                (lo, hi, n) = (lo.min(boxes[i].0), hi.max(boxes[i].1), n + boxes[i].2);
                (area(lo, hi) * n as f64, n)
            })
            .collect()
    };
    let left = sweep(&mut (0..BINS));
    let right = sweep(&mut (0..BINS).rev());
    let (best, cost) = (0..BINS - 1)
        .map(|i| (i, left[i].0 + right[BINS - 2 - i].0))
        .filter(|&(i, _)| left[i].1 > 0 && right[BINS - 2 - i].1 > 0)
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    if cost >= parent_area * spheres.len() as f64 {
        return None;
    }
    let mut m = 0;
    for i in 0..spheres.len() {
        if bin(&spheres[i]) <= best {
            spheres.swap(i, m);
            m += 1;
        }
    }
    (m > 0 && m < spheres.len()).then_some(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tracer::intersect::nearest;

    /// A deterministic field of spheres and a few rays from inside and outside it.
    #[test]
    fn hierarchy_finds_exactly_what_the_plain_loop_finds() {
        let mut objects = Vec::new();
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            let center = DVec3::new(
                rnd() * 20.0 - 10.0,
                rnd() * 20.0 - 10.0,
                rnd() * 20.0 - 10.0,
            );
            objects.push(Object {
                shape: Shape::Sphere {
                    center,
                    radius: 0.05 + rnd() * 0.5,
                },
                material: 0,
            });
        }
        objects.push(Object {
            shape: Shape::Plane {
                point: DVec3::new(0.0, -11.0, 0.0),
                normal: DVec3::Y,
            },
            material: 0,
        });
        let geometry = Geometry::new(&objects);
        assert!(geometry.has_bvh());
        for i in 0..4000 {
            let origin = if i % 2 == 0 {
                DVec3::new(0.0, 0.0, 30.0)
            } else {
                DVec3::new(rnd(), rnd(), rnd())
            };
            let dir =
                DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5 - f64::from(i % 2)).normalize();
            let ray = Ray {
                origin,
                dir,
                leaving: None,
            };
            let (a, b) = (geometry.nearest(&ray), nearest(&objects, &ray));
            assert_eq!(a, b, "ray {i}");
            let limit = a.map_or(f64::INFINITY, |h| h.t * 0.999);
            assert!(
                !geometry.occluded(&ray, limit) || limit == f64::INFINITY,
                "ray {i}"
            );
            assert_eq!(
                geometry.occluded(&ray, f64::INFINITY),
                b.is_some(),
                "ray {i}"
            );
        }
    }
}
