//! The sphere hierarchy's build: binned surface area heuristic along the widest centroid axis.

use super::{Ball, LEAF_SIZE, Node};
use glam::DVec3;

fn bounds(b: &Ball) -> (DVec3, DVec3) {
    // Padding keeps the box conservative against rounding in the hit computation.
    let pad = b.radius + 1e-9 * (b.radius + b.center.abs().max_element());
    (b.center - pad, b.center + pad)
}

/// Builds node `at` over `spheres[lo..hi]`, split where the surface area heuristic (binned
/// along the widest centroid axis) says rays will test the fewest spheres.
pub(super) fn build(nodes: &mut Vec<Node>, spheres: &mut [Ball], at: usize, lo: usize, hi: usize) {
    let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut cmin, mut cmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for b in &spheres[lo..hi] {
        let (a, z) = bounds(b);
        (min, max) = (min.min(a), max.max(z));
        (cmin, cmax) = (cmin.min(b.center), cmax.max(b.center));
    }
    let leaf = Node {
        min,
        max,
        first: lo as u32,
        count: (hi - lo) as u32,
        axis: 0,
    };
    if hi - lo <= LEAF_SIZE {
        nodes[at] = leaf;
        return;
    }
    let extent = cmax - cmin;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let (start, span) = (cmin[axis], extent[axis]);
    let split = sah_split(&spheres[lo..hi], axis, start, span, area(min, max))
        .and_then(|bin| partition(&mut spheres[lo..hi], axis, start, span, bin));
    let mid = match split {
        Some(m) => lo + m,
        None if hi - lo <= 4 * LEAF_SIZE => {
            nodes[at] = leaf;
            return;
        }
        None => {
            // Coincident centres or no better split: halve by rank to keep depth bounded.
            let mid = (lo + hi) / 2;
            spheres[lo..hi].select_nth_unstable_by(mid - lo, |a, b| {
                a.center[axis]
                    .total_cmp(&b.center[axis])
                    .then(a.object.cmp(&b.object))
            });
            mid
        }
    };
    let left = nodes.len();
    nodes.push(leaf);
    nodes.push(leaf);
    nodes[at] = Node {
        min,
        max,
        first: left as u32,
        count: 0,
        axis: axis as u32,
    };
    build(nodes, spheres, left, lo, mid);
    build(nodes, spheres, left + 1, mid, hi);
}

fn area(min: DVec3, max: DVec3) -> f64 {
    let d = (max - min).max(DVec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

const BINS: usize = 16;

/// The bin of a sphere's centre among 16 along `axis`.
fn bin(b: &Ball, axis: usize, start: f64, extent: f64) -> usize {
    (((b.center[axis] - start) / extent * BINS as f64) as usize).min(BINS - 1)
}

/// The cheapest of 16 bin boundaries along `axis` by the surface area heuristic; None when
/// no split beats a leaf.
fn sah_split(
    spheres: &[Ball],
    axis: usize,
    start: f64,
    extent: f64,
    parent_area: f64,
) -> Option<usize> {
    if extent <= 0.0 || parent_area <= 0.0 {
        return None;
    }
    let mut boxes = [(DVec3::INFINITY, DVec3::NEG_INFINITY, 0usize); BINS];
    for b in spheres {
        let (lo, hi) = bounds(b);
        let e = &mut boxes[bin(b, axis, start, extent)];
        *e = (e.0.min(lo), e.1.max(hi), e.2 + 1);
    }
    // Cost of splitting after bin i: area-weighted sphere counts on both sides.
    let sweep = |order: &mut dyn Iterator<Item = usize>| -> Vec<(f64, usize)> {
        let (mut lo, mut hi, mut n) = (DVec3::INFINITY, DVec3::NEG_INFINITY, 0);
        order
            .map(|i| {
                (lo, hi, n) = (lo.min(boxes[i].0), hi.max(boxes[i].1), n + boxes[i].2);
                (area(lo, hi) * n as f64, n)
            })
            .collect()
    };
    let left = sweep(&mut (0..BINS));
    let right = sweep(&mut (0..BINS).rev());
    let (best, cost) = (0..BINS - 1)
        .map(|i| (i, left[i].0 + right[BINS - 2 - i].0))
        .filter(|&(i, _)| left[i].1 > 0 && right[BINS - 2 - i].1 > 0)
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    (cost < parent_area * spheres.len() as f64).then_some(best)
}

/// Moves the spheres in bins up to `last` to the front; returns how many, if both sides
/// have some.
fn partition(
    spheres: &mut [Ball],
    axis: usize,
    start: f64,
    extent: f64,
    last: usize,
) -> Option<usize> {
    let mut m = 0;
    for i in 0..spheres.len() {
        if bin(&spheres[i], axis, start, extent) <= last {
            spheres.swap(i, m);
            m += 1;
        }
    }
    (m > 0 && m < spheres.len()).then_some(m)
}
