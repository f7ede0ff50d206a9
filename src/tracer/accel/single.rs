//! One ray's walk through a wide hierarchy, for the lanes of a packet whose rays went their
//! own ways (reflections off curved surfaces, refractions, shadow rays from scattered hits):
//! the ray tests the 4 children of a node at once (one box a lane of a 4-wide vector), visits
//! them nearest first, and stops as soon as its `Visit` says it no longer searches.
//!
//! Why it never skips a box its lane would enter: each child's entry and exit are computed
//! with exactly the operations of the lane's own test (`Slabs::enters`: fl(fl(p − o)·i) per
//! plane, in the lane's precision, then max and min with 0 and the limit, then the same f32
//! slack), so a child is skipped only when the lane's test would say no. Which of a box's two
//! planes is the entry follows from the sign of i (never 0: `Slabs` puts ±TINY there), as the
//! lane's min and max pick it. A child waiting on the stack is dropped when its entry lies past
//! a limit that shrank meanwhile: that entry is the one the lane's test compares.

use super::Slabs;
use super::four::Four;
use super::frustum::Real;
use super::walk::{Stack, Visit, farthest_first};
use super::wide::{Node, WIDTH};
use crate::lanes::{Lanes, MAX_LANES, Mask};
use std::mem::MaybeUninit;

/// Each lane's origin and reciprocal direction per axis, in the lanes' precision.
pub(crate) struct Rays1<R: Real> {
    origin: [[R; MAX_LANES]; 3],
    inv: [[R; MAX_LANES]; 3],
}

impl<R: Real> Rays1<R> {
    #[inline(always)]
    pub(crate) fn new<V: Lanes>(slabs: &Slabs<V>) -> Rays1<R> {
        let (origin, inv, _) = slabs.parts();
        Rays1 {
            origin: [
                R::lanes(origin[0]),
                R::lanes(origin[1]),
                R::lanes(origin[2]),
            ],
            inv: [R::lanes(inv[0]), R::lanes(inv[1]), R::lanes(inv[2])],
        }
    }

    /// Lane `k` alone.
    #[inline(always)]
    fn ray<V: Lanes>(&self, k: usize) -> Ray1<R> {
        let inv = [self.inv[0][k], self.inv[1][k], self.inv[2][k]];
        Ray1 {
            origin: [self.origin[0][k], self.origin[1][k], self.origin[2][k]],
            inv,
            backwards: [inv[0] < R::ZERO, inv[1] < R::ZERO, inv[2] < R::ZERO],
            less: R::of(1.0 - V::BOX_SLACK),
            more: R::of(1.0 + V::BOX_SLACK),
        }
    }
}

/// One lane's ray as its box tests see it.
struct Ray1<R: Real> {
    origin: [R; 3],
    inv: [R; 3],
    backwards: [bool; 3],
    less: R,
    more: R,
}

impl<R: Real> Ray1<R> {
    /// Which children of `node` the ray enters at or before `limit`, and each one's entry.
    #[inline(always)]
    fn children(&self, node: &Node, limit: R) -> (u32, [R; WIDTH]) {
        let mut near = R::X4::splat(R::ZERO);
        let mut far = R::X4::splat(limit);
        for axis in 0..3 {
            let (entry, exit) = match self.backwards[axis] {
                false => (&node.lo[axis], &node.hi[axis]),
                true => (&node.hi[axis], &node.lo[axis]),
            };
            let (o, i) = (
                R::X4::splat(self.origin[axis]),
                R::X4::splat(self.inv[axis]),
            );
            near = near.max(R::X4::load(entry).sub(o).mul(i));
            far = far.min(R::X4::load(exit).sub(o).mul(i));
        }
        let (less, more) = (R::X4::splat(self.less), R::X4::splat(self.more));
        let hit = near.mul(less).le(far.mul(more));
        (hit & ((1 << node.kids) - 1), near.array())
    }

    /// Whether a box entered at `near` still starts at or before `limit`.
    #[inline(always)]
    fn before(&self, near: R, limit: R) -> bool {
        near * self.less <= limit * self.more
    }
}

/// Walks lane `k` alone through the subtree of node `at` (whose box the lane enters), leaves
/// nearest first, until its `Visit` stops searching on it.
#[inline(always)]
pub(crate) fn walk<V: Lanes, S: Visit<V>, R: Real>(
    nodes: &[Node],
    slabs: &Slabs<V>,
    rays: &Rays1<R>,
    k: usize,
    at: u32,
    visit: &mut S,
) {
    let lane = V::M::from_bits(1 << k);
    let ray = rays.ray::<V>(k);
    let mut limit = R::lanes(visit.limit())[k];
    let mut entries = MaybeUninit::uninit();
    let mut stack = Stack {
        entries: &mut entries,
        top: 0,
    };
    push_children(&ray, nodes, at, limit, &mut stack, visit);
    while let Some((at, c, near)) = stack.pop() {
        if !ray.before(near, limit) {
            continue;
        }
        let node = &nodes[at as usize];
        let (first, count) = (node.first[c as usize], u32::from(node.count[c as usize]));
        if count == 0 {
            push_children(&ray, nodes, first, limit, &mut stack, visit);
            continue;
        }
        visit.leaf_one(slabs, first as usize, count as usize, k);
        if !visit.open(lane).any() {
            return;
        }
        limit = R::lanes(visit.limit())[k];
    }
}

/// Pushes the children of node `at` the ray enters before `limit`, farthest first. One or
/// two children (most nodes a single ray opens) are pushed without the general sort.
#[inline(always)]
fn push_children<V: Lanes, S: Visit<V>, R: Real>(
    ray: &Ray1<R>,
    nodes: &[Node],
    at: u32,
    limit: R,
    stack: &mut Stack<(u32, u32, R)>,
    visit: &S,
) {
    let node = &nodes[at as usize];
    let (hit, near) = ray.children(node, limit);
    if hit == 0 {
        return;
    }
    let mut bits = hit;
    while bits != 0 {
        ahead(nodes, node, bits.trailing_zeros() as usize, visit);
        bits &= bits - 1;
    }
    let (a, b) = (hit.trailing_zeros(), 31 - hit.leading_zeros());
    if hit & (hit - 1) == 0 {
        return stack.push((at, a, near[a as usize]));
    }
    if hit == 1 << a | 1 << b {
        // The sort's order: the nearer last, the lower slot last between equals.
        let (far, close) = match near[a as usize] < near[b as usize] {
            true => (b, a),
            false => (a, b),
        };
        stack.push((at, far, near[far as usize]));
        return stack.push((at, close, near[close as usize]));
    }
    let mut found = [(R::ZERO, 0u32); WIDTH];
    let mut n = 0;
    let mut bits = hit;
    while bits != 0 {
        let c = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        found[n] = (near[c], c as u32);
        n += 1;
    }
    farthest_first(&mut found[..n]);
    for &(near, c) in &found[..n] {
        stack.push((at, c, near));
    }
}

/// Asks the memory for child `c` of `node`: its node (both lines), or its leaf's items. The
/// misses of all the entered children then overlap, the farther ones' with the work on the
/// nearer (a hint, which changes no result). Measured in docs/performance.md ("a single ray
/// asks for its children's memory ahead"): even the nearest child gains, its node's two lines
/// or its leaf's triangles asked for at once.
#[inline(always)]
fn ahead<V: Lanes, S: Visit<V>>(nodes: &[Node], node: &Node, c: usize, visit: &S) {
    let first = node.first[c] as usize;
    match node.count[c] {
        0 => crate::lanes::fetch(&nodes[first..first + 1]),
        n => visit.fetch(first, usize::from(n)),
    }
}
