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
use super::triangle::cross;
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::scene::{Mesh, MeshShading, Placement, Shape};
use glam::DVec3;
use std::mem::MaybeUninit;

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

/// What the lanes' arithmetic reads of each mesh lane besides its t, u, v and hit point:
/// x, y, z of the triangle's corners (rows 0–8) and of their vertex normals (9–17).
const ROWS: usize = 18;

/// `MeshLanes::of`'s per-lane work on the lanes in `bits`, from each lane's object, t, u, v
/// and hit point x, y, z (`lanes`, one array each) and triangle. The fetches are scalar; the
/// arithmetic runs in f64 lanes (`V::F64`), the lanes on one object at a time, with the
/// operations of the scalar definition (`tests::normals`, `lift_distance`) in their order,
/// so every lane gets the same bits on every width.
#[inline(always)]
fn gather<V: Lanes>(
    world: &World,
    bits: u32,
    lanes: &[[f64; MAX_LANES]; 7],
    prim: &[u32; MAX_LANES],
    roundoff: f64,
) -> Gathered {
    let [objects, _, u, v, ..] = lanes;
    // Filled in place and returned whole: built in locals, it was copied out (2.8 KB a call).
    let mut g = Gathered {
        at: [(0usize, NO_TRIANGLE, 0.0, 0.0); MAX_LANES],
        out: [[0.0f64; MAX_LANES]; 7],
        gouraud: 0,
        constant: 0,
    };
    // Every lane's triangle (its vertex indices) first, then the lanes' vertices: no lane's
    // vertex fetches then wait on its own triangle's, and the fetches of different lanes
    // overlap (a fine mesh's hits often miss the cache).
    let mut tris = [[0u32; 3]; MAX_LANES];
    let mut last = (usize::MAX, None);
    let mut rest = bits;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        g.at[k] = (objects[k] as usize, prim[k], u[k], v[k]);
        tris[k] = mesh_of(world, g.at[k].0, &mut last).triangles[prim[k] as usize];
    }
    // The corners of every lane of a group of V::F64::N that holds a mesh lane (0 on the
    // lanes of the group without one).
    let group_of = |k: usize| low_bits(V::F64::N) << (k / V::F64::N * V::F64::N);
    let mut space = MaybeUninit::uninit();
    let mut rows = Rows {
        rows: &mut space,
        written: 0,
    };
    let mut rest = bits;
    while rest != 0 {
        let mut fill = group_of(rest.trailing_zeros() as usize);
        rest &= !fill;
        while fill != 0 {
            let k = fill.trailing_zeros() as usize;
            fill &= fill - 1;
            let mut row = [0.0; ROWS];
            if bits >> k & 1 == 1 {
                let m = mesh_of(world, g.at[k].0, &mut last);
                for (i, &vertex) in tris[k].iter().enumerate() {
                    let (q, n) = (m.positions[vertex as usize], m.normals[vertex as usize]);
                    row[3 * i..3 * i + 3].copy_from_slice(&[q.x, q.y, q.z]);
                    row[9 + 3 * i..12 + 3 * i].copy_from_slice(&[n.x, n.y, n.z]);
                }
            }
            rows.set(k, row);
        }
    }
    let mut rest = bits;
    while rest != 0 {
        let object = g.at[rest.trailing_zeros() as usize].0;
        let group = on_object(&g.at, rest, object);
        rest &= !group;
        let (place, _, shading) = placed(world, object);
        match shading {
            MeshShading::Gouraud => g.gouraud |= group,
            MeshShading::Constant => g.constant |= group,
            _ => {}
        }
        let face = matches!(shading, MeshShading::Flat | MeshShading::Constant);
        let mut from = 0;
        while from < V::N {
            let mask = group >> from & low_bits(V::F64::N);
            if mask != 0 {
                let part = Part {
                    from,
                    mask: <V::F64 as Lanes>::M::from_bits(mask),
                };
                lanes_of::<V::F64>(&place, face, &rows, lanes, part, roundoff, &mut g.out);
            }
            from += V::F64::N;
        }
    }
    g
}

/// Bits 0..n set (n from 1 to 32).
#[inline(always)]
fn low_bits(n: usize) -> u32 {
    u32::MAX >> (32 - n)
}

/// The mesh of `object`, looked up again only when the object changes from the `last` one.
#[inline(always)]
fn mesh_of<'w>(world: &'w World, object: usize, last: &mut (usize, Option<&'w Mesh>)) -> &'w Mesh {
    match *last {
        (o, Some(m)) if o == object => m,
        _ => {
            let m = placed(world, object).1;
            *last = (object, Some(m));
            m
        }
    }
}

/// The lanes of `lanes` (bit k for lane k) whose hit is on `object`.
#[inline(always)]
fn on_object(at: &[(usize, u32, f64, f64); MAX_LANES], lanes: u32, object: usize) -> u32 {
    let mut group = 0;
    let mut rest = lanes;
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        group |= u32::from(at[k].0 == object) << k;
    }
    group
}

/// Per-lane values, `ROWS` rows of them, left unwritten on the lanes no group needs: zeroing
/// them first cost more than the arithmetic (4.6 KB a packet). Only the array lives in the
/// caller's frame (as `walk::Stack`'s): a struct that also held `written` was zeroed whole
/// by the compiler.
struct Rows<'a> {
    rows: &'a mut MaybeUninit<[[f64; MAX_LANES]; ROWS]>,
    /// Bit k: lane k of every row is written.
    written: u32,
}

impl Rows<'_> {
    /// Writes lane k of every row.
    #[inline(always)]
    fn set(&mut self, k: usize, values: [f64; ROWS]) {
        assert!(k < MAX_LANES);
        let rows = self.rows.as_mut_ptr().cast::<f64>();
        for (r, x) in values.into_iter().enumerate() {
            // SAFETY: row r < ROWS and lane k < MAX_LANES lie inside the arrays; a write
            // through the pointer reads nothing.
            unsafe { rows.add(r * MAX_LANES + k).write(x) };
        }
        self.written |= 1 << k;
    }

    /// Lanes `from..from + n` of row `r`, all of them written.
    #[inline(always)]
    fn row(&self, r: usize, from: usize, n: usize) -> &[f64] {
        let want = low_bits(n) << from;
        assert!(r < ROWS && from + n <= MAX_LANES && self.written & want == want);
        // SAFETY: in bounds (checked), and lanes from..from + n of every row were written by
        // `set`.
        unsafe {
            let rows = self.rows.as_ptr().cast::<f64>();
            std::slice::from_raw_parts(rows.add(r * MAX_LANES + from), n)
        }
    }

    /// Lanes `from..from + W::N` of rows r, r + 1 and r + 2 (x, y, z).
    #[inline(always)]
    fn v3<W: Lanes>(&self, r: usize, from: usize) -> V3<W> {
        V3 {
            x: W::load(self.row(r, from, W::N)),
            y: W::load(self.row(r + 1, from, W::N)),
            z: W::load(self.row(r + 2, from, W::N)),
        }
    }
}

/// Lanes `from..from + W::N` of the per-lane arrays, of which `mask` are to be written.
struct Part<W: Lanes> {
    from: usize,
    mask: W::M,
}

/// `tests::normals` and `lift_distance` in the lanes `part` of one object's hits (placement `place`;
/// `face`: shaded with the face normal), from their corners (`rows`) and their t, u, v and
/// hit point (`lanes`): the geometric normal, shading normal and δ written into `out` on the
/// masked lanes.
#[inline(always)]
fn lanes_of<W: Lanes>(
    place: &Placement,
    face: bool,
    rows: &Rows<'_>,
    lanes: &[[f64; MAX_LANES]; 7],
    part: Part<W>,
    roundoff: f64,
    out: &mut [[f64; MAX_LANES]; 7],
) {
    let from = part.from;
    let (q0, q1, q2) = (rows.v3::<W>(0, from), rows.v3(3, from), rows.v3(6, from));
    let (n0, n1, n2) = (rows.v3::<W>(9, from), rows.v3(12, from), rows.v3(15, from));
    let (t, u, v) = (
        W::load(&lanes[1][from..]),
        W::load(&lanes[2][from..]),
        W::load(&lanes[3][from..]),
    );
    let one = W::splat(1.0);
    let b0 = one - u - v;
    let wound = placed_normal(place, cross(q1 - q0, q2 - q0));
    let smooth = placed_normal(place, n0 * b0 + n1 * u + n2 * v);
    // `smooth_or`: |s·s − 1| < 0.5, false for NaN and infinities.
    let finite = (smooth.dot(smooth) - one).copysign(one).lt(W::splat(0.5));
    let smooth = V3::select(finite, smooth, wound);
    let geom = V3::select(wound.dot(smooth).lt(W::splat(0.0)), -wound, wound);
    let shade = if face { geom } else { smooth };
    // Loaded where they lie: `V3::load` takes one array of three, which cost a copy of these.
    let p = V3 {
        x: W::load(&lanes[4][from..]),
        y: W::load(&lanes[5][from..]),
        z: W::load(&lanes[6][from..]),
    };
    let most =
        p.x.copysign(one)
            .max(p.y.copysign(one))
            .max(p.z.copysign(one));
    let delta = W::splat(64.0 * roundoff) * (most + t);
    let values = [geom.x, geom.y, geom.z, shade.x, shade.y, shade.z, delta];
    for (i, x) in values.into_iter().enumerate() {
        let old = W::load(&out[i][from..]);
        W::select(part.mask, x, old).store(&mut out[i][from..]);
    }
}

/// `Placement::normal` in lanes: (R · (n / s)) normalised, as glam computes it (R's columns
/// times n's components, summed x, y, z in order; 1/√(n·n) times each component).
#[inline(always)]
fn placed_normal<W: Lanes>(place: &Placement, n: V3<W>) -> V3<W> {
    let s = place.scale;
    let w = V3 {
        x: n.x / W::splat(s.x),
        y: n.y / W::splat(s.y),
        z: n.z / W::splat(s.z),
    };
    let r = place.rotation;
    (V3::splat(r.x_axis) * w.x + V3::splat(r.y_axis) * w.y + V3::splat(r.z_axis) * w.z).normalize()
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
        } = V::outlined(
            // Out of line: compiled once per lane type, and nothing of it in the shading of
            // scenes without meshes.
            #[inline(always)]
            || gather::<V>(world, bits, &lanes, &hit.prim, roundoff::<V>()),
        );
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
    use crate::lanes::F64x1;
    use glam::DMat3;

    /// The scalar definition of a mesh lane's normals (docs/spec/mesh.md), which `lanes_of`
    /// computes in lanes: the geometric and shading normals of a hit at barycentrics (u, v)
    /// of the triangle with corners `q` and vertex normals `n` under `place`.
    fn normals(
        place: &Placement,
        q: [DVec3; 3],
        n: [DVec3; 3],
        (u, v): (f64, f64),
        face: bool,
    ) -> (DVec3, DVec3) {
        let b = [1.0 - u - v, u, v];
        let wound = place.normal((q[1] - q[0]).cross(q[2] - q[0]));
        let smooth = smooth_or(place, n[0] * b[0] + n[1] * b[1] + n[2] * b[2], wound);
        // The vertex normals say which side is out (a file may wind its faces either way).
        let geom = if wound.dot(smooth) < 0.0 {
            -wound
        } else {
            wound
        };
        (geom, if face { geom } else { smooth })
    }

    /// The placed smooth normal of the blend `sum` of vertex normals; `wound` where that is
    /// not finite: opposed vertex normals that cancel to (0, 0, 0), or nearly, normalise to
    /// NaN or infinity.
    fn smooth_or(place: &Placement, sum: DVec3, wound: DVec3) -> DVec3 {
        let smooth = place.normal(sum);
        match (smooth.dot(smooth) - 1.0).abs() < 0.5 {
            true => smooth,
            false => wound,
        }
    }

    /// `lanes_of` gives the scalar definition's bits, δ included, on random triangles under
    /// rotated, non-uniformly scaled placements, cancelling vertex normals among them.
    #[test]
    fn lane_normals_are_the_scalar_definition() {
        let mut unit = crate::testing::uniform(3);
        let mut rnd = || unit() * 2.0 - 1.0;
        for case in 0..4000 {
            let mut r = [0.0; 40];
            r.iter_mut().for_each(|x| *x = rnd());
            let mut at = 0;
            let mut v3 = || {
                at += 3;
                DVec3::new(r[at - 3], r[at - 2], r[at - 1])
            };
            let place = Placement {
                scale: DVec3::new(0.1, 1.0, 7.0) + v3().abs() * 3.0,
                rotation: DMat3::from_euler(
                    glam::EulerRot::XYZ,
                    v3().x * 3.0,
                    v3().y * 3.0,
                    v3().z * 3.0,
                ),
                translate: v3() * 100.0,
            };
            let q = [v3(), v3() * 1e-3, v3() * 1e3];
            let mut n = [v3().normalize(), v3().normalize(), v3().normalize()];
            if case % 7 == 0 {
                n[1] = -n[0];
            }
            let (u, v) = if case % 7 == 0 {
                (0.5, 0.0)
            } else {
                (r[38].abs() * 0.5, r[39].abs() * 0.5)
            };
            let (t, p) = (r[37].abs() * 50.0, v3() * 10f64.powi(case % 9 - 4));
            let face = case % 3 == 0;
            let mut space = MaybeUninit::uninit();
            let mut rows = Rows {
                rows: &mut space,
                written: 0,
            };
            let mut row = [0.0; ROWS];
            for i in 0..3 {
                row[3 * i..3 * i + 3].copy_from_slice(&q[i].to_array());
                row[9 + 3 * i..12 + 3 * i].copy_from_slice(&n[i].to_array());
            }
            rows.set(0, row);
            let mut lanes = [[0.0; MAX_LANES]; 7];
            for (i, x) in [0.0, t, u, v, p.x, p.y, p.z].into_iter().enumerate() {
                lanes[i][0] = x;
            }
            let mut out = [[0.0; MAX_LANES]; 7];
            let part = Part::<F64x1> {
                from: 0,
                mask: true,
            };
            lanes_of(
                &place,
                face,
                &rows,
                &lanes,
                part,
                f64::EPSILON / 2.0,
                &mut out,
            );
            let (geom, shade) = normals(&place, q, n, (u, v), face);
            let want = [
                geom.x,
                geom.y,
                geom.z,
                shade.x,
                shade.y,
                shade.z,
                lift_distance(p, t, f64::EPSILON / 2.0),
            ];
            for i in 0..7 {
                assert_eq!(
                    out[i][0].to_bits(),
                    want[i].to_bits(),
                    "case {case}, value {i}"
                );
            }
        }
    }

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
