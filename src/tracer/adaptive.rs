//! Adaptive sampling in rounds, for frames whose samples differ in time or on the lens
//! (motion blur, depth of field). Two samples that happen to agree say little there: a
//! defocused edge is a mixture, and its grain only shows over many samples. So every pixel
//! first gets `samples`, and each round doubles the samples of the pixels whose mean is
//! still uncertain, until none is or they have `max_samples`. A pixel's uncertainty is how
//! far apart two independent halves of its samples are (the first pass's two halves; after
//! a round, the mean before it and the round's own samples, which are as many): an estimate
//! of the error that follows the sampler's real convergence, where a variance would assume
//! independent samples. One pair is a rough estimate and grain comes in patches, so a pixel
//! goes on while it or any of its eight neighbours is uncertain.

use super::rows::{Pass, Planes, RowStats};
use super::{Adaptive, Kernel, Samples, extend};
use crate::lanes::{Lanes, V3};
use rayon::prelude::*;

/// Runs the rounds after `first`, which traced `samples` for every pixel and recorded in
/// `error` each pixel's error estimate.
pub(super) fn rounds(
    kernel: Kernel,
    first: &Pass,
    a: Adaptive,
    planes: &mut Planes,
    error: &mut [f32],
) -> RowStats {
    let (w, h) = (
        first.settings.width as usize,
        first.settings.height as usize,
    );
    let q = a.threshold;
    let mut have = first.settings.samples;
    let mut active: Vec<u32> = (0..(w * h) as u32).collect();
    let mut stats = RowStats::default();
    while have < a.max_samples && !first.stopped() {
        active = active
            .into_par_iter()
            .filter(|&i| uncertain(error, w, h, i as usize, q))
            .collect();
        if active.is_empty() {
            break;
        }
        let total = have.saturating_mul(2).min(a.max_samples);
        let pass = Pass {
            samples: Samples::More { have, total },
            ..*first
        };
        let (more, round) = extend(kernel, &pass, &active, planes);
        stats = stats + more;
        for (&p, e) in active.iter().zip(round) {
            error[p as usize] = e;
        }
        have = total;
    }
    stats
}

/// The error estimate of a mean made of two halves whose means are `a` and `b`: half the
/// largest difference of their channels' square roots (about what the sRGB curve does to
/// a difference), each mean taken in [0, 1] first.
#[inline(always)]
pub(super) fn disagreement<V: Lanes>(a: V3<V>, b: V3<V>, zero: V, one: V) -> V {
    let (x, y) = (apart(a.x, b.x, zero, one), apart(a.y, b.y, zero, one));
    x.max(y).max(apart(a.z, b.z, zero, one)) * V::splat(0.5)
}

/// |√x − √y| of x and y taken in [0, 1].
#[inline(always)]
fn apart<V: Lanes>(x: V, y: V, zero: V, one: V) -> V {
    let d = x.max(zero).min(one).sqrt() - y.max(zero).min(one).sqrt();
    d.max(zero - d)
}

/// Whether pixel `i` or one of its eight neighbours (those inside the frame) has an error
/// estimate above `q`: one pair of half-means is a rough estimate, and grain comes in
/// patches, so a pixel goes on while any pixel next to it is uncertain.
fn uncertain(error: &[f32], w: usize, h: usize, i: usize, q: f32) -> bool {
    let (row, col) = (i / w, i % w);
    let cols = col.saturating_sub(1)..(col + 2).min(w);
    (row.saturating_sub(1)..(row + 2).min(h))
        .any(|r| error[r * w..][cols.clone()].iter().any(|&e| e > q))
}
