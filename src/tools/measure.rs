//! `rayreel measure`: what each speed/accuracy setting costs and buys on one frame of the
//! user's own scene. A converged reference is rendered once; then a ladder of settings
//! (uniform samples, adaptive thresholds, max_depth, the presets), each timed as the median of
//! several runs and compared with the reference on the 8-bit image the user would get.

use crate::frame::Frame;
use crate::schedule::render_with;
use crate::sequence::{Quality, Sequence, preset};
use crate::tracer::{Adaptive, Precision, Sampler, Settings, World};
use crate::transfer::Encoding;
use std::fmt::Write as _;
use std::time::Instant;

/// Samples per pixel of the reference (a jittered 32×32 grid) and its max_depth: with the
/// reflection coefficients users give (≤ 1) and the 16th bounce weighted at most by
/// r^15, deeper paths add nothing visible in practice; `convergence` reports the check.
pub const REFERENCE_SAMPLES: u32 = 1024;
pub const REFERENCE_DEPTH: u32 = 16;
/// The reference where paths branch (glass): a tree of depth d traces up to 2^d − 1 rays a
/// sample, so a 16×16 grid at depth 12 costs about what the plain reference does.
pub const TREE_REFERENCE_SAMPLES: u32 = 256;
pub const TREE_REFERENCE_DEPTH: u32 = 12;
/// The reference is computed in f64 whatever the file says: it is what f32 is measured against.
pub const REFERENCE_PRECISION: Precision = Precision::F64;

/// How far an image is from the reference, in 8-bit levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Error {
    pub rmse: f64,
    pub psnr: f64,
    pub max: u8,
    /// Share of pixels with some channel off by more than one level.
    pub off: f64,
}

pub fn compare(a: &[u8], b: &[u8]) -> Error {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    let mut sum = 0.0;
    let mut max = 0u8;
    let mut off = 0usize;
    for (pa, pb) in a.chunks(3).zip(b.chunks(3)) {
        let mut worst = 0;
        for (x, y) in pa.iter().zip(pb) {
            let d = x.abs_diff(*y);
            sum += f64::from(d) * f64::from(d);
            worst = worst.max(d);
        }
        max = max.max(worst);
        off += usize::from(worst > 1);
    }
    let rmse = (sum / a.len() as f64).sqrt();
    let psnr = if rmse == 0.0 {
        f64::INFINITY
    } else {
        20.0 * (255.0 / rmse).log10()
    };
    Error {
        rmse,
        psnr,
        max,
        off: off as f64 / (a.len() / 3) as f64,
    }
}

/// One rung of the ladder.
#[derive(Debug, Clone)]
pub struct Row {
    pub group: &'static str,
    pub label: String,
    pub settings: Settings,
    /// Whether the image is rendered at half size and upscaled (the draft preset).
    pub half: bool,
    pub samples_per_pixel: f64,
    pub seconds: [f64; 3],
    pub error: Error,
}

/// Renders frame `n` with `settings` in place of the sequence's (building the geometry; the
/// measurement itself builds it once for all its renders).
pub fn render(seq: &Sequence, n: u64, settings: &Settings) -> Result<Frame, String> {
    Ok(render_with(
        &World::new(seq.scene.clone()),
        seq,
        n,
        settings,
    )?)
}

/// The reference `measure` compares against, for a scene whose paths are trees or not.
pub fn reference_settings(base: &Settings, trees: bool) -> Settings {
    let (samples, max_depth) = match trees {
        false => (REFERENCE_SAMPLES, REFERENCE_DEPTH),
        true => (TREE_REFERENCE_SAMPLES, TREE_REFERENCE_DEPTH),
    };
    Settings {
        samples,
        adaptive: None,
        max_depth,
        sampler: Sampler::Stratified,
        depth: false,
        alpha: false,
        precision: REFERENCE_PRECISION,
        ..*base
    }
}

/// The ladder of settings measured against the reference.
pub fn ladder(base: &Settings) -> Vec<(&'static str, String, Settings, bool)> {
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
        preset(&mut s, q);
        out.push(("preset", name.to_string(), s, q == Quality::Draft));
    }
    out
}

/// Times `runs` renders; returns the 8-bit image of the last, samples per pixel and times.
fn timed(
    world: &World,
    seq: &Sequence,
    n: u64,
    s: &Settings,
    half: bool,
    runs: usize,
) -> Result<(Vec<u8>, f64, Vec<f64>), String> {
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

pub struct Report {
    /// The encoding of the 8-bit values the errors are measured on: the sequence's, so the
    /// figures are the differences a viewer of its frames sees.
    pub encoding: Encoding,
    /// Samples per pixel and max_depth of the reference.
    pub reference: (u32, u32),
    pub reference_seconds: f64,
    /// Error of a reference with half the samples, against the reference.
    pub convergence: Error,
    pub rows: Vec<Row>,
}

/// Renders the reference and the ladder; `progress` hears each rung as it finishes.
pub fn measure(
    seq: &Sequence,
    n: u64,
    runs: usize,
    progress: &mut dyn FnMut(&str),
) -> Result<Report, String> {
    let world = World::new(seq.scene.clone());
    let reference = reference_settings(&seq.settings, world.trees());
    let start = Instant::now();
    let ref_image = render_with(&world, seq, n, &reference)?.to_rgb8();
    let reference_seconds = start.elapsed().as_secs_f64();
    progress(&format!(
        "reference: {} spp, max_depth {}, {reference_seconds:.2} s",
        reference.samples, reference.max_depth
    ));
    let half = Settings {
        samples: reference.samples / 2,
        ..reference
    };
    let convergence = compare(&render_with(&world, seq, n, &half)?.to_rgb8(), &ref_image);
    let mut rows = Vec::new();
    for (group, label, settings, half) in ladder(&seq.settings) {
        let (image, spp, times) = timed(&world, seq, n, &settings, half, runs)?;
        let error = compare(&image, &ref_image);
        progress(&format!("{label}: rmse {:.3}", error.rmse));
        rows.push(Row {
            group,
            label,
            settings,
            half,
            samples_per_pixel: spp,
            seconds: spread(times),
            error,
        });
    }
    Ok(Report {
        encoding: seq.settings.encoding,
        reference: (reference.samples, reference.max_depth),
        reference_seconds,
        convergence,
        rows,
    })
}

impl Report {
    pub fn table(&self) -> String {
        let mut s = format!(
            "errors on the 8-bit {} values of each frame (render.encoding)\n",
            self.encoding.name()
        );
        let _ = writeln!(
            s,
            "{:<24} {:>9} {:>9} {:>9} {:>8} {:>8} {:>7} {:>4} {:>7}",
            "settings", "spp", "time s", "speed-up", "rmse", "psnr dB", "max", "", ">1/255"
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "{:<24} {:>9.2} {:>9.4} {:>8.1}x {:>8.3} {:>8.2} {:>7} {:>4} {:>6.2}%",
                r.label,
                r.samples_per_pixel,
                r.seconds[0],
                self.reference_seconds / r.seconds[0],
                r.error.rmse,
                r.error.psnr,
                r.error.max,
                "",
                100.0 * r.error.off
            );
        }
        s
    }

    /// Each row as (column, value) pairs, shared by the CSV and the JSON.
    fn records(&self) -> Vec<Vec<(&'static str, String)>> {
        self.rows
            .iter()
            .map(|r| {
                vec![
                    ("group", format!("\"{}\"", r.group)),
                    ("settings", format!("\"{}\"", r.label)),
                    ("samples_per_pixel", format!("{:.4}", r.samples_per_pixel)),
                    ("max_depth", r.settings.max_depth.to_string()),
                    ("seconds_median", format!("{:.6}", r.seconds[0])),
                    ("seconds_min", format!("{:.6}", r.seconds[1])),
                    ("seconds_max", format!("{:.6}", r.seconds[2])),
                    (
                        "speedup",
                        format!("{:.3}", self.reference_seconds / r.seconds[0]),
                    ),
                    ("rmse", format!("{:.5}", r.error.rmse)),
                    ("psnr_db", format!("{:.3}", finite_or(r.error.psnr, 999.0))),
                    ("max_error", r.error.max.to_string()),
                    ("share_off", format!("{:.6}", r.error.off)),
                    ("encoding", format!("\"{}\"", self.encoding.name())),
                ]
            })
            .collect()
    }

    pub fn csv(&self) -> String {
        let records = self.records();
        let header: Vec<&str> = records
            .first()
            .map_or(Vec::new(), |r| r.iter().map(|(k, _)| *k).collect());
        let mut s = header.join(",") + "\n";
        for r in &records {
            let cells: Vec<&str> = r.iter().map(|(_, v)| v.trim_matches('"')).collect();
            s += &(cells.join(",") + "\n");
        }
        s
    }

    pub fn json(&self) -> String {
        let rows: Vec<String> = self
            .records()
            .iter()
            .map(|r| {
                let fields: Vec<String> = r.iter().map(|(k, v)| format!("\"{k}\": {v}")).collect();
                format!("    {{{}}}", fields.join(", "))
            })
            .collect();
        format!(
            "{{\n  \"reference\": {{\"samples_per_pixel\": {}, \"max_depth\": {}, \"seconds\": {:.6}, \"half_samples_rmse\": {:.5}}},\n  \"rows\": [\n{}\n  ]\n}}\n",
            self.reference.0,
            self.reference.1,
            self.reference_seconds,
            self.convergence.rmse,
            rows.join(",\n")
        )
    }

    /// Error against time, log-log, uniform and adaptive as lines, presets labelled.
    pub fn svg(&self) -> String {
        let (w, h, m) = (720.0, 460.0, 60.0);
        let pts: Vec<(f64, f64)> = self
            .rows
            .iter()
            .map(|r| (r.seconds[0], r.error.rmse.max(1e-3)))
            .collect();
        let (x0, x1) = bounds(pts.iter().map(|p| p.0));
        let (y0, y1) = bounds(pts.iter().map(|p| p.1));
        let px = |x: f64| m + (x.log10() - x0) / (x1 - x0) * (w - 2.0 * m);
        let py = |y: f64| h - m - (y.log10() - y0) / (y1 - y0) * (h - 2.0 * m);
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        );
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">render time per frame (s, log)</text>",
            w / 2.0,
            h - 15.0
        );
        let _ = writeln!(
            s,
            "<text x=\"15\" y=\"{}\" transform=\"rotate(-90 15 {})\" text-anchor=\"middle\">RMSE vs reference (8-bit levels, log)</text>",
            h / 2.0,
            h / 2.0
        );
        let _ = writeln!(
            s,
            "<rect x=\"{m}\" y=\"{m}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>",
            w - 2.0 * m,
            h - 2.0 * m
        );
        for (decade, axis_x) in [(x0, true), (y0, false)] {
            let end = if axis_x { x1 } else { y1 };
            let mut d = decade.floor();
            while d <= end.ceil() {
                let v = 10f64.powf(d);
                if axis_x && (x0..=x1).contains(&d) {
                    let _ = writeln!(
                        s,
                        "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{v}</text>",
                        px(v),
                        h - m + 16.0
                    );
                } else if !axis_x && (y0..=y1).contains(&d) {
                    let _ = writeln!(
                        s,
                        "<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{v}</text>",
                        m - 4.0,
                        py(v) + 4.0
                    );
                }
                d += 1.0;
            }
        }
        for (group, color) in [
            ("uniform", "#1f77b4"),
            ("adaptive", "#2ca02c"),
            ("depth", "#9467bd"),
        ] {
            let line: Vec<String> = self
                .rows
                .iter()
                .filter(|r| r.group == group)
                .map(|r| format!("{:.1},{:.1}", px(r.seconds[0]), py(r.error.rmse.max(1e-3))))
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"/>",
                line.join(" ")
            );
            for p in &line {
                let (x, y) = p.split_once(',').expect("x,y");
                let _ = writeln!(
                    s,
                    "<circle cx=\"{x}\" cy=\"{y}\" r=\"3\" fill=\"{color}\"/>"
                );
            }
        }
        for r in self.rows.iter().filter(|r| r.group == "preset") {
            let (x, y) = (px(r.seconds[0]), py(r.error.rmse.max(1e-3)));
            let _ = writeln!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"9\" height=\"9\" fill=\"#d62728\"/>",
                x - 4.5,
                y - 4.5
            );
            let _ = writeln!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" fill=\"#d62728\">{}</text>",
                x + 8.0,
                y - 6.0,
                r.label
            );
        }
        let legend = [
            ("#1f77b4", "uniform 1-256 spp"),
            ("#2ca02c", "adaptive 4-64"),
            ("#9467bd", "max_depth 1-8 @16 spp"),
            ("#d62728", "presets"),
        ];
        for (i, (color, text)) in legend.iter().enumerate() {
            let y = m + 16.0 + 16.0 * i as f64;
            let _ = writeln!(
                s,
                "<rect x=\"{}\" y=\"{}\" width=\"10\" height=\"10\" fill=\"{color}\"/><text x=\"{}\" y=\"{}\">{text}</text>",
                w - m - 170.0,
                y - 9.0,
                w - m - 155.0,
                y
            );
        }
        s.push_str("</svg>\n");
        s
    }
}

fn finite_or(v: f64, fallback: f64) -> f64 {
    if v.is_finite() { v } else { fallback }
}

/// Log10 bounds with a little room.
fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let (lo, hi) = (lo.log10() - 0.1, hi.log10() + 0.1);
    if hi - lo < 0.5 {
        (lo - 0.25, hi + 0.25)
    } else {
        (lo, hi)
    }
}
