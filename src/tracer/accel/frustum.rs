//! One box test for a whole packet: the intervals its origins and reciprocal directions span
//! on each axis bound every lane's slab distances, so a wide node's children are culled for
//! the packet at once (interval arithmetic, as in Wald, Boulos and Shirley's "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies"), and only leaves are tested
//! lane by lane.
//!
//! Why it never culls a box a lane would enter: a lane enters when
//! max(x₀, y₀, z₀, 0) ≤ min(x₁, y₁, z₁, limit) (`Slabs::enters`), each x₀ = fl(fl(p − o)·i)
//! for the box's entry plane p, its origin o and reciprocal direction i. Rounding is
//! monotone, so fl(fl(p − o)·i) moves the same way as (p − o)·i when o or i moves alone; the
//! product is bilinear, so over the box [o_lo, o_hi] × [i_lo, i_hi] both its exact and its
//! rounded values are smallest (and largest) at a corner. The corners' least entry and
//! greatest exit, computed with the same operations in the same precision, therefore bound
//! every lane's, and max and min keep the order: the packet's test passes whenever a lane's
//! does (with the same f32 slack as the lanes' test). Two consequences the walk uses: the
//! bounds of fewer lanes still bound each of them (a walk narrows its bounds as its shadow rays
//! stop), and a child tested before a limit shrank can be tested again with the smaller one
//! from its least entry alone (`before`), since every lane's exit is at most its limit.

use super::Slabs;
use super::four::{Four, Four32, Four64};
use super::walk::fold;
use super::wide::{Node, WIDTH};
use crate::lanes::{Lanes, MAX_LANES, Mask};
use std::ops::{Mul, Sub};

/// The float the lanes compute in: f32 or f64.
pub(crate) trait Real: Copy + PartialOrd + Sub<Output = Self> + Mul<Output = Self> {
    const ZERO: Self;
    /// A node's 4 children side by side in this precision.
    type X4: Four<R = Self>;
    fn of(x: f64) -> Self;
    fn wide(self) -> f64;
    /// The lanes of `v` (exactly: `v` holds values of this precision).
    fn lanes<V: Lanes>(v: V) -> [Self; MAX_LANES];
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o { self } else { o }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o { self } else { o }
    }
}

impl Real for f32 {
    const ZERO: f32 = 0.0;
    type X4 = Four32;
    #[inline(always)]
    fn of(x: f64) -> f32 {
        x as f32
    }
    #[inline(always)]
    fn wide(self) -> f64 {
        f64::from(self)
    }
    #[inline(always)]
    fn lanes<V: Lanes>(v: V) -> [f32; MAX_LANES] {
        let mut out = [0.0; MAX_LANES];
        v.store_f32(&mut out);
        out
    }
}

impl Real for f64 {
    const ZERO: f64 = 0.0;
    type X4 = Four64;
    #[inline(always)]
    fn of(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn wide(self) -> f64 {
        self
    }
    #[inline(always)]
    fn lanes<V: Lanes>(v: V) -> [f64; MAX_LANES] {
        v.array()
    }
}

/// A packet's bounds per axis: its origins' and reciprocal directions' least and greatest
/// values, and whether it runs backwards (every direction negative) along the axis.
#[derive(Clone, Copy)]
pub(crate) struct Frustum<R: Real> {
    origin: [(R, R); 3],
    inv: [(R, R); 3],
    backwards: [bool; 3],
    /// Every lane starts at one point (a pinhole's eye rays): each origin interval is that
    /// point, and a plane's corners reduce to its two products (`corners` with o₀ = o₁).
    point: bool,
    less: R,
    more: R,
}

impl<R: Real> Frustum<R> {
    /// The bounds of the `lanes` of `slabs`; None when on some axis they run both ways (the
    /// intervals would then span everything and cull nothing).
    #[inline(always)]
    pub(crate) fn new<V: Lanes>(slabs: &Slabs<V>, lanes: V::M) -> Option<Frustum<R>> {
        let (origin, inv, backwards) = slabs.parts();
        let mut f = Frustum {
            origin: [(R::ZERO, R::ZERO); 3],
            inv: [(R::ZERO, R::ZERO); 3],
            backwards: [false; 3],
            point: false,
            less: R::of(1.0 - V::BOX_SLACK),
            more: R::of(1.0 + V::BOX_SLACK),
        };
        for axis in 0..3 {
            f.backwards[axis] = backwards[axis]?;
            f.origin[axis] = range(origin[axis], lanes);
            f.inv[axis] = range(inv[axis], lanes);
        }
        f.point = f.origin.iter().all(|&(o0, o1)| o0 == o1);
        Some(f)
    }

    /// Whether the packet is narrow next to the box [lo, hi] it is about to walk: its origins
    /// and the spread of its directions over the distance to the box's far side stay within
    /// an eighth of the box's size. A wide packet's intervals would let every lane test the
    /// union of every lane's boxes; the lanes' own tests are then cheaper (a heuristic: it
    /// changes what is tested, never what is hit).
    #[inline(always)]
    pub(crate) fn narrow(&self, lo: glam::Vec3, hi: glam::Vec3) -> bool {
        let (mut spread, mut scale, mut origins, mut far, mut size) =
            (0.0, 0.0, 0.0f64, 0.0f64, 0.0f64);
        for a in 0..3 {
            let (o0, o1) = (self.origin[a].0.wide(), self.origin[a].1.wide());
            let (d0, d1) = (1.0 / self.inv[a].1.wide(), 1.0 / self.inv[a].0.wide());
            spread += (d1 - d0).abs();
            scale += d0.abs().max(d1.abs());
            origins = origins.max(o1 - o0);
            let mid = 0.5 * (o0 + o1);
            let (l, h) = (f64::from(lo[a]), f64::from(hi[a]));
            far = far.max((h - mid).abs().max((l - mid).abs()));
            size = size.max(h - l);
        }
        origins + spread / scale * far <= size / 8.0
    }

    /// Which children of `node` some lane may enter at or before `limit` (the greatest of
    /// the lanes' limits), and each one's least entry distance.
    #[inline(always)]
    pub(crate) fn children(&self, node: &Node, limit: R) -> (u32, [R; WIDTH]) {
        match self.point {
            true => self.children_as(node, limit, from_point),
            false => self.children_as(node, limit, corners),
        }
    }

    /// `children` with the corners' bounds of a plane taken by `bound`.
    #[inline(always)]
    fn children_as(&self, node: &Node, limit: R, bound: Bound<R::X4>) -> (u32, [R; WIDTH]) {
        let mut near = R::X4::splat(R::ZERO);
        let mut far = R::X4::splat(limit);
        for axis in 0..3 {
            let (entry, exit) = match self.backwards[axis] {
                false => (&node.lo[axis], &node.hi[axis]),
                true => (&node.hi[axis], &node.lo[axis]),
            };
            let (o, i) = (self.origin[axis], self.inv[axis]);
            near = near.max(bound(R::X4::load(entry), o, i, R::X4::min));
            far = far.min(bound(R::X4::load(exit), o, i, R::X4::max));
        }
        let (less, more) = (R::X4::splat(self.less), R::X4::splat(self.more));
        let hit = near.mul(less).le(far.mul(more));
        (hit & ((1 << node.kids) - 1), near.array())
    }

    /// Whether a child whose least entry is `near` may still be entered at or before
    /// `limit`: `children`'s test of the child again, after the limit shrank.
    #[inline(always)]
    pub(crate) fn before(&self, near: R, limit: R) -> bool {
        near * self.less <= limit * self.more
    }
}

/// A plane's bound over the packet's corners, as `corners` computes it.
type Bound<X> =
    fn(X, (<X as Four>::R, <X as Four>::R), (<X as Four>::R, <X as Four>::R), fn(X, X) -> X) -> X;

/// `corners` when o₀ = o₁: its two differences are equal, so pick(pick(a·i₀, a·i₁),
/// pick(a·i₀, a·i₁)) is pick(a·i₀, a·i₁) (picking a value against itself returns it).
#[inline(always)]
fn from_point<X: Four>(
    p: X,
    (o, _): (X::R, X::R),
    (i0, i1): (X::R, X::R),
    pick: fn(X, X) -> X,
) -> X {
    let a = p.sub(X::splat(o));
    pick(a.mul(X::splat(i0)), a.mul(X::splat(i1)))
}

/// The least (`pick` = min) or greatest (max) of fl(fl(p − o)·i) over the corners of
/// [o₀, o₁] × [i₀, i₁], for the 4 children's planes `p` at once.
#[inline(always)]
fn corners<X: Four>(
    p: X,
    (o0, o1): (X::R, X::R),
    (i0, i1): (X::R, X::R),
    pick: fn(X, X) -> X,
) -> X {
    let (i0, i1) = (X::splat(i0), X::splat(i1));
    let (a, b) = (p.sub(X::splat(o1)), p.sub(X::splat(o0)));
    pick(pick(a.mul(i0), a.mul(i1)), pick(b.mul(i0), b.mul(i1)))
}

/// The least and greatest value of `v` over `lanes` (at least one).
#[inline(always)]
fn range<V: Lanes, R: Real>(v: V, lanes: V::M) -> (R, R) {
    // Lanes outside `lanes` take the first lane's value, which changes neither bound.
    let first = v.lane(lanes.bits().trailing_zeros() as usize);
    let v = V::select(lanes, v, V::splat(first));
    // A pair's halves met in registers first (the lanes' min and max are `Real`'s), so
    // the folds run over half as many values.
    let (h0, h1) = (v.half(0), v.half(1));
    let mut lo = R::lanes(h0.min(h1));
    let mut hi = R::lanes(h0.max(h1));
    (
        fold::<V::Half, R>(&mut lo, R::min),
        fold::<V::Half, R>(&mut hi, R::max),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From one point, `from_point` gives `corners`' bits, in both precisions and for both
    /// picks, over planes on either side of the origin and directions of either sign.
    #[test]
    fn a_point_origin_bounds_as_its_corners_do() {
        let mut unit = crate::testing::uniform(7);
        let mut rnd = || (unit() - 0.5) * 8.0;
        for _ in 0..20_000 {
            let row = [rnd() as f32, rnd() as f32, rnd() as f32, rnd() as f32];
            let o = rnd();
            let (a, b) = (rnd(), rnd());
            let (i0, i1) = (a.min(b), a.max(b));
            check::<Four32>(&row, o as f32, (i0 as f32, i1 as f32));
            check::<Four64>(&row, o, (i0, i1));
        }
    }

    fn check<X: Four>(row: &[f32; WIDTH], o: X::R, i: (X::R, X::R))
    where
        X::R: Into<f64>,
    {
        let bits = |x: X| x.array().map(|r| r.into().to_bits());
        for pick in [X::min as fn(X, X) -> X, X::max] {
            let p = X::load(row);
            assert_eq!(
                bits(from_point(p, (o, o), i, pick)),
                bits(corners(p, (o, o), i, pick))
            );
        }
    }
}
