//! The one walk through a wide hierarchy (`wide::Tree`), for any packet and any leaves: a
//! mesh's triangles, or the placed meshes under the top level. The walker only decides which
//! leaves a packet's lanes look at (every box test is conservative); what a leaf does with
//! them, and which lanes still search and how far, is the `Visit`'s.
//!
//! Two ways down. A packet whose rays are narrow next to the tree (`Frustum::narrow`: a tile
//! of eye rays, the shadow rays of its hits towards one light) culls each node's children
//! once for all its lanes, and tests lane by lane only at leaves. Any other packet walks as
//! `Divergent` says: by default each of its rays alone (`single`: one ray against a node's
//! children at once, nearest first); with `RAYREEL_DIVERGENT=lanes` (tests and measurements)
//! it tests every child lane by lane and carries each child's lanes down with it.

use super::frustum::{Frustum, Real};
use super::single::{self, Rays1};
use super::wide::{MAX_DEPTH, Node, Tree, WIDTH};
use super::{Rays, Slabs};
use crate::lanes::{self, Lanes, MAX_LANES, Mask};
use std::mem::MaybeUninit;

/// What a walk does at a leaf, and which lanes still search and how far.
pub(crate) trait Visit<V: Lanes> {
    /// The lanes of `lanes` still searching.
    fn open(&self, lanes: V::M) -> V::M;
    /// How far along its ray each lane still searches.
    fn limit(&self) -> V;
    /// Looks at the `count` leaf items from `first` (in the tree's leaf order) for `enter`.
    fn leaf(&mut self, slabs: &Slabs<V>, first: usize, count: usize, enter: V::M);
    /// `leaf` for lane `k` alone (a single ray's walk): by default the packet's leaf with one
    /// lane set; a visit may compute the lane alone in `V::One`, which gives the same bits.
    #[inline(always)]
    fn leaf_one(&mut self, slabs: &Slabs<V>, first: usize, count: usize, k: usize) {
        self.leaf(slabs, first, count, V::M::from_bits(1 << k));
    }
    /// Asks the memory for the `count` leaf items from `first`, which a single ray's walk
    /// will look at soon (a hint: by default nothing).
    #[inline(always)]
    fn fetch(&self, _first: usize, _count: usize) {}
}

/// Visits the leaves of `tree` whose boxes a lane of `lanes` enters before its limit, nearer
/// children first.
#[inline(always)]
pub(crate) fn walk<V: Lanes, S: Visit<V>>(tree: &Tree, rays: &Rays<V>, lanes: V::M, visit: &mut S) {
    walk_as(tree, rays, lanes, visit, Divergent::chosen());
}

/// `walk` with packets that are not narrow walked as `policy` says.
#[inline(always)]
pub(crate) fn walk_as<V: Lanes, S: Visit<V>>(
    tree: &Tree,
    rays: &Rays<V>,
    lanes: V::M,
    visit: &mut S,
    policy: Divergent,
) {
    let slabs = Slabs::new(rays, lanes);
    match lanes::single::<V>() {
        true => walk_in::<V, S, f32>(tree, rays, &slabs, lanes, visit, policy),
        false => walk_in::<V, S, f64>(tree, rays, &slabs, lanes, visit, policy),
    }
}

/// `walk` with the packet's bounds and the single rays' box tests in the lanes' precision `R`.
#[inline(always)]
fn walk_in<V: Lanes, S: Visit<V>, R: Real>(
    tree: &Tree,
    rays: &Rays<V>,
    slabs: &Slabs<V>,
    lanes: V::M,
    visit: &mut S,
    policy: Divergent,
) {
    // A lone lane walks as a single ray unless lane-by-lane walks are asked for.
    let lone = lanes.count() == 1 && policy != Divergent::Lanes;
    if !lone
        && let Some(f) = Frustum::<R>::new(slabs, lanes)
        && f.narrow(tree.lo, tree.hi)
    {
        return packet(&tree.nodes, slabs, &f, lanes, visit);
    }
    let below = match policy {
        Divergent::Lanes => 0,
        Divergent::Rays => V::N + 1,
        Divergent::Below(k) => k,
    };
    if lanes.count() < below as u64 {
        return each_lane::<V, S, R>(&tree.nodes, slabs, lanes, 0, visit);
    }
    by_lanes::<V, S, R>(&tree.nodes, rays, slabs, lanes, below, visit);
}

/// How a packet that is not narrow walks: lane by lane down the tree (`Lanes`), one ray at a
/// time (`Rays`), or lane by lane until fewer than k lanes enter a subtree, then one ray at a
/// time through it (`Below(k)`). Only which boxes are tested depends on it, never a hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Divergent {
    Lanes,
    Rays,
    Below(usize),
}

impl Divergent {
    /// The policy frames use, or the one `RAYREEL_DIVERGENT=lanes|rays|below:K` asks for (tests
    /// and measurements only). Decided once per process.
    pub fn chosen() -> Divergent {
        static CHOSEN: std::sync::OnceLock<Divergent> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let asked = std::env::var("RAYREEL_DIVERGENT").unwrap_or_default();
            match asked.as_str() {
                "lanes" => Divergent::Lanes,
                "rays" => Divergent::Rays,
                _ => match asked.strip_prefix("below:").map(str::parse) {
                    Some(Ok(k)) => Divergent::Below(k),
                    _ => Divergent::DEFAULT,
                },
            }
        })
    }

    /// Measured best on glass and mirror meshes (docs/performance.md, "Rays that leave their
    /// packet").
    pub const DEFAULT: Divergent = Divergent::Rays;
}

/// Walks each lane of `lanes` alone through the subtree of node `at`.
#[inline(always)]
fn each_lane<V: Lanes, S: Visit<V>, R: Real>(
    nodes: &[Node],
    slabs: &Slabs<V>,
    lanes: V::M,
    at: u32,
    visit: &mut S,
) {
    let singles = Rays1::<R>::new(slabs);
    let mut bits = lanes.bits();
    while bits != 0 {
        let k = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        single::walk(nodes, slabs, &singles, k, at, visit);
    }
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
    // The bounds of the lanes still searching: a shadow packet's rays stop one by one, and
    // the bounds of those left are tighter (a frustum of fewer lanes bounds each of them).
    let mut frustum = *frustum;
    let mut bounded = lanes.count();
    let mut limit = greatest::<V, R>(visit.limit(), lanes);
    open_node(&mut stack, &frustum, nodes, 0, limit);
    while let Some((at, slot, near)) = stack.pop() {
        // Pushed before the limit shrank: the packet's test with today's limit.
        if !frustum.before(near, limit) {
            continue;
        }
        let node = &nodes[at as usize];
        let c = slot as usize;
        if node.count[c] == 0 {
            open_node(&mut stack, &frustum, nodes, node.first[c], limit);
            continue;
        }
        // The leaf's box again, lane by lane and against limits that may have shrunk.
        let open = visit.open(lanes);
        let enter = slabs.enters_f32(node, c, visit.limit()).and(open);
        if !enter.any() {
            continue;
        }
        visit.leaf(slabs, node.first[c] as usize, node.count[c] as usize, enter);
        let open = visit.open(lanes);
        if !open.any() {
            return;
        }
        limit = greatest::<V, R>(visit.limit(), open);
        let left = open.count();
        if left * 4 <= bounded * 3
            && let Some(f) = Frustum::new(slabs, open)
        {
            (frustum, bounded) = (f, left);
        }
    }
}

/// Pushes the children of node `at` that the packet may enter before `limit`, farthest
/// first (so the nearest is opened next).
#[inline(always)]
fn open_node<R: Real>(
    stack: &mut Stack<(u32, u32, R)>,
    frustum: &Frustum<R>,
    nodes: &[Node],
    at: u32,
    limit: R,
) {
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
    for &(near, c) in &found[..n] {
        stack.push((at, c, near));
    }
}

/// The walk of any packet: every child's box tested lane by lane, its lanes carried down.
#[inline(always)]
fn by_lanes<V: Lanes, S: Visit<V>, R: Real>(
    nodes: &[Node],
    rays: &Rays<V>,
    slabs: &Slabs<V>,
    lanes: V::M,
    below: usize,
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
    for c in (0..u32::from(nodes[0].kids)).rev() {
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
        if open.count() < below as u64 {
            each_lane::<V, S, R>(nodes, slabs, open, child, visit);
            continue;
        }
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
pub(super) fn farthest_first<K: PartialOrd + Copy, T: Copy>(found: &mut [(K, T)]) {
    for i in 1..found.len() {
        let mut j = i;
        while j > 0 && found[j - 1].0 < found[j].0 {
            found.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// The greatest value of `v` over `lanes` (none: 0; every limit is at least 0).
#[inline(always)]
fn greatest<V: Lanes, R: Real>(v: V, lanes: V::M) -> R {
    let mut values = R::lanes(V::select(lanes, v, V::splat(0.0)));
    fold::<V, R>(&mut values, R::max)
}

/// `pick` (min or max) over the first `V::N` of `values`, in halving steps: each step is a
/// lane-wise `pick` of two halves, which the compiler turns into a few vector instructions
/// (a fold lane after lane, the obvious loop, cost a tenth of a shadow walk). Every lane type
/// has a power of two of lanes, so the halves always meet.
#[inline(always)]
pub(super) fn fold<V: Lanes, R: Real>(values: &mut [R; MAX_LANES], pick: fn(R, R) -> R) -> R {
    let mut n = V::N;
    while n > 1 {
        n /= 2;
        for k in 0..n {
            values[k] = pick(values[k], values[k + n]);
        }
    }
    values[0]
}

/// The deepest walk: at most `WIDTH` − 1 siblings wait on each of `MAX_DEPTH` levels.
pub(super) const STACK: usize = (WIDTH - 1) * MAX_DEPTH + WIDTH;

/// The walk's stack of (node, child slot, lanes) entries, left uninitialised above its top
/// (zeroing its `STACK` entries cost more than a short walk). Only the array lives in the
/// caller's frame: a struct that also held the top was zeroed whole by the compiler.
pub(super) struct Stack<'a, E = (u32, u32, u32)> {
    pub(super) entries: &'a mut MaybeUninit<[E; STACK]>,
    pub(super) top: usize,
}

impl<E: Copy> Stack<'_, E> {
    #[inline(always)]
    pub(super) fn push(&mut self, e: E) {
        assert!(self.top < STACK);
        // SAFETY: in bounds (checked above); writing through the pointer reads nothing.
        unsafe { self.entries.as_mut_ptr().cast::<E>().add(self.top).write(e) };
        self.top += 1;
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<E> {
        self.top = self.top.checked_sub(1)?;
        // SAFETY: every entry below the top is in bounds and was written by `push`.
        Some(unsafe { self.entries.as_ptr().cast::<E>().add(self.top).read() })
    }
}
