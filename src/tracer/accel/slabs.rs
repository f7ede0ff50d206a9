//! The slab test a packet's walk shares between its boxes.

use super::{Node, Rays, wide};
use crate::lanes::{Lanes, Mask, V3};
use glam::DVec3;

/// What the box tests of one walk share: each lane's origin and reciprocal direction, and
/// per axis whether every searching lane runs the same way along it (then the near and far
/// planes of a box are known without comparing).
pub(crate) struct Slabs<V: Lanes> {
    origin: V3<V>,
    inv: V3<V>,
    /// Per axis: Some(true) when every lane's direction is negative, Some(false) when every
    /// one is positive, None when they differ.
    backwards: [Option<bool>; 3],
}

impl<V: Lanes> Slabs<V> {
    #[inline(always)]
    pub(crate) fn new(rays: &Rays<V>, lanes: V::M) -> Slabs<V> {
        let inv = V3 {
            x: inverse(rays.dir.x),
            y: inverse(rays.dir.y),
            z: inverse(rays.dir.z),
        };
        let zero = V::splat(0.0);
        let backwards = [
            uniform(inv.x.lt(zero), zero.lt(inv.x), lanes),
            uniform(inv.y.lt(zero), zero.lt(inv.y), lanes),
            uniform(inv.z.lt(zero), zero.lt(inv.z), lanes),
        ];
        Slabs {
            origin: rays.origin,
            inv,
            backwards,
        }
    }

    /// Each axis's origins, reciprocal directions and direction (see `backwards`).
    #[inline(always)]
    pub(crate) fn parts(&self) -> ([V; 3], [V; 3], [Option<bool>; 3]) {
        let (o, i) = (self.origin, self.inv);
        ([o.x, o.y, o.z], [i.x, i.y, i.z], self.backwards)
    }

    /// The lanes whose ray enters the node's box at or before their `limit`.
    #[inline(always)]
    pub(super) fn entry(&self, node: &Node, limit: V) -> V::M {
        self.enters(node.min, node.max, limit)
    }

    /// The lanes whose ray enters child `c`'s box of a wide node at or before their `limit`.
    #[inline(always)]
    pub(crate) fn enters_f32(&self, n: &wide::Node, c: usize, limit: V) -> V::M {
        let at = |a: &[[f32; wide::WIDTH]; 3]| {
            DVec3::new(a[0][c].into(), a[1][c].into(), a[2][c].into())
        };
        self.enters(at(&n.lo), at(&n.hi), limit)
    }

    /// The lanes whose ray enters the box [min, max] at or before their `limit`.
    #[inline(always)]
    pub(crate) fn enters(&self, min: DVec3, max: DVec3, limit: V) -> V::M {
        let node = Node {
            min,
            max,
            first: 0,
            count: 0,
            axis: 0,
        };
        let (x0, x1) = slab(
            node.min.x,
            node.max.x,
            self.origin.x,
            self.inv.x,
            self.backwards[0],
        );
        let (y0, y1) = slab(
            node.min.y,
            node.max.y,
            self.origin.y,
            self.inv.y,
            self.backwards[1],
        );
        let (z0, z1) = slab(
            node.min.z,
            node.max.z,
            self.origin.z,
            self.inv.z,
            self.backwards[2],
        );
        let near = x0.max(y0).max(z0).max(V::splat(0.0));
        let far = x1.min(y1).min(z1).min(limit);
        if V::BOX_SLACK == 0.0 {
            return near.le(far);
        }
        // f32: the entry and the sphere's own t each carry a few ulps of the distance they
        // measure; widening the interval by 2^-16 of it (hundreds of ulps) keeps the test
        // conservative, so the hierarchy still never changes which sphere is nearest.
        let (less, more) = (V::splat(1.0 - V::BOX_SLACK), V::splat(1.0 + V::BOX_SLACK));
        (near * less).le(far * more)
    }
}

/// Some(true) when every lane of `lanes` is `negative`, Some(false) when every one is
/// `positive`, None otherwise.
#[inline(always)]
fn uniform<M: Mask>(negative: M, positive: M, lanes: M) -> Option<bool> {
    let all = lanes.bits();
    if negative.and(lanes).bits() == all {
        Some(true)
    } else if positive.and(lanes).bits() == all {
        Some(false)
    } else {
        None
    }
}

/// Where the rays cross the planes at `lo` and `hi` along one axis: (entry, exit).
#[inline(always)]
fn slab<V: Lanes>(lo: f64, hi: f64, origin: V, inv: V, backwards: Option<bool>) -> (V, V) {
    let t0 = (V::splat(lo) - origin) * inv;
    let t1 = (V::splat(hi) - origin) * inv;
    match backwards {
        Some(false) => (t0, t1),
        Some(true) => (t1, t0),
        None => (t0.min(t1), t0.max(t1)),
    }
}

/// 1/d for the slab test. A zero component would make 0 · ∞ = NaN at a box face, and so
/// would one whose reciprocal overflows; `TINY` in their place keeps every slab finite and the
/// test conservative.
#[inline(always)]
fn inverse<V: Lanes>(d: V) -> V {
    let tiny = V::splat(V::TINY);
    let small = d.lt(tiny).and((-tiny).lt(d));
    V::splat(1.0) / V::select(small, tiny.copysign(d), d)
}
