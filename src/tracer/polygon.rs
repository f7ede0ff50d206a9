//! Shading on meshes, the talk's polygon shading: per hit triangle its normals (geometric and
//! shading), the lift that keeps secondary rays off the mesh, and the two models that light
//! somewhere else than at the hit: `gouraud` (at the three vertices, colours interpolated)
//! and `constant` (once at the centroid with the face normal).
//!
//! Everything per lane here is computed in f64 from the scene's data and the hit's t, u and v
//! (widened exactly from the lanes), then rounded once into the lanes: each lane's value is the
//! same for every packet width.

use super::World;
use super::accel::{Nearest, Rays};
use super::mesh::NO_TRIANGLE;
use super::shade::Lift;
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::scene::{MeshShading, Shape};
use glam::DVec3;

/// What shading needs about the lanes that hit a triangle.
pub(super) struct MeshLanes<V: Lanes> {
    pub is_mesh: V::M,
    /// Unit geometric normal (v1 − v0) × (v2 − v0) placed in the world, turned to the side
    /// the interpolated vertex normal points to (the outside).
    pub geom: V3<V>,
    /// Unit shading normal: interpolated vertex normals (`phong`, `gouraud`) or the face's.
    pub shade: V3<V>,
    /// How far secondary rays start off the surface (0 on other lanes).
    pub delta: V,
    gouraud: V::M,
    constant: V::M,
    corners: [[DVec3; MAX_LANES]; 3],
    corner_normals: [[DVec3; MAX_LANES]; 3],
    weights: [[f64; MAX_LANES]; 3],
}

/// Secondary rays from a mesh start δ = 64·u·(‖p‖∞ + t) off the hit along the geometric
/// normal, on the side they leave to (u: the lanes' unit roundoff). The hit point o + t·d
/// carries an error of a few u·(‖o‖∞ + t) and the triangle's own plane one of a few u·‖p‖∞.
pub(super) fn lift_distance(p: DVec3, t: f64, roundoff: f64) -> f64 {
    64.0 * roundoff * (p.abs().max_element() + t)
}

/// The unit roundoff of the lanes' float type.
#[inline(always)]
pub(super) fn roundoff<V: Lanes>() -> f64 {
    if V::BOX_SLACK == 0.0 {
        f64::EPSILON / 2.0
    } else {
        f64::from(f32::EPSILON) / 2.0
    }
}

impl<V: Lanes> MeshLanes<V> {
    /// The mesh lanes of `hit` (None when no lane hit a triangle).
    #[inline(always)]
    pub(super) fn of(world: &World, hit: &Nearest<V>, point: V3<V>) -> Option<MeshLanes<V>> {
        let mut bits = 0u32;
        for k in 0..V::N {
            if hit.hit.lane(k) && hit.prim[k] != NO_TRIANGLE {
                bits |= 1 << k;
            }
        }
        if bits == 0 {
            return None;
        }
        let (objects, t, u, v) = (
            hit.object.array(),
            hit.t.array(),
            hit.u.array(),
            hit.v.array(),
        );
        let mut out = [Lane::default(); MAX_LANES];
        let (mut gouraud, mut constant) = (0u32, 0u32);
        let u_lanes = roundoff::<V>();
        for (k, lane) in out.iter_mut().enumerate().take(V::N) {
            if bits >> k & 1 == 0 {
                continue;
            }
            let at = (objects[k] as usize, hit.prim[k], u[k], v[k]);
            let shading;
            (*lane, shading) = Lane::of(world, at, point.lane(k), t[k], u_lanes);
            match shading {
                MeshShading::Gouraud => gouraud |= 1 << k,
                MeshShading::Constant => constant |= 1 << k,
                _ => {}
            }
        }
        Some(MeshLanes {
            is_mesh: V::M::from_bits(bits),
            geom: V3::from_fn(|k| out[k].geom),
            shade: V3::from_fn(|k| out[k].shade),
            delta: V::from_fn(|k| out[k].delta),
            gouraud: V::M::from_bits(gouraud),
            constant: V::M::from_bits(constant),
            corners: std::array::from_fn(|i| std::array::from_fn(|k| out[k].corners[i])),
            corner_normals: std::array::from_fn(|i| {
                std::array::from_fn(|k| out[k].corner_normals[i])
            }),
            weights: std::array::from_fn(|i| std::array::from_fn(|k| out[k].weights[i])),
        })
    }

    /// The lanes that are lit somewhere else than at the hit.
    #[inline(always)]
    pub(super) fn elsewhere(&self) -> V::M {
        self.gouraud.or(self.constant)
    }

    /// On the mesh lanes, given the other lanes' normal and entering mask: the shading normal
    /// turned to the side the ray comes from (the side the geometric normal faces it from),
    /// the lanes entering the mesh (hitting a front face, against the geometric normal), and
    /// the lift for rays leaving the hits.
    #[inline(always)]
    pub(super) fn facing(
        &self,
        dir: V3<V>,
        normal: V3<V>,
        entering: V::M,
    ) -> (V3<V>, V::M, Lift<V>) {
        let back = self.geom.dot(dir).gt(V::splat(0.0));
        let shade = V3::select(back, -self.shade, self.shade);
        let front = V::M::first(V::N).andnot(back);
        (
            V3::select(self.is_mesh, shade, normal),
            self.is_mesh.and(front).or(entering.andnot(self.is_mesh)),
            Lift {
                normal: V3::select(back, -self.geom, self.geom),
                delta: V::select(self.is_mesh, self.delta, V::splat(0.0)),
            },
        )
    }

    /// Where `gouraud` lanes are lit (stations 0–2: the vertices, with their normals turned
    /// like the face) and `constant` lanes (station 3: the centroid ((p0 + p1) + p2)·(1/3),
    /// with the face normal turned to the ray): the lanes, point, normal, the direction light
    /// leaves towards the viewer reversed (normalize(p − o), o the hit ray's origin) and lift.
    #[inline(always)]
    pub(super) fn station(&self, station: usize, ray: &Rays<V>, lift: &Lift<V>) -> Station<V> {
        let (lanes, p, n) = if station < 3 {
            let back = self.geom.dot(ray.dir).gt(V::splat(0.0));
            let p = V3::from_fn(|k| self.corners[station][k]);
            let n = V3::from_fn(|k| self.corner_normals[station][k]);
            (self.gouraud, p, V3::select(back, -n, n))
        } else {
            let c0 = V3::from_fn(|k| self.corners[0][k]);
            let c1 = V3::from_fn(|k| self.corners[1][k]);
            let c2 = V3::from_fn(|k| self.corners[2][k]);
            (
                self.constant,
                (c0 + c1 + c2) * V::splat(1.0 / 3.0),
                lift.normal,
            )
        };
        let at = Lift {
            normal: lift.normal,
            delta: self.lift_at(p),
        };
        Station {
            lanes,
            point: p,
            normal: n,
            view: (p - ray.origin).normalize(),
            lift: at,
        }
    }

    /// The colour of each lane from the stations' light: `lit[0]` at the hit, on `gouraud`
    /// lanes ((b0·c0 + b1·c1) + b2·c2) of the vertices' `lit[1..4]`, on `constant` lanes the
    /// centroid's `lit[4]`.
    #[inline(always)]
    pub(super) fn mixed(&self, lit: &[V3<V>; 5]) -> V3<V> {
        let w0 = V::from_fn(|k| self.weights[0][k]);
        let w1 = V::from_fn(|k| self.weights[1][k]);
        let w2 = V::from_fn(|k| self.weights[2][k]);
        let vertices = lit[1] * w0 + lit[2] * w1 + lit[3] * w2;
        let color = V3::select(self.gouraud, vertices, lit[0]);
        V3::select(self.constant, lit[4], color)
    }

    /// δ for rays leaving `p` (a vertex or the centroid) of the hit triangles; 0 off meshes.
    #[inline(always)]
    fn lift_at(&self, p: V3<V>) -> V {
        let u = roundoff::<V>();
        // Lane values leave the lanes before the closure, which sees plain f64 only.
        let (x, y, z) = (p.x.array(), p.y.array(), p.z.array());
        let delta = V::from_fn(|k| lift_distance(DVec3::new(x[k], y[k], z[k]), 0.0, u));
        V::select(self.is_mesh, delta, V::splat(0.0))
    }
}

/// Where a station lights its lanes: the point, the normal facing the ray, the direction from
/// the viewer (in the place of the ray's), and the lift of its shadow rays.
pub(super) struct Station<V: Lanes> {
    pub lanes: V::M,
    pub point: V3<V>,
    pub normal: V3<V>,
    pub view: V3<V>,
    pub lift: Lift<V>,
}

/// One lane's values while they are gathered.
#[derive(Clone, Copy, Default)]
struct Lane {
    geom: DVec3,
    shade: DVec3,
    delta: f64,
    corners: [DVec3; 3],
    corner_normals: [DVec3; 3],
    weights: [f64; 3],
}

impl Lane {
    /// The values of one lane that hit triangle `prim` of object `object` at barycentrics
    /// (u, v), point `p` and distance `t`. Scalar f64 code, compiled once for every kernel.
    #[inline(never)]
    fn of(
        world: &World,
        (object, prim, u, v): (usize, u32, f64, f64),
        p: DVec3,
        t: f64,
        roundoff: f64,
    ) -> (Lane, MeshShading) {
        let scene = &world.scene;
        let Shape::Mesh {
            mesh,
            place,
            shading,
        } = scene.objects[object].shape
        else {
            unreachable!("a triangle hit on an object that is not a mesh");
        };
        let m = &scene.meshes[mesh];
        let tri = m.triangles[prim as usize];
        let q = tri.map(|i| m.positions[i as usize]);
        let n = tri.map(|i| m.normals[i as usize]);
        let b = [1.0 - u - v, u, v];
        let wound = place.normal((q[1] - q[0]).cross(q[2] - q[0]));
        let smooth = place.normal(n[0] * b[0] + n[1] * b[1] + n[2] * b[2]);
        // The vertex normals say which side is out (a file may wind its faces either way).
        let geom = if wound.dot(smooth) < 0.0 {
            -wound
        } else {
            wound
        };
        let lane = Lane {
            geom,
            shade: match shading {
                MeshShading::Phong | MeshShading::Gouraud => smooth,
                MeshShading::Flat | MeshShading::Constant => geom,
            },
            delta: lift_distance(p, t, roundoff),
            corners: q.map(|x| place.point(x)),
            corner_normals: n.map(|x| place.normal(x)),
            weights: b,
        };
        (lane, shading)
    }
}
