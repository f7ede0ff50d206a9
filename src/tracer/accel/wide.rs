//! The one hierarchy the tracer builds: 4-wide nodes with f32 boxes, over any list of boxes
//! (a mesh file's triangles, in its own coordinates; a scene's placed meshes, in the world).
//!
//! **Build.** Top-down binned surface area heuristic (16 bins on each axis, centroids binned
//! in f32): a node takes its box's primitives, splits them in two, then splits the larger-area
//! half again (and so on) until it has 4 children or none is worth splitting. Large subtrees
//! are built in parallel with rayon and large nodes binned in parallel chunks; every choice
//! depends on the boxes alone (minima, maxima and counts, which no grouping changes), so the
//! tree is the same on any number of threads.
//!
//! **Boxes only decide what is tested.** A child's box is the union of its primitives' boxes,
//! each the f64 box rounded outward to f32, grown by `PAD` of its reach (largest coordinate
//! plus largest extent) and rounded outward again. So it holds every primitive whole, in f64
//! as in f32, and leaves the same room for rounding as the f64 boxes before it did: wider than
//! f32's rounding of a vertex (2^-24) and of the slab test (see docs/spec/mesh.md, "The
//! hierarchy"). Rays in f64 frames compare these f32 values widened exactly.

use glam::{DVec3, Vec3, Vec3A};
use std::collections::TryReserveError;

/// Children per node.
pub const WIDTH: usize = 4;
/// Boxes grow by this share of their reach (largest coordinate plus largest extent).
pub const PAD: f64 = 1.0 / (1 << 20) as f64;
const BINS: usize = 16;
/// The deepest a leaf may lie: below `MAX_DEPTH - 33` levels nodes are halved by count, which
/// ends any list of up to 2^32 primitives in 33 more.
pub const MAX_DEPTH: usize = 96;
/// Below this many primitives a subtree is built, and a node binned, on one thread.
const PARALLEL_BELOW: usize = 1 << 14;

/// Up to `WIDTH` children, each a box and either a node or a run of primitives. Children
/// `0..kids` are used; a leaf child has `count[i]` > 0 primitives from `first[i]` (in leaf
/// order), an interior one `count[i]` = 0 and its node index in `first[i]`. Two cache lines:
/// a leaf holds at most `Shape::max_leaf` primitives, so its count fits 16 bits.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub struct Node {
    /// Per axis, per child: the box's low and high corner, rounded outward.
    pub lo: [[f32; WIDTH]; 3],
    pub hi: [[f32; WIDTH]; 3],
    pub first: [u32; WIDTH],
    pub count: [u16; WIDTH],
    pub kids: u16,
}

const _: () = assert!(std::mem::size_of::<Node>() == 128);

/// A primitive as the build sees it: its box rounded outward to f32, and its index.
#[derive(Debug, Clone, Copy)]
pub struct Prim {
    pub lo: Vec3,
    pub hi: Vec3,
    /// lo + hi: twice the box's centre, what the bins sort by.
    c: Vec3,
    pub id: u32,
}

impl Prim {
    /// The primitive `id` with the f64 box [lo, hi].
    pub fn new(lo: DVec3, hi: DVec3, id: u32) -> Prim {
        let (lo, hi) = (down(lo), up(hi));
        Prim {
            lo,
            hi,
            c: lo + hi,
            id,
        }
    }
}

/// A built hierarchy: the nodes (node 0 the root) and the primitives' indices in leaf order.
#[derive(Debug, Clone)]
pub struct Tree {
    pub nodes: Vec<Node>,
    pub order: Vec<u32>,
    /// The root's box, padded (the union of its children's).
    pub lo: Vec3,
    pub hi: Vec3,
}

/// The nearest f32 at or below `x`, per component.
pub fn down(x: DVec3) -> Vec3 {
    Vec3::new(below(x.x), below(x.y), below(x.z))
}

/// The nearest f32 at or above `x`, per component.
pub fn up(x: DVec3) -> Vec3 {
    -down(-x)
}

fn below(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x { f.next_down() } else { f }
}

/// `[lo, hi]` grown by `PAD` of its reach, rounded outward.
pub fn padded(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let (lo64, hi64) = (lo.as_dvec3(), hi.as_dvec3());
    let reach = lo64.abs().max(hi64.abs()).max_element() + (hi64 - lo64).max_element();
    (down(lo64 - PAD * reach), up(hi64 + PAD * reach))
}

/// How wide a tree's nodes are and how full its leaves: `Shape::WIDE` is what frames use;
/// `Shape::BINARY` (2 children, leaves of 1) is another tree over the same primitives, which
/// the tests compare frames against (`RAYREEL_HIERARCHY=binary`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    pub width: usize,
    pub max_leaf: usize,
}

impl Shape {
    pub const WIDE: Shape = Shape {
        width: WIDTH,
        max_leaf: 4,
    };
    pub const BINARY: Shape = Shape {
        width: 2,
        max_leaf: 1,
    };

    /// `WIDE`, or `BINARY` when `RAYREEL_HIERARCHY=binary` asks for it (tests and
    /// measurements: the hierarchy never changes a frame). Decided once per process.
    pub fn chosen() -> Shape {
        static CHOSEN: std::sync::OnceLock<Shape> = std::sync::OnceLock::new();
        *CHOSEN.get_or_init(|| match std::env::var("RAYREEL_HIERARCHY").as_deref() {
            Ok("binary") => Shape::BINARY,
            _ => Shape::WIDE,
        })
    }
}

impl Tree {
    /// The hierarchy over `prims` (at least one), of the `chosen` shape.
    pub fn build(prims: Vec<Prim>) -> Tree {
        Tree::try_build(prims)
            .unwrap_or_else(|_| std::alloc::handle_alloc_error(std::alloc::Layout::new::<Node>()))
    }

    /// `build`, an error where the nodes or the order cannot be allocated (a mesh's
    /// hierarchy: the run then says so rather than aborting).
    pub fn try_build(prims: Vec<Prim>) -> Result<Tree, TryReserveError> {
        Tree::build_as(prims, Shape::chosen())
    }

    /// The hierarchy over `prims` (at least one) with nodes of `shape`.
    pub fn build_as(mut prims: Vec<Prim>, shape: Shape) -> Result<Tree, TryReserveError> {
        assert!(!prims.is_empty(), "a hierarchy over nothing");
        let (lo, hi) = bounds(&prims);
        let nodes = match node(&mut prims, lo, hi, (0, shape))? {
            Child::Node(nodes) => nodes,
            Child::Leaf(_) => {
                let (lo, hi) = padded(lo, hi);
                wrap(&prims, lo, hi)
            }
        };
        let (lo, hi) = padded(lo, hi);
        let mut order = Vec::new();
        order.try_reserve_exact(prims.len())?;
        order.extend(prims.iter().map(|p| p.id));
        Ok(Tree {
            nodes,
            order,
            lo,
            hi,
        })
    }

    /// Bytes the nodes and the order take.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.order.len() * 4
    }

    /// This tree with every box moved by −`by` and grown by `pad` of its new reach, rounded
    /// outward (f32 frames trace in coordinates around the camera).
    pub fn shifted(&self, by: DVec3, pad: f64) -> Tree {
        let move_box = |lo: Vec3, hi: Vec3| {
            let (lo, hi) = (lo.as_dvec3() - by, hi.as_dvec3() - by);
            let reach = lo.abs().max(hi.abs()).max_element() + (hi - lo).max_element();
            (down(lo - pad * reach), up(hi + pad * reach))
        };
        let nodes = self
            .nodes
            .iter()
            .map(|n| {
                let mut m = *n;
                for c in 0..n.kids as usize {
                    let (lo, hi) = move_box(corner(&n.lo, c), corner(&n.hi, c));
                    set_box(&mut m, c, lo, hi);
                }
                m
            })
            .collect();
        let (lo, hi) = move_box(self.lo, self.hi);
        Tree {
            nodes,
            order: self.order.clone(),
            lo,
            hi,
        }
    }
}

/// Child `c`'s corner from a node's per-axis array.
pub fn corner(a: &[[f32; WIDTH]; 3], c: usize) -> Vec3 {
    Vec3::new(a[0][c], a[1][c], a[2][c])
}

fn set_box(n: &mut Node, c: usize, lo: Vec3, hi: Vec3) {
    for axis in 0..3 {
        n.lo[axis][c] = lo[axis];
        n.hi[axis][c] = hi[axis];
    }
}

/// A root that is itself a leaf, under a node of one child.
fn wrap(prims: &[Prim], lo: Vec3, hi: Vec3) -> Vec<Node> {
    let mut n = empty_node();
    set_box(&mut n, 0, lo, hi);
    n.count[0] = leaf_count(prims.len());
    n.kids = 1;
    vec![n]
}

fn empty_node() -> Node {
    Node {
        lo: [[f32::INFINITY; WIDTH]; 3],
        hi: [[f32::NEG_INFINITY; WIDTH]; 3],
        first: [0; WIDTH],
        count: [0; WIDTH],
        kids: 0,
    }
}

/// What a run of primitives becomes: a leaf (its primitive count) or a subtree's nodes
/// (indices relative to the subtree: node 0 its root, primitive 0 the run's first).
enum Child {
    Leaf(usize),
    Node(Vec<Node>),
}

/// What opening a node costs, against testing one primitive (the surface area heuristic's
/// traversal cost).
const TRAVERSAL: f32 = 2.0;

/// A run of primitives a node's child covers: where it starts in its node's slice, how
/// many, the union of their boxes, and whether it may still split.
#[derive(Clone, Copy)]
struct Run {
    start: usize,
    len: usize,
    lo: Vec3,
    hi: Vec3,
    splits: bool,
}

/// The subtree over `prims` (reordered in place), whose boxes' union is [lo, hi].
/// `at` is the node's depth and the tree's shape.
fn node(
    prims: &mut [Prim],
    lo: Vec3,
    hi: Vec3,
    at: (usize, Shape),
) -> Result<Child, TryReserveError> {
    let (depth, shape) = at;
    let whole = Run {
        start: 0,
        len: prims.len(),
        lo,
        hi,
        splits: true,
    };
    let Some((l, r)) = split(prims, &whole, at) else {
        return Ok(Child::Leaf(prims.len()));
    };
    // Split the largest-area child that may split until there are WIDTH of them.
    let mut runs = vec![l, r];
    while runs.len() < shape.width {
        let widest = runs
            .iter()
            .enumerate()
            .filter(|(_, r)| r.splits && r.len > 1)
            .map(|(i, r)| (i, area(r.lo, r.hi)))
            .fold(None, |best: Option<(usize, f32)>, (i, a)| match best {
                Some((_, b)) if b >= a => best,
                _ => Some((i, a)),
            });
        let Some((i, _)) = widest else { break };
        let run = runs[i];
        match split(&mut prims[run.start..run.start + run.len], &run, at) {
            Some((mut a, mut b)) => {
                a.start += run.start;
                b.start += run.start;
                runs[i] = a;
                runs.insert(i + 1, b);
            }
            None => runs[i].splits = false,
        }
    }
    let children = build_runs(prims, &runs, (depth + 1, shape))?;
    Ok(Child::Node(assemble(&runs, children)?))
}

/// Each run's subtree, large ones in parallel.
fn build_runs(
    prims: &mut [Prim],
    runs: &[Run],
    at: (usize, Shape),
) -> Result<Vec<Child>, TryReserveError> {
    let mut slices = Vec::with_capacity(runs.len());
    let mut rest = prims;
    for run in runs {
        let (head, tail) = rest.split_at_mut(run.len);
        slices.push((head, *run));
        rest = tail;
    }
    let sub = |(s, run): (&mut [Prim], Run)| match run.splits {
        true => node(s, run.lo, run.hi, at),
        false => Ok(Child::Leaf(s.len())),
    };
    if runs.iter().map(|r| r.len).sum::<usize>() < PARALLEL_BELOW {
        return slices.into_iter().map(sub).collect();
    }
    use rayon::prelude::*;
    slices.into_par_iter().map(sub).collect()
}

/// The node over `runs` followed by its children's subtrees.
fn assemble(runs: &[Run], children: Vec<Child>) -> Result<Vec<Node>, TryReserveError> {
    let total: usize = children
        .iter()
        .map(|c| match c {
            Child::Node(n) => n.len(),
            Child::Leaf(_) => 0,
        })
        .sum();
    let mut nodes = Vec::new();
    nodes.try_reserve_exact(1 + total)?;
    let mut top = empty_node();
    top.kids = runs.len() as u16;
    nodes.push(top);
    for (c, (child, run)) in children.into_iter().zip(runs).enumerate() {
        let (lo, hi) = padded(run.lo, run.hi);
        set_box(&mut nodes[0], c, lo, hi);
        let start = run.start as u32;
        match child {
            Child::Leaf(n) => {
                nodes[0].first[c] = start;
                nodes[0].count[c] = leaf_count(n);
            }
            Child::Node(sub) => {
                let at = nodes.len() as u32;
                nodes[0].first[c] = at;
                nodes.extend(sub.into_iter().map(|mut n| {
                    for k in 0..n.kids as usize {
                        n.first[k] += if n.count[k] > 0 { start } else { at };
                    }
                    n
                }));
            }
        }
    }
    Ok(nodes)
}

/// How to split `prims` (the run `run`, starting at 0): its two parts, the first moved to
/// the front. None when a leaf is as cheap and small enough.
fn split(prims: &mut [Prim], run: &Run, (depth, shape): (usize, Shape)) -> Option<(Run, Run)> {
    let n = prims.len();
    if n <= 1 {
        return None;
    }
    if depth >= MAX_DEPTH - 33 {
        return Some(halves(prims));
    }
    let (cmin, cmax) = centre_bounds(prims);
    let span = cmax - cmin;
    let mut bins = [[EMPTY_BIN; BINS]; 3];
    binned(prims, cmin, span, &mut bins);
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if span[axis].is_nan() || span[axis] <= 0.0 {
            continue;
        }
        if let Some((cost, bin)) = sah(&bins[axis])
            && best.is_none_or(|b| cost < b.0)
        {
            best = Some((cost, axis, bin));
        }
    }
    // In units of one primitive test over the parent's area: a split costs a visit of the
    // children's boxes on top of their primitives.
    let whole = area(run.lo, run.hi);
    let leaf_cost = whole * n as f32;
    match best {
        Some((cost, axis, bin)) if cost + TRAVERSAL * whole < leaf_cost || n > shape.max_leaf => {
            let (start, scale) = (cmin[axis], BINS as f32 / span[axis]);
            let mid = partition(prims, |p| bin_of(p.c[axis], start, scale) <= bin);
            let (l, r) = bins[axis].split_at(bin + 1);
            let (l, r) = (
                l.iter().fold(EMPTY_BIN, grow),
                r.iter().fold(EMPTY_BIN, grow),
            );
            let part = |start, b: Bin| Run {
                start,
                len: b.count as usize,
                lo: b.lo.into(),
                hi: b.hi.into(),
                splits: true,
            };
            let cut = mid > 0 && mid < n && mid == l.count as usize;
            // (Always so, as the bins and the partition place centres alike; else halves, so
            // that no leaf outgrows max_leaf.)
            match cut {
                true => Some((part(0, l), part(mid, r))),
                false => (n > shape.max_leaf).then(|| halves(prims)),
            }
        }
        // Every centre coincides: halve by position in the list to bound the depth.
        None if n > shape.max_leaf => Some(halves(prims)),
        _ => None,
    }
}

/// A leaf's primitive count as its node stores it.
fn leaf_count(n: usize) -> u16 {
    u16::try_from(n).expect("a leaf holds at most max_leaf primitives")
}

/// `prims` cut in two by position in the list.
fn halves(prims: &[Prim]) -> (Run, Run) {
    let mid = prims.len() / 2;
    let part = |start, s: &[Prim]| {
        let (lo, hi) = bounds(s);
        Run {
            start,
            len: s.len(),
            lo,
            hi,
            splits: true,
        }
    };
    (part(0, &prims[..mid]), part(mid, &prims[mid..]))
}

/// The bin of centre `c` along an axis whose centres start at `start` and span BINS/`scale`.
#[inline(always)]
fn bin_of(c: f32, start: f32, scale: f32) -> usize {
    (((c - start) * scale) as usize).min(BINS - 1)
}

fn area(lo: Vec3, hi: Vec3) -> f32 {
    let d = (hi - lo).max(Vec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The union of the primitives' boxes.
fn bounds(prims: &[Prim]) -> (Vec3, Vec3) {
    let mut acc = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for_chunks(prims, &mut acc, |a, p| {
        a.0 = a.0.min(p.lo);
        a.1 = a.1.max(p.hi);
    });
    acc
}

fn centre_bounds(prims: &[Prim]) -> (Vec3, Vec3) {
    let mut acc = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for_chunks(prims, &mut acc, |a, p| {
        a.0 = a.0.min(p.c);
        a.1 = a.1.max(p.c);
    });
    acc
}

/// A per-primitive accumulation whose merge is `add` again on the merged parts' fields:
/// minima, maxima and counts only, so any grouping gives the same result.
trait Merge: Copy + Send + Sync {
    fn merge(&mut self, o: &Self);
}

impl Merge for (Vec3, Vec3) {
    fn merge(&mut self, o: &Self) {
        self.0 = self.0.min(o.0);
        self.1 = self.1.max(o.1);
    }
}

type Bins = [Bin; BINS];

/// The boxes binned together, in SIMD vectors (minima and maxima of finite boxes are the
/// same in any lanes).
#[derive(Clone, Copy)]
struct Bin {
    lo: Vec3A,
    hi: Vec3A,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    lo: Vec3A::INFINITY,
    hi: Vec3A::NEG_INFINITY,
    count: 0,
};

impl Merge for [Bins; 3] {
    fn merge(&mut self, o: &Self) {
        for (x, y) in self.iter_mut().flatten().zip(o.iter().flatten()) {
            x.lo = x.lo.min(y.lo);
            x.hi = x.hi.max(y.hi);
            x.count += y.count;
        }
    }
}

/// Folds `add` over `prims` into `acc` in place, in parallel chunks for large runs.
fn for_chunks<T: Merge>(prims: &[Prim], acc: &mut T, add: impl Fn(&mut T, &Prim) + Sync) {
    use rayon::prelude::*;
    if prims.len() < PARALLEL_BELOW {
        for p in prims {
            add(acc, p);
        }
        return;
    }
    let start = *acc;
    let parts: Vec<T> = prims
        .par_chunks(PARALLEL_BELOW)
        .map(|c| {
            let mut a = start;
            for p in c {
                add(&mut a, p);
            }
            a
        })
        .collect();
    for p in &parts {
        acc.merge(p);
    }
}

/// The bins of every axis (empty ones given) filled in one pass over the primitives. (Filled
/// in place: returned, 2 KiB of bins were copied for every node, which near the leaves cost
/// more than binning its few primitives.)
fn binned(prims: &[Prim], start: Vec3, span: Vec3, bins: &mut [Bins; 3]) {
    let scale = Vec3::splat(BINS as f32) / span;
    for_chunks(prims, bins, |bins, p| {
        let (lo, hi) = (Vec3A::from(p.lo), Vec3A::from(p.hi));
        for axis in 0..3 {
            if span[axis] > 0.0 {
                let b = &mut bins[axis][bin_of(p.c[axis], start[axis], scale[axis])];
                b.lo = b.lo.min(lo);
                b.hi = b.hi.max(hi);
                b.count += 1;
            }
        }
    });
}

/// The cheapest split after one of the first 15 of an axis's bins, and its cost: the
/// primitive counts of both sides weighted by their boxes' areas. Only the non-empty bins are
/// swept: a cut after an empty bin has the sides (and so the cost) of the cut after the last
/// non-empty bin before it, which comes first and wins the tie, so skipping them changes no
/// choice; it saves most of the sweep in the many small nodes near the leaves.
fn sah(bins: &Bins) -> Option<(f32, usize)> {
    let mut used = [0usize; BINS];
    let mut k = 0;
    for (i, b) in bins.iter().enumerate() {
        used[k] = i;
        k += usize::from(b.count > 0);
    }
    if k < 2 {
        return None;
    }
    let mut right = [0.0f32; BINS];
    let mut acc = EMPTY_BIN;
    for j in (1..k).rev() {
        acc = grow(acc, &bins[used[j]]);
        right[j] = area(acc.lo.into(), acc.hi.into()) * acc.count as f32;
    }
    let mut acc = EMPTY_BIN;
    let mut best: Option<(f32, usize)> = None;
    for j in 0..k - 1 {
        acc = grow(acc, &bins[used[j]]);
        let cost = area(acc.lo.into(), acc.hi.into()) * acc.count as f32 + right[j + 1];
        if best.is_none_or(|b| cost < b.0) {
            best = Some((cost, used[j]));
        }
    }
    best
}

fn grow(a: Bin, b: &Bin) -> Bin {
    Bin {
        lo: a.lo.min(b.lo),
        hi: a.hi.max(b.hi),
        count: a.count + b.count,
    }
}

/// Moves the primitives `first` accepts to the front (in place, two cursors moving inwards);
/// returns how many.
fn partition(prims: &mut [Prim], first: impl Fn(&Prim) -> bool) -> usize {
    let (mut i, mut j) = (0, prims.len());
    while i < j {
        if first(&prims[i]) {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(n: usize) -> Vec<Prim> {
        let mut rnd = crate::testing::uniform(1);
        (0..n)
            .map(|i| {
                let c = DVec3::new(rnd(), rnd(), rnd()) * 100.0;
                let r = DVec3::new(rnd(), rnd(), rnd());
                Prim::new(c - r, c + r, i as u32)
            })
            .collect()
    }

    /// Every primitive sits in exactly one leaf, inside every box on its way down.
    fn check(tree: &Tree, prims: &[Prim]) {
        let mut seen = vec![0u32; prims.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &tree.nodes[i];
            assert!((1..=WIDTH as u16).contains(&n.kids));
            for c in 0..n.kids as usize {
                let (lo, hi) = (corner(&n.lo, c), corner(&n.hi, c));
                if n.count[c] == 0 {
                    let sub = &tree.nodes[n.first[c] as usize];
                    for k in 0..sub.kids as usize {
                        assert!(corner(&sub.lo, k).cmpge(lo).all());
                        assert!(corner(&sub.hi, k).cmple(hi).all());
                    }
                    stack.push(n.first[c] as usize);
                    continue;
                }
                let run = n.first[c] as usize..(n.first[c] + u32::from(n.count[c])) as usize;
                for &id in &tree.order[run] {
                    seen[id as usize] += 1;
                    let p = prims[id as usize];
                    assert!(p.lo.cmpge(lo).all() && p.hi.cmple(hi).all());
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn every_primitive_is_in_one_leaf_inside_its_boxes() {
        for n in [1, 2, 3, 5, 17, 1000, 40000] {
            let prims = boxes(n);
            check(&Tree::build(prims.clone()), &prims);
        }
    }

    #[test]
    fn coincident_boxes_still_end() {
        let prims: Vec<Prim> = (0..5000)
            .map(|i| Prim::new(DVec3::ONE, DVec3::splat(2.0), i))
            .collect();
        check(&Tree::build(prims.clone()), &prims);
    }

    #[test]
    fn the_tree_is_the_same_on_any_pool() {
        let prims = boxes(100_000);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let a = one.install(|| Tree::build(prims.clone()));
        let b = Tree::build(prims);
        assert_eq!(a.order, b.order);
        assert_eq!(a.nodes.len(), b.nodes.len());
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            assert_eq!(
                (x.lo, x.hi, x.first, x.count),
                (y.lo, y.hi, y.first, y.count)
            );
        }
    }

    /// The sweep over every bin, as the build first chose: the sweep over the non-empty bins
    /// chooses the same cut at the same cost.
    fn sah_every_bin(bins: &Bins) -> Option<(f32, usize)> {
        let mut best: Option<(f32, usize)> = None;
        for i in 0..BINS - 1 {
            let left = bins[..=i].iter().fold(EMPTY_BIN, grow);
            let right = bins[i + 1..].iter().rev().fold(EMPTY_BIN, grow);
            if left.count == 0 || right.count == 0 {
                continue;
            }
            let cost = area(left.lo.into(), left.hi.into()) * left.count as f32
                + area(right.lo.into(), right.hi.into()) * right.count as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, i));
            }
        }
        best
    }

    #[test]
    fn the_sweep_skips_empty_bins_without_changing_the_cut() {
        let prims = boxes(4000);
        for (k, chunk) in prims.chunks(1 + prims.len() / 97).enumerate() {
            for n in [1, 2, 3, 5, 9, chunk.len()] {
                let part = &chunk[..n.min(chunk.len())];
                let (lo, hi) = centre_bounds(part);
                let mut bins = [[EMPTY_BIN; BINS]; 3];
                binned(part, lo, hi - lo, &mut bins);
                for axis in &bins {
                    let (a, b) = (sah(axis), sah_every_bin(axis));
                    assert_eq!(
                        a.map(|(c, i)| (c.to_bits(), i)),
                        b.map(|(c, i)| (c.to_bits(), i)),
                        "chunk {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn rounding_is_outward() {
        let x = 0.1f64;
        assert!(f64::from(below(x)) <= x && f64::from(-below(-x)) >= x);
        assert_eq!(below(0.5), 0.5);
    }
}
