//! `rayreel measure`: what each speed/accuracy setting costs and buys on one frame of the
//! user's own scene. A converged reference is rendered once; then a ladder of settings
//! (uniform samples, adaptive thresholds, max_depth, the presets), each timed as the median of
//! several runs and compared with the reference on the 8-bit image the user would get.
//! Last, the file's own settings in f64 and in f32, rendered in turn, each also compared with
//! the f64 image (the reference itself is always f64).

use crate::frame::Frame;
use crate::scene::Light;
use crate::schedule::{RunError, render_with};
use crate::sequence::{Film, Quality, Sequence, default_sampling};
use crate::timeline::motion::Posed;
use crate::tracer::{Adaptive, Precision, Sampler, Settings, World};
use crate::transfer::Encoding;
use std::time::Instant;

mod plot;
pub mod reference;
mod report;

/// Samples per pixel of the reference (a jittered 32×32 grid) and its max_depth: with the
/// reflection coefficients users give (≤ 1) and the 16th bounce weighted at most by
/// r^15, deeper paths add nothing visible in practice; `convergence` reports the check.
pub(crate) const REFERENCE_SAMPLES: u32 = 1024;
pub(crate) const REFERENCE_DEPTH: u32 = 16;
/// The reference where paths branch (glass): a tree of depth d traces up to 2^d − 1 rays a
/// sample, so a 16×16 grid at depth 12 costs about what the plain reference does.
pub(crate) const TREE_REFERENCE_SAMPLES: u32 = 256;
pub(crate) const TREE_REFERENCE_DEPTH: u32 = 12;
/// The reference is computed in f64 whatever the file says: it is what f32 is measured against.
pub(crate) const REFERENCE_PRECISION: Precision = Precision::F64;
/// Issue 19's target for f32: at most this share of pixels off by more than 2 levels from the
/// f64 image of the same settings.
pub(crate) const F32_TARGET_OFF2: f64 = 0.0005;

/// How far an image is from the reference, in 8-bit levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Distance {
    pub rmse: f64,
    pub(crate) psnr: f64,
    pub max: u8,
    /// Share of pixels with some channel off by more than one level.
    pub off: f64,
    /// Share of pixels with some channel off by more than two levels.
    pub off2: f64,
    /// Share of pixels with some channel off by more than eight levels: grain a viewer sees.
    pub off8: f64,
}

pub fn compare(a: &[u8], b: &[u8]) -> Distance {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    let mut sum = 0.0;
    let mut max = 0u8;
    let (mut off, mut off2, mut off8) = (0usize, 0usize, 0usize);
    for (pa, pb) in a.chunks(3).zip(b.chunks(3)) {
        let mut worst = 0;
        for (x, y) in pa.iter().zip(pb) {
            let d = x.abs_diff(*y);
            sum += f64::from(d) * f64::from(d);
            worst = worst.max(d);
        }
        max = max.max(worst);
        off += usize::from(worst > 1);
        off2 += usize::from(worst > 2);
        off8 += usize::from(worst > 8);
    }
    let rmse = (sum / a.len() as f64).sqrt();
    let psnr = if rmse == 0.0 {
        f64::INFINITY
    } else {
        20.0 * (255.0 / rmse).log10()
    };
    let pixels = (a.len() / 3) as f64;
    Distance {
        rmse,
        psnr,
        max,
        off: off as f64 / pixels,
        off2: off2 as f64 / pixels,
        off8: off8 as f64 / pixels,
    }
}

/// One rung of the ladder.
#[derive(Debug, Clone)]
pub(crate) struct Row {
    pub(crate) group: &'static str,
    pub(crate) label: String,
    pub(crate) settings: Settings,
    pub(crate) samples_per_pixel: f64,
    pub(crate) seconds: [f64; 3],
    pub(crate) error: Distance,
    /// Precision rows only: against the f64 render of the same settings.
    pub(crate) versus_f64: Option<Versus>,
}

/// A precision row against the f64 row of the same settings (the f64 row against itself).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Versus {
    /// The median over rounds of that round's f64 time over this row's time.
    pub(crate) speedup: f64,
    pub(crate) error: Distance,
}

/// Renders frame `n` with `settings` in place of the sequence's (building the geometry; the
/// measurement itself builds it once for all its renders).
pub fn render(seq: &Sequence, n: u64, settings: &Settings) -> Result<Frame, RunError> {
    render_with(&World::new(seq.scene.clone()), seq, n, settings)
}

/// The reference `measure` compares against, for a scene whose paths are trees or not.
pub fn reference_settings(base: &Settings, trees: bool) -> Settings {
    reference_with(base, trees, &reference::Options::default())
}

/// `reference_settings` with the samples and max_depth `options` give, where they give them.
fn reference_with(base: &Settings, trees: bool, options: &reference::Options) -> Settings {
    let (samples, max_depth) = match trees {
        false => (REFERENCE_SAMPLES, REFERENCE_DEPTH),
        true => (TREE_REFERENCE_SAMPLES, TREE_REFERENCE_DEPTH),
    };
    Settings {
        samples: options.samples.unwrap_or(samples),
        adaptive: None,
        max_depth: options.depth.unwrap_or(max_depth),
        sampler: Sampler::Stratified,
        depth: false,
        alpha: false,
        precision: REFERENCE_PRECISION,
        denoise: false,
        ..*base
    }
}

/// The ladder of settings measured against the reference. The presets are what `--quality`
/// gives this file (they keep the sampling values it sets itself).
pub fn ladder(seq: &Sequence) -> Vec<LadderRow> {
    let (base, film) = (&seq.settings, seq.film());
    let mut out = Vec::new();
    let with = |samples, adaptive, max_depth| Settings {
        samples,
        adaptive,
        max_depth,
        depth: false,
        alpha: false,
        sampler: Sampler::Stratified,
        ..*base
    };
    for n in [1, 2, 4, 8, 16, 32, 64, 128, 256] {
        out.push((
            "uniform",
            format!("{n} spp"),
            with(n, None, base.max_depth),
            false,
        ));
    }
    for t in [0.05f32, 0.02, 0.01] {
        let a = Some(Adaptive {
            threshold: t,
            max_samples: 64,
        });
        out.push((
            "adaptive",
            format!("adaptive 4-64 @{t}"),
            with(4, a, base.max_depth),
            false,
        ));
    }
    for d in 1..=8 {
        out.push(("depth", format!("max_depth {d}"), with(16, None, d), false));
    }
    for (q, name) in [
        (Quality::Draft, "draft"),
        (Quality::Preview, "preview"),
        (Quality::Final, "final"),
    ] {
        let mut s = with(1, None, base.max_depth);
        (seq.explicit).preset(&mut s, q, seq.scene.has_glass(), film);
        if s.adaptive.is_some_and(|a| a.max_samples <= s.samples) {
            s.adaptive = None;
        }
        out.push(("preset", name.to_string(), s, q == Quality::Draft));
    }
    // What the sampler and the default buy: independent samples beside the 16 spp row above,
    // and a file's default sampling (film's rounds on film) beside the older pinhole default.
    out.push((
        "sampler",
        "16 spp independent".to_string(),
        Settings {
            sampler: Sampler::Random,
            ..with(16, None, base.max_depth)
        },
        false,
    ));
    for (label, f) in [("default", film), ("pinhole default", Film::Pinhole)] {
        if label == "pinhole default" && film == Film::Pinhole {
            continue;
        }
        let mut s = with(1, None, base.max_depth);
        default_sampling(&mut s, f);
        out.push(("default", label.to_string(), s, false));
    }
    if film != Film::Pinhole {
        out.extend(unfiltered(&out));
    }
    out
}

/// What the film filter buys: the default and `final` rows again with it off.
fn unfiltered(rows: &[(&'static str, String, Settings, bool)]) -> Vec<LadderRow> {
    let wanted = |label: &str| label == "default" || label == "final";
    (rows.iter().filter(|r| wanted(&r.1)))
        .map(|(_, label, s, half)| {
            let s = Settings {
                denoise: false,
                ..*s
            };
            ("denoise", format!("{label} (denoise off)"), s, *half)
        })
        .collect()
}

/// A rung: its group, label, settings, and whether it renders at half size.
type LadderRow = (&'static str, String, Settings, bool);

/// The file's own settings in f64 and in f32 (both, whatever the file says), f64 first.
pub(crate) fn precisions(base: &Settings) -> [(String, Settings); 2] {
    [Precision::F64, Precision::F32].map(|precision| {
        let s = Settings {
            precision,
            depth: false,
            alpha: false,
            ..*base
        };
        (format!("precision {}", precision.name()), s)
    })
}

/// The precision rows: rendered in turn, round by round, so a busy moment slows both alike.
fn precision_rows(
    world: &World,
    seq: &Sequence,
    n: u64,
    runs: usize,
    ref_image: &[u8],
) -> Result<Vec<Row>, RunError> {
    let pair = precisions(&seq.settings);
    let mut times = [Vec::new(), Vec::new()];
    let mut out = [(Vec::new(), 0.0), (Vec::new(), 0.0)];
    for _ in 0..runs {
        for (i, (_, s)) in pair.iter().enumerate() {
            let (image, spp, t) = timed(world, seq, n, s, false, 1)?;
            times[i].extend(t);
            out[i] = (image, spp);
        }
    }
    let rows = pair.into_iter().enumerate().map(|(i, (label, settings))| {
        let ratios = (0..runs).map(|r| times[0][r] / times[i][r]).collect();
        let versus = Versus {
            speedup: spread(ratios)[0],
            error: compare(&out[i].0, &out[0].0),
        };
        Row {
            group: "precision",
            label,
            settings,
            samples_per_pixel: out[i].1,
            seconds: spread(times[i].clone()),
            error: compare(&out[i].0, ref_image),
            versus_f64: Some(versus),
        }
    });
    Ok(rows.collect())
}

/// Times `runs` renders; returns the 8-bit image of the last, samples per pixel and times.
fn timed(
    world: &World,
    seq: &Sequence,
    n: u64,
    s: &Settings,
    half: bool,
    runs: usize,
) -> Result<(Vec<u8>, f64, Vec<f64>), RunError> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..runs {
        let mut settings = *s;
        if half {
            settings.width = s.width.div_ceil(2);
            settings.height = s.height.div_ceil(2);
        }
        let start = Instant::now();
        let frame = render_with(world, seq, n, &settings)?;
        times.push(start.elapsed().as_secs_f64());
        last = Some(frame);
    }
    let frame = last.expect("at least one run");
    let spp = frame.samples as f64 / (f64::from(s.width) * f64::from(s.height));
    let image = if half {
        upscale2(&frame.to_rgb8(), frame.width, s.width, s.height)
    } else {
        frame.to_rgb8()
    };
    Ok((image, spp, times))
}

/// Nearest-neighbour ×2, cropped to the full size: how a half-size draft compares.
fn upscale2(rgb: &[u8], half_w: u32, w: u32, h: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity((3 * w * h) as usize);
    for row in 0..h {
        for col in 0..w {
            let i = 3 * ((row / 2) * half_w + col / 2) as usize;
            out.extend_from_slice(&rgb[i..i + 3]);
        }
    }
    out
}

/// Median, min and max.
fn spread(mut t: Vec<f64>) -> [f64; 3] {
    t.sort_by(f64::total_cmp);
    [t[t.len() / 2], t[0], t[t.len() - 1]]
}

pub(crate) struct Report {
    /// The encoding of the 8-bit values the errors are measured on: the sequence's, so the
    /// figures are the differences a viewer of its frames sees.
    pub(crate) encoding: Encoding,
    /// Samples per pixel and max_depth of the reference.
    pub(crate) reference: (u32, u32),
    pub(crate) reference_seconds: f64,
    /// Samples of the check render, and its error against the reference.
    pub(crate) convergence: (u32, Distance),
    /// The reference (written as reference.png).
    pub(crate) reference_frame: Frame,
    pub(crate) rows: Vec<Row>,
}

/// Light samples per eye sample, the trade next to pixel samples: with area lights, the file's
/// settings with every area light at 1, 4, 16 and 64 samples (nothing without them).
fn light_rows(
    seq: &Sequence,
    n: u64,
    runs: usize,
    reference: &[u8],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Row>, RunError> {
    let mut rows = Vec::new();
    if !seq.scene.lights.iter().any(|l| l.area_samples().is_some()) {
        return Ok(rows);
    }
    for m in [1, 4, 16, 64] {
        let mut seq = seq.clone();
        let set = |l: &mut Light| {
            if let Light::Sphere { samples, .. } | Light::Rect { samples, .. } = l {
                *samples = m;
            }
        };
        for l in &mut seq.scene.lights {
            set(l);
        }
        // A light with keys is posed from its rig's copy, not from the still scene.
        for rig in &mut seq.timeline.motion {
            if let Posed::Light(l) = &mut rig.base {
                set(l);
            }
        }
        let world = World::new(seq.scene.clone());
        let (image, spp, times) = timed(&world, &seq, n, &seq.settings, false, runs)?;
        let error = compare(&image, reference);
        let label = format!("{m} light samples");
        progress(&format!("{label}: rmse {:.3}", error.rmse));
        rows.push(Row {
            group: "lights",
            label,
            settings: seq.settings,
            samples_per_pixel: spp,
            seconds: spread(times),
            error,
            versus_f64: None,
        });
    }
    Ok(rows)
}

/// What to measure besides the frame: the reference, and which groups of rows.
#[derive(Debug, Clone, Default)]
pub struct Options {
    pub reference: reference::Options,
    /// Only these groups of rows (`GROUPS`); all when None.
    pub only: Option<Vec<String>>,
}

/// The groups of rows, in the order they are measured.
pub const GROUPS: [&str; 9] = [
    "uniform",
    "adaptive",
    "depth",
    "preset",
    "sampler",
    "default",
    "denoise",
    "lights",
    "precision",
];

impl Options {
    fn wants(&self, group: &str) -> bool {
        self.only
            .as_ref()
            .is_none_or(|only| only.iter().any(|g| g == group))
    }
}

/// Renders the reference and the ladder; `progress` hears each rung as it finishes.
pub(crate) fn measure(
    seq: &Sequence,
    n: u64,
    runs: usize,
    options: &Options,
    progress: &mut dyn FnMut(&str),
) -> Result<Report, RunError> {
    let world = World::new(seq.scene.clone());
    let reference = reference_with(&seq.settings, world.trees(), &options.reference);
    let cache = options.reference.cache.as_deref();
    let (truth, reference_seconds) =
        reference::reference(&world, seq, n, &reference, cache, false)?;
    let ref_image = truth.to_rgb8();
    progress(&format!(
        "reference: {} spp, max_depth {}, {reference_seconds:.2} s",
        reference.samples, reference.max_depth
    ));
    let check = Settings {
        samples: (options.reference.check_samples).unwrap_or(reference.samples / 2),
        ..reference
    };
    let check_image = reference::reference(&world, seq, n, &check, cache, true)?.0;
    let convergence = compare(&check_image.to_rgb8(), &ref_image);
    let mut rows = Vec::new();
    let ladder = ladder(seq);
    for (group, label, settings, half) in ladder.into_iter().filter(|r| options.wants(r.0)) {
        let (image, spp, times) = timed(&world, seq, n, &settings, half, runs)?;
        let error = compare(&image, &ref_image);
        progress(&format!("{label}: rmse {:.3}", error.rmse));
        rows.push(Row {
            group,
            label,
            settings,
            samples_per_pixel: spp,
            seconds: spread(times),
            error,
            versus_f64: None,
        });
    }
    if options.wants("lights") {
        rows.extend(light_rows(seq, n, runs, &ref_image, progress)?);
    }
    if options.wants("precision") {
        for row in precision_rows(&world, seq, n, runs, &ref_image)? {
            let e = row.versus_f64.expect("a precision row").error;
            progress(&format!(
                "{}: rmse {:.3}, against f64 rmse {:.3}",
                row.label, row.error.rmse, e.rmse
            ));
            rows.push(row);
        }
    }
    Ok(Report {
        encoding: seq.settings.encoding,
        reference: (reference.samples, reference.max_depth),
        reference_seconds,
        convergence: (check.samples, convergence),
        reference_frame: truth,
        rows,
    })
}
