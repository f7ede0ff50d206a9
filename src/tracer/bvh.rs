//! The bounding volume hierarchy over one mesh's triangles, in the mesh's own coordinates
//! (built once per file and shared by every placement). Binary nodes, split by the surface
//! area heuristic over 16 bins on each axis; the two halves of a large node are built in
//! parallel with rayon, and since every split depends on the triangles alone the tree is the
//! same on any number of threads. Boxes are padded (see `PAD`) so traversal never skips a
//! triangle a ray hits, in f64 or f32: the hierarchy decides what is tested, never what is hit.

use crate::scene::Mesh;
use glam::DVec3;

/// A triangle as the traversal tests it: vertices in mesh coordinates, the unnormalised
/// normal (v1 − v0) × (v2 − v0), and its index in the mesh's triangle list.
#[derive(Debug, Clone, Copy)]
pub struct Tri {
    pub v: [DVec3; 3],
    pub n: DVec3,
    pub id: u32,
}

#[derive(Debug, Clone, Copy)]
pub struct Node {
    pub min: DVec3,
    pub max: DVec3,
    /// Leaf: the first triangle; interior: the second child (the first follows the node).
    pub first: u32,
    /// Triangles in a leaf; 0 for an interior node.
    pub count: u32,
    /// Interior: the axis the children were split along (the first holds smaller centres).
    pub axis: u32,
}

#[derive(Debug, Clone)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    pub tris: Vec<Tri>,
}

/// Boxes grow by this share of their largest coordinate and extent: wider than f32's rounding
/// of a vertex (2^-24) and of the slab test, so a box always holds its triangles.
const PAD: f64 = 1.0 / (1 << 20) as f64;
const BINS: usize = 16;
const MAX_LEAF: usize = 8;
/// The deepest a leaf may lie: below `MAX_DEPTH - 33` levels nodes are halved by count, which
/// ends any list of up to 2^32 triangles in 33 more.
pub const MAX_DEPTH: usize = 96;
/// Below this many triangles a subtree is built on one thread.
const PARALLEL_BELOW: usize = 1 << 14;

impl Bvh {
    pub fn build(mesh: &Mesh) -> Bvh {
        use rayon::prelude::*;
        let p = &mesh.positions;
        let tri = |i: usize| {
            let v = mesh.triangles[i].map(|k| p[k as usize]);
            Tri {
                v,
                n: (v[1] - v[0]).cross(v[2] - v[0]),
                id: i as u32,
            }
        };
        let mut prims: Vec<Prim> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|i| Prim::of(&tri(i)))
            .collect();
        let nodes = subtree(&mut prims, 0);
        let tris = prims.par_iter().map(|p| tri(p.id as usize)).collect();
        Bvh { nodes, tris }
    }

    /// The root's box.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.nodes[0].min, self.nodes[0].max)
    }

    /// Bytes the hierarchy holds (for `check`).
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
            + self.tris.len() * std::mem::size_of::<Tri>()
    }
}

/// A triangle's box, the centre of that box and its index, computed once for the whole build
/// and moved as the build sorts: every pass over a node's triangles reads memory in order.
#[derive(Clone, Copy)]
struct Prim {
    lo: DVec3,
    hi: DVec3,
    c: DVec3,
    id: u32,
}

impl Prim {
    fn of(t: &Tri) -> Prim {
        let lo = t.v[0].min(t.v[1]).min(t.v[2]);
        let hi = t.v[0].max(t.v[1]).max(t.v[2]);
        Prim {
            lo,
            hi,
            c: (lo + hi) * 0.5,
            id: t.id,
        }
    }
}

fn padded(min: DVec3, max: DVec3) -> (DVec3, DVec3) {
    let reach = min.abs().max(max.abs()).max_element() + (max - min).max_element();
    (min - PAD * reach, max + PAD * reach)
}

/// Folds `prims` into `empty` with `add`, in parallel chunks merged by `join` when there are
/// many. Only for folds whose result does not depend on the grouping (minima, maxima, counts),
/// so the tree is the same on any pool.
fn fold<T: Copy + Send + Sync>(
    prims: &[Prim],
    empty: T,
    add: impl Fn(T, &Prim) -> T + Sync,
    join: impl Fn(T, T) -> T + Sync,
) -> T {
    use rayon::prelude::*;
    if prims.len() < PARALLEL_BELOW {
        return prims.iter().fold(empty, &add);
    }
    prims
        .par_chunks(4096)
        .map(|c| c.iter().fold(empty, &add))
        .reduce(|| empty, &join)
}

/// Boxes of the triangles and of their centres: [min, max, centre min, centre max].
fn extents(prims: &[Prim]) -> [DVec3; 4] {
    let (inf, ninf) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    fold(
        prims,
        [inf, ninf, inf, ninf],
        |e, p| [e[0].min(p.lo), e[1].max(p.hi), e[2].min(p.c), e[3].max(p.c)],
        |a, b| {
            [
                a[0].min(b[0]),
                a[1].max(b[1]),
                a[2].min(b[2]),
                a[3].max(b[3]),
            ]
        },
    )
}

/// The nodes over `prims` (reordered in place), indices relative to this subtree: node 0 is
/// its root, triangle 0 is `prims[0]`'s.
fn subtree(prims: &mut [Prim], depth: usize) -> Vec<Node> {
    let [min, max, cmin, cmax] = extents(prims);
    let (min, max) = padded(min, max);
    let leaf = Node {
        min,
        max,
        first: 0,
        count: prims.len() as u32,
        axis: 0,
    };
    let chosen = match depth < MAX_DEPTH - 33 {
        true => split(prims, cmin, cmax, min, max),
        false => (prims.len() > 1).then_some((0, prims.len() / 2)),
    };
    let Some((axis, mid)) = chosen else {
        return vec![leaf];
    };
    let (left, right) = prims.split_at_mut(mid);
    let (l, r) = if left.len() + right.len() >= PARALLEL_BELOW {
        rayon::join(|| subtree(left, depth + 1), || subtree(right, depth + 1))
    } else {
        (subtree(left, depth + 1), subtree(right, depth + 1))
    };
    let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
    nodes.push(Node {
        min,
        max,
        first: (1 + l.len()) as u32,
        count: 0,
        axis: axis as u32,
    });
    append(&mut nodes, l, 1, 0);
    let at = nodes.len() as u32;
    append(&mut nodes, r, at, mid as u32);
    nodes
}

/// Appends a subtree's nodes, moving its node indices by `at` and triangle indices by `tri`.
fn append(nodes: &mut Vec<Node>, sub: Vec<Node>, at: u32, tri: u32) {
    nodes.extend(sub.into_iter().map(|n| Node {
        first: n.first + if n.count > 0 { tri } else { at },
        ..n
    }));
}

/// Where to split `prims`: the axis, and how many triangles go first (they are moved there).
/// None when a leaf is as cheap (and small enough).
fn split(
    prims: &mut [Prim],
    cmin: DVec3,
    cmax: DVec3,
    min: DVec3,
    max: DVec3,
) -> Option<(usize, usize)> {
    let n = prims.len();
    if n <= 2 {
        return None;
    }
    let extent = cmax - cmin;
    let bins = binned(prims, cmin, extent);
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if extent[axis].is_nan() || extent[axis] <= 0.0 {
            continue;
        }
        if let Some((cost, bin)) = sah(&bins[axis])
            && best.is_none_or(|b| cost < b.0)
        {
            best = Some((cost, axis, bin));
        }
    }
    let leaf_cost = area(min, max) * n as f64;
    match best {
        Some((cost, axis, bin)) if cost < leaf_cost || n > MAX_LEAF => {
            let (start, span) = (cmin[axis], extent[axis]);
            let mid = partition(prims, |p| bin_of(p.c[axis], start, span) <= bin);
            (mid > 0 && mid < n).then_some((axis, mid))
        }
        None if n > MAX_LEAF => {
            // Every centre coincides: halve by position in the list to bound the depth.
            Some((0, n / 2))
        }
        _ => None,
    }
}

fn bin_of(c: f64, start: f64, span: f64) -> usize {
    (((c - start) / span * BINS as f64) as usize).min(BINS - 1)
}

fn area(min: DVec3, max: DVec3) -> f64 {
    let d = (max - min).max(DVec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

type Bins = [(DVec3, DVec3, usize); BINS];

/// The bins of every axis in one pass over the triangles.
fn binned(prims: &[Prim], start: DVec3, span: DVec3) -> [Bins; 3] {
    let empty: [Bins; 3] = [[(DVec3::INFINITY, DVec3::NEG_INFINITY, 0usize); BINS]; 3];
    let add = |mut bins: [Bins; 3], p: &Prim| {
        for (axis, axis_bins) in bins.iter_mut().enumerate() {
            if span[axis] > 0.0 {
                let b = &mut axis_bins[bin_of(p.c[axis], start[axis], span[axis])];
                *b = (b.0.min(p.lo), b.1.max(p.hi), b.2 + 1);
            }
        }
        bins
    };
    let join = |mut a: [Bins; 3], b: [Bins; 3]| {
        for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
            *x = (x.0.min(y.0), x.1.max(y.1), x.2 + y.2);
        }
        a
    };
    fold(prims, empty, add, join)
}

/// The cheapest split after one of the first 15 of an axis's bins, and its cost: the triangle
/// counts of both sides weighted by their boxes' areas.
fn sah(bins: &Bins) -> Option<(f64, usize)> {
    let mut right = [(0.0, 0usize); BINS];
    let (mut lo, mut hi, mut count) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0);
    for i in (1..BINS).rev() {
        (lo, hi, count) = (lo.min(bins[i].0), hi.max(bins[i].1), count + bins[i].2);
        right[i] = (area(lo, hi) * count as f64, count);
    }
    let (mut lo, mut hi, mut count) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0);
    let mut best: Option<(f64, usize)> = None;
    for i in 0..BINS - 1 {
        (lo, hi, count) = (lo.min(bins[i].0), hi.max(bins[i].1), count + bins[i].2);
        if count == 0 || right[i + 1].1 == 0 {
            continue;
        }
        let cost = area(lo, hi) * count as f64 + right[i + 1].0;
        if best.is_none_or(|b| cost < b.0) {
            best = Some((cost, i));
        }
    }
    best
}

/// Moves the triangles `first` accepts to the front (in place, two cursors moving inwards);
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

    pub(crate) fn grid(n: usize) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let (x, z) = (i as f64 / n as f64, j as f64 / n as f64);
                positions.push(DVec3::new(x, (7.0 * x).sin() * (5.0 * z).cos() * 0.2, z));
            }
        }
        let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..n {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        Mesh {
            file: "grid".into(),
            normals: vec![DVec3::Y; positions.len()],
            positions,
            uvs: None,
            triangles,
            file_normals: 0,
            skipped: 0,
            notes: Vec::new(),
            digest: 0,
            bytes: 0,
            load_seconds: 0.0,
        }
    }

    #[test]
    fn every_triangle_is_in_one_leaf_inside_its_box() {
        let bvh = Bvh::build(&grid(60));
        let mut seen = vec![0u32; bvh.tris.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = bvh.nodes[i];
            if n.count == 0 {
                stack.push(i + 1);
                stack.push(n.first as usize);
                continue;
            }
            for t in &bvh.tris[n.first as usize..(n.first + n.count) as usize] {
                seen[t.id as usize] += 1;
                let p = Prim::of(t);
                assert!(p.lo.cmpge(n.min).all() && p.hi.cmple(n.max).all());
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn the_tree_is_the_same_on_any_pool() {
        let mesh = grid(200);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let a = one.install(|| Bvh::build(&mesh));
        let b = Bvh::build(&mesh);
        assert_eq!(a.nodes.len(), b.nodes.len());
        for (x, y) in a.nodes.iter().zip(&b.nodes) {
            assert_eq!(
                (x.min, x.max, x.first, x.count),
                (y.min, y.max, y.first, y.count)
            );
        }
        assert!(a.tris.iter().zip(&b.tris).all(|(x, y)| x.id == y.id));
    }
}
