//! What a job will take, measured: `check`, `render --dry-run` and their warnings render a few
//! small tiles of a few of the job's frames at the job's own settings (sampling, depth, glass,
//! film, precision) on the job's threads, for about a second, and scale what they took to the
//! job's pixels and frames, plus the scene's setup (hierarchies built once) and the encoding
//! of each frame file. The ray count stays beside it as an upper bound.
//!
//! A tile is rendered through its own camera: the frame's camera (each of its shutter's
//! instants too) turned towards the tile's centre, its field of view narrowed to the tile's
//! width, so it holds what that part of the frame holds, at the frame's pixel density.

use super::render::plural;
use crate::budget::OutOfMemory;
use crate::camera::Camera;
use crate::frameset::FrameSet;
use crate::output::{Expected, FileFormat, RunIdentity};
use crate::sequence::Sequence;
use crate::settings::Settings;
use crate::shutter::Exposure;
use crate::tracer::{self, World};
use rayon::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// How long the probe renders once its first round is done: it stops at the end of the
/// round that passes this.
const BUDGET: Duration = Duration::from_millis(1200);
/// The probe gives up on a round that has not ended after this long (a frame of hours): the
/// estimate is then a lower bound.
const HARD_STOP: Duration = Duration::from_secs(3);
/// Frames probed, evenly spaced over the job's, and tiles a frame each round.
const FRAMES: u64 = 5;
const TILES_A_ROUND: usize = 4;
/// Rounds at least (a round of every frame's tiles), while they take under `MIN_PROBE`, and
/// at most.
const ROUNDS: usize = 4;
const MIN_PROBE: Duration = Duration::from_millis(300);
const MAX_ROUNDS: usize = 32;
/// A round of every probed frame's tiles should take about this long, which sizes the tiles.
const ROUND_SECONDS: f64 = 0.25;

/// A job's measured cost.
pub(crate) struct Estimate {
    /// Seconds for the whole job: setup, then every frame rendered and encoded.
    pub(crate) seconds: f64,
    /// What the figure rests on, in words.
    pub(crate) basis: String,
    /// The probe was stopped: the real figure is larger.
    pub(crate) lower_bound: bool,
    /// Each mesh's hierarchy as the probe built it: bytes (nodes, order and the triangle
    /// copies made) and seconds, in the scene's order (`check` prints them).
    pub(crate) hierarchies: Vec<(usize, f64)>,
}

/// Measures `frames` of `seq` on `threads` threads, written as `format` (None: not written
/// to files). None when there is nothing to render or no frame has a camera; an error when
/// the system refuses the memory of a mesh's hierarchy or triangle copies.
pub(crate) fn estimate(
    seq: &Sequence,
    frames: &FrameSet,
    threads: usize,
    format: Option<&FileFormat>,
) -> Result<Option<Estimate>, OutOfMemory> {
    if frames.is_empty() {
        return Ok(None);
    }
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
        return Ok(None);
    };
    pool.install(|| measure(seq, frames, threads, format))
}

fn measure(
    seq: &Sequence,
    frames: &FrameSet,
    threads: usize,
    format: Option<&FileFormat>,
) -> Result<Option<Estimate>, OutOfMemory> {
    let started = Instant::now();
    // Loading the file, its meshes and images (as this command just did), then the world.
    let loaded = super::STARTED
        .get()
        .map_or(0.0, |t| t.elapsed().as_secs_f64());
    let world = World::try_new(seq.scene.clone())?;
    let setup = loaded + started.elapsed().as_secs_f64();
    let probed = probe_frames(seq, frames);
    let Some(first) = probed.first() else {
        return Ok(None);
    };
    let s = &seq.settings;
    let stop = Arc::new(AtomicBool::new(false));
    let watchdog = Watchdog::start(&stop);
    // The first refusal of a triangle copy's memory, which stops the probe.
    let refused = std::sync::Mutex::new(None);
    let timed = |tile: Tile, (n, e): &(u64, Exposure)| {
        let t = Instant::now();
        let done = match render_tile(&world, s, e, *n, tile, &stop) {
            Ok(done) => done.is_some(),
            Err(e) => {
                stop.store(true, Ordering::Relaxed);
                *refused.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                false
            }
        };
        (t.elapsed().as_secs_f64(), done)
    };
    // A one-pixel frame is what every frame costs besides its pixels; a small tile then
    // sizes the others (and warms the pool up). Either stopped: a pixel takes at least that.
    let (overhead, done) = timed(Tile::at(0, 0, 1, 1), first);
    let side = s.width.min(s.height).clamp(1, 8);
    let (warm, warmed) = match done {
        true => timed(Tile::at(0, 0, side, side), first),
        false => (overhead, false),
    };
    let pixels = f64::from(if done { side * side } else { 1 });
    let per_pixel = ((warm - if done { overhead } else { 0.0 }).max(0.0) / pixels).max(1e-9);
    let probe = match done && warmed {
        true => rounds(
            &probed,
            (s.width, s.height),
            threads,
            per_pixel,
            &timed,
            overhead,
        ),
        // A frame of hours: the small tile's rate, on one band of rows.
        false => Probe {
            seconds_a_pixel: per_pixel / threads as f64,
            tiles: 0,
            side: pixels.sqrt() as u32,
            frames: 1,
            stopped: true,
        },
    };
    let stopped = probe.stopped || stop.load(Ordering::Relaxed);
    drop(watchdog);
    if let Some(e) = refused.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let (w, h) = (f64::from(s.width), f64::from(s.height));
    let render = overhead + probe.seconds_a_pixel * w * h;
    let encode = format.map_or(0.0, |f| encode_seconds(seq, f, first.0));
    let per_frame = render + encode;
    let what = match probe.tiles {
        0 => format!(
            "{} pixel{} had not finished after {:.1} s",
            probe.side * probe.side,
            if probe.side == 1 { "" } else { "s" },
            HARD_STOP.as_secs_f64()
        ),
        n => format!(
            "{} of {}x{} pixels in {}",
            plural(n, "tile"),
            probe.side,
            probe.side,
            plural(probe.frames, "frame")
        ),
    };
    let basis = format!(
        "measured: {what} on {threads} thread{}, {:.2} s; {} a frame{}",
        if threads == 1 { "" } else { "s" },
        started.elapsed().as_secs_f64(),
        duration(per_frame),
        match format {
            Some(_) => " with its file",
            None => "",
        }
    );
    let hierarchies = (world.hierarchies().iter())
        .map(|b| (b.bytes(), b.seconds))
        .collect();
    Ok(Some(Estimate {
        seconds: setup + per_frame * frames.len() as f64,
        basis,
        lower_bound: stopped,
        hierarchies,
    }))
}

/// What the rounds of tiles found: seconds a pixel of a frame on every thread (the mean over
/// the probed frames), and what was rendered.
struct Probe {
    seconds_a_pixel: f64,
    tiles: u64,
    side: u32,
    frames: u64,
    stopped: bool,
}

/// Renders a tile of a probed frame: its seconds, and whether it finished.
type Timed<'a> = dyn Fn(Tile, &(u64, Exposure)) -> (f64, bool) + Sync + 'a;

/// Rounds of `TILES_A_ROUND` tiles of every probed frame, each round's tiles rendered side by
/// side on the pool: at least `ROUNDS` of them and `MIN_PROBE` seconds (the tiles cycle),
/// until `BUDGET` is spent. A round's wall time, less the tiles' per-call `overhead` spread
/// over the threads, is shared among its frames in proportion to their tiles' own times; the
/// round's rate is the mean over its frames, and the probe's the median over its rounds, so a
/// moment when other programs took the cores counts for little.
fn rounds(
    probed: &[(u64, Exposure)],
    (w, h): (u32, u32),
    threads: usize,
    per_pixel: f64,
    timed: &Timed<'_>,
    overhead: f64,
) -> Probe {
    let pixels_a_round = ROUND_SECONDS * threads as f64 / per_pixel;
    let tile_pixels = pixels_a_round / (probed.len() * TILES_A_ROUND) as f64;
    let side = (tile_pixels.sqrt() as u32)
        .clamp(4, 32)
        .min(w)
        .min(h)
        .max(1);
    let tiles = tile_grid(w, h, side);
    let clock = Instant::now();
    let (mut rates, mut count, mut stopped) = (Vec::new(), 0, false);
    for round in 0..MAX_ROUNDS {
        let batch: Vec<(usize, Tile)> = (0..probed.len())
            .flat_map(|f| (0..TILES_A_ROUND).map(move |k| (f, round * TILES_A_ROUND + k)))
            .map(|(f, k)| (f, tiles[k % tiles.len()]))
            .collect();
        let wall = Instant::now();
        let results: Vec<(f64, bool)> = batch
            .par_iter()
            .map(|(f, t)| timed(*t, &probed[*f]))
            .collect();
        let wall = wall.elapsed().as_secs_f64();
        let busy = (wall - overhead * batch.len() as f64 / threads as f64).max(0.1 * wall);
        let total: f64 = results.iter().map(|r| r.0).sum::<f64>().max(1e-12);
        let mut spent = vec![(0.0f64, 0u64); probed.len()];
        for (&(f, tile), &(t, done)) in batch.iter().zip(&results) {
            stopped |= !done;
            spent[f].0 += busy * t / total;
            spent[f].1 += u64::from(tile.w * tile.h);
        }
        let frames = spent.iter().map(|(t, px)| t / (*px).max(1) as f64);
        rates.push(frames.sum::<f64>() / probed.len() as f64);
        count += batch.len() as u64;
        let elapsed = clock.elapsed();
        let enough = round + 1 >= ROUNDS && elapsed >= MIN_PROBE;
        if stopped || enough || elapsed >= BUDGET {
            break;
        }
    }
    rates.sort_by(f64::total_cmp);
    let mid = rates.len() / 2;
    let median = match rates.len() % 2 {
        1 => rates[mid],
        _ => 0.5 * (rates[mid - 1] + rates[mid]),
    };
    Probe {
        seconds_a_pixel: median,
        tiles: count,
        side,
        frames: probed.len() as u64,
        stopped,
    }
}

/// Up to `FRAMES` of the job's frames, evenly spaced (the first and the last among them),
/// with their cameras; frames without one are left out.
fn probe_frames(seq: &Sequence, frames: &FrameSet) -> Vec<(u64, Exposure)> {
    let n = frames.len();
    let take = n.min(FRAMES);
    let picks: Vec<u64> = (0..take)
        .map(|i| match take {
            1 => 0,
            _ => i * (n - 1) / (take - 1),
        })
        .collect();
    let mut out = Vec::new();
    let mut it = frames.iter().enumerate();
    for pick in picks {
        let Some((_, frame)) = it.by_ref().find(|(i, _)| *i as u64 == pick) else {
            continue;
        };
        let view = seq.settings.frame_view(&seq.timeline, frame);
        if let Ok(e) = view.exposure {
            out.push((frame, e));
        }
    }
    out
}

/// A rectangle of the frame: top-left pixel and size.
#[derive(Debug, Clone, Copy)]
struct Tile {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
}

impl Tile {
    fn at(x: u32, y: u32, w: u32, h: u32) -> Tile {
        Tile { x, y, w, h }
    }
}

/// Tiles of `side` pixels centred on a 4×4 grid over the frame, in an order whose every run
/// of four spreads over the four quadrants.
fn tile_grid(w: u32, h: u32, side: u32) -> Vec<Tile> {
    const ORDER: [(u32, u32); 16] = [
        (0, 0),
        (2, 2),
        (2, 0),
        (0, 2),
        (1, 1),
        (3, 3),
        (3, 1),
        (1, 3),
        (1, 0),
        (3, 2),
        (3, 0),
        (1, 2),
        (0, 1),
        (2, 3),
        (2, 1),
        (0, 3),
    ];
    ORDER
        .iter()
        .map(|&(i, j)| {
            let cx = (2 * i + 1) * w / 8;
            let cy = (2 * j + 1) * h / 8;
            let x = cx.saturating_sub(side / 2).min(w - side);
            let y = cy.saturating_sub(side / 2).min(h - side);
            Tile::at(x, y, side, side)
        })
        .collect()
}

/// Renders `tile` of frame `n` (None when stopped).
fn render_tile(
    world: &World,
    s: &Settings,
    exposure: &Exposure,
    n: u64,
    tile: Tile,
    stop: &AtomicBool,
) -> Result<Option<()>, OutOfMemory> {
    let settings = Settings {
        width: tile.w,
        height: tile.h,
        ..*s
    };
    let turned = Exposure {
        camera: aimed(&exposure.camera, s, tile),
        instants: exposure
            .instants
            .iter()
            .map(|c| aimed(c, s, tile))
            .collect(),
        motion: exposure.motion.clone(),
    };
    tracer::render_or_stop(world, &turned, &settings, n, stop, false).map(|f| f.map(|_| ()))
}

/// `c` turned towards the centre of `tile` of a `s.width` × `s.height` frame, its field of
/// view the tile's width.
fn aimed(c: &Camera, s: &Settings, tile: Tile) -> Camera {
    let (w, h) = (f64::from(s.width), f64::from(s.height));
    let x = -1.0 + 2.0 * (f64::from(tile.x) + 0.5 * f64::from(tile.w)) / w;
    let y = (1.0 - 2.0 * (f64::from(tile.y) + 0.5 * f64::from(tile.h)) / h) * h / w;
    let t = c.tan_half_fov;
    let forward = (c.forward + c.right * (x * t) + c.up * (y * t)).normalize();
    let up = (c.up - forward * c.up.dot(forward)).normalize();
    Camera {
        forward,
        up,
        right: forward.cross(up),
        tan_half_fov: t * f64::from(tile.w) / w,
        ..*c
    }
}

/// Seconds one frame file of the job takes besides rendering: a frame of its size and
/// channels, of varied values (compression has work to do), encoded as `format`, written and
/// synced as frames are (to a temporary in the system's temporary folder, removed at once),
/// and checked as a finished run checks what it wrote.
fn encode_seconds(seq: &Sequence, format: &FileFormat, n: u64) -> f64 {
    let s = &seq.settings;
    let pixels = (s.width * s.height) as usize;
    let mut frame = crate::frame::Frame {
        width: s.width,
        height: s.height,
        rgb: (0..3 * pixels)
            .map(|i| ((i * 7919) % 997) as f32 / 997.0)
            .collect(),
        depth: s.depth.then(|| vec![1.0; pixels]),
        alpha: s.alpha.then(|| vec![1.0; pixels]),
        aov: None,
        encoding: s.encoding,
        non_finite: 0,
        samples: 0,
        rays: 0,
        levels8: None,
    };
    let view = s.frame_view(&seq.timeline, n);
    let meta = RunIdentity::new(seq, format).meta(&view);
    let t = Instant::now();
    let Ok((bytes, _)) = crate::output::encode_file(&mut frame, format, &meta) else {
        return t.elapsed().as_secs_f64();
    };
    let temp = std::env::temp_dir().join(format!(".rayreel-estimate-{}", std::process::id()));
    let _ = crate::output::atomic::write_atomic(&temp, &bytes);
    let _ = std::fs::remove_file(&temp);
    let expected = Expected {
        width: s.width,
        height: s.height,
        format: *format,
        alpha: s.alpha,
    };
    let _ = match format {
        FileFormat::Png { .. } => crate::output::png::inspect(&bytes, &expected),
        FileFormat::Exr { .. } => crate::output::exr::inspect(&bytes, &expected),
    };
    t.elapsed().as_secs_f64()
}

/// Sets `stop` once `HARD_STOP` has passed, unless dropped first.
struct Watchdog {
    done: Arc<AtomicBool>,
}

impl Watchdog {
    fn start(stop: &Arc<AtomicBool>) -> Watchdog {
        let done = Arc::new(AtomicBool::new(false));
        let (flag, stop) = (done.clone(), stop.clone());
        std::thread::spawn(move || {
            let start = Instant::now();
            while !flag.load(Ordering::Relaxed) {
                if start.elapsed() >= HARD_STOP {
                    stop.store(true, Ordering::Relaxed);
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        });
        Watchdog { done }
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
    }
}

/// `about 45 s`, `about 12 min`, `about 3.4 h`, `about 2.1 days`: two significant digits.
pub(crate) fn duration(seconds: f64) -> String {
    let (value, unit) = match seconds {
        s if s < 0.005 => return "under 0.01 s".into(),
        s if s < 1.0 => return format!("{:.2} s", s),
        s if s < 120.0 => (s, "s"),
        s if s < 7200.0 => (s / 60.0, "min"),
        s if s < 172_800.0 => (s / 3600.0, "h"),
        s => (s / 86_400.0, "days"),
    };
    let text = match value {
        v if v >= 10.0 => format!("{v:.0}"),
        v => format!("{v:.1}"),
    };
    format!("{text} {unit}")
}
