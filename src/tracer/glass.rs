//! Transparent materials, the talk's fourth kind of ray: refraction by Snell's law, total
//! internal reflection, Schlick's Fresnel term, light reaching a point through transparent
//! objects, and the path tree a scene with them traces (a hit may send on a reflection ray
//! and a transmission ray). A scene without such materials never comes here.
//!
//! Every medium but the one behind a surface (inside a sphere, behind a plane) has index 1:
//! a ray entering a surface goes from 1 to its `ior`, one leaving it from `ior` to 1. Nested
//! or touching glass is simplified to that.

use super::World;
use super::accel::Rays;
use super::bvh::Bvh;
use super::intersect::{plane_hit, sphere_hit};
use super::mesh::Instance;
use super::path::Eye;
use super::shade::{NEGLIGIBLE_WEIGHT, Shaded, powi, shade_hit};
use super::sky::Background;
use super::texture::{self, Cone};
use crate::lanes::{F64x1, Lanes, MAX_LANES, Mask, V3};
use crate::scene::{Material, Object, Shape};
use glam::DVec3;
use std::sync::Arc;

/// An object light passes through, for shadow rays.
#[derive(Debug, Clone)]
pub struct Clear {
    shape: Shape,
    /// r² for a sphere, as the intersection forms it.
    r2: f64,
    object: f64,
    filter: DVec3,
    /// A mesh's placement.
    mesh: Option<Instance>,
}

impl Clear {
    pub fn new(o: &Object, index: usize, filter: DVec3, bvhs: &[Arc<Bvh>]) -> Clear {
        let (r2, mesh) = match o.shape {
            Shape::Sphere { radius, .. } => (radius * radius, None),
            Shape::Plane { .. } => (0.0, None),
            Shape::Mesh { mesh, place, .. } => {
                (0.0, Some(Instance::new(index, bvhs[mesh].clone(), &place)))
            }
        };
        Clear {
            shape: o.shape,
            r2,
            object: index as f64,
            filter,
            mesh,
        }
    }
}

/// What reaches each `open` lane's point from its light through the transparent objects:
/// the product, in file order starting from (1, 1, 1), of the filters of those the shadow
/// ray meets before `dist` (each object once, however often the ray crosses it; no caustics).
#[inline(always)]
pub(super) fn transmittance<V: Lanes>(
    world: &World,
    shadow: &Rays<V>,
    dist: V,
    open: V::M,
) -> V3<V> {
    let mut through = V3::splat(DVec3::ONE);
    for c in &world.clear {
        let own = shadow.leaving.eq(V::splat(c.object));
        let (hit, t) = match (c.shape, &c.mesh) {
            (Shape::Sphere { center, .. }, _) => {
                let f = shadow.origin - V3::splat(center);
                sphere_hit(f, None, V::splat(c.r2), shadow.dir, own, open)
            }
            (Shape::Plane { point, normal, .. }, _) => plane_hit(
                V3::splat(point),
                V3::splat(normal),
                shadow.origin,
                shadow.dir,
                own,
                open,
            ),
            // A mesh answers "crossed before dist" itself; t = 0 passes the test below.
            (Shape::Mesh { .. }, Some(m)) => (m.blocked(shadow, dist, open), V::splat(0.0)),
            (Shape::Mesh { .. }, None) => unreachable!("a clear mesh keeps its placement"),
        };
        let crossed = hit.and(t.lt(dist));
        if crossed.any() {
            through = V3::select(crossed, through * V3::splat(c.filter), through);
        }
    }
    through
}

/// How a hit shares its light between the two rays it sends on.
pub(super) struct Split<V: Lanes> {
    /// Weight of the mirror ray, per channel.
    pub reflect: V3<V>,
    /// Weight of the transmission ray, per channel (0 under total internal reflection).
    pub transmit: V3<V>,
    /// Direction of the transmission ray.
    pub refracted: V3<V>,
}

/// The optical constants of the materials the lanes hit.
struct Optics<V: Lanes> {
    reflection: V,
    filter: V3<V>,
    ior: V,
    fresnel: V::M,
}

impl<V: Lanes> Optics<V> {
    #[inline(always)]
    fn of(at: &Shaded<V>) -> Optics<V> {
        let m = &at.surface.materials;
        if at.surface.shared {
            return Optics {
                reflection: at.surface.reflection,
                filter: V3::splat(m[0].transmission),
                ior: V::splat(m[0].ior),
                fresnel: if m[0].fresnel {
                    V::M::first(V::N)
                } else {
                    V::M::none_set()
                },
            };
        }
        let bits = (0..V::N)
            .filter(|&k| m[k].fresnel)
            .fold(0, |b, k| b | 1 << k);
        Optics {
            reflection: at.surface.reflection,
            filter: V3::from_fn(|k| m[k].transmission),
            ior: V::from_fn(|k| m[k].ior),
            fresnel: V::M::from_bits(bits),
        }
    }
}

/// Snell's law and the weights where rays with direction `d` meet a surface of normal `n`
/// (facing them), from outside where `entering`: the weights are r and the filter T, or with
/// `fresnel` F and (1 − F)·T (Schlick); under total internal reflection the transmitted
/// weight joins the reflected one.
#[inline(always)]
fn scatter<V: Lanes>(o: &Optics<V>, d: V3<V>, n: V3<V>, entering: V::M) -> Split<V> {
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let cos_i = -n.dot(d);
    // n₁/n₂: from outside into the medium, or from the medium out.
    let eta = V::select(entering, one / o.ior, o.ior);
    let k = one - eta * eta * (one - cos_i * cos_i);
    let total = k.lt(zero);
    let root = V::select(total, zero, k).sqrt();
    let bent = (d * eta + n * (eta * cos_i - root)).normalize();
    // Equal indices: the ray goes straight on, exactly.
    let refracted = V3::select(eta.eq(one), d, bent);
    // Schlick: F = R₀ + (1 − R₀)(1 − c)⁵, c the cosine on the side of the smaller index.
    let (n1, n2) = (
        V::select(entering, one, o.ior),
        V::select(entering, o.ior, one),
    );
    let q = (n1 - n2) / (n1 + n2);
    let r0 = q * q;
    let c = V::select(entering, cos_i, root);
    let f = r0 + (one - r0) * powi(one - c, 5);
    let f = V::select(total, one, f);
    let r = o.reflection;
    let reflect = V3::select(o.fresnel, V3 { x: f, y: f, z: f }, V3 { x: r, y: r, z: r });
    let transmit = V3::select(o.fresnel, o.filter * (one - f), o.filter);
    Split {
        reflect: V3::select(total, reflect + transmit, reflect),
        transmit: V3::select(total, V3::zero(), transmit),
        refracted,
    }
}

/// How one ray with direction `d` meets a surface of `material` with unit normal `n` (facing
/// the ray), from outside where `entering`: the one-lane `scatter`, for tests and tools.
/// Returns the reflected and transmitted weights and the transmitted direction.
pub fn scatter_one(
    material: &Material,
    d: DVec3,
    n: DVec3,
    entering: bool,
) -> (DVec3, DVec3, DVec3) {
    let o = Optics {
        reflection: F64x1(material.reflection),
        filter: V3::splat(material.transmission),
        ior: F64x1(material.ior),
        fresnel: material.fresnel,
    };
    let s = scatter(&o, V3::splat(d), V3::splat(n), entering);
    (s.reflect.lane(0), s.transmit.lane(0), s.refracted.lane(0))
}

/// One branch of a path tree: a packet of rays and each lane's weight.
struct Branch<V: Lanes> {
    rays: Rays<V>,
    active: V::M,
    weight: V3<V>,
    /// The rays' footprint cones (used when the eye's `footprint` is set).
    cone: Cone<V>,
}

/// Rays one eye sample's tree may trace (eye, reflection and transmission rays, not shadow
/// rays): at least 1024, and never fewer than a single path of `max_depth` surfaces.
pub fn tree_budget(max_depth: u32) -> u32 {
    max_depth.max(1024)
}

/// Follows each lane's eye ray through a tree of at most `max_depth` surfaces on any path,
/// level by level: every surface k bounces from the eye before any at k + 1, and within a
/// level the branches in order, each hit's reflection branch before its transmission branch.
/// A lane's branches stop when their weight is negligible, at `max_depth`, or when the lane
/// has traced `tree_budget` rays. Colour sums in that order, so it is the same for every
/// packing of rays into lanes.
#[inline(always)]
pub(super) fn trace_tree<V: Lanes>(
    world: &World,
    eye: &Eye<V>,
    max_depth: u32,
    rays: &mut u64,
) -> (V3<V>, V::M) {
    let background = Background::of(world);
    let budget = tree_budget(max_depth);
    let mut covered = V::M::none_set();
    let mut spent = [0u32; MAX_LANES];
    let mut color = V3::zero();
    let mut level = vec![Branch {
        rays: eye.rays,
        active: eye.active,
        weight: V3::splat(DVec3::ONE),
        cone: Cone::eye(eye.footprint.unwrap_or(0.0)),
    }];
    let textured = eye.footprint.is_some();
    let mut next = Vec::new();
    for depth in 0..max_depth {
        for b in &level {
            let active = afford(b.active, &mut spent, budget);
            if !active.any() {
                continue;
            }
            *rays += active.count();
            let from_origin = if depth == 0 { eye.from_origin } else { None };
            let hit = world.geometry.nearest(&b.rays, from_origin, active);
            let missed = active.andnot(hit.hit);
            if missed.any() && !(depth == 0 && eye.transparent) {
                let spread = if textured { Some(b.cone.spread) } else { None };
                let seen = background.seen(&b.rays.dir, missed, spread);
                color = V3::select(missed, color + seen * b.weight, color);
            }
            if depth == 0 {
                covered = hit.hit;
            }
            if !hit.hit.any() {
                continue;
            }
            let pixel = if depth == 0 { eye.pixel } else { None };
            let width = if textured {
                Some((b.cone.at(hit.t), pixel))
            } else {
                None
            };
            let at = shade_hit(world, &b.rays, &hit, eye.lights, rays, width);
            color = V3::select(hit.hit, color + at.local * b.weight, color);
            if depth + 1 == max_depth {
                continue;
            }
            let (mirror, through) = match textured {
                true => {
                    let bend = texture::curvature(world, hit.object);
                    let flat = V::splat(0.0);
                    (
                        b.cone.leaving(hit.t, bend, at.entering),
                        b.cone.leaving(hit.t, flat, at.entering),
                    )
                }
                false => (b.cone, b.cone),
            };
            let split = scatter(&Optics::of(&at), b.rays.dir, at.normal, at.entering);
            let transmitted = Rays {
                origin: at.leave(split.refracted),
                dir: split.refracted,
                leaving: hit.object,
            };
            let reflected = at.reflected(&b.rays, &hit);
            grow(
                &mut next,
                (reflected, mirror),
                b.weight * split.reflect,
                hit.hit,
            );
            grow(
                &mut next,
                (transmitted, through),
                b.weight * split.transmit,
                hit.hit,
            );
        }
        if next.is_empty() {
            break;
        }
        std::mem::swap(&mut level, &mut next);
        next.clear();
    }
    (color, covered)
}

/// Adds the branch for the lanes of `active` whose weight is not negligible in every channel.
/// Branches split a packet's lanes (glass lanes transmit, the others do not), so a branch
/// whose lanes are all idle in the last packet of the level fills those instead of starting
/// a packet of its own. Each lane still meets its own branches in the same order, so no
/// pixel changes; only fewer, fuller packets are traced.
#[inline(always)]
fn grow<V: Lanes>(
    next: &mut Vec<Branch<V>>,
    (rays, cone): (Rays<V>, Cone<V>),
    weight: V3<V>,
    active: V::M,
) {
    let largest = weight.x.max(weight.y).max(weight.z);
    let active = active.andnot(largest.lt(V::splat(NEGLIGIBLE_WEIGHT)));
    if !active.any() {
        return;
    }
    if let Some(last) = next.last_mut()
        && !last.active.and(active).any()
    {
        last.rays = Rays {
            origin: V3::select(active, rays.origin, last.rays.origin),
            dir: V3::select(active, rays.dir, last.rays.dir),
            leaving: V::select(active, rays.leaving, last.rays.leaving),
        };
        last.weight = V3::select(active, weight, last.weight);
        last.cone = Cone::select(active, cone, last.cone);
        last.active = last.active.or(active);
        return;
    }
    next.push(Branch {
        rays,
        active,
        weight,
        cone,
    });
}

/// The lanes of `active` that may trace one more ray, charging it to them.
#[inline(always)]
fn afford<M: Mask>(active: M, spent: &mut [u32; MAX_LANES], budget: u32) -> M {
    let mut bits = 0;
    for (k, s) in spent.iter_mut().enumerate() {
        if active.lane(k) && *s < budget {
            *s += 1;
            bits |= 1 << k;
        }
    }
    M::from_bits(bits)
}
