//! A frame's pixels traced in packets, for any lane type. A pass takes its pixels N at a time
//! (a near-square tile of a band of rows, or the marked pixels of the whole frame in raster order, so
//! their rays are coherent and packets stay full), and each packet traces sample k of all its
//! pixels together, for k in order. Every pixel therefore sums exactly the samples it summed
//! one ray at a time, in the same order, and its value cannot depend on the width.

use super::accel::{FromOrigin, Rays};
use super::area::Discs;
use super::intersect::Ray;
use super::path::{self, Eye, LightSeeds};
use super::sample::{self, Dims, Pattern, Seed};
use super::sobol;
use super::texture::PixelRays;
use super::{Sampler, Samples, Settings, World, finite};
use super::{adaptive, lens};
use crate::camera::{Camera, screen_points};
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::shutter::{Exposure, INSTANTS};
use glam::DVec3;
use std::ops::{Add, Div, Mul};
use std::sync::atomic::{AtomicBool, Ordering};

/// Everything one pass over a frame needs, shared by its packets.
pub(super) struct Pass<'a> {
    pub world: &'a World,
    /// The camera at the frame's time: every eye ray's, unless `exposure` is set.
    pub camera: &'a Camera,
    /// Set when eye rays leave from more than one point (a lens, or a camera moving while
    /// the shutter is open): each sample then takes its own instant and lens point.
    pub exposure: Option<&'a Exposure>,
    pub settings: &'a Settings,
    pub frame: u64,
    pub samples: Samples,
    /// Adaptive sampling in rounds (`adaptive`): what a pass records of each pixel is its
    /// error estimate (how far two halves of its samples disagree), not their spread.
    pub rounds: bool,
    /// `Geometry::from_origin` of the camera position.
    pub from_origin: &'a [FromOrigin],
    /// The world at each instant of the open shutter when objects or lights move while it
    /// is open (each sample is traced in its instant's); otherwise empty.
    pub instants: &'a [World],
    /// Set when the frame is no longer wanted: packets and samples not yet begun are skipped.
    pub stop: &'a AtomicBool,
    /// The pass records which pixels are smooth on one object (`World::tracks_smooth`).
    pub smooth: bool,
}

impl Pass<'_> {
    pub(super) fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// A frame's colour, 3 floats per pixel, and its coverage when the settings ask for alpha.
pub(super) struct Planes<'a> {
    pub rgb: &'a mut [f32],
    pub alpha: Option<&'a mut [f32]>,
}

/// A frame's colour and coverage as they are before a pass extends some pixels.
pub(super) type Old<'a> = (&'a [f32], Option<&'a [f32]>);

/// One band's slice of the frame: 3 floats per pixel, each pixel's sample spread (the
/// largest channel range) when the pass records it, and its coverage with alpha.
pub(super) struct RowOut<'a> {
    pub rgb: &'a mut [f32],
    pub spread: Option<&'a mut [f32]>,
    pub alpha: Option<&'a mut [f32]>,
    /// When the pass records it, the object each pixel is smooth on, or `NOT_SMOOTH`.
    pub smooth: Option<&'a mut [u32]>,
}

/// A pixel smooth on no object.
pub(super) const NOT_SMOOTH: u32 = u32::MAX;

#[derive(Debug, Default, Clone, Copy)]
pub(super) struct RowStats {
    pub samples: u64,
    pub rays: u64,
    pub non_finite: u64,
}

impl std::ops::Add for RowStats {
    type Output = RowStats;
    fn add(self, o: RowStats) -> RowStats {
        RowStats {
            samples: self.samples + o.samples,
            rays: self.rays + o.rays,
            non_finite: self.non_finite + o.non_finite,
        }
    }
}

/// Up to `MAX_LANES` pixels traced together. Lane k holds a pixel when bit k of `valid` is set; other
/// lanes repeat the first pixel (a valid ray, masked out of every result).
#[derive(Clone, Copy)]
struct Pixels {
    rows: [u32; MAX_LANES],
    cols: [u32; MAX_LANES],
    valid: u32,
}

impl Pixels {
    /// The pixels `at(k)` gives for lanes 0..n, where it gives one.
    #[inline(always)]
    fn new(n: usize, at: impl Fn(usize) -> Option<(u32, u32)>) -> Pixels {
        let (mut rows, mut cols, mut valid) = ([0; MAX_LANES], [0; MAX_LANES], 0u32);
        for k in 0..n {
            if let Some((r, c)) = at(k) {
                (rows[k], cols[k]) = (r, c);
                valid |= 1 << k;
            }
        }
        let lead = valid.trailing_zeros() as usize;
        for k in (0..n).filter(|k| valid >> k & 1 == 0) {
            (rows[k], cols[k]) = (rows[lead], cols[lead]);
        }
        Pixels { rows, cols, valid }
    }

    /// The pixels of the tile of a band (`rows` rows from `top`, `w` columns) whose left
    /// column is `left`: lane k is the tile's pixel (k / tile width, k % tile width), valid
    /// inside the band and the frame. A tile wholly inside needs no test a lane.
    #[inline(always)]
    fn tile<V: Lanes>(top: u32, left: u32, rows: u32, w: u32) -> Pixels {
        let tile_w = (V::N / tile_rows(V::N)) as u32;
        if rows < tile_rows(V::N) as u32 || left + tile_w > w {
            return Pixels::new(V::N, |k| {
                let (r, c) = (k as u32 / tile_w, left + k as u32 % tile_w);
                (r < rows && c < w).then_some((top + r, c))
            });
        }
        let (mut rows, mut cols) = ([0; MAX_LANES], [0; MAX_LANES]);
        for k in 0..V::N {
            (rows[k], cols[k]) = (top + k as u32 / tile_w, left + k as u32 % tile_w);
        }
        let valid = u32::MAX >> (MAX_LANES - V::N);
        Pixels { rows, cols, valid }
    }

    /// The lanes holding a pixel, in order: one step per set bit of `valid`.
    fn lanes(&self) -> impl Iterator<Item = usize> + use<> {
        let mut rest = self.valid;
        std::iter::from_fn(move || {
            let k = rest.trailing_zeros() as usize;
            rest &= rest.wrapping_sub(1);
            (k < 32).then_some(k)
        })
    }
}

/// Rows of a tile of `n` lanes: packets are near-square tiles (4×8 for 32 lanes, 4×4 for 16,
/// 2×4 for 8),
/// whose rays stay closer together than a strip's, so they visit fewer hierarchy nodes and
/// more often hit one object.
pub(super) const fn tile_rows(n: usize) -> usize {
    match n {
        32 | 16 => 4,
        8 | 4 => 2,
        _ => 1,
    }
}

/// What a packet found for its pixels: the f32 means (already made finite) a channel at a
/// time, as the lanes store them, spreads and coverage (0 without alpha).
#[derive(Default)]
struct Means {
    rgb: [[f32; MAX_LANES]; 3],
    spread: [f32; MAX_LANES],
    alpha: [f32; MAX_LANES],
    /// Written only by passes that record smooth pixels.
    smooth: [u32; MAX_LANES],
}

/// A pass that traces every pixel of a band of `tile_rows(V::N)` rows starting at `top` (the
/// last band may be shorter), a tile per packet.
#[inline(always)]
pub(super) fn band<V: Lanes>(pass: &Pass, top: u32, out: RowOut) -> RowStats {
    if pass.smooth {
        // Its own copy, out of line: the smooth-pixel bookkeeping in the one band loop cost
        // the talk's stream 1–5% in instructions.
        return V::outlined(
            #[inline(always)]
            || band_of::<V, true>(pass, top, out),
        );
    }
    band_of::<V, false>(pass, top, out)
}

/// `band`; with `SMOOTH`, also recording which pixels are smooth on one object.
#[inline(always)]
fn band_of<V: Lanes, const SMOOTH: bool>(pass: &Pass, top: u32, out: RowOut) -> RowStats {
    let w = pass.settings.width;
    let RowOut {
        rgb,
        mut spread,
        mut alpha,
        mut smooth,
    } = out;
    let rows = (rgb.len() / (3 * w as usize)) as u32;
    let tile_w = (V::N / tile_rows(V::N)) as u32;
    let mut stats = RowStats::default();
    let mut means = Means::default();
    for left in (0..w).step_by(tile_w as usize) {
        if pass.stopped() {
            break;
        }
        let pixels = Pixels::tile::<V>(top, left, rows, w);
        let ranges = spread.is_some();
        packet::<V, SMOOTH>(pass, &pixels, None, ranges, &mut stats, &mut means);
        // Lane k is the tile's pixel (k / tile_w, k % tile_w); those inside the band and
        // the frame are its valid lanes, stored a tile row at a time.
        let cols = tile_w.min(w - left) as usize;
        for r in 0..tile_rows(V::N).min(rows as usize) {
            let (start, lane) = (r * w as usize + left as usize, r * tile_w as usize);
            let dst = &mut rgb[3 * start..][..3 * cols];
            if cols == tile_w as usize {
                // A whole tile row: a trip count the compiler knows, which it unrolls into
                // vector shuffles (8.5 instructions a pixel as a loop of unknown length).
                interleave(dst, &means.rgb, lane, tile_w as usize);
            } else {
                interleave(dst, &means.rgb, lane, cols);
            }
            if let Some(spread) = spread.as_deref_mut() {
                spread[start..][..cols].copy_from_slice(&means.spread[lane..][..cols]);
            }
            if let Some(alpha) = alpha.as_deref_mut() {
                alpha[start..][..cols].copy_from_slice(&means.alpha[lane..][..cols]);
            }
            if SMOOTH && let Some(smooth) = smooth.as_deref_mut() {
                smooth[start..][..cols].copy_from_slice(&means.smooth[lane..][..cols]);
            }
        }
    }
    stats
}

/// `cols` pixels of the planar channels from lane `lane` on, interleaved (r, g, b a pixel)
/// into `dst`.
#[inline(always)]
fn interleave(dst: &mut [f32], rgb: &[[f32; MAX_LANES]; 3], lane: usize, cols: usize) {
    let [red, green, blue] = rgb.each_ref().map(|c| &c[lane..][..cols]);
    for (dst, ((&r, &g), &b)) in dst[..3 * cols]
        .chunks_exact_mut(3)
        .zip(red.iter().zip(green).zip(blue))
    {
        dst.copy_from_slice(&[r, g, b]);
    }
}

/// A pass that adds samples to the pixels `marked` (row-major indices) of a frame whose
/// current means are `rgb` (and coverage `alpha`); writes their new means, coverage fourth
/// and (in rounds) its error estimate fifth, to `out`, one per marked pixel.
#[inline(always)]
pub(super) fn marked<V: Lanes>(
    pass: &Pass,
    marked: &[u32],
    (rgb, alpha): Old,
    out: &mut [[f32; 5]],
) -> RowStats {
    let w = pass.settings.width;
    let mut stats = RowStats::default();
    let mut means = Means::default();
    for (pixels, out) in marked.chunks(V::N).zip(out.chunks_mut(V::N)) {
        if pass.stopped() {
            break;
        }
        let packet_pixels = Pixels::new(V::N, |k| pixels.get(k).map(|&p| (p / w, p % w)));
        let old = per_lane(V::N, [0.0; 4], |k| {
            let p = pixels[k.min(pixels.len() - 1)] as usize;
            let a = alpha.map_or(0.0, |a| a[p]);
            [rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2], a]
        });
        packet::<V, false>(
            pass,
            &packet_pixels,
            Some(&old),
            pass.rounds,
            &mut stats,
            &mut means,
        );
        for (k, o) in out.iter_mut().enumerate() {
            let c = &means.rgb;
            *o = [c[0][k], c[1][k], c[2][k], means.alpha[k], means.spread[k]];
        }
    }
    stats
}

/// Traces every sample of up to N pixels and sets `means` to their means, folding in the means
/// `old` they had (with the samples before this pass) when a pass extends them. Lane k's sum,
/// range and mean are the scalar ones of its pixel: glam's `DVec3::min`/`max` and
/// `max_element` compare exactly as the lanes' `min`/`max` do.
/// With `SMOOTH`, also records which pixels are smooth on one object (`Pass::smooth`).
#[inline(always)]
fn packet<V: Lanes, const SMOOTH: bool>(
    pass: &Pass,
    px: &Pixels,
    old: Option<&[[f32; 4]; MAX_LANES]>,
    spread: bool,
    stats: &mut RowStats,
    means: &mut Means,
) {
    let s = pass.settings;
    let pattern = match (pass.samples, s.sampler) {
        // The talk's image: one ray through the pixel centre, whatever the sampler.
        (Samples::All(1), _) => Pattern::Centre,
        // Blur and focus: the pixel, the lens and the shutter sampled together.
        (_, Sampler::Stratified) if pass.exposure.is_some() => Pattern::Sobol,
        (Samples::More { .. }, _) => Pattern::R2,
        (Samples::All(n), Sampler::Stratified) => Pattern::stratified(n),
        (Samples::All(_), Sampler::Random) => Pattern::Independent,
    };
    let pixel = |k: usize| u64::from(px.rows[k]) * u64::from(s.width) + u64::from(px.cols[k]);
    let centre = Seed::new(Pattern::Centre, 0, 0);
    let seeds = match pattern {
        // The centre needs no seed, Sobol' points their own.
        Pattern::Centre | Pattern::Sobol => None,
        _ => Some(per_lane(V::N, centre, |k| {
            Seed::new(pattern, pass.frame, pixel(k))
        })),
    };
    let lead = px.valid.trailing_zeros() as usize;
    let sobol = (pattern == Pattern::Sobol).then(|| {
        sobol::Packet::<MAX_LANES>::new(V::N, |k| {
            let k = if px.valid >> k & 1 == 1 { k } else { lead };
            sample::state(pass.frame, pixel(k))
        })
    });
    let (first, end) = match pass.samples {
        Samples::All(n) => (0, n),
        Samples::More { have, total } => (have, total),
    };
    let range = spread && end - first > 1;
    let halves = spread && pass.rounds;
    // In rounds, a first pass also sums its two halves apart (see `adaptive`).
    let half = match pass.samples {
        Samples::All(n) if halves => first + n / 2,
        _ => first,
    };
    let (mut early, mut late) = (V3::<V>::zero(), V3::<V>::zero());
    // The lanes all of whose samples so far are smooth on the first sample's object.
    let (mut smooth, mut on) = (V::M::from_bits(px.valid), V::splat(-1.0));
    let (row, col) = (V::from_u32(&px.rows), V::from_u32(&px.cols));
    let mut sum = V3::<V>::zero();
    let (mut cover, one, zero) = (V::splat(0.0), V::splat(1.0), V::splat(0.0));
    let (mut lo, mut hi) = (
        V3::<V>::splat(DVec3::INFINITY),
        V3::<V>::splat(DVec3::NEG_INFINITY),
    );
    // Each sample's cone spans the pixel's width divided by √samples (docs/spec/texture.md).
    let footprint = pass.world.textured.then(|| match pass.world.point_sampled {
        true => 0.0,
        false => 2.0 * pass.camera.tan_half_fov / f64::from(s.width) / f64::from(s.samples).sqrt(),
    });
    // A checker's eye hits read their pixel's average: a pinhole's pixels are the same for
    // every sample, a lens's and a moving camera's are made with each sample's rays.
    // Lent, never moved: moved into every sample's `Eye` they cost the talk, which has none,
    // a 600-byte copy a sample; boxed, an allocation a packet (5% of a checker frame).
    let checkered = pass.world.checkered();
    let pinhole_store;
    let pinhole_pixels = match checkered && pass.exposure.is_none() {
        true => {
            pinhole_store = pixel_rays(
                (s.width, s.height),
                (row, col),
                &[pass.camera; MAX_LANES],
                None,
            );
            Some(&pinhole_store)
        }
        false => None,
    };
    let mut film_store;
    let mut film_pixels = match checkered && pass.exposure.is_some() {
        true => {
            film_store = PixelRays::<V>::zero();
            Some(&mut film_store)
        }
        false => None,
    };
    // Area lights only: each pixel's light state, for the points its samples take on them,
    // and the points' coordinates a sample's paths share (the talk's packets make neither).
    let area = pass.world.area_lights.then(|| {
        let seeds = per_lane(V::N, 0, |k| sample::light_seed(pass.frame, pixel(k)));
        (seeds, Discs::default())
    });
    let dims = match (pass.exposure, pattern) {
        (Some(_), Pattern::Sobol) | (None, _) => None,
        (Some(_), _) => Some(per_lane(V::N, Dims::new(pattern, 0, 0), |k| {
            Dims::new(pattern, pass.frame, pixel(k))
        })),
    };
    // Per lane, with the shutter open: u, v, then the lens's a, b, then the time (a pinhole
    // frame neither needs nor zeroes them).
    let mut film = pass.exposure.map(|_| [[0.0; MAX_LANES]; 5]);
    for k in (first..end).take_while(|_| !pass.stopped()) {
        let (u, v) = match (&sobol, &seeds, &mut film) {
            (Some(sobol), _, Some(x)) => {
                sobol.at(k, V::N, x);
                (V::load(&x[0]), V::load(&x[1]))
            }
            (None, Some(seeds), _) => offsets::<V>(pattern, seeds, k),
            // The centre (Sobol' points come only with the shutter open).
            _ => (V::splat(0.5), V::splat(0.5)),
        };
        if let (Some(dims), Some(x)) = (&dims, &mut film) {
            for lane in 0..V::N {
                [x[4][lane], x[2][lane], x[3][lane]] = dims[lane].at(pattern, k);
            }
        }
        let lights = area.as_ref().map(|(seeds, discs)| {
            discs.clear();
            LightSeeds { seeds, k, discs }
        });
        // While things move under the open shutter, each lane's instant (else None).
        let mut js = None;
        let eye = match (pass.exposure, &film) {
            (Some(exposure), Some(x)) => {
                if !pass.instants.is_empty() {
                    js = Some(std::array::from_fn(|k| instant(x[4][k]) as u8));
                }
                let rays = sampled_rays(
                    pass,
                    exposure,
                    (row, col),
                    (u, v),
                    &x[4],
                    (V::load(&x[2]), V::load(&x[3])),
                    film_pixels.as_deref_mut(),
                );
                Eye {
                    rays,
                    active: V::M::from_bits(px.valid),
                    from_origin: None,
                    transparent: s.alpha,
                    footprint,
                    pixel: film_pixels.as_deref(),
                    lights,
                }
            }
            _ => Eye {
                rays: Rays {
                    origin: V3::splat(pass.camera.origin),
                    dir: eye_directions(pass, row, col, u, v),
                    leaving: V::splat(-1.0),
                },
                active: V::M::from_bits(px.valid),
                from_origin: Some(pass.from_origin),
                transparent: s.alpha,
                footprint,
                pixel: pinhole_pixels,
                lights,
            },
        };
        let (c, covered) = match &js {
            None if SMOOTH => {
                let t = path::trace_smooth(pass.world, &eye, s.max_depth, &mut stats.rays);
                if k == first {
                    on = t.object;
                }
                smooth = smooth.and(t.smooth).and(t.object.eq(on));
                (t.color, t.covered)
            }
            None => path::trace_packet(pass.world, &eye, s.max_depth, &mut stats.rays),
            Some(js) => {
                let rays = &mut stats.rays;
                V::outlined(
                    #[inline(always)]
                    || in_instants(pass, &eye, js, rays),
                )
            }
        };
        sum = sum + c;
        if s.alpha {
            cover = cover + V::select(covered, one, zero);
        }
        if halves && k < half {
            early = early + c;
        } else if halves {
            late = late + c;
        } else if range {
            lo = V3 {
                x: lo.x.min(c.x),
                y: lo.y.min(c.y),
                z: lo.z.min(c.z),
            };
            hi = V3 {
                x: hi.x.max(c.x),
                y: hi.y.max(c.y),
                z: hi.z.max(c.z),
            };
        }
    }
    // Set in place, and not zeroed: returned, the 640 bytes cost every packet a memcpy (2% of
    // the talk), and zeroed a memset (1%). The fields a pass reads but no packet writes (the
    // spread and the coverage, by `range`, `halves` and `s.alpha`, which hold for the whole
    // pass) keep the zeros of the caller's `Means::default()`; the others are written over
    // on every lane a caller reads.
    if range && !halves {
        let d = hi - lo;
        d.x.max(d.y).max(d.z).store_f32(&mut means.spread);
    }
    let (old_rgb, old_alpha) = match old {
        Some(o) => (
            Some(V3::from_fn(|k| {
                DVec3::from_array([0, 1, 2].map(|c| f64::from(o[k][c])))
            })),
            Some(V::from_fn(|k| f64::from(o[k][3]))),
        ),
        None => (None, None),
    };
    if halves {
        let (a, b) = match old_rgb {
            Some(old) => (old, late / V::splat(f64::from(end - first))),
            None => (
                early / V::splat(f64::from(half - first)),
                late / V::splat(f64::from(end - half)),
            ),
        };
        adaptive::disagreement(a, b, zero, one).store_f32(&mut means.spread);
    }
    let mean = mean_of::<V, _>(pass.samples, sum, old_rgb);
    finish(mean, px, &mut means.rgb, stats);
    if s.alpha {
        mean_of::<V, V>(pass.samples, cover, old_alpha).store_f32(&mut means.alpha);
        if range {
            edge_spread(means, end - first);
        }
    }
    if SMOOTH {
        let (bits, on) = (smooth.bits(), on.array());
        for (k, m) in means.smooth.iter_mut().enumerate().take(V::N) {
            *m = match bits >> k & 1 {
                1 => on[k] as u32,
                _ => NOT_SMOOTH,
            };
        }
    }
    stats.samples += u64::from(end - first) * u64::from(px.valid.count_ones());
}

/// `f(k)` for lanes 0..n, `fill` beyond.
#[inline(always)]
fn per_lane<T: Copy>(n: usize, fill: T, mut f: impl FnMut(usize) -> T) -> [T; MAX_LANES] {
    let mut out = [fill; MAX_LANES];
    for (k, x) in out.iter_mut().enumerate().take(n) {
        *x = f(k);
    }
    out
}

/// The mean of a pixel's samples: `sum` over this pass's samples, and when the pass extends
/// a pixel, the f32 mean `old` it had; for colours and coverage alike.
#[inline(always)]
fn mean_of<V: Lanes, T>(samples: Samples, sum: T, old: Option<T>) -> T
where
    T: Add<Output = T> + Mul<V, Output = T> + Div<V, Output = T>,
{
    match (samples, old) {
        // x / 1 = x exactly: one sample needs no division.
        (Samples::All(1), _) => sum,
        // Each pixel folds in the f32 mean it already had.
        (Samples::More { have, total }, Some(old)) => {
            (old * V::splat(f64::from(have)) + sum) / V::splat(f64::from(total))
        }
        (Samples::All(n), _) | (Samples::More { total: n, .. }, None) => {
            sum / V::splat(f64::from(n))
        }
    }
}

/// A pixel whose eye rays partly hit and partly missed is an edge of the coverage: its spread
/// is at least 1 (above any threshold), so adaptive sampling refines alpha edges too, even
/// where colour alone would not show them (a black object).
fn edge_spread(means: &mut Means, n: u32) {
    for (spread, &a) in means.spread.iter_mut().zip(&means.alpha) {
        if n > 1 && a > 0.0 && a < 1.0 {
            *spread = spread.max(1.0);
        }
    }
}

/// Each lane's mean as f32, a channel at a time. When every value is within ±f32::MAX (the
/// usual case, checked in the vector) the conversion cannot overflow or give NaN, and `finite`
/// would change nothing.
#[inline(always)]
fn finish<V: Lanes>(
    mean: V3<V>,
    px: &Pixels,
    rgb: &mut [[f32; MAX_LANES]; 3],
    stats: &mut RowStats,
) {
    let (max, min) = (
        V::splat(f64::from(f32::MAX)),
        V::splat(-f64::from(f32::MAX)),
    );
    let within = |v: V| v.le(max).and(min.le(v));
    let tame = within(mean.x).and(within(mean.y)).and(within(mean.z));
    mean.x.store_f32(&mut rgb[0]);
    mean.y.store_f32(&mut rgb[1]);
    mean.z.store_f32(&mut rgb[2]);
    if tame.bits() & px.valid == px.valid {
        return;
    }
    for lane in px.lanes() {
        let m = [rgb[0][lane], rgb[1][lane], rgb[2][lane]];
        stats.non_finite += m.iter().filter(|v| !v.is_finite()).count() as u64;
        [rgb[0][lane], rgb[1][lane], rgb[2][lane]] = finite(m);
    }
}

/// Sub-pixel offsets of sample `k` for each lane's pixel (see `sample`); the centre's are
/// (0.5, 0.5) and need no seed.
#[inline(always)]
fn offsets<V: Lanes>(pattern: Pattern, seeds: &[Seed; MAX_LANES], k: u32) -> (V, V) {
    let (mut u, mut v) = ([0.0; MAX_LANES], [0.0; MAX_LANES]);
    for i in 0..V::N {
        (u[i], v[i]) = seeds[i].offset(pattern, k);
    }
    (V::load(&u), V::load(&v))
}

#[inline(always)]
fn eye_directions<V: Lanes>(pass: &Pass, row: V, col: V, u: V, v: V) -> V3<V> {
    let s = pass.settings;
    let (x, y) = screen_points(row, col, u, v, s.width, s.height);
    pass.camera.directions(x, y)
}

/// Eye rays from each lane's own camera: the one at its sample's instant (time coordinate
/// `times`) while the shutter is open, else the frame's; through the point (a, b) of its
/// lens when the aperture is open there. A lane whose camera is a pinhole gets exactly the
/// ray `eye_directions` gives.
#[inline(always)]
fn sampled_rays<V: Lanes>(
    pass: &Pass,
    exposure: &Exposure,
    (row, col): (V, V),
    (u, v): (V, V),
    times: &[f64; MAX_LANES],
    (a, b): (V, V),
    pixels: Option<&mut PixelRays<V>>,
) -> Rays<V> {
    let mut cameras = [&exposure.camera; MAX_LANES];
    if !exposure.instants.is_empty() {
        for lane in 0..V::N {
            cameras[lane] = &exposure.instants[instant(times[lane])];
        }
    }
    let s = pass.settings;
    let (x, y) = screen_points(row, col, u, v, s.width, s.height);
    let tan = V::from_fn(|i| cameras[i].tan_half_fov);
    let (x, y) = (x * tan, y * tan);
    let origin = V3::from_fn(|i| cameras[i].origin);
    let right = V3::from_fn(|i| cameras[i].right);
    let up = V3::from_fn(|i| cameras[i].up);
    // The direction through the screen point, before it is normalised: its component along
    // the view axis is 1, so origin + focus·w lies on the plane in focus.
    let w = V3::from_fn(|i| cameras[i].forward) + right * x + up * y;
    let pinhole = w.normalize();
    let radius = V::from_fn(|i| cameras[i].lens_radius);
    let open = V::splat(0.0).lt(radius);
    if !open.any() {
        if let Some(out) = pixels {
            *out = pixel_rays((s.width, s.height), (row, col), &cameras, None);
        }
        return Rays {
            origin,
            dir: pinhole,
            leaving: V::splat(-1.0),
        };
    }
    let focus = V::from_fn(|i| cameras[i].focus_distance);
    let (dx, dy) = lens::disc(a, b);
    let lens = origin + right * (radius * dx) + up * (radius * dy);
    let target = origin + w * focus;
    let rays = Rays {
        origin: V3::select(open, lens, origin),
        dir: V3::select(open, (target - lens).normalize(), pinhole),
        leaving: V::splat(-1.0),
    };
    if let Some(out) = pixels {
        *out = pixel_rays(
            (s.width, s.height),
            (row, col),
            &cameras,
            Some((rays.origin, open)),
        );
    }
    rays
}

/// Each lane's pixel (`texture::PixelRays`, docs/spec/texture.md **The pixel**) as its camera
/// `cameras[lane]` sees it: w = forward + right·(x·tan) + up·(y·tan) through the pixel's
/// centre and the steps right·(2/W·tan) and up·(−2/W·tan); where a lane's lens is open
/// (`lens`: the rays' origins and the open lanes), the centre ray runs from the lane's lens
/// point to origin + w·focus and the steps are times the focus distance.
#[inline(always)]
pub(super) fn pixel_rays<V: Lanes>(
    (width, height): (u32, u32),
    (row, col): (V, V),
    cameras: &[&Camera; MAX_LANES],
    lens: Option<(V3<V>, V::M)>,
) -> PixelRays<V> {
    let half = V::splat(0.5);
    let (x, y) = screen_points(row, col, half, half, width, height);
    let tan = V::from_fn(|i| cameras[i].tan_half_fov);
    let (x, y) = (x * tan, y * tan);
    let right = V3::from_fn(|i| cameras[i].right);
    let up = V3::from_fn(|i| cameras[i].up);
    let w = V3::from_fn(|i| cameras[i].forward) + right * x + up * y;
    let step = V::splat(2.0 / f64::from(width)) * tan;
    let (r, d) = (right * step, up * -step);
    let Some((from, open)) = lens else {
        return PixelRays {
            centre: w,
            right: r,
            down: d,
        };
    };
    let focus = V::from_fn(|i| cameras[i].focus_distance);
    let origin = V3::from_fn(|i| cameras[i].origin);
    PixelRays {
        centre: V3::select(open, (origin + w * focus) - from, w),
        right: V3::select(open, r * focus, r),
        down: V3::select(open, d * focus, d),
    }
}

/// The instant (0 … INSTANTS − 1) a sample at time coordinate `time` in [0, 1) falls in.
#[inline(always)]
fn instant(time: f64) -> usize {
    ((time * INSTANTS as f64) as usize).min(INSTANTS - 1)
}

/// Traces each lane of `eye` in the world of its own instant `js[lane]` (things move under
/// the open shutter): the lanes that share an instant go together, the others masked off (a
/// lane's result never depends on the others', so each is what it would be alone).
#[inline(always)]
fn in_instants<V: Lanes>(
    pass: &Pass,
    eye: &Eye<V>,
    js: &[u8; MAX_LANES],
    rays: &mut u64,
) -> (V3<V>, V::M) {
    let mut left = eye.active.bits();
    let (mut colour, mut covered) = (V3::<V>::zero(), V::M::from_bits(0));
    while left != 0 {
        let j = js[left.trailing_zeros() as usize];
        let same = (0..V::N)
            .filter(|&k| left >> k & 1 == 1 && js[k] == j)
            .fold(0u32, |m, k| m | 1 << k);
        left &= !same;
        let mask = V::M::from_bits(same);
        let one = Eye {
            rays: eye.rays,
            active: mask,
            from_origin: None,
            transparent: eye.transparent,
            footprint: eye.footprint,
            pixel: eye.pixel,
            lights: eye.lights,
        };
        let world = &pass.instants[usize::from(j)];
        let (c, hit) = path::trace_packet(world, &one, pass.settings.max_depth, rays);
        colour = V3::select(mask, c, colour);
        covered = covered.or(hit.and(mask));
    }
    (colour, covered)
}

/// Background `Z`: far beyond any scene a compositor meets, yet finite, so arithmetic on the
/// channel (`oiiotool --mulc 0`, a fog ramp) never makes NaN or Inf. Blender's value.
pub const FAR: f32 = 1e10;

/// `Z` of each pixel centre's eye ray: the first hit's planar depth t·(d·forward), the
/// camera-space z of `worldToCamera`, as f32 and at most `FAR`; `FAR` for background.
#[inline(always)]
pub(super) fn depth<V: Lanes>(pass: &Pass, row: u32, out: &mut [f32]) {
    let w = pass.settings.width as usize;
    let half = V::splat(0.5);
    let forward = V3::splat(pass.camera.forward);
    for first in (0..w).step_by(V::N) {
        let n = V::N.min(w - first);
        let col = V::from_fn(|k| (first + k.min(n - 1)) as f64);
        let rays = Rays {
            origin: V3::splat(pass.camera.origin),
            dir: eye_directions(pass, V::splat(f64::from(row)), col, half, half),
            leaving: V::splat(-1.0),
        };
        let hit = pass
            .world
            .geometry
            .nearest(&rays, Some(pass.from_origin), V::M::first(n));
        let z = (hit.t * rays.dir.dot(forward)).array();
        for k in 0..n {
            out[first + k] = if hit.hit.lane(k) {
                (z[k] as f32).min(FAR)
            } else {
                FAR
            };
        }
    }
}

/// Traces arbitrary rays, each lane with its own origin and the object it leaves (tests and
/// tools); colours into `out`. Returns the rays cast.
#[inline(always)]
pub(super) fn rays<V: Lanes>(
    world: &World,
    rays: &[Ray],
    max_depth: u32,
    out: &mut [DVec3],
) -> u64 {
    let mut cast = 0;
    for (chunk, out) in rays.chunks(V::N).zip(out.chunks_mut(V::N)) {
        let at = |k: usize| chunk[k.min(chunk.len() - 1)];
        let eye = Eye {
            rays: Rays {
                origin: V3::from_fn(|k| at(k).origin),
                dir: V3::from_fn(|k| at(k).dir),
                leaving: V::from_fn(|k| at(k).leaving.map_or(-1.0, |o| o as f64)),
            },
            active: V::M::first(chunk.len()),
            from_origin: None,
            transparent: false,
            footprint: world.textured.then_some(0.0),
            pixel: None,
            lights: None,
        };
        let (c, _) = path::trace_packet(world, &eye, max_depth, &mut cast);
        for (k, o) in out.iter_mut().enumerate() {
            *o = c.lane(k);
        }
    }
    cast
}
