//! The walks decide only what is tested: every policy for packets whose rays diverge (lane by
//! lane, one ray at a time, or lane by lane down to a few lanes) finds the same nearest hits
//! (t, triangle, u, v) and the same blocked lanes, in f64 and in f32, for coherent packets
//! (which take the packet walk) and scattered ones; and a packet's lanes find what one-lane
//! walks of the same rays find.

use super::*;
use crate::lanes::{F32x1, F64x1, Pair};
use crate::tools::meshgen;
use crate::tracer::accel::walk::{Divergent, walk_as};

type Wide64 = Pair<Pair<Pair<F64x1>>>;
type Wide32 = Pair<Pair<Pair<Pair<F32x1>>>>;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

/// A soup of `n` random triangles, small and large, in [-1, 1]³.
fn soup(n: usize, rng: &mut Rng) -> crate::scene::Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for i in 0..n {
        let c = rng.unit() * rng.next();
        let size = if i % 7 == 0 { 0.5 } else { 0.05 };
        for _ in 0..3 {
            positions.push(c + rng.unit() * size * rng.next());
        }
        let k = 3 * i as u32;
        triangles.push([k, k + 1, k + 2]);
    }
    crate::sequence::mesh::from_triangles("soup", positions, triangles)
}

/// Packets of every kind: eye-like (one origin, a narrow cone), shadow-like (scattered
/// origins towards one point), and scattered (random origins and directions, some inside).
fn packets(rng: &mut Rng, n: usize) -> Vec<(Vec<DVec3>, Vec<DVec3>)> {
    let mut out = Vec::new();
    for p in 0..24 {
        let (mut o, mut d) = (Vec::new(), Vec::new());
        let eye = rng.unit() * 4.0;
        let light = rng.unit() * 5.0;
        let aim = rng.unit() * 0.3;
        for _ in 0..n {
            let (origin, dir) = match p % 3 {
                0 => (eye, (aim + rng.unit() * 0.05 - eye).normalize()),
                1 => {
                    let from = rng.unit() * rng.next();
                    (from, (light - from).normalize())
                }
                _ => (rng.unit() * 3.0 * rng.next(), rng.unit()),
            };
            o.push(origin);
            d.push(dir);
        }
        out.push((o, d));
    }
    out
}

type Traced = (Vec<(f64, u32, f64, f64)>, u32);

/// (t, triangle, u, v) of each lane's nearest hit, and which lanes are blocked before 2.5,
/// under `policy`.
fn trace<V: Lanes>(mesh: &Instance, o: &[DVec3], d: &[DVec3], policy: Divergent) -> Traced {
    let lanes = |f: fn(DVec3) -> f64, p: &[DVec3]| V::from_fn(|k| f(p[k]));
    let rays = Rays::<V> {
        origin: V3 {
            x: lanes(|p| p.x, o),
            y: lanes(|p| p.y, o),
            z: lanes(|p| p.z, o),
        },
        dir: V3 {
            x: lanes(|p| p.x, d),
            y: lanes(|p| p.y, d),
            z: lanes(|p| p.z, d),
        },
        leaving: V::splat(-1.0),
    };
    let all = V::M::first(V::N);
    let local = mesh.local(&rays);
    let from = mesh.start(&local);
    let mut best = Best {
        t: V::splat(f64::INFINITY),
        object: V::splat(-1.0),
        u: V::splat(0.0),
        v: V::splat(0.0),
        prim: [NO_TRIANGLE; MAX_LANES],
    };
    let (tree, bvh) = (&mesh.bvh.tree, &mesh.bvh);
    let blocked = if single::<V>() {
        nearest_as(tree, &local, from, bvh.tris32(), &mut best, policy);
        blocked_as(tree, &local, from, bvh.tris32(), all, policy)
    } else {
        nearest_as(tree, &local, from, bvh.tris(), &mut best, policy);
        blocked_as(tree, &local, from, bvh.tris(), all, policy)
    };
    let (t, u, v) = (best.t.array(), best.u.array(), best.v.array());
    let hits = (0..V::N)
        .map(|k| (t[k], best.prim[k], u[k], v[k]))
        .collect();
    (hits, blocked.bits())
}

fn nearest_as<V: Lanes, T: Stored>(
    tree: &Tree,
    rays: &Rays<V>,
    from: (V3<V>, Option<V>),
    tris: &[T],
    best: &mut Best<V>,
    policy: Divergent,
) {
    let mut visit = NearestVisit {
        rays,
        from,
        tris,
        object: 0,
        best,
    };
    walk_as(tree, rays, V::M::first(V::N), &mut visit, policy);
}

fn blocked_as<V: Lanes, T: Stored>(
    tree: &Tree,
    rays: &Rays<V>,
    from: (V3<V>, Option<V>),
    tris: &[T],
    open: V::M,
    policy: Divergent,
) -> V::M {
    let mut visit = AnyVisit {
        rays,
        from,
        tris,
        max_t: V::splat(2.5),
        blocked: V::M::none_set(),
    };
    walk_as(tree, rays, open, &mut visit, policy);
    visit.blocked
}

/// Every policy against lane-by-lane walks, packet by packet, and each lane against the
/// one-lane walk of its ray; the number of lanes that hit.
fn policies_agree<V: Lanes, One: Lanes>(mesh: &Instance, rng: &mut Rng) -> usize {
    let policies = [
        Divergent::Rays,
        Divergent::Below(2),
        Divergent::Below(5),
        Divergent::DEFAULT,
    ];
    let mut hits = 0;
    for (o, d) in packets(rng, V::N) {
        let lanes = trace::<V>(mesh, &o, &d, Divergent::Lanes);
        for p in policies {
            assert!(trace::<V>(mesh, &o, &d, p) == lanes, "{p:?}");
        }
        for k in 0..V::N {
            let one = trace::<One>(mesh, &o[k..], &d[k..], Divergent::Rays);
            assert!(
                one.0[0] == lanes.0[k] && one.1 == lanes.1 >> k & 1,
                "lane {k}"
            );
        }
        hits += lanes.0.iter().filter(|h| h.1 != NO_TRIANGLE).count();
    }
    hits
}

fn placed(mesh: crate::scene::Mesh, scale: DVec3, turn: f64) -> Instance {
    let bvh = Arc::new(Bvh::build(&Arc::new(mesh)).unwrap());
    let place = Placement {
        scale,
        rotation: DMat3::from_rotation_y(turn) * DMat3::from_rotation_x(0.3 * turn),
        translate: DVec3::new(0.1, -0.2, 0.05),
    };
    Instance::new(0, bvh, &place)
}

#[test]
fn every_walk_finds_the_same_hits_in_f64_and_f32() {
    let mut rng = Rng(99);
    let meshes = [
        placed(soup(3000, &mut rng), DVec3::ONE, 0.0),
        placed(soup(500, &mut rng), DVec3::new(1.3, 0.4, 0.9), 0.7),
        placed(meshgen::blob(40, 20), DVec3::splat(0.8), 2.1),
        placed(meshgen::terrain(31), DVec3::new(2.0, 1.0, 2.0), 0.4),
    ];
    for mesh in &meshes {
        let hits = policies_agree::<Wide64, F64x1>(mesh, &mut rng);
        let hits32 = policies_agree::<Wide32, F32x1>(mesh, &mut rng);
        assert!(
            hits > 20 && hits32 > 40,
            "{hits} {hits32} hits: rays must meet the mesh"
        );
    }
}
