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
use crate::scene::{Mesh, MeshShading, Placement, Shape};
use glam::DVec3;

/// What shading needs about the lanes that hit a triangle. The stations of `gouraud` and
/// `constant` lanes (their placed corners and corner normals) are worked out only when
/// shading asks for them: most meshes are lit at the hit.
pub(super) struct MeshLanes<'w, V: Lanes> {
    world: &'w World,
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
    /// Each lane's (object, triangle, u, v), for the stations.
    at: [(usize, u32, f64, f64); MAX_LANES],
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

/// What `gather` finds: each mesh lane's (object, triangle, u, v); its geometric normal,
/// shading normal and lift (x, y, z, x, y, z, δ, one array each); the lanes lit at their
/// vertices (`gouraud`) and at their centroid (`constant`).
struct Gathered {
    at: [(usize, u32, f64, f64); MAX_LANES],
    out: [[f64; MAX_LANES]; 7],
    gouraud: u32,
    constant: u32,
}

/// `MeshLanes::of`'s per-lane work on the lanes in `bits`, from each lane's object, t, u, v
/// and hit point x, y, z (`lanes`, one array each) and triangle. Scalar f64 code, compiled
/// once for every kernel and kept out of the shading of scenes without meshes.
#[inline(never)]
fn gather(
    world: &World,
    bits: u32,
    lanes: &[[f64; MAX_LANES]; 7],
    prim: &[u32; MAX_LANES],
    roundoff: f64,
) -> Gathered {
    let [objects, t, u, v, px, py, pz] = lanes;
    // Filled in place and returned whole: built in locals, it was copied out (2.8 KB a call).
    let mut g = Gathered {
        at: [(0usize, NO_TRIANGLE, 0.0, 0.0); MAX_LANES],
        out: [[0.0f64; MAX_LANES]; 7],
        gouraud: 0,
        constant: 0,
    };
    let at = &mut g.at;
    // Every lane's triangle (its vertex indices) first, then the lanes' vertices: no lane's
    // vertex fetches then wait on its own triangle's, and the fetches of different lanes
    // overlap (a fine mesh's hits often miss the cache).
    let mut corners = [[0u32; 3]; MAX_LANES];
    let mut rest = bits;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        at[k] = (objects[k] as usize, prim[k], u[k], v[k]);
        corners[k] = indices(world, at[k]);
    }
    let mut rest = bits;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let p = DVec3::new(px[k], py[k], pz[k]);
        let (geom, shade, shading) = normals(world, at[k], corners[k]);
        let delta = lift_distance(p, t[k], roundoff);
        for (i, x) in [geom.x, geom.y, geom.z, shade.x, shade.y, shade.z, delta]
            .into_iter()
            .enumerate()
        {
            g.out[i][k] = x;
        }
        match shading {
            MeshShading::Gouraud => g.gouraud |= 1 << k,
            MeshShading::Constant => g.constant |= 1 << k,
            _ => {}
        }
    }
    g
}

impl<'w, V: Lanes> MeshLanes<'w, V> {
    /// The mesh lanes of `hit` (None when no lane hit a triangle).
    #[inline(always)]
    pub(super) fn of(world: &'w World, hit: &Nearest<V>, point: V3<V>) -> Option<MeshLanes<'w, V>> {
        let hits = hit.hit.bits();
        let mut bits = 0u32;
        for k in 0..V::N {
            if hits >> k & 1 == 1 && hit.prim[k] != NO_TRIANGLE {
                bits |= 1 << k;
            }
        }
        if bits == 0 {
            return None;
        }
        let lanes = [
            hit.object.array(),
            hit.t.array(),
            hit.u.array(),
            hit.v.array(),
            point.x.array(),
            point.y.array(),
            point.z.array(),
        ];
        let Gathered {
            at,
            out,
            gouraud,
            constant,
        } = gather(world, bits, &lanes, &hit.prim, roundoff::<V>());
        // Loads written out: a closure is compiled outside the kernel's target feature.
        Some(MeshLanes {
            world,
            is_mesh: V::M::from_bits(bits),
            geom: V3 {
                x: V::load(&out[0]),
                y: V::load(&out[1]),
                z: V::load(&out[2]),
            },
            shade: V3 {
                x: V::load(&out[3]),
                y: V::load(&out[4]),
                z: V::load(&out[5]),
            },
            delta: V::load(&out[6]),
            gouraud: V::M::from_bits(gouraud),
            constant: V::M::from_bits(constant),
            at,
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
            let p = self.corner_lanes(self.gouraud, station, false);
            let n = self.corner_lanes(self.gouraud, station, true);
            (self.gouraud, p, V3::select(back, -n, n))
        } else {
            let c0 = self.corner_lanes(self.constant, 0, false);
            let c1 = self.corner_lanes(self.constant, 1, false);
            let c2 = self.corner_lanes(self.constant, 2, false);
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
        let mut w = [[0.0; MAX_LANES]; 3];
        let mut bits = self.gouraud.bits();
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (_, _, u, v) = self.at[k];
            (w[0][k], w[1][k], w[2][k]) = (1.0 - u - v, u, v);
        }
        let (w0, w1, w2) = (V::load(&w[0]), V::load(&w[1]), V::load(&w[2]));
        let vertices = lit[1] * w0 + lit[2] * w1 + lit[3] * w2;
        let color = V3::select(self.gouraud, vertices, lit[0]);
        V3::select(self.constant, lit[4], color)
    }

    /// Corner `i` of the hit triangles placed, or its normal placed, on `lanes` (0 elsewhere).
    #[inline(always)]
    fn corner_lanes(&self, lanes: V::M, i: usize, normal: bool) -> V3<V> {
        let mut out = [[0.0; MAX_LANES]; 3];
        let mut bits = lanes.bits();
        while bits != 0 {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let x = corner(self.world, self.at[k], i, normal);
            (out[0][k], out[1][k], out[2][k]) = (x.x, x.y, x.z);
        }
        V3 {
            x: V::load(&out[0]),
            y: V::load(&out[1]),
            z: V::load(&out[2]),
        }
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

/// The placement and shading model of mesh object `object`, and its mesh.
#[inline(always)]
fn placed(world: &World, object: usize) -> (Placement, &Mesh, MeshShading) {
    let scene = &world.scene;
    let Shape::Mesh {
        mesh,
        place,
        shading,
    } = scene.objects[object].shape
    else {
        unreachable!("a triangle hit on an object that is not a mesh");
    };
    (place, &scene.meshes[mesh], shading)
}

/// The vertex indices of one lane's hit triangle.
#[inline(always)]
fn indices(world: &World, (object, prim, _, _): (usize, u32, f64, f64)) -> [u32; 3] {
    placed(world, object).1.triangles[prim as usize]
}

/// The geometric and shading normals of one lane that hit the triangle of `object` with vertex
/// indices `tri` at barycentrics (u, v), and the object's shading model. Scalar f64 code,
/// compiled once for every kernel (in `gather`).
#[inline(always)]
fn normals(
    world: &World,
    (object, _, u, v): (usize, u32, f64, f64),
    tri: [u32; 3],
) -> (DVec3, DVec3, MeshShading) {
    let (place, m, shading) = placed(world, object);
    let q = tri.map(|i| m.positions[i as usize]);
    let n = tri.map(|i| m.normals[i as usize]);
    let b = [1.0 - u - v, u, v];
    let wound = place.normal((q[1] - q[0]).cross(q[2] - q[0]));
    let smooth = smooth_or(&place, n[0] * b[0] + n[1] * b[1] + n[2] * b[2], wound);
    // The vertex normals say which side is out (a file may wind its faces either way).
    let geom = if wound.dot(smooth) < 0.0 {
        -wound
    } else {
        wound
    };
    let shade = match shading {
        MeshShading::Phong | MeshShading::Gouraud => smooth,
        MeshShading::Flat | MeshShading::Constant => geom,
    };
    (geom, shade, shading)
}

/// The placed smooth normal of the blend `sum` of vertex normals; `wound` where that is not
/// finite: opposed vertex normals that cancel to (0, 0, 0), or nearly, normalise to NaN or
/// infinity (docs/spec/mesh.md).
#[inline(always)]
fn smooth_or(place: &Placement, sum: DVec3, wound: DVec3) -> DVec3 {
    let smooth = place.normal(sum);
    // A finite unit vector has s·s within rounding of 1; NaN and infinities fail the test.
    match (smooth.dot(smooth) - 1.0).abs() < 0.5 {
        true => smooth,
        false => wound,
    }
}

/// Corner `i` of one lane's triangle placed, or (`normal`) its vertex normal placed.
#[inline(never)]
fn corner(
    world: &World,
    (object, prim, _, _): (usize, u32, f64, f64),
    i: usize,
    normal: bool,
) -> DVec3 {
    let (place, m, _) = placed(world, object);
    let v = m.triangles[prim as usize][i] as usize;
    match normal {
        false => place.point(m.positions[v]),
        true => place.normal(m.normals[v]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

    #[test]
    fn cancelled_vertex_normals_fall_back_to_the_wound_normal() {
        let place = Placement {
            scale: DVec3::new(2.0, 1.0, 0.5),
            rotation: DMat3::IDENTITY,
            translate: DVec3::ZERO,
        };
        let wound = DVec3::Z;
        // n0 = +y, n1 = −y, met half way along their edge: the blend is exactly 0.
        let sum = DVec3::Y * 0.5 + DVec3::NEG_Y * 0.5;
        assert_eq!(smooth_or(&place, sum, wound), wound);
        assert_eq!(
            smooth_or(&place, DVec3::new(1e-320, 0.0, 0.0), wound),
            wound
        );
        let s = smooth_or(&place, DVec3::new(0.0, 3.0, 0.0), wound);
        assert_eq!(s, DVec3::Y);
    }
}
