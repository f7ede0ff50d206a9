//! The film filter: a bilateral filter guided by each pixel's own error estimate, for film
//! frames (motion blur, depth of field), whose grain is the sampling error the rounds stopped
//! short of. A pixel whose samples agree is left as it is; a noisy one becomes a weighted
//! mean of its neighbours, each weighted down as its colour departs from the pixel's by more
//! than their noise allows, so grain in a blur is averaged away while an edge that stands out
//! from the noise stays. A shutter's blur is a smear along the motion, with detail left
//! across it, so there the filter takes one 3×3 pass; a lens blurs every way at once, so a
//! frame whose lens is open takes three passes of the same 3×3 weights at steps of 1, 2 and
//! 4 pixels (an "à-trous" cascade, each pass guided by the last one's colour and noise), and
//! reaches 15 pixels across where its grain is wide.
//!
//! It is a pure function of the frame's colour, coverage and error estimates: every
//! operation is one IEEE-754 f32 operation in a fixed order (no fused multiply-add, no libm),
//! so the bytes are the same on every machine, lane width and thread count.
//! docs/spec/tracer.md (**Film filter**) states each one.
//!
//! ```yaml
//! render:
//!   denoise: true   # the default on film; false keeps the rounds' means as they are
//! ```

use rayon::prelude::*;

/// How far the filter reaches: one pass, or the lens's cascade.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Reach {
    /// A shutter's blur alone: one 3×3 pass.
    Shutter,
    /// An open lens: 3×3 passes at steps 1, 2 and 4.
    Lens,
}

impl Reach {
    pub(crate) fn of(lens_open: bool) -> Reach {
        match lens_open {
            true => Reach::Lens,
            false => Reach::Shutter,
        }
    }

    /// The passes' steps in pixels, and κ² (a neighbour whose √-colour differs from the
    /// pixel's by κ standard deviations of their difference keeps a quarter of its weight).
    /// Tuned on the tuning half of the film test set (docs/quality.md): κ = 4 with the
    /// cascade, where the passes after the first see less noise and so weigh more strictly;
    /// κ = 3 with one pass, where a wider κ smeared the pans' detail.
    fn passes(self) -> (&'static [usize], f32) {
        match self {
            Reach::Shutter => (&[1], 9.0),
            Reach::Lens => (&[1, 2, 4], 16.0),
        }
    }
}

/// Pixels whose pooled noise variance is at most this (a standard deviation of 0.004 in
/// √-colour, about one 8-bit level) are left as they are: filtering them gains nothing
/// visible and costs time.
const FLOOR2: f32 = 1.6e-5;

/// The 3-tap kernel's weights: centre, then either side.
const TAP: [f32; 2] = [0.5, 0.25];

/// Filters `rgb` (3 floats a pixel, row-major, `w` wide) in place, guided by `noise` (each
/// pixel's error estimate: about the standard deviation of its mean in √-colour), as far as
/// `reach` says. Pixels whose coverage (`alpha`) is not 1 are neither filtered nor used.
pub(crate) fn filter(
    rgb: &mut [f32],
    noise: &[f32],
    alpha: Option<&[f32]>,
    w: usize,
    reach: Reach,
) {
    let h = noise.len() / w;
    // Planar channels, so that a row's pixels go through each tap together in the lanes.
    let mut means: [Vec<f32>; 3] =
        std::array::from_fn(|k| rgb.iter().skip(k).step_by(3).copied().collect());
    let mut var = pooled(noise, alpha, w);
    let (steps, kappa2) = reach.passes();
    for &step in steps {
        let guide = means
            .each_ref()
            .map(|m| m.iter().map(|&c| c.max(0.0).sqrt()).collect::<Vec<f32>>());
        let pass = Pass {
            means: &means,
            guide: &guide,
            var: &var,
            alpha,
            w,
            h,
            step,
            kappa2,
        };
        let mut out: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0f32; w * h]);
        let mut out_var = vec![0f32; w * h];
        let [r, g, b] = &mut out;
        (r.par_chunks_mut(w).zip(g.par_chunks_mut(w)))
            .zip(b.par_chunks_mut(w).zip(out_var.par_chunks_mut(w)))
            .enumerate()
            .for_each(|(row, ((r, g), (b, v)))| pass.row(row, [r, g, b], v));
        (means, var) = (out, out_var);
    }
    for (k, m) in means.iter().enumerate() {
        for (dst, &c) in rgb.iter_mut().skip(k).step_by(3).zip(m) {
            *dst = c;
        }
    }
}

/// Each pixel's noise variance: the mean of e² over the whole pixels of its 3×3 block
/// (within the frame), summed in row-major order; one estimate from two halves is rough, and
/// noise varies slowly. 0 for a pixel that is not whole.
fn pooled(noise: &[f32], alpha: Option<&[f32]>, w: usize) -> Vec<f32> {
    let h = noise.len() / w;
    let mut var = vec![0f32; w * h];
    var.par_chunks_mut(w).enumerate().for_each(|(row, out)| {
        let mut n = vec![0f32; w];
        for (_, r) in near(row, h, 1) {
            for (_, b) in SIDES {
                let (cols, q0) = columns(w, 1, b);
                let eq = &noise[r * w + q0..][..cols.len()];
                let aq = alpha.map(|a| &a[r * w + q0..][..cols.len()]);
                let (out, n) = (&mut out[cols.clone()], &mut n[cols]);
                for i in 0..eq.len() {
                    let keep = aq.is_none_or(|a| a[i] == 1.0);
                    out[i] += if keep { eq[i] * eq[i] } else { 0.0 };
                    n[i] += if keep { 1.0 } else { 0.0 };
                }
            }
        }
        let ap = alpha.map(|a| &a[row * w..][..w]);
        for c in 0..w {
            let whole = ap.is_none_or(|a| a[c] == 1.0);
            out[c] = if whole { out[c] / n[c] } else { 0.0 };
        }
    });
    var
}

/// The columns of a block's side `b` (−1 left, 0 centre, 1 right): the columns c whose
/// neighbour c + b·step lies within the frame, and the first such neighbour's column.
fn columns(w: usize, step: usize, b: isize) -> (std::ops::Range<usize>, usize) {
    match b {
        -1 => (step.min(w)..w, 0),
        0 => (0..w, 0),
        _ => (0..w.saturating_sub(step), step.min(w)),
    }
}

/// A block's columns in its order, each with its distance in steps.
const SIDES: [(usize, isize); 3] = [(1, -1), (0, 0), (1, 1)];

/// The pixels `step` apart around `i` (a 3×3 block of them) that lie within a `w`×`h`
/// frame, row-major.
#[cfg(test)]
fn block(i: usize, w: usize, h: usize, step: usize) -> impl Iterator<Item = usize> {
    let (row, col) = (i / w, i % w);
    near(row, h, step).flat_map(move |(_, r)| near(col, w, step).map(move |(_, c)| r * w + c))
}

/// x − step, x and x + step where they lie in 0 … n − 1, each with its distance in steps.
fn near(x: usize, n: usize, step: usize) -> impl Iterator<Item = (usize, usize)> + Clone {
    let lo = x.checked_sub(step).map(|y| (1, y));
    let hi = Some(x + step).filter(|&y| y < n).map(|y| (1, y));
    [lo, Some((0, x)), hi].into_iter().flatten()
}

/// Pixels of a row filtered together: in local arrays of this length the compiler keeps
/// them in vector registers (no f32 operation changes: each lane does the rule's own
/// sequence).
const LANES: usize = 8;

/// What one pass reads.
struct Pass<'a> {
    means: &'a [Vec<f32>; 3],
    guide: &'a [Vec<f32>; 3],
    var: &'a [f32],
    alpha: Option<&'a [f32]>,
    w: usize,
    h: usize,
    step: usize,
    kappa2: f32,
}

impl Pass<'_> {
    /// Row `row` after the pass: its means into `out` and, for the next pass, the noise
    /// variance of each weighted mean (Σ w²·v over (Σ w)², as if the neighbours' errors were
    /// independent) into `out_var`. `LANES` pixels at a time where all their neighbours'
    /// columns lie within the frame, one at a time near the sides.
    fn row(&self, row: usize, out: [&mut [f32]; 3], out_var: &mut [f32]) {
        let (w, s) = (self.w, self.step);
        // Columns s … w − s − 1 have both side neighbours within the frame.
        let (lo, chunks) = (s.min(w), w.saturating_sub(2 * s) / LANES);
        let hi = lo + chunks * LANES;
        let mut to = (out, out_var);
        for c in 0..lo {
            self.pixels::<1>(row, c, &mut to);
        }
        for c in (lo..hi).step_by(LANES) {
            self.pixels::<LANES>(row, c, &mut to);
        }
        for c in hi..w {
            self.pixels::<1>(row, c, &mut to);
        }
    }

    /// The `L` pixels of row `row` from column `c0`, each through the taps of its block in
    /// the block's order (a neighbour outside the frame is not visited; one that is not
    /// whole adds a weight of 0, which changes no sum); a pixel at or under the floor keeps
    /// its mean and variance. With `L` > 1 every neighbour's column is within the frame.
    #[inline(always)]
    fn pixels<const L: usize>(
        &self,
        row: usize,
        c0: usize,
        (out, out_var): &mut ([&mut [f32]; 3], &mut [f32]),
    ) {
        let (w, s) = (self.w, self.step);
        let p = row * w + c0;
        let at = |v: &[f32], i: usize| -> [f32; L] { v[i..][..L].try_into().unwrap() };
        let (vp, gp) = (at(self.var, p), self.guide.each_ref().map(|g| at(g, p)));
        let (mut acc, mut sum, mut var) = ([[0f32; L]; 3], [0f32; L], [0f32; L]);
        for (dr, r) in near(row, self.h, s) {
            for (dc, b) in SIDES {
                let col = c0 as isize + b * s as isize;
                if L == 1 && (col < 0 || col as usize >= w) {
                    continue;
                }
                let q = r * w + col as usize;
                let tap = TAP[dr] * TAP[dc];
                let (vq, gq) = (at(self.var, q), self.guide.each_ref().map(|g| at(g, q)));
                let mut d2 = [0f32; L];
                for k in 0..3 {
                    for l in 0..L {
                        let d = gp[k][l] - gq[k][l];
                        let dd = d * d;
                        d2[l] = if dd > d2[l] { dd } else { d2[l] };
                    }
                }
                let mut weight = [0f32; L];
                for l in 0..L {
                    let a = self.kappa2 * (vp[l] + vq[l]);
                    let r = a / (a + d2[l]);
                    weight[l] = tap * (r * r);
                }
                if let Some(alpha) = self.alpha {
                    let aq = at(alpha, q);
                    for l in 0..L {
                        weight[l] = if aq[l] == 1.0 { weight[l] } else { 0.0 };
                    }
                }
                for (acc, means) in acc.iter_mut().zip(self.means) {
                    let m = at(means, q);
                    for l in 0..L {
                        acc[l] += weight[l] * m[l];
                    }
                }
                for l in 0..L {
                    sum[l] += weight[l];
                    var[l] += weight[l] * weight[l] * vq[l];
                }
            }
        }
        for l in 0..L {
            let (i, c) = (p + l, c0 + l);
            let keep = vp[l] <= FLOOR2;
            for k in 0..3 {
                out[k][c] = if keep {
                    self.means[k][i]
                } else {
                    acc[k][l] / sum[l]
                };
            }
            out_var[c] = if keep {
                vp[l]
            } else {
                var[l] / (sum[l] * sum[l])
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A w×h frame of one grey with a hash's noise of amplitude `amp` around it.
    fn noisy(w: usize, h: usize, grey: f32, amp: f32) -> Vec<f32> {
        (0..3 * w * h)
            .map(|i| {
                let x = (i as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 40;
                grey + amp * (x as f32 / (1u64 << 24) as f32 - 0.5)
            })
            .collect()
    }

    fn spread(rgb: &[f32]) -> f32 {
        let mean = rgb.iter().sum::<f32>() / rgb.len() as f32;
        (rgb.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / rgb.len() as f32).sqrt()
    }

    const BOTH: [Reach; 2] = [Reach::Shutter, Reach::Lens];

    #[test]
    fn grain_in_a_flat_patch_is_averaged_away() {
        let (w, h) = (16, 12);
        let before = spread(&noisy(w, h, 0.25, 0.04));
        // The noise's standard deviation in √-colour: 0.04/√12 linear at 0.25 is ≈ 0.023.
        let after = BOTH.map(|reach| {
            let mut rgb = noisy(w, h, 0.25, 0.04);
            filter(&mut rgb, &vec![0.023; w * h], None, w, reach);
            spread(&rgb)
        });
        assert!(after[0] < 0.6 * before, "{before} -> {after:?}");
        // The lens's cascade reaches further, so it leaves less grain than one pass.
        assert!(after[1] < 0.6 * after[0], "{before} -> {after:?}");
    }

    #[test]
    fn converged_pixels_keep_their_bits() {
        let (w, h) = (9, 7);
        let rgb = noisy(w, h, 0.5, 0.3);
        for reach in BOTH {
            let mut out = rgb.clone();
            // Noise below the floor (a standard deviation of 0.004) changes nothing.
            filter(&mut out, &vec![0.0039; w * h], None, w, reach);
            assert!(
                rgb.iter()
                    .zip(&out)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
            );
        }
    }

    #[test]
    fn an_edge_far_above_the_noise_stays() {
        let (w, h) = (20, 12);
        let before: Vec<f32> = (0..w * h)
            .flat_map(|i| [if i % w < 10 { 0.1 } else { 0.8 }; 3])
            .collect();
        for reach in BOTH {
            let mut rgb = before.clone();
            filter(&mut rgb, &vec![0.01; w * h], None, w, reach);
            for (a, b) in rgb.iter().zip(&before) {
                assert!((a - b).abs() < 1e-3, "{reach:?}: {b} -> {a}");
            }
        }
    }

    #[test]
    fn partly_covered_pixels_are_neither_changed_nor_used() {
        let (w, h) = (12, 10);
        for reach in BOTH {
            let mut rgb = noisy(w, h, 0.3, 0.1);
            let mut alpha = vec![1.0; w * h];
            alpha[4 * w + 5] = 0.5;
            rgb[3 * (4 * w + 5)] = 1000.0;
            let before = rgb.clone();
            filter(&mut rgb, &vec![0.05; w * h], Some(&alpha), w, reach);
            assert_eq!(rgb[3 * (4 * w + 5)], 1000.0);
            // Its neighbours would be far above 0.3 had they used it.
            assert!(
                rgb.iter()
                    .zip(&before)
                    .all(|(a, b)| (a - b).abs() < 0.1 || *b == 1000.0)
            );
            assert!(rgb != before);
        }
    }

    #[test]
    fn the_steps_reach_within_the_frame_only() {
        // A 3×3 block at step 4 near a corner: the pixel itself and those 4 away inside.
        let got: Vec<usize> = block(10 * 3 + 2, 10, 8, 4).collect();
        assert_eq!(got, vec![32, 36, 72, 76]);
        let got: Vec<usize> = block(0, 10, 8, 1).collect();
        assert_eq!(got, vec![0, 1, 10, 11]);
    }

    /// The rule as docs/spec/tracer.md states it, pixel by pixel: the oracle of `filter`'s
    /// rows.
    fn by_the_rule(rgb: &mut [f32], noise: &[f32], alpha: Option<&[f32]>, w: usize, reach: Reach) {
        let h = noise.len() / w;
        let whole = |i: usize| alpha.is_none_or(|a| a[i] == 1.0);
        let mut var: Vec<f32> = (0..w * h)
            .map(|i| {
                let (mut s, mut n) = (0f32, 0f32);
                for q in block(i, w, h, 1).filter(|&q| whole(q)) {
                    s += noise[q] * noise[q];
                    n += 1.0;
                }
                if whole(i) { s / n } else { 0.0 }
            })
            .collect();
        let (steps, k2) = reach.passes();
        for &step in steps {
            let g: Vec<f32> = rgb.iter().map(|&c| c.max(0.0).sqrt()).collect();
            let (mut next, mut next_var) = (rgb.to_vec(), var.clone());
            for p in (0..w * h).filter(|&p| var[p] > FLOOR2) {
                let (mut a, mut sum, mut v) = ([0f32; 3], 0f32, 0f32);
                for q in block(p, w, h, step).filter(|&q| whole(q)) {
                    let mut d = 0f32;
                    for k in 0..3 {
                        let x = g[3 * p + k] - g[3 * q + k];
                        d = if x * x > d { x * x } else { d };
                    }
                    let big = k2 * (var[p] + var[q]);
                    let r = big / (big + d);
                    let t =
                        TAP[(q / w).abs_diff(p / w) / step] * TAP[(q % w).abs_diff(p % w) / step];
                    let weight = t * (r * r);
                    for k in 0..3 {
                        a[k] += weight * rgb[3 * q + k];
                    }
                    sum += weight;
                    v += weight * weight * var[q];
                }
                for k in 0..3 {
                    next[3 * p + k] = a[k] / sum;
                }
                next_var[p] = v / (sum * sum);
            }
            rgb.copy_from_slice(&next);
            var = next_var;
        }
    }

    #[test]
    fn the_rows_give_the_rule_pixel_by_pixel() {
        let (w, h) = (23, 17);
        for reach in BOTH {
            for with_alpha in [false, true] {
                let rgb = noisy(w, h, 0.3, 0.5);
                let noise: Vec<f32> = (0..w * h).map(|i| (i * 7 % 11) as f32 * 0.006).collect();
                let alpha: Vec<f32> = (0..w * h)
                    .map(|i| if i % 13 == 5 { 0.5 } else { 1.0 })
                    .collect();
                let alpha = with_alpha.then_some(&alpha[..]);
                let (mut fast, mut slow) = (rgb.clone(), rgb.clone());
                filter(&mut fast, &noise, alpha, w, reach);
                by_the_rule(&mut slow, &noise, alpha, w, reach);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&slow), "{reach:?}, alpha {with_alpha}");
                assert!(fast != rgb);
            }
        }
    }

    #[test]
    fn the_bytes_do_not_depend_on_the_threads() {
        let (w, h) = (37, 23);
        let rgb = noisy(w, h, 0.4, 0.2);
        let noise: Vec<f32> = (0..w * h).map(|i| (i % 7) as f32 * 0.01).collect();
        for reach in BOTH {
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut out = rgb.clone();
                pool.install(|| filter(&mut out, &noise, None, w, reach));
                out.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(run(1), run(3));
        }
    }
}
