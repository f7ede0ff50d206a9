//! `rayreel preview FILE`: two pictures to check a sequence before spending hours rendering it.
//!
//! * The **path plot** shows the scene from above (x across, z down) and from the side (z
//!   across, y up), each panel to scale (one scale for both of its axes). Spheres are discs in
//!   their material's colour; planes and giant spheres (a floor of radius 9000) would cover
//!   everything, so they are drawn as the solid region they cut from the panel's slice plane,
//!   which passes through the camera path's mean height (top) or mean x (side). On top: the
//!   camera at every frame (a polyline, with dots when they are far enough apart to show
//!   speed), numbered keyframes, look-at targets, view-direction ticks, start, end and lights.
//!   Frames where the camera is inside a sphere, behind a plane or rolling over are red and
//!   come back as warnings.
//! * The **contact sheet** renders a few frames small at draft depth, `columns = ceil(sqrt(N))`
//!   tiles per row, each with its frame number and time underneath.
//!
//! Everything is drawn with plain pixel writes and a built-in 5×7 font, so the preview needs
//! no font or plotting crate and is byte-identical everywhere.

mod speed;

use crate::camera::{Camera, Pose};
use crate::scene::{Light, Material, Shape};
use crate::schedule::render_with;
use crate::sequence::Sequence;
use crate::timeline::{Path as TimelinePath, Timeline};
use crate::tracer::World;
use glam::DVec3;
use image::{Rgb, RgbImage};
use std::path::Path;

/// The camera path's colour; nothing else in a panel uses it, so tests can find the trace.
pub const PATH: Rgb<u8> = Rgb([0, 92, 230]);
/// The path where the camera is inside an object, and warning text.
pub const BAD: Rgb<u8> = Rgb([225, 25, 25]);
const BACKGROUND: Rgb<u8> = Rgb([246, 246, 244]);
const PANEL: Rgb<u8> = Rgb([255, 255, 255]);
const GRID: Rgb<u8> = Rgb([234, 234, 234]);
const AXIS: Rgb<u8> = Rgb([200, 200, 200]);
const BORDER: Rgb<u8> = Rgb([150, 150, 150]);
const INK: Rgb<u8> = Rgb([30, 30, 30]);
const MUTED: Rgb<u8> = Rgb([120, 120, 120]);
const LABEL: Rgb<u8> = Rgb([80, 80, 80]);
const KEYFRAME: Rgb<u8> = Rgb([20, 20, 20]);
const TARGET: Rgb<u8> = Rgb([240, 130, 0]);
const TARGET_LINK: Rgb<u8> = Rgb([250, 200, 150]);
const TICK: Rgb<u8> = Rgb([160, 80, 10]);
const START: Rgb<u8> = Rgb([0, 170, 70]);
const END: Rgb<u8> = Rgb([150, 40, 200]);
const LIGHT: Rgb<u8> = Rgb([255, 205, 0]);

/// Default number of contact-sheet tiles.
pub const DEFAULT_TILES: u64 = 12;
/// Most tiles one sheet holds: beyond this the picture stops being a glance.
pub const MAX_TILES: u64 = 400;
/// Default tile width in pixels; the height follows the sequence's aspect ratio.
pub const TILE_WIDTH: u32 = 256;

// ---------------------------------------------------------------------------------------------
// Which frames, and how small

/// `n` frames spread evenly over `0..frame_count`, first and last included:
/// n_k = round(k·(frame_count − 1)/(n − 1)), ascending and without repeats.
pub fn evenly_spaced(frame_count: u64, n: u64) -> Vec<u64> {
    if frame_count == 0 || n == 0 {
        return Vec::new();
    }
    if n == 1 {
        return vec![0];
    }
    // Steps shorter than one frame round onto every frame: skip building n values.
    if n >= frame_count {
        return (0..frame_count).collect();
    }
    let (last, d) = (u128::from(frame_count - 1), u128::from(n - 1));
    // Integer rounding (half up) so the choice is exact for any frame count.
    let mut out: Vec<u64> = (0..u128::from(n))
        .map(|k| ((2 * k * last + d) / (2 * d)) as u64)
        .collect();
    out.dedup();
    out
}

/// The sequence as the contact sheet renders it: the draft preset (1 sample, 2 surfaces per
/// path, which keeps reflections visible but cheap) at `tile_w`×`tile_h` pixels.
pub fn draft(seq: &Sequence, tile_w: u32, tile_h: u32) -> Sequence {
    let mut d = seq.clone();
    crate::sequence::preset(&mut d.settings, crate::sequence::Quality::Draft);
    d.settings.width = tile_w;
    d.settings.height = tile_h;
    d
}

/// The tile height for `tile_w` with the sequence's aspect ratio, rounded, at least 1.
pub fn tile_height(seq: &Sequence, tile_w: u32) -> u32 {
    let (w, h) = (
        f64::from(seq.settings.width),
        f64::from(seq.settings.height),
    );
    ((f64::from(tile_w) * h / w).round() as u32).max(1)
}

// ---------------------------------------------------------------------------------------------
// Contact sheet

const SHEET_BACKGROUND: Rgb<u8> = Rgb([34, 34, 38]);
const SHEET_TEXT: Rgb<u8> = Rgb([235, 235, 235]);
const SHEET_DIM: Rgb<u8> = Rgb([150, 150, 160]);
const SHEET_GAP: u32 = 8;
const SHEET_HEADER: u32 = 34;
const LABEL_STRIP: u32 = 24;

/// Where the tiles of a contact sheet go: `columns = ceil(sqrt(tiles))`, row by row, with a
/// header line on top and a label strip under every tile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SheetLayout {
    pub columns: u32,
    pub rows: u32,
    pub tile_w: u32,
    pub tile_h: u32,
    pub width: u32,
    pub height: u32,
}

impl SheetLayout {
    pub fn new(tiles: usize, tile_w: u32, tile_h: u32) -> SheetLayout {
        let tiles = tiles.max(1) as u32;
        let columns = (f64::from(tiles).sqrt().ceil() as u32).max(1);
        let rows = tiles.div_ceil(columns);
        SheetLayout {
            columns,
            rows,
            tile_w,
            tile_h,
            width: SHEET_GAP + columns * (tile_w + SHEET_GAP),
            height: SHEET_HEADER + rows * (tile_h + LABEL_STRIP + SHEET_GAP),
        }
    }

    /// Top-left pixel of tile `k`.
    pub fn origin(&self, k: usize) -> (u32, u32) {
        let (col, row) = (k as u32 % self.columns, k as u32 / self.columns);
        (
            SHEET_GAP + col * (self.tile_w + SHEET_GAP),
            SHEET_HEADER + row * (self.tile_h + LABEL_STRIP + SHEET_GAP),
        )
    }
}

/// (frame, x, y): which frame a contact-sheet tile shows and its top-left pixel.
pub type TileOrigin = (u64, u32, u32);

/// Renders `frames` at draft quality, `tile_w` pixels wide, into one picture; returns it with
/// each tile's (frame, x, y) origin.
pub fn contact_sheet(
    seq: &Sequence,
    frames: &[u64],
    tile_w: u32,
) -> Result<(RgbImage, Vec<TileOrigin>), String> {
    let count = seq.timeline.frame_count;
    if frames.is_empty() {
        return Err("no frames to put on the contact sheet".into());
    }
    if let Some(n) = frames.iter().find(|&&n| n >= count) {
        return Err(format!(
            "frame {n} is outside the timeline, which has frames 0-{}",
            count - 1
        ));
    }
    let tile_h = tile_height(seq, tile_w);
    let small = draft(seq, tile_w, tile_h);
    let layout = SheetLayout::new(frames.len(), tile_w, tile_h);
    let mut img = RgbImage::from_pixel(layout.width, layout.height, SHEET_BACKGROUND);
    sheet_header(
        &mut img,
        seq,
        frames.len(),
        tile_w,
        tile_h,
        small.settings.max_depth,
    );
    let mut origins = Vec::with_capacity(frames.len());
    let world = World::new(small.scene.clone());
    for (k, &n) in frames.iter().enumerate() {
        let (x, y) = layout.origin(k);
        match render_with(&world, &small, n, &small.settings) {
            Ok(frame) => paste(&mut img, &frame.to_rgb8(), (x, y), (tile_w, tile_h)),
            // An invalid path (see `sequence::load_drawable`) has frames with no camera.
            Err(_) => no_camera(&mut img, (x, y), (tile_w, tile_h)),
        }
        tile_label(&mut img, seq, n, (x, y + tile_h), tile_w);
        origins.push((n, x, y));
    }
    Ok((img, origins))
}

fn sheet_header(img: &mut RgbImage, seq: &Sequence, tiles: usize, w: u32, h: u32, depth: u32) {
    let mut c = Canvas::whole(img);
    let t = &seq.timeline;
    let head = format!("{}: {tiles} of {} frames", seq.name, t.frame_count);
    let x = c.text(SHEET_GAP as i64, 10, &head, 2, SHEET_TEXT);
    let note = format!("   draft {w}x{h}, max_depth {depth}");
    c.text(x, 10, &note, 2, SHEET_DIM);
}

/// Copies rgb8 bytes of a `size` picture into `img` at `at`.
fn paste(img: &mut RgbImage, pixels: &[u8], at: (u32, u32), size: (u32, u32)) {
    for row in 0..size.1 {
        for col in 0..size.0 {
            let i = 3 * (row * size.0 + col) as usize;
            let p = Rgb([pixels[i], pixels[i + 1], pixels[i + 2]]);
            img.put_pixel(at.0 + col, at.1 + row, p);
        }
    }
}

/// A red tile saying that this frame has no camera.
fn no_camera(img: &mut RgbImage, at: (u32, u32), size: (u32, u32)) {
    let (x, y) = (i64::from(at.0), i64::from(at.1));
    let rect = Rect::new(x, y, x + i64::from(size.0), y + i64::from(size.1));
    let mut c = Canvas::new(img, rect);
    c.fill(Rgb([90, 20, 20]));
    c.text(x + 6, y + 6, "no camera", 2, SHEET_TEXT);
}

/// `12  0.50s` under a tile: the number bright, the time dimmer, clipped to the tile's width.
fn tile_label(img: &mut RgbImage, seq: &Sequence, n: u64, at: (u32, u32), w: u32) {
    let (x, y) = (i64::from(at.0), i64::from(at.1));
    let clip = Rect::new(x, y, x + i64::from(w), y + i64::from(LABEL_STRIP));
    let mut c = Canvas::new(img, clip);
    let after = c.text(x + 2, y + 5, &n.to_string(), 2, SHEET_TEXT);
    let time = format!("  {:.2}s", seq.timeline.time_of(n));
    c.text(after, y + 5, &time, 2, SHEET_DIM);
}

/// Encodes `img` as PNG and writes it atomically (a complete file or none) to `path`.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<(), String> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| format!("{}: cannot encode: {e}", path.display()))?;
    crate::output::atomic::write_atomic(path, bytes.get_ref())
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))
}

// ---------------------------------------------------------------------------------------------
// What the path plot shows: samples, problems, fit

/// Above this many frames the path is drawn from evenly spaced samples: a smooth path loses
/// nothing visible, and the plot stays fast for timelines of millions of frames.
const MAX_PATH_SAMPLES: u64 = 100_000;
/// A sphere this many times larger than the whole camera motion and view (a floor of radius
/// 9000, a sky dome) is scenery: its silhouette would fill both panels, so it is drawn like a
/// plane and left out of the fit.
const HUGE_SPHERE: f64 = 10.0;
/// Look-at targets and lights farther out than this fraction of the scene's size (beyond the
/// box of path and objects) would shrink the scene to a speck (a sun at 1e5); they are drawn
/// at the panel edge with their coordinates instead of being fitted.
const EXTRA_REACH: f64 = 0.5;
/// View-direction ticks drawn along the path.
const TICKS: u64 = 12;

/// Everything the path plot draws, computed once from the sequence.
struct Plot {
    /// (frame, pose) for every frame, or evenly spaced samples of very long timelines.
    samples: Vec<(u64, Pose)>,
    /// Per sample: the camera is inside an object or rolls over there.
    bad: Vec<bool>,
    warnings: Vec<String>,
    /// Keyframe (position, look_at), numbered by index.
    keys: Vec<(DVec3, DVec3)>,
    /// Distinct look-at targets of the keyframes, or the orbit's.
    targets: Vec<DVec3>,
    /// Per object: a sphere too big to draw as a disc.
    huge: Vec<bool>,
    /// The box the panels are fitted to.
    fit: Bounds,
}

impl Plot {
    fn new(seq: &Sequence) -> Plot {
        let t = &seq.timeline;
        let samples: Vec<(u64, Pose)> = evenly_spaced(t.frame_count, MAX_PATH_SAMPLES)
            .into_iter()
            .map(|n| (n, t.pose_of(n)))
            .collect();
        let (bad, warnings) = problems(seq, &samples);
        let (keys, targets) = keys_and_targets(t);
        let huge = huge_spheres(seq, &samples);
        let mut plot = Plot {
            samples,
            bad,
            warnings,
            keys,
            targets,
            huge,
            fit: Bounds::EMPTY,
        };
        plot.fit = fit(seq, &plot);
        plot
    }
}

fn keys_and_targets(t: &Timeline) -> (Vec<(DVec3, DVec3)>, Vec<DVec3>) {
    match &t.path {
        TimelinePath::Orbit(o) => (Vec::new(), vec![o.look_at]),
        TimelinePath::Keys(keyed) => {
            let keys = &keyed.keys;
            let mut targets: Vec<DVec3> = Vec::new();
            for k in keys {
                if !targets.contains(&k.pose.look_at) {
                    targets.push(k.pose.look_at);
                }
            }
            let keyed = keys.iter().map(|k| (k.pose.position, k.pose.look_at));
            (keyed.collect(), targets)
        }
    }
}

/// Point and spot lights: (index in `lights`, position).
fn positioned_lights(seq: &Sequence) -> Vec<(usize, DVec3)> {
    let at = |l: &Light| match *l {
        Light::Point { position, .. } | Light::Spot { position, .. } => Some(position),
        _ => None,
    };
    let lights = seq.scene.lights.iter().enumerate();
    lights.filter_map(|(i, l)| at(l).map(|p| (i, p))).collect()
}

/// Checks every sampled frame: inside a sphere, behind a plane (the side its normal points
/// away from), or a camera that cannot be built or rolls over since the previous frame.
fn problems(seq: &Sequence, samples: &[(u64, Pose)]) -> (Vec<bool>, Vec<String>) {
    let mut bad = vec![false; samples.len()];
    let mut warnings = Vec::new();
    let positions: Vec<DVec3> = samples.iter().map(|(_, p)| p.position).collect();
    let frames: Vec<u64> = samples.iter().map(|(n, _)| *n).collect();
    for (what, flags) in inside_objects(seq, &positions) {
        report(&flags, &frames, &what, &mut bad, &mut warnings);
    }
    let rolls = roll_flags(samples);
    let what = "the camera cannot be built or rolls over by more than 60° from the previous frame";
    report(&rolls, &frames, what, &mut bad, &mut warnings);
    (bad, warnings)
}

/// Distance tests `inside_warnings` may spend: the frames it samples shrink as objects grow.
const INSIDE_BUDGET: u64 = 20_000_000;

/// `frames 9-11: the camera is inside objects[0] (sphere)` for every run of frames where the
/// camera is inside a sphere or behind a plane; `check` and `render` print these. Long
/// timelines are sampled (every frame up to 100 000, fewer in scenes of many objects).
pub fn inside_warnings(seq: &Sequence) -> Vec<String> {
    let t = &seq.timeline;
    let objects = seq.scene.objects.len().max(1) as u64;
    let n = (INSIDE_BUDGET / objects).clamp(100, MAX_PATH_SAMPLES);
    let frames = evenly_spaced(t.frame_count, n);
    let positions: Vec<DVec3> = frames.iter().map(|&f| t.pose_of(f).position).collect();
    let mut bad = vec![false; frames.len()];
    let mut warnings = Vec::new();
    for (what, flags) in inside_objects(seq, &positions) {
        report(&flags, &frames, &what, &mut bad, &mut warnings);
    }
    warnings
}

/// Per object the camera enters: what to call it and, per position, whether it is inside.
fn inside_objects(seq: &Sequence, positions: &[DVec3]) -> Vec<(String, Vec<bool>)> {
    let mut reach = Bounds::EMPTY;
    for &p in positions {
        reach.add(p);
    }
    let mut out = Vec::new();
    for (i, o) in seq.scene.objects.iter().enumerate() {
        let (flags, what): (Vec<bool>, _) = match o.shape {
            // A sphere whose box misses every position's box cannot hold one.
            Shape::Sphere { center, radius } if !reach.grown(radius).contains(center) => continue,
            Shape::Sphere { center, radius } => (
                positions
                    .iter()
                    .map(|p| p.distance(center) < radius)
                    .collect(),
                format!("the camera is inside objects[{i}] (sphere)"),
            ),
            Shape::Plane { point, normal } => (
                positions
                    .iter()
                    .map(|&p| (p - point).dot(normal) < 0.0)
                    .collect(),
                format!("the camera is behind objects[{i}] (plane), against its normal"),
            ),
        };
        if flags.contains(&true) {
            out.push((what, flags));
        }
    }
    out
}

/// Turns per-sample flags into one warning per run of consecutive flagged samples.
fn report(
    flags: &[bool],
    frames: &[u64],
    what: &str,
    bad: &mut [bool],
    warnings: &mut Vec<String>,
) {
    let mut i = 0;
    while i < flags.len() {
        if !flags[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < flags.len() && flags[i] {
            bad[i] = true;
            i += 1;
        }
        let (a, b) = (frames[start], frames[i - 1]);
        let frames = if a == b {
            format!("frame {a}")
        } else {
            format!("frames {a}-{b}")
        };
        warnings.push(format!("{frames}: {what}"));
    }
}

/// The load-time roll check (`sequence::check_every_frame`) repeated on the samples, so a
/// sequence built in code is flagged too.
fn roll_flags(samples: &[(u64, Pose)]) -> Vec<bool> {
    let limit = crate::sequence::MAX_ROLL_PER_FRAME_DEGREES
        .to_radians()
        .cos();
    let mut previous: Option<DVec3> = None;
    let mut flags = Vec::with_capacity(samples.len());
    for (_, pose) in samples {
        let flag = match Camera::new(pose) {
            Ok(c) => {
                let rolled = previous.is_some_and(|r| r.dot(c.right) < limit);
                previous = Some(c.right);
                rolled
            }
            Err(_) => true,
        };
        flags.push(flag);
    }
    flags
}

/// Spheres much larger than everything the camera does and looks at.
fn huge_spheres(seq: &Sequence, samples: &[(u64, Pose)]) -> Vec<bool> {
    let mut reach = Bounds::EMPTY;
    for (_, p) in samples {
        reach.add(p.position);
        reach.add(p.look_at);
    }
    let size = reach.size().length().max(f64::MIN_POSITIVE);
    let huge = |o: &crate::scene::Object| match o.shape {
        Shape::Sphere { radius, .. } => radius > HUGE_SPHERE * size,
        Shape::Plane { .. } => false,
    };
    seq.scene.objects.iter().map(huge).collect()
}

/// The box both panels show: the camera path, the keyframes (the last may lie beyond the last
/// frame) and the ordinary spheres, plus look-at targets and lights not far outside them.
fn fit(seq: &Sequence, plot: &Plot) -> Bounds {
    let mut core = Bounds::EMPTY;
    let keys = plot.keys.iter().map(|k| k.0);
    for p in plot.samples.iter().map(|(_, p)| p.position).chain(keys) {
        core.add(p);
    }
    for (o, &huge) in seq.scene.objects.iter().zip(&plot.huge) {
        if let (Shape::Sphere { center, radius }, false) = (o.shape, huge) {
            core.add(center - DVec3::splat(radius));
            core.add(center + DVec3::splat(radius));
        }
    }
    // A still camera with nothing around it still needs a size: its distance to the target.
    let first = plot.samples[0].1;
    let floor = first.position.distance(first.look_at).max(1e-300);
    let size = core.size().max_element().max(floor);
    let near = core.grown(EXTRA_REACH * size);
    let mut all = core;
    let lights = positioned_lights(seq).into_iter().map(|(_, p)| p);
    for p in plot.targets.iter().copied().chain(lights) {
        if near.contains(p) {
            all.add(p);
        }
    }
    // No axis may be flat, or a panel's scale would be infinite.
    let min = 0.1 * all.size().max_element().max(floor);
    all.at_least(min)
}

#[derive(Debug, Clone, Copy)]
struct Bounds {
    min: DVec3,
    max: DVec3,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    fn add(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn size(&self) -> DVec3 {
        (self.max - self.min).max(DVec3::ZERO)
    }

    fn grown(&self, by: f64) -> Bounds {
        Bounds {
            min: self.min - DVec3::splat(by),
            max: self.max + DVec3::splat(by),
        }
    }

    fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Widens every axis shorter than `min` around its middle.
    fn at_least(&self, min: f64) -> Bounds {
        let mid = (self.min + self.max) / 2.0;
        let half = self.size().max(DVec3::splat(min)) / 2.0;
        Bounds {
            min: mid - half,
            max: mid + half,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Panels: world ↔ pixels

const PANEL_H: u32 = 600;
const PANEL_MIN_W: u32 = 380;
const PANEL_MAX_W: u32 = 860;
/// Inner padding, so markers and labels at the edge of the fitted box stay inside.
const PAD: f64 = 34.0;
const MARGIN: u32 = 20;
const TITLE_H: u32 = 40;
const CAPTION_H: u32 = 26;
const PANEL_GAP: u32 = 24;
const LEGEND_ROW: u32 = 26;
const WARNING_ROW: u32 = 20;
/// Warnings written into the picture; the rest are only counted (all go to stderr).
const MAX_WARNING_LINES: usize = 4;

/// One panel of the path plot: a pixel rectangle showing two world axes at one scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Panel {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    /// World axis shown left to right (0 = x, 1 = y, 2 = z).
    pub across: usize,
    /// World axis shown vertically.
    pub down: usize,
    /// Whether `down` grows downwards on screen (the top view's z) rather than up (side's y).
    pub flipped: bool,
    /// Pixels per scene unit, the same on both axes.
    pub scale: f64,
    /// World (across, down) coordinates at the panel's centre.
    pub centre: (f64, f64),
    /// Where the slice plane for planes and giant spheres cuts the third axis.
    pub slice: f64,
}

impl Panel {
    /// Pixel coordinates of `p` (continuous: pixel (i, j) covers [i, i+1) × [j, j+1)).
    pub fn to_px(&self, p: DVec3) -> (f64, f64) {
        let (a, b) = (p[self.across] - self.centre.0, p[self.down] - self.centre.1);
        let sign = if self.flipped { 1.0 } else { -1.0 };
        (
            f64::from(self.x) + f64::from(self.width) / 2.0 + a * self.scale,
            f64::from(self.y) + f64::from(self.height) / 2.0 + sign * b * self.scale,
        )
    }

    /// The point on the slice plane under pixel position (x, y).
    fn world_at(&self, x: f64, y: f64) -> DVec3 {
        let sign = if self.flipped { 1.0 } else { -1.0 };
        let a = (x - f64::from(self.x) - f64::from(self.width) / 2.0) / self.scale;
        let b = sign * (y - f64::from(self.y) - f64::from(self.height) / 2.0) / self.scale;
        let mut p = DVec3::splat(self.slice);
        p[self.across] = self.centre.0 + a;
        p[self.down] = self.centre.1 + b;
        p
    }

    /// The axis the panel looks along.
    fn depth_axis(&self) -> usize {
        3 - self.across - self.down
    }

    /// +1 when larger coordinates along the depth axis are nearer the viewer.
    fn toward_viewer(&self) -> f64 {
        // Right-handed: right × up points at the viewer.
        let (mut r, mut u) = (DVec3::ZERO, DVec3::ZERO);
        r[self.across] = 1.0;
        u[self.down] = if self.flipped { -1.0 } else { 1.0 };
        r.cross(u)[self.depth_axis()]
    }

    fn rect(&self) -> Rect {
        let (x, y) = (i64::from(self.x), i64::from(self.y));
        Rect::new(x, y, x + i64::from(self.width), y + i64::from(self.height))
    }

    fn centre_px(&self) -> (f64, f64) {
        (
            f64::from(self.x) + f64::from(self.width) / 2.0,
            f64::from(self.y) + f64::from(self.height) / 2.0,
        )
    }
}

/// The top view (x across, z down: seen from above) and the side view (z across, y up: seen
/// from −x), as `path_plot` draws them.
pub fn panels(seq: &Sequence) -> [Panel; 2] {
    layout(&Plot::new(seq))
}

fn layout(plot: &Plot) -> [Panel; 2] {
    let mean = plot
        .samples
        .iter()
        .fold(DVec3::ZERO, |s, (_, p)| s + p.position)
        / plot.samples.len() as f64;
    let y = MARGIN + TITLE_H + CAPTION_H;
    let top = fit_panel(&plot.fit, (0, 2, true), mean.y, (MARGIN, y));
    let side_x = MARGIN + top.width + PANEL_GAP;
    let side = fit_panel(&plot.fit, (2, 1, false), mean.x, (side_x, y));
    [top, side]
}

/// A panel whose width follows the box's aspect ratio (within limits) and whose scale fits it.
fn fit_panel(b: &Bounds, axes: (usize, usize, bool), slice: f64, at: (u32, u32)) -> Panel {
    let (across, down, flipped) = axes;
    let size = b.size();
    let (ra, rb) = (size[across], size[down]);
    let inner_h = f64::from(PANEL_H) - 2.0 * PAD;
    let want = inner_h * ra / rb + 2.0 * PAD;
    let width = (want.round() as u32).clamp(PANEL_MIN_W, PANEL_MAX_W);
    let scale = ((f64::from(width) - 2.0 * PAD) / ra).min(inner_h / rb);
    let mid = (b.min + b.max) / 2.0;
    Panel {
        x: at.0,
        y: at.1,
        width,
        height: PANEL_H,
        across,
        down,
        flipped,
        scale,
        centre: (mid[across], mid[down]),
        slice,
    }
}

// ---------------------------------------------------------------------------------------------
// The path plot

/// Draws the path plot and, under it, the speed panel; returns the picture with the warnings
/// (without a `warning: ` prefix). `invalid` is why the file cannot render, written in red.
pub fn path_plot(seq: &Sequence, invalid: Option<&str>) -> (RgbImage, Vec<String>) {
    let plot = Plot::new(seq);
    let [top, side] = layout(&plot);
    let width = (side.x + side.width + MARGIN).max(LEGEND_MIN_W);
    let speed_y = top.y + PANEL_H + CAPTION_H + 16;
    let speed_rect = Rect::new(
        i64::from(MARGIN),
        i64::from(speed_y),
        i64::from(width - MARGIN),
        i64::from(speed_y + speed::HEIGHT),
    );
    let legend_y = speed_y + speed::HEIGHT + 16;
    let columns = ((width - 2 * MARGIN) / (ADVANCE as u32 * 2)) as usize;
    let invalid = invalid.map(|why| format!("invalid: {}", why.replace('`', "'")));
    let warned = plot.warnings.iter().take(MAX_WARNING_LINES);
    let notes = invalid
        .into_iter()
        .chain(warned.map(|w| format!("warning: {w}")));
    let mut lines: Vec<String> = notes.flat_map(|n| wrap(&n, columns)).collect();
    if plot.warnings.len() > MAX_WARNING_LINES {
        let more = plot.warnings.len() - MAX_WARNING_LINES;
        lines.push(format!("... and {more} more warnings (on stderr)"));
    }
    let notes_y = legend_y + 2 * LEGEND_ROW + 8;
    let height = notes_y + lines.len() as u32 * WARNING_ROW + MARGIN;
    let mut img = RgbImage::from_pixel(width, height, BACKGROUND);
    title(&mut img, seq);
    for panel in [&top, &side] {
        caption(&mut img, panel);
        draw_panel(&mut img, panel, seq, &plot);
    }
    let mut c = Canvas::whole(&mut img);
    let what = "speed along the path (scene units per second) against time; squares: keyframes";
    c.text(i64::from(MARGIN), speed_rect.y0 - 22, what, 2, INK);
    let mut c = Canvas::new(&mut img, speed_rect);
    speed::draw(&mut c, speed_rect, seq, &plot.samples, &plot.bad);
    legend(&mut img, legend_y);
    red_lines(&mut img, &lines, notes_y);
    (img, plot.warnings)
}

/// Words of `text` in lines of at most `columns` characters (a longer word gets its own line).
fn wrap(text: &str, columns: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if line.chars().count() + 1 + word.chars().count() <= columns => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

fn title(img: &mut RgbImage, seq: &Sequence) {
    let t = &seq.timeline;
    let motion = match &t.path {
        TimelinePath::Orbit(o) => format!("orbit of radius {}", fmt_num(o.radius)),
        TimelinePath::Keys(k) if k.keys.len() == 1 => "still camera".into(),
        TimelinePath::Keys(k) => {
            format!("{} keyframes, {:?}", k.keys.len(), k.interpolation).to_lowercase()
        }
    };
    let frames = match t.frame_count {
        1 => "1 frame".to_string(),
        n => format!("{n} frames"),
    };
    let text = format!(
        "{}: {frames} at {} fps ({:.2} s), {motion}",
        seq.name,
        fmt_num(t.fps),
        t.frame_count as f64 / t.fps
    );
    Canvas::whole(img).text(i64::from(MARGIN), i64::from(MARGIN), &text, 2, INK);
}

fn caption(img: &mut RgbImage, p: &Panel) {
    let text = if p.flipped {
        "top view: x across, z down"
    } else {
        "side view: z across, y up"
    };
    let y = i64::from(p.y) - 22;
    Canvas::whole(img).text(i64::from(p.x), y, text, 2, INK);
}

fn draw_panel(img: &mut RgbImage, p: &Panel, seq: &Sequence, plot: &Plot) {
    let mut c = Canvas::new(img, p.rect());
    c.fill(PANEL);
    draw_solids(&mut c, p, seq, plot);
    draw_grid(&mut c, p);
    draw_spheres(&mut c, p, seq, plot);
    draw_target_links(&mut c, p, plot);
    draw_path(&mut c, p, plot);
    draw_ticks(&mut c, p, plot);
    draw_targets(&mut c, p, plot);
    draw_lights(&mut c, p, seq);
    draw_ends(&mut c, p, plot);
    // Last, so labels of far-off targets and lights never hide a keyframe.
    draw_keys(&mut c, p, plot);
    draw_gizmo(&mut c, p);
    c.frame_rect(p.rect(), BORDER);
}

/// Planes and giant spheres, as the solid region they cut from the slice plane, tinted with
/// their material; a camera inside one is obvious.
fn draw_solids(c: &mut Canvas, p: &Panel, seq: &Sequence, plot: &Plot) {
    for (o, &huge) in seq.scene.objects.iter().zip(&plot.huge) {
        let material = &seq.scene.materials[o.material];
        let (fill, edge) = (tint(material, 0.22), shade(material));
        match o.shape {
            Shape::Plane { point, normal } => c.mask(
                p.rect(),
                |x, y| (p.world_at(x, y) - point).dot(normal) < 0.0,
                fill,
                edge,
            ),
            Shape::Sphere { center, radius } if huge => c.mask(
                p.rect(),
                |x, y| p.world_at(x, y).distance(center) < radius,
                fill,
                edge,
            ),
            Shape::Sphere { .. } => {}
        }
    }
}

/// Light lines every 1, 2 or 5 × 10^k units, the world axes a little darker, and the
/// spacing written in the corner.
fn draw_grid(c: &mut Canvas, p: &Panel) {
    let r = p.rect();
    let (w, h) = (f64::from(p.width) / p.scale, f64::from(p.height) / p.scale);
    let step = nice_step(w.max(h) / 8.0);
    let (lo_a, lo_b) = (p.centre.0 - w / 2.0, p.centre.1 - h / 2.0);
    for k in (lo_a / step).ceil() as i64..=((lo_a + w) / step).floor() as i64 {
        let mut q = DVec3::ZERO;
        q[p.across] = k as f64 * step;
        let x = p.to_px(q).0;
        let colour = if k == 0 { AXIS } else { GRID };
        c.line((x, r.y0 as f64), (x, r.y1 as f64), 1.0, colour);
    }
    for k in (lo_b / step).ceil() as i64..=((lo_b + h) / step).floor() as i64 {
        let mut q = DVec3::ZERO;
        q[p.down] = k as f64 * step;
        let y = p.to_px(q).1;
        let colour = if k == 0 { AXIS } else { GRID };
        c.line((r.x0 as f64, y), (r.x1 as f64, y), 1.0, colour);
    }
    let label = format!("grid {}", fmt_num(step));
    let x = r.x1 - 8 - text_width(&label, 1);
    c.text(x, r.y0 + 8, &label, 1, MUTED);
}

/// Ordinary spheres as discs, far ones first so near ones cover them, labelled `[i]` as the
/// warnings name them.
fn draw_spheres(c: &mut Canvas, p: &Panel, seq: &Sequence, plot: &Plot) {
    let mut order: Vec<(usize, DVec3, f64)> = Vec::new();
    for (i, o) in seq.scene.objects.iter().enumerate() {
        if let (Shape::Sphere { center, radius }, false) = (o.shape, plot.huge[i]) {
            order.push((i, center, radius));
        }
    }
    let (axis, toward) = (p.depth_axis(), p.toward_viewer());
    order.sort_by(|a, b| (toward * a.1[axis]).total_cmp(&(toward * b.1[axis])));
    for (i, center, radius) in order {
        let material = &seq.scene.materials[seq.scene.objects[i].material];
        let (cx, cy) = p.to_px(center);
        let r = radius * p.scale;
        let bbox = Rect::around((cx, cy), r + 2.0);
        let inside = |x: f64, y: f64| (x - cx).hypot(y - cy) < r;
        c.mask(bbox, inside, tint(material, 0.45), shade(material));
        let label = format!("[{i}]");
        // Inside the disc when it fits (large, else small type), otherwise just right of it.
        let fits = |scale: i64| 2.0 * r > (text_width(&label, scale) + 6) as f64;
        let scale = if fits(2) { 2 } else { 1 };
        let lw = text_width(&label, scale) as f64;
        let lx = if fits(scale) {
            cx - lw / 2.0
        } else {
            cx + r + 4.0
        };
        let ly = cy - 3.5 * scale as f64;
        c.text(lx.round() as i64, ly.round() as i64, &label, scale, LABEL);
    }
}

/// Faint dashed lines from each keyframe to its look-at target, and the look-at track when
/// the target moves.
fn draw_target_links(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for &(pos, look) in &plot.keys {
        c.dashed(p.to_px(pos), p.to_px(look), 6.0, TARGET_LINK);
    }
    if plot.targets.len() > 1 {
        let track = plot.samples.iter().map(|(_, pose)| p.to_px(pose.look_at));
        c.polyline(track, 1.0, TARGET);
    }
}

fn draw_path(c: &mut Canvas, p: &Panel, plot: &Plot) {
    let pts: Vec<(f64, f64)> = plot
        .samples
        .iter()
        .map(|(_, s)| p.to_px(s.position))
        .collect();
    for i in 1..pts.len() {
        let bad = plot.bad[i - 1] || plot.bad[i];
        let (w, colour) = if bad { (4.0, BAD) } else { (2.0, PATH) };
        c.line(pts[i - 1], pts[i], w, colour);
    }
    // Dots at the frames show speed (bunched up near a stop) when they are far enough apart.
    let every = dot_stride(&pts);
    for (i, &pt) in pts.iter().enumerate().step_by(every) {
        let colour = if plot.bad[i] { BAD } else { PATH };
        c.disc(pt, 2.5, colour);
    }
}

/// Every how many samples a dot goes, so that dots are about 5 px apart or more.
fn dot_stride(pts: &[(f64, f64)]) -> usize {
    let mut steps: Vec<f64> = pts.windows(2).map(|w| dist(w[0], w[1])).collect();
    if steps.is_empty() {
        return 1;
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2].max(1e-3);
    ((5.0 / median).ceil() as usize).clamp(1, pts.len())
}

/// Short arrows from the camera along its view direction, as long as the direction lies in
/// the panel's plane (a camera looking straight at the viewer gets a dot-sized arrow).
fn draw_ticks(c: &mut Canvas, p: &Panel, plot: &Plot) {
    const LENGTH: f64 = 30.0;
    for k in evenly_spaced(plot.samples.len() as u64, TICKS) {
        let pose = plot.samples[k as usize].1;
        let Ok(cam) = Camera::new(&pose) else {
            continue;
        };
        let from = p.to_px(pose.position);
        let ahead = p.to_px(pose.position + cam.forward / p.scale);
        let d = (ahead.0 - from.0, ahead.1 - from.1);
        if d.0.hypot(d.1) * LENGTH < 4.0 {
            continue;
        }
        let to = (from.0 + LENGTH * d.0, from.1 + LENGTH * d.1);
        c.arrow(from, to, 2.0, TICK);
    }
}

fn draw_keys(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for (i, &(k, _)) in plot.keys.iter().enumerate() {
        let at = p.to_px(k);
        c.square_outline(at, 8.0, 2.0, KEYFRAME);
        let label = i.to_string();
        let (x, y) = ((at.0 + 10.0) as i64, (at.1 - 22.0) as i64);
        c.text(x, y, &label, 2, KEYFRAME);
    }
}

fn draw_targets(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for &t in &plot.targets {
        match edge_point(p, p.to_px(t)) {
            None => c.cross(p.to_px(t), 6.0, 2.0, TARGET),
            Some(at) => {
                c.cross(at, 6.0, 2.0, TARGET);
                c.text_near(p, at, &format!("look-at {}", fmt_vec(t)), TARGET);
            }
        }
    }
}

fn draw_ends(c: &mut Canvas, p: &Panel, plot: &Plot) {
    let first = p.to_px(plot.samples[0].1.position);
    let last = p.to_px(plot.samples[plot.samples.len() - 1].1.position);
    c.square(last, 6.0, END);
    c.disc(first, 7.0, PANEL);
    c.disc(first, 5.5, START);
}

/// Point and spot lights as diamonds labelled `L<i>`; one outside the view sits hollow at
/// the panel edge in its direction, with its coordinates.
fn draw_lights(c: &mut Canvas, p: &Panel, seq: &Sequence) {
    for (i, pos) in positioned_lights(seq) {
        let at = p.to_px(pos);
        match edge_point(p, at) {
            None => {
                c.diamond(at, 8.0, LIGHT, INK);
                c.text(
                    (at.0 + 10.0) as i64,
                    (at.1 - 4.0) as i64,
                    &format!("L{i}"),
                    1,
                    INK,
                );
            }
            Some(edge) => {
                c.diamond(edge, 8.0, PANEL, INK);
                c.diamond(edge, 5.0, LIGHT, LIGHT);
                c.text_near(p, edge, &format!("L{i} {}", fmt_vec(pos)), INK);
            }
        }
    }
}

/// Where a point outside the panel is drawn: on the line from the panel's centre towards it,
/// just inside the border. None when it is inside.
fn edge_point(p: &Panel, at: (f64, f64)) -> Option<(f64, f64)> {
    const INSET: f64 = 12.0;
    let (cx, cy) = p.centre_px();
    let (dx, dy) = (at.0 - cx, at.1 - cy);
    let (hw, hh) = (
        f64::from(p.width) / 2.0 - INSET,
        f64::from(p.height) / 2.0 - INSET,
    );
    let t = (hw / dx.abs()).min(hh / dy.abs());
    if t.is_nan() || t >= 1.0 {
        return None;
    }
    Some((cx + t * dx, cy + t * dy))
}

/// Two small arrows in a corner naming the axes, so each panel reads without the caption.
fn draw_gizmo(c: &mut Canvas, p: &Panel) {
    const NAMES: [&str; 3] = ["x", "y", "z"];
    let r = p.rect();
    // The vertical arrow points into the panel: down from the top-left for the top view's z,
    // up from the bottom-left for the side view's y.
    let (ox, oy, dy) = if p.flipped {
        (r.x0 as f64 + 16.0, r.y0 as f64 + 16.0, 1.0)
    } else {
        (r.x0 as f64 + 16.0, r.y1 as f64 - 16.0, -1.0)
    };
    c.arrow((ox, oy), (ox + 34.0, oy), 1.0, MUTED);
    c.arrow((ox, oy), (ox, oy + dy * 34.0), 1.0, MUTED);
    c.text(
        (ox + 38.0) as i64,
        (oy - 3.0) as i64,
        NAMES[p.across],
        1,
        MUTED,
    );
    let ty = if dy > 0.0 { oy + 38.0 } else { oy - 45.0 };
    c.text((ox - 2.0) as i64, ty as i64, NAMES[p.down], 1, MUTED);
}

const LEGEND_MIN_W: u32 = 1000;

fn legend(img: &mut RgbImage, y: u32) {
    let mut c = Canvas::whole(img);
    let y = i64::from(y);
    let rows: [&[(&str, Marker)]; 2] = [
        &[
            ("camera path", Marker::Line(PATH)),
            ("inside an object / no camera", Marker::Line(BAD)),
            ("keyframe", Marker::Key),
            ("start", Marker::Start),
            ("end", Marker::End),
        ],
        &[
            ("look-at target", Marker::Target),
            ("view direction", Marker::Tick),
            ("light", Marker::Light),
            ("object [index]", Marker::Object),
        ],
    ];
    for (row, items) in rows.iter().enumerate() {
        let mut x = i64::from(MARGIN);
        let yy = y + row as i64 * i64::from(LEGEND_ROW);
        for (label, marker) in items.iter() {
            marker.draw(&mut c, (x as f64 + 14.0, yy as f64 + 7.0));
            x = c.text(x + 34, yy, label, 2, INK) + 28;
        }
    }
}

#[derive(Clone, Copy)]
enum Marker {
    Line(Rgb<u8>),
    Key,
    Start,
    End,
    Target,
    Tick,
    Light,
    Object,
}

impl Marker {
    fn draw(self, c: &mut Canvas, (x, y): (f64, f64)) {
        match self {
            Marker::Line(colour) => {
                let w = if colour == BAD { 4.0 } else { 2.0 };
                c.line((x - 12.0, y), (x + 12.0, y), w, colour);
                c.disc((x, y), 2.5, colour);
            }
            Marker::Key => c.square_outline((x, y), 8.0, 2.0, KEYFRAME),
            Marker::Start => c.disc((x, y), 5.5, START),
            Marker::End => c.square((x, y), 6.0, END),
            Marker::Target => c.cross((x, y), 6.0, 2.0, TARGET),
            Marker::Tick => c.arrow((x - 12.0, y), (x + 12.0, y), 2.0, TICK),
            Marker::Light => c.diamond((x, y), 8.0, LIGHT, INK),
            Marker::Object => {
                let grey = Rgb([200, 200, 200]);
                c.mask(
                    Rect::around((x, y), 9.0),
                    |a, b| (a - x).hypot(b - y) < 7.0,
                    grey,
                    MUTED,
                )
            }
        }
    }
}

fn red_lines(img: &mut RgbImage, lines: &[String], y: u32) {
    let mut c = Canvas::whole(img);
    for (i, line) in lines.iter().enumerate() {
        let y = i64::from(y + i as u32 * WARNING_ROW);
        c.text(i64::from(MARGIN), y, line, 2, BAD);
    }
}

/// The material's diffuse colour brightened to full and mixed with white: `amount` of colour.
fn tint(m: &Material, amount: f64) -> Rgb<u8> {
    let base = hue(m);
    to_rgb(base * amount + DVec3::ONE * (1.0 - amount))
}

/// The material's colour darkened, for outlines.
fn shade(m: &Material) -> Rgb<u8> {
    to_rgb(hue(m) * 0.6)
}

/// The diffuse colour brightened towards full strength as far as it is saturated: a dark red
/// reads as red, a grey stays grey instead of turning white.
fn hue(m: &Material) -> DVec3 {
    let d = m.diffuse.clamp(DVec3::ZERO, DVec3::ONE);
    let top = d.max_element();
    if top < 1e-6 {
        return DVec3::ZERO;
    }
    let saturation = (top - d.min_element()) / top;
    d + (d / top) * (1.0 - top) * saturation
}

fn to_rgb(c: DVec3) -> Rgb<u8> {
    let q = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    Rgb([q(c.x), q(c.y), q(c.z)])
}

/// 1, 2 or 5 × 10^k, the nearest to `raw`.
fn nice_step(raw: f64) -> f64 {
    let e = 10f64.powf(raw.log10().floor());
    let m = raw / e;
    let k = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    k * e
}

/// A number in at most 3 decimals without trailing zeros, or in exponent form when tiny or huge.
fn fmt_num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e7).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn fmt_vec(v: DVec3) -> String {
    format!("({}, {}, {})", fmt_num(v.x), fmt_num(v.y), fmt_num(v.z))
}

fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).hypot(a.1 - b.1)
}

// ---------------------------------------------------------------------------------------------
// Pixel drawing, clipped to a rectangle

/// Half-open pixel rectangle [x0, x1) × [y0, y1).
#[derive(Debug, Clone, Copy)]
struct Rect {
    x0: i64,
    y0: i64,
    x1: i64,
    y1: i64,
}

impl Rect {
    fn new(x0: i64, y0: i64, x1: i64, y1: i64) -> Rect {
        Rect { x0, y0, x1, y1 }
    }

    /// The square of half-size `r` around a continuous point, clamped far out so huge
    /// discs cost no more than the picture.
    fn around((x, y): (f64, f64), r: f64) -> Rect {
        let c = |v: f64| v.clamp(-1e6, 1e6) as i64;
        Rect::new(c(x - r), c(y - r), c(x + r) + 1, c(y + r) + 1)
    }

    fn intersect(&self, o: &Rect) -> Rect {
        Rect::new(
            self.x0.max(o.x0),
            self.y0.max(o.y0),
            self.x1.min(o.x1),
            self.y1.min(o.y1),
        )
    }

    fn contains(&self, x: i64, y: i64) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }
}

struct Canvas<'a> {
    img: &'a mut RgbImage,
    clip: Rect,
}

impl<'a> Canvas<'a> {
    fn new(img: &'a mut RgbImage, clip: Rect) -> Canvas<'a> {
        let all = Rect::new(0, 0, i64::from(img.width()), i64::from(img.height()));
        Canvas {
            clip: clip.intersect(&all),
            img,
        }
    }

    fn whole(img: &'a mut RgbImage) -> Canvas<'a> {
        Canvas::new(img, Rect::new(0, 0, i64::MAX, i64::MAX))
    }

    fn put(&mut self, x: i64, y: i64, c: Rgb<u8>) {
        if self.clip.contains(x, y) {
            self.img.put_pixel(x as u32, y as u32, c);
        }
    }

    fn fill(&mut self, c: Rgb<u8>) {
        let r = self.clip;
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                self.put(x, y, c);
            }
        }
    }

    fn frame_rect(&mut self, r: Rect, c: Rgb<u8>) {
        for x in r.x0..r.x1 {
            self.put(x, r.y0, c);
            self.put(x, r.y1 - 1, c);
        }
        for y in r.y0..r.y1 {
            self.put(r.x0, y, c);
            self.put(r.x1 - 1, y, c);
        }
    }

    /// A `w`×`w` pixel square centred on a continuous point.
    fn stamp(&mut self, (x, y): (f64, f64), w: f64, c: Rgb<u8>) {
        let n = w.max(1.0).round() as i64;
        let half = n as f64 / 2.0;
        let (x0, y0) = ((x - half).round() as i64, (y - half).round() as i64);
        for dy in 0..n {
            for dx in 0..n {
                self.put(x0 + dx, y0 + dy, c);
            }
        }
    }

    /// A straight line `w` pixels thick, clipped first so far-off ends cost nothing.
    fn line(&mut self, a: (f64, f64), b: (f64, f64), w: f64, c: Rgb<u8>) {
        let r = &self.clip;
        let pad = w + 1.0;
        let bounds = (
            r.x0 as f64 - pad,
            r.y0 as f64 - pad,
            r.x1 as f64 + pad,
            r.y1 as f64 + pad,
        );
        let Some((a, b)) = clip_segment(a, b, bounds) else {
            return;
        };
        let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as i64;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            self.stamp((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), w, c);
        }
    }

    fn polyline(&mut self, pts: impl Iterator<Item = (f64, f64)>, w: f64, c: Rgb<u8>) {
        let mut prev: Option<(f64, f64)> = None;
        for p in pts {
            if let Some(q) = prev {
                self.line(q, p, w, c);
            }
            prev = Some(p);
        }
    }

    fn dashed(&mut self, a: (f64, f64), b: (f64, f64), dash: f64, c: Rgb<u8>) {
        let n = (dist(a, b) / dash).floor() as i64;
        let at = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        for i in (0..n.min(2000)).step_by(2) {
            let (t0, t1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
            self.line(at(t0), at(t1), 1.0, c);
        }
    }

    /// A line with a small head at `b`.
    fn arrow(&mut self, a: (f64, f64), b: (f64, f64), w: f64, c: Rgb<u8>) {
        self.line(a, b, w, c);
        let len = dist(a, b).max(1e-9);
        let (ux, uy) = ((b.0 - a.0) / len, (b.1 - a.1) / len);
        let head = 6.0;
        for side in [-1.0, 1.0] {
            let (px, py) = (-uy * side, ux * side);
            let tip = (
                b.0 - head * ux + 0.6 * head * px,
                b.1 - head * uy + 0.6 * head * py,
            );
            self.line(b, tip, w, c);
        }
    }

    fn disc(&mut self, (cx, cy): (f64, f64), r: f64, c: Rgb<u8>) {
        let bbox = Rect::around((cx, cy), r + 1.0).intersect(&self.clip);
        for y in bbox.y0..bbox.y1 {
            for x in bbox.x0..bbox.x1 {
                if (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy) <= r {
                    self.put(x, y, c);
                }
            }
        }
    }

    fn square(&mut self, (x, y): (f64, f64), half: f64, c: Rgb<u8>) {
        self.stamp((x, y), 2.0 * half, c);
    }

    fn square_outline(&mut self, (x, y): (f64, f64), half: f64, w: f64, c: Rgb<u8>) {
        let (l, r, t, b) = (x - half, x + half, y - half, y + half);
        self.line((l, t), (r, t), w, c);
        self.line((l, b), (r, b), w, c);
        self.line((l, t), (l, b), w, c);
        self.line((r, t), (r, b), w, c);
    }

    fn cross(&mut self, (x, y): (f64, f64), half: f64, w: f64, c: Rgb<u8>) {
        self.line((x - half, y - half), (x + half, y + half), w, c);
        self.line((x - half, y + half), (x + half, y - half), w, c);
    }

    fn diamond(&mut self, (cx, cy): (f64, f64), r: f64, fill: Rgb<u8>, edge: Rgb<u8>) {
        let inside = |x: f64, y: f64| (x - cx).abs() + (y - cy).abs() < r;
        self.mask(Rect::around((cx, cy), r + 1.0), inside, fill, edge);
    }

    /// Fills the pixels of `bbox` whose centre is `inside`, outlining the boundary. The clip
    /// edge is not a boundary: a shape cut off by the panel border gets no outline there.
    fn mask(
        &mut self,
        bbox: Rect,
        inside: impl Fn(f64, f64) -> bool,
        fill: Rgb<u8>,
        edge: Rgb<u8>,
    ) {
        let r = Rect::new(bbox.x0 - 1, bbox.y0 - 1, bbox.x1 + 1, bbox.y1 + 1).intersect(&self.clip);
        if r.x0 >= r.x1 || r.y0 >= r.y1 {
            return;
        }
        let w = (r.x1 - r.x0) as usize;
        let mut m = Vec::with_capacity(w * (r.y1 - r.y0) as usize);
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                m.push(inside(x as f64 + 0.5, y as f64 + 0.5));
            }
        }
        let at = |x: i64, y: i64| {
            // Outside the evaluated area counts as inside, so clip edges stay unoutlined.
            !r.contains(x, y) || m[(y - r.y0) as usize * w + (x - r.x0) as usize]
        };
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                if !at(x, y) {
                    continue;
                }
                let border = !(at(x - 1, y) && at(x + 1, y) && at(x, y - 1) && at(x, y + 1));
                self.put(x, y, if border { edge } else { fill });
            }
        }
    }

    /// Draws `s` with its top-left at (x, y); returns the x after the last glyph.
    fn text(&mut self, x: i64, y: i64, s: &str, scale: i64, c: Rgb<u8>) -> i64 {
        let mut x = x;
        for ch in s.chars() {
            for (row, bits) in glyph(ch).split('/').enumerate() {
                for (col, b) in bits.bytes().enumerate() {
                    if b == b'#' {
                        let (px, py) = (x + col as i64 * scale, y + row as i64 * scale);
                        for d in 0..scale * scale {
                            self.put(px + d % scale, py + d / scale, c);
                        }
                    }
                }
            }
            x += ADVANCE * scale;
        }
        x
    }

    /// A label beside a marker at the panel edge, on the inner side and kept inside the panel.
    fn text_near(&mut self, p: &Panel, at: (f64, f64), s: &str, c: Rgb<u8>) {
        let r = p.rect();
        let w = text_width(s, 1);
        let y = if at.1 < p.centre_px().1 {
            at.1 + 10.0
        } else {
            at.1 - 18.0
        } as i64;
        let x = ((at.0 - w as f64 / 2.0) as i64).clamp(r.x0 + 4, (r.x1 - 4 - w).max(r.x0 + 4));
        // A backing box keeps the label readable over the grid and the path.
        for yy in y - 2..y + 9 {
            for xx in x - 2..x + w + 1 {
                self.put(xx, yy, PANEL);
            }
        }
        self.text(x, y, s, 1, c);
    }
}

/// Liang–Barsky: the part of segment a–b inside (x0, y0, x1, y1), if any.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    (x0, y0, x1, y1): (f64, f64, f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
            continue;
        }
        let t = q / p;
        if p < 0.0 {
            t0 = t0.max(t);
        } else {
            t1 = t1.min(t);
        }
    }
    if t0.is_nan() || t0 > t1 {
        return None;
    }
    let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
    Some((at(t0), at(t1)))
}

// ---------------------------------------------------------------------------------------------
// A 5×7 bitmap font (descenders take two more rows): '#' is ink, rows separated by '/'.

/// Horizontal advance per glyph at scale 1: 5 columns and a 1-column gap.
const ADVANCE: i64 = 6;

fn text_width(s: &str, scale: i64) -> i64 {
    s.chars().count() as i64 * ADVANCE * scale
}

fn glyph(c: char) -> &'static str {
    FONT.iter()
        .find(|(g, _)| *g == c)
        .or_else(|| FONT.iter().find(|(g, _)| *g == '?'))
        .map_or("", |(_, rows)| rows)
}

#[rustfmt::skip]
const FONT: &[(char, &str)] = &[
    (' ', "...../...../...../...../...../...../....."),
    ('0', ".###./#...#/#..##/#.#.#/##..#/#...#/.###."),
    ('1', "..#../.##../..#../..#../..#../..#../.###."),
    ('2', ".###./#...#/....#/...#./..#../.#.../#####"),
    ('3', "#####/...#./..#../...#./....#/#...#/.###."),
    ('4', "...#./..##./.#.#./#..#./#####/...#./...#."),
    ('5', "#####/#..../####./....#/....#/#...#/.###."),
    ('6', "..##./.#.../#..../####./#...#/#...#/.###."),
    ('7', "#####/....#/...#./..#../.#.../.#.../.#..."),
    ('8', ".###./#...#/#...#/.###./#...#/#...#/.###."),
    ('9', ".###./#...#/#...#/.####/....#/...#./.##.."),
    ('A', ".###./#...#/#...#/#####/#...#/#...#/#...#"),
    ('B', "####./#...#/#...#/####./#...#/#...#/####."),
    ('C', ".###./#...#/#..../#..../#..../#...#/.###."),
    ('D', "###../#..#./#...#/#...#/#...#/#..#./###.."),
    ('E', "#####/#..../#..../####./#..../#..../#####"),
    ('F', "#####/#..../#..../####./#..../#..../#...."),
    ('G', ".###./#...#/#..../#.###/#...#/#...#/.####"),
    ('H', "#...#/#...#/#...#/#####/#...#/#...#/#...#"),
    ('I', ".###./..#../..#../..#../..#../..#../.###."),
    ('J', "..###/...#./...#./...#./...#./#..#./.##.."),
    ('K', "#...#/#..#./#.#../##.../#.#../#..#./#...#"),
    ('L', "#..../#..../#..../#..../#..../#..../#####"),
    ('M', "#...#/##.##/#.#.#/#.#.#/#...#/#...#/#...#"),
    ('N', "#...#/#...#/##..#/#.#.#/#..##/#...#/#...#"),
    ('O', ".###./#...#/#...#/#...#/#...#/#...#/.###."),
    ('P', "####./#...#/#...#/####./#..../#..../#...."),
    ('Q', ".###./#...#/#...#/#...#/#.#.#/#..#./.##.#"),
    ('R', "####./#...#/#...#/####./#.#../#..#./#...#"),
    ('S', ".####/#..../#..../.###./....#/....#/####."),
    ('T', "#####/..#../..#../..#../..#../..#../..#.."),
    ('U', "#...#/#...#/#...#/#...#/#...#/#...#/.###."),
    ('V', "#...#/#...#/#...#/#...#/#...#/.#.#./..#.."),
    ('W', "#...#/#...#/#...#/#.#.#/#.#.#/#.#.#/.#.#."),
    ('X', "#...#/#...#/.#.#./..#../.#.#./#...#/#...#"),
    ('Y', "#...#/#...#/.#.#./..#../..#../..#../..#.."),
    ('Z', "#####/....#/...#./..#../.#.../#..../#####"),
    ('a', "...../...../.###./....#/.####/#...#/.####"),
    ('b', "#..../#..../#.##./##..#/#...#/#...#/####."),
    ('c', "...../...../.###./#..../#..../#...#/.###."),
    ('d', "....#/....#/.##.#/#..##/#...#/#...#/.####"),
    ('e', "...../...../.###./#...#/#####/#..../.###."),
    ('f', "..##./.#..#/.#.../###../.#.../.#.../.#..."),
    ('g', "...../...../.####/#...#/#...#/#...#/.####/....#/.###."),
    ('h', "#..../#..../#.##./##..#/#...#/#...#/#...#"),
    ('i', "..#../...../.##../..#../..#../..#../.###."),
    ('j', "...#./...../..##./...#./...#./...#./...#./#..#./.##.."),
    ('k', "#..../#..../#..#./#.#../##.../#.#../#..#."),
    ('l', ".##../..#../..#../..#../..#../..#../.###."),
    ('m', "...../...../##.#./#.#.#/#.#.#/#...#/#...#"),
    ('n', "...../...../#.##./##..#/#...#/#...#/#...#"),
    ('o', "...../...../.###./#...#/#...#/#...#/.###."),
    ('p', "...../...../####./#...#/#...#/#...#/####./#..../#...."),
    ('q', "...../...../.####/#...#/#...#/#...#/.####/....#/....#"),
    ('r', "...../...../#.##./##..#/#..../#..../#...."),
    ('s', "...../...../.####/#..../.###./....#/####."),
    ('t', ".#.../.#.../###../.#.../.#.../.#..#/..##."),
    ('u', "...../...../#...#/#...#/#...#/#..##/.##.#"),
    ('v', "...../...../#...#/#...#/#...#/.#.#./..#.."),
    ('w', "...../...../#...#/#...#/#.#.#/#.#.#/.#.#."),
    ('x', "...../...../#...#/.#.#./..#../.#.#./#...#"),
    ('y', "...../...../#...#/#...#/#...#/#...#/.####/....#/.###."),
    ('z', "...../...../#####/...#./..#../.#.../#####"),
    ('.', "...../...../...../...../...../.##../.##.."),
    (',', "...../...../...../...../...../.##../..#../.#..."),
    (':', "...../.##../.##../...../.##../.##../....."),
    (';', "...../.##../.##../...../.##../..#../.#..."),
    ('-', "...../...../...../.###./...../...../....."),
    ('+', "...../..#../..#../#####/..#../..#../....."),
    ('=', "...../...../#####/...../#####/...../....."),
    ('_', "...../...../...../...../...../...../#####"),
    ('(', "...#./..#../.#.../.#.../.#.../..#../...#."),
    (')', ".#.../..#../...#./...#./...#./..#../.#..."),
    ('[', ".###./.#.../.#.../.#.../.#.../.#.../.###."),
    (']', ".###./...#./...#./...#./...#./...#./.###."),
    ('/', "...../....#/...#./..#../.#.../#..../....."),
    ('#', ".#.#./.#.#./#####/.#.#./#####/.#.#./.#.#."),
    ('%', "##..#/##..#/...#./..#../.#.../#..##/#..##"),
    ('\'', "..#../..#../.#.../...../...../...../....."),
    ('"', ".#.#./.#.#./...../...../...../...../....."),
    ('!', "..#../..#../..#../..#../..#../...../..#.."),
    ('?', ".###./#...#/....#/...#./..#../...../..#.."),
    ('<', "...#./..#../.#.../#..../.#.../..#../...#."),
    ('>', ".#.../..#../...#./....#/...#./..#../.#..."),
    ('*', "...../..#../#.#.#/.###./#.#.#/..#../....."),
    ('°', ".##../#..#./#..#./.##../...../...../....."),
    ('×', "...../...../#...#/.#.#./..#../.#.#./#...#"),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_spaced_hits_both_ends() {
        assert_eq!(evenly_spaced(144, 12).first(), Some(&0));
        assert_eq!(evenly_spaced(144, 12).last(), Some(&143));
        assert_eq!(evenly_spaced(144, 12).len(), 12);
        assert_eq!(evenly_spaced(5, 3), vec![0, 2, 4]);
        assert_eq!(evenly_spaced(4, 12), vec![0, 1, 2, 3]);
        assert_eq!(evenly_spaced(10, 1), vec![0]);
        assert_eq!(evenly_spaced(1, 12), vec![0]);
        // round(k·3/2) for k = 0..2 is 0, 2 (1.5 rounds up), 3.
        assert_eq!(evenly_spaced(4, 3), vec![0, 2, 3]);
    }

    #[test]
    fn every_font_row_is_five_wide() {
        for (c, rows) in FONT {
            let rows: Vec<&str> = rows.split('/').collect();
            assert!((7..=9).contains(&rows.len()), "{c}");
            assert!(rows.iter().all(|r| r.len() == 5), "{c}");
        }
    }

    #[test]
    fn segments_clip_to_the_box() {
        let b = (0.0, 0.0, 10.0, 10.0);
        assert_eq!(
            clip_segment((-5.0, 5.0), (15.0, 5.0), b),
            Some(((0.0, 5.0), (10.0, 5.0)))
        );
        assert_eq!(clip_segment((-5.0, -5.0), (-1.0, 20.0), b), None);
    }

    #[test]
    fn steps_are_nice() {
        assert_eq!(nice_step(0.45), 0.5);
        assert_eq!(nice_step(1.2), 1.0);
        assert!((nice_step(0.00023) - 0.0002).abs() < 1e-12);
    }
}
