//! The one walk through a wide hierarchy (`wide::Tree`), for any packet and any leaves: a
//! mesh's triangles, or the placed meshes under the top level. The walker only decides which
//! leaves a packet's lanes look at (every box test is conservative); what a leaf does with
//! them, and which lanes still search and how far, is the `Visit`'s.
//!
//! Two ways down. A packet whose rays are narrow next to the tree (`Frustum::narrow`: a tile
//! of eye rays, the shadow rays of its hits towards one light) culls each node's children
//! once for all its lanes, and tests lane by lane only at leaves. Any other packet tests
//! every child lane by lane and carries each child's lanes down with it.

use super::frustum::{Frustum, Real};
use super::wide::{MAX_DEPTH, Node, Tree, WIDTH};
use super::{Rays, Slabs};
use crate::lanes::{Lanes, Mask, single};
use std::mem::MaybeUninit;

/// What a walk does at a leaf, and which lanes still search and how far.
pub(crate) trait Visit<V: Lanes> {
    /// The lanes of `lanes` still searching.
    fn open(&self, lanes: V::M) -> V::M;
    /// How far along its ray each lane still searches.
    fn limit(&self) -> V;
    /// Looks at the `count` leaf items from `first` (in the tree's leaf order) for `enter`.
    fn leaf(&mut self, slabs: &Slabs<V>, first: usize, count: usize, enter: V::M);
}

/// Visits the leaves of `tree` whose boxes a lane of `lanes` enters before its limit, nearer
/// children first.
#[inline(always)]
pub(crate) fn walk<V: Lanes, S: Visit<V>>(tree: &Tree, rays: &Rays<V>, lanes: V::M, visit: &mut S) {
    let slabs = Slabs::new(rays, lanes);
    let (lo, hi) = (tree.lo, tree.hi);
    if single::<V>() {
        if let Some(f) = Frustum::<f32>::new(&slabs, lanes)
            && f.narrow(lo, hi)
        {
            return packet(&tree.nodes, &slabs, &f, lanes, visit);
        }
    } else if let Some(f) = Frustum::<f64>::new(&slabs, lanes)
        && f.narrow(lo, hi)
    {
        return packet(&tree.nodes, &slabs, &f, lanes, visit);
    }
    by_lanes(&tree.nodes, rays, &slabs, lanes, visit);
}

/// The walk of a narrow packet: children culled for the whole packet, leaves lane by lane.
#[inline(always)]
fn packet<V: Lanes, S: Visit<V>, R: Real>(
    nodes: &[Node],
    slabs: &Slabs<V>,
    frustum: &Frustum<R>,
    lanes: V::M,
    visit: &mut S,
) {
    let mut entries = MaybeUninit::uninit();
    let mut stack = Stack {
        entries: &mut entries,
        top: 0,
    };
    let mut limit = greatest::<V, R>(visit.limit(), lanes);
    open_node(&mut stack, frustum, nodes, 0, limit);
    while let Some((at, slot, _)) = stack.pop() {
        let open = visit.open(lanes);
        if !open.any() {
            return;
        }
        let node = &nodes[at as usize];
        let c = slot as usize;
        if node.count[c] == 0 {
            open_node(&mut stack, frustum, nodes, node.first[c], limit);
            continue;
        }
        // The leaf's box again, lane by lane and against limits that may have shrunk.
        let enter = slabs.enters_f32(node, c, visit.limit()).and(open);
        if enter.any() {
            visit.leaf(slabs, node.first[c] as usize, node.count[c] as usize, enter);
            limit = greatest::<V, R>(visit.limit(), visit.open(lanes));
        }
    }
}

/// Pushes the children of node `at` that the packet may enter before `limit`, farthest
/// first (so the nearest is opened next).
#[inline(always)]
fn open_node<R: Real>(stack: &mut Stack, frustum: &Frustum<R>, nodes: &[Node], at: u32, limit: R) {
    let (hit, near) = frustum.children(&nodes[at as usize], limit);
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
    for &(_, c) in &found[..n] {
        stack.push((at, c, 0));
    }
}

/// The walk of any packet: every child's box tested lane by lane, its lanes carried down.
#[inline(always)]
fn by_lanes<V: Lanes, S: Visit<V>>(
    nodes: &[Node],
    rays: &Rays<V>,
    slabs: &Slabs<V>,
    lanes: V::M,
    visit: &mut S,
) {
    // Children are ordered along the first lane's direction (a heuristic only).
    let lead = lanes.bits().trailing_zeros() as usize;
    let towards = [
        rays.dir.x.lane(lead) as f32,
        rays.dir.y.lane(lead) as f32,
        rays.dir.z.lane(lead) as f32,
    ];
    let mut entries = MaybeUninit::uninit();
    let mut stack = Stack {
        entries: &mut entries,
        top: 0,
    };
    for c in (0..nodes[0].kids).rev() {
        stack.push((0, c, lanes.bits()));
    }
    while let Some((at, slot, mask)) = stack.pop() {
        let open = visit.open(V::M::from_bits(mask));
        if !open.any() {
            continue;
        }
        let node = &nodes[at as usize];
        let c = slot as usize;
        if node.count[c] > 0 {
            let enter = slabs.enters_f32(node, c, visit.limit()).and(open);
            if enter.any() {
                visit.leaf(slabs, node.first[c] as usize, node.count[c] as usize, enter);
            }
            continue;
        }
        let child = node.first[c];
        let inner = &nodes[child as usize];
        let limit = visit.limit();
        let mut found = [(0f32, (0u32, 0u32)); WIDTH];
        let mut n = 0;
        for k in 0..inner.kids as usize {
            let enter = slabs.enters_f32(inner, k, limit).and(open);
            if enter.any() {
                found[n] = (centre_along(inner, k, towards), (k as u32, enter.bits()));
                n += 1;
            }
        }
        farthest_first(&mut found[..n]);
        for &(_, (k, bits)) in &found[..n] {
            stack.push((child, k, bits));
        }
    }
}

/// How far along `towards` child `c`'s box centre lies (twice that: only the order counts).
#[inline(always)]
fn centre_along(n: &Node, c: usize, towards: [f32; 3]) -> f32 {
    let along = |a: usize| (n.lo[a][c] + n.hi[a][c]) * towards[a];
    along(0) + along(1) + along(2)
}

/// Sorts by the first field, greatest first (an insertion sort: at most `WIDTH` entries).
#[inline(always)]
fn farthest_first<K: PartialOrd + Copy, T: Copy>(found: &mut [(K, T)]) {
    for i in 1..found.len() {
        let mut j = i;
        while j > 0 && found[j - 1].0 < found[j].0 {
            found.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// The greatest value of `v` over `lanes` (none: 0).
#[inline(always)]
fn greatest<V: Lanes, R: Real>(v: V, lanes: V::M) -> R {
    let values = v.array();
    let mut bits = lanes.bits();
    let mut most = R::ZERO;
    while bits != 0 {
        most = most.max(R::of(values[bits.trailing_zeros() as usize]));
        bits &= bits - 1;
    }
    most
}

/// The deepest walk: at most `WIDTH` − 1 siblings wait on each of `MAX_DEPTH` levels.
const STACK: usize = (WIDTH - 1) * MAX_DEPTH + WIDTH;

/// The walk's stack of (node, child slot, lanes) entries, left uninitialised above its top
/// (zeroing its `STACK` entries cost more than a short walk). Only the array lives in the
/// caller's frame: a struct that also held the top was zeroed whole by the compiler.
struct Stack<'a> {
    entries: &'a mut MaybeUninit<[(u32, u32, u32); STACK]>,
    top: usize,
}

impl Stack<'_> {
    #[inline(always)]
    fn push(&mut self, e: (u32, u32, u32)) {
        assert!(self.top < STACK);
        // SAFETY: in bounds (checked above); writing through the pointer reads nothing.
        unsafe {
            self.entries
                .as_mut_ptr()
                .cast::<(u32, u32, u32)>()
                .add(self.top)
                .write(e)
        };
        self.top += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, u32, u32)> {
        self.top = self.top.checked_sub(1)?;
        // SAFETY: every entry below the top is in bounds and was written by `push`.
        Some(unsafe {
            self.entries
                .as_ptr()
                .cast::<(u32, u32, u32)>()
                .add(self.top)
                .read()
        })
    }
}
