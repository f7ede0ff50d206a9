//! The film filter: a 3×3 bilateral filter guided by each pixel's own error estimate, for
//! film frames (motion blur, depth of field), whose grain is the sampling error the rounds
//! stopped short of. A pixel whose samples agree is left as it is; a noisy one becomes a
//! weighted mean of its neighbours, each weighted down as its colour departs from the
//! pixel's by more than their noise allows, so grain in a blur is averaged away while an
//! edge that stands out from the noise stays. It is a pure function of the frame's colour,
//! coverage and error estimates: every operation is one IEEE-754 f32 operation in a fixed
//! order (no fused multiply-add, no libm), so the bytes are the same on every machine, lane
//! width and thread count. docs/spec/tracer.md (**Film filter**) states each one.
//!
//! ```yaml
//! render:
//!   denoise: true   # the default on film; false keeps the rounds' means as they are
//! ```

use rayon::prelude::*;

/// κ²: a neighbour whose √-colour differs from the pixel's by κ standard deviations of their
/// difference keeps a quarter of its weight (κ = 3).
const KAPPA2: f32 = 9.0;

/// Pixels whose pooled noise variance is at most this (a standard deviation of 0.004 in
/// √-colour, about one 8-bit level) are left as they are: filtering them gains nothing
/// visible and costs time.
const FLOOR2: f32 = 1.6e-5;

/// The 3-tap kernel's weights: centre, then either side.
const TAP: [f32; 2] = [0.5, 0.25];

/// Filters `rgb` (3 floats a pixel, row-major, `w` wide) in place, guided by `noise` (each
/// pixel's error estimate: about the standard deviation of its mean in √-colour). Pixels
/// whose coverage (`alpha`) is not 1 are neither filtered nor used.
pub(crate) fn filter(rgb: &mut [f32], noise: &[f32], alpha: Option<&[f32]>, w: usize) {
    let h = noise.len() / w;
    let whole = Whole(alpha);
    let var: Vec<f32> = (0..w * h)
        .into_par_iter()
        .map(|i| pooled(noise, (w, h), whole, i))
        .collect();
    let guide: Vec<f32> = rgb.iter().map(|&c| c.max(0.0).sqrt()).collect();
    let plane = Plane {
        rgb,
        guide: &guide,
        var: &var,
        whole,
        w,
        h,
    };
    let out: Vec<[f32; 3]> = (0..w * h).into_par_iter().map(|i| plane.pixel(i)).collect();
    for (c, o) in rgb.chunks_exact_mut(3).zip(out) {
        c.copy_from_slice(&o);
    }
}

/// The noise variance of pixel `i`: the mean of e² over the whole pixels of its 3×3 block
/// (within the frame), summed in row-major order; one estimate from two halves is rough, and
/// noise varies slowly. 0 for a pixel that is not whole.
fn pooled(noise: &[f32], (w, h): (usize, usize), whole: Whole, i: usize) -> f32 {
    if !whole.at(i) {
        return 0.0;
    }
    let (mut sum, mut n) = (0f32, 0f32);
    for q in block(i, w, h).filter(|&q| whole.at(q)) {
        sum += noise[q] * noise[q];
        n += 1.0;
    }
    sum / n
}

/// The pixels of the 3×3 block around `i` that lie within a `w`×`h` frame, row-major.
fn block(i: usize, w: usize, h: usize) -> impl Iterator<Item = usize> {
    let (row, col) = (i / w, i % w);
    let cols = col.saturating_sub(1)..(col + 2).min(w);
    (row.saturating_sub(1)..(row + 2).min(h))
        .flat_map(move |r| cols.clone().map(move |c| r * w + c))
}

/// Which pixels are whole (no coverage recorded, or coverage 1): the only ones filtered.
#[derive(Clone, Copy)]
struct Whole<'a>(Option<&'a [f32]>);

impl Whole<'_> {
    fn at(self, i: usize) -> bool {
        self.0.is_none_or(|a| a[i] == 1.0)
    }
}

/// The planes the filter reads.
struct Plane<'a> {
    rgb: &'a [f32],
    guide: &'a [f32],
    var: &'a [f32],
    whole: Whole<'a>,
    w: usize,
    h: usize,
}

impl Plane<'_> {
    fn colour(&self, i: usize) -> [f32; 3] {
        [self.rgb[3 * i], self.rgb[3 * i + 1], self.rgb[3 * i + 2]]
    }

    /// Pixel `i` after the filter.
    fn pixel(&self, i: usize) -> [f32; 3] {
        let vp = self.var[i];
        if vp <= FLOOR2 {
            return self.colour(i);
        }
        let (row, col) = (i / self.w, i % self.w);
        let (mut acc, mut sum) = ([0f32; 3], 0f32);
        for q in block(i, self.w, self.h).filter(|&q| self.whole.at(q)) {
            let tap = TAP[(q / self.w).abs_diff(row)] * TAP[(q % self.w).abs_diff(col)];
            let weight = tap * self.closeness(i, q, vp);
            let c = self.colour(q);
            for k in 0..3 {
                acc[k] += weight * c[k];
            }
            sum += weight;
        }
        acc.map(|a| a / sum)
    }

    /// 1/(1 + d²/a)², as (a/(a + d²))² with one division: d² the largest squared difference
    /// of the √-colours of `p` and `q` over the channels, a = κ²(v_p + v_q), the variance of
    /// their difference scaled by κ². 1 for equal colours, ¼ at κ deviations.
    fn closeness(&self, p: usize, q: usize, vp: f32) -> f32 {
        let mut d2 = 0f32;
        for k in 0..3 {
            let d = self.guide[3 * p + k] - self.guide[3 * q + k];
            let dd = d * d;
            d2 = if dd > d2 { dd } else { d2 };
        }
        let a = KAPPA2 * (vp + self.var[q]);
        let r = a / (a + d2);
        r * r
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

    #[test]
    fn grain_in_a_flat_patch_is_averaged_away() {
        let (w, h) = (16, 12);
        let mut rgb = noisy(w, h, 0.25, 0.04);
        let before = spread(&rgb);
        // The noise's standard deviation in √-colour: 0.04/√12 linear at 0.25 is ≈ 0.023.
        filter(&mut rgb, &vec![0.023; w * h], None, w);
        assert!(
            spread(&rgb) < 0.6 * before,
            "{} -> {}",
            before,
            spread(&rgb)
        );
    }

    #[test]
    fn converged_pixels_keep_their_bits() {
        let (w, h) = (9, 7);
        let rgb = noisy(w, h, 0.5, 0.3);
        let mut out = rgb.clone();
        // Noise below the floor (a standard deviation of 0.004) changes nothing.
        filter(&mut out, &vec![0.0039; w * h], None, w);
        assert!(
            rgb.iter()
                .zip(&out)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }

    #[test]
    fn an_edge_far_above_the_noise_stays() {
        let (w, h) = (10, 6);
        let mut rgb: Vec<f32> = (0..w * h)
            .flat_map(|i| [if i % w < 5 { 0.1 } else { 0.8 }; 3])
            .collect();
        let before = rgb.clone();
        filter(&mut rgb, &vec![0.01; w * h], None, w);
        for (a, b) in rgb.iter().zip(&before) {
            assert!((a - b).abs() < 1e-3, "{b} -> {a}");
        }
    }

    #[test]
    fn partly_covered_pixels_are_neither_changed_nor_used() {
        let (w, h) = (6, 5);
        let mut rgb = noisy(w, h, 0.3, 0.1);
        let mut alpha = vec![1.0; w * h];
        alpha[2 * w + 3] = 0.5;
        rgb[3 * (2 * w + 3)] = 1000.0;
        let before = rgb.clone();
        filter(&mut rgb, &vec![0.05; w * h], Some(&alpha), w);
        assert_eq!(rgb[3 * (2 * w + 3)], 1000.0);
        // Its neighbours would be far above 0.3 had they used it.
        assert!(
            rgb.iter()
                .zip(&before)
                .all(|(a, b)| (a - b).abs() < 0.1 || *b == 1000.0)
        );
        assert!(rgb != before);
    }

    #[test]
    fn the_bytes_do_not_depend_on_the_threads() {
        let (w, h) = (37, 23);
        let rgb = noisy(w, h, 0.4, 0.2);
        let noise: Vec<f32> = (0..w * h).map(|i| (i % 7) as f32 * 0.01).collect();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut out = rgb.clone();
            pool.install(|| filter(&mut out, &noise, None, w));
            out.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        assert_eq!(run(1), run(3));
    }
}
