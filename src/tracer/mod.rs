//! The core tracer: `render(scene, camera, settings, frame) → Frame`. Pixels are sampled at
//! their centre (1 sample), on a jittered grid, or adaptively; rows spread over the rayon pool,
//! and within a row rays travel in packets of as many f64 (or, with `render.precision: f32`,
//! f32) lanes as the CPU has (`kernel`). Every pixel depends only on the scene, the camera,
//! the frame number and its own coordinates, so a frame is byte-identical whatever the thread
//! count, order of work or lane width.

pub mod accel;
mod adaptive;
pub mod aov;
mod area;
pub(crate) mod bvh;
mod cone;
pub mod glass;
pub mod intersect;
pub mod kernel;
mod lens;
mod mesh;
pub mod path;
mod polygon;
pub mod precision;
mod rows;
pub mod sample;
pub mod shade;
pub mod sky;
pub mod sobol;
pub mod texture;
mod triangle;

use crate::budget::OutOfMemory;
use crate::frame::Frame;
use crate::scene::Scene;
pub use crate::settings::{Adaptive, Precision, Sampler, Settings};
use crate::shutter::{Exposure, Staged};
use crate::timeline::motion::{Posed, Poses, Thing};
use glam::DVec3;
pub use kernel::Kernel;
use rayon::prelude::*;
use rows::{Pass, Planes, RowOut, RowStats};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A scene ready to trace: the validated data and the geometry built from it once.
#[derive(Debug, Clone)]
pub struct World {
    pub scene: Scene,
    pub geometry: accel::Geometry,
    /// What blocks shadow rays when some objects let light through: the opaque ones only.
    opaque: Option<accel::Geometry>,
    /// The objects that let light through, in file order (shadow rays multiply their
    /// filters in this order).
    clear: Vec<glass::Clear>,
    /// Some material spawns more than one ray (or reflects by angle): paths are trees.
    branches: bool,
    /// The hierarchy of each of `scene.meshes`, built once and shared by every placement.
    bvhs: Vec<Arc<bvh::Bvh>>,
    /// Some material has a texture: eye rays carry footprint cones (`texture`).
    textured: bool,
    /// Eye cones have spread 0 (point-sampled textures), to measure what filtering buys.
    point_sampled: bool,
    /// Where the scene's origin lies in the world: zero, or the camera's position in an f32
    /// frame's shifted world (textures are looked up in world coordinates).
    origin: DVec3,
    /// The scene in world coordinates when `scene` is shifted and textured.
    unshifted: Option<Arc<Scene>>,
    /// Each object's curvature for the cones (empty without textures).
    curvature: Vec<f64>,
    /// Some light is an area light: eye samples then carry their pixels' light seeds.
    area_lights: bool,
    /// The opaque objects an area light's shadow cones are tested against, when the test
    /// applies (`cone::occluders`).
    cones: Option<Vec<cone::Occluder>>,
}

impl World {
    /// The world of `scene`, its meshes' hierarchies built; where the system refuses their
    /// memory this panics (the run, `check` and the probe use `try_new`, which says so).
    pub fn new(scene: Scene) -> World {
        World::try_new(scene).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The world of `scene`, or which mesh's hierarchy the system refused memory for.
    pub(crate) fn try_new(scene: Scene) -> Result<World, OutOfMemory> {
        let bvhs = (scene.meshes.iter())
            .map(|m| bvh::Bvh::build(m).map(Arc::new))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(World::with_bvhs(scene, bvhs))
    }

    /// Makes the meshes' triangle copies a frame traced in `precision` tests (each once).
    pub(crate) fn prepare(&self, precision: Precision) -> Result<(), OutOfMemory> {
        let single = precision == Precision::F32;
        self.bvhs.iter().try_for_each(|b| b.prepare(single))
    }

    /// The hierarchy of each of `scene.meshes`, in order.
    pub(crate) fn hierarchies(&self) -> &[Arc<bvh::Bvh>] {
        &self.bvhs
    }

    /// The world of `scene`, whose meshes' hierarchies are `bvhs`.
    fn with_bvhs(scene: Scene, bvhs: Vec<Arc<bvh::Bvh>>) -> World {
        let geometry = accel::Geometry::subset(&scene.objects, &bvhs, |_| true);
        let material = |i: usize| &scene.materials[scene.objects[i].material];
        let clear = clear(&scene, &bvhs);
        let opaque = (!clear.is_empty()).then(|| {
            accel::Geometry::subset(&scene.objects, &bvhs, |i| !material(i).transparent())
        });
        // An image sky is filtered by the rays' footprints too.
        let textured = scene.materials.iter().any(|m| m.textured())
            || matches!(scene.sky, Some(crate::scene::Sky::Image { .. }));
        let mut world = World {
            cones: cone::occluders(&scene),
            branches: scene.materials.iter().any(|m| m.branches()),
            area_lights: scene.lights.iter().any(|l| l.area_samples().is_some()),
            scene,
            geometry,
            opaque,
            clear,
            bvhs,
            textured,
            point_sampled: false,
            origin: DVec3::ZERO,
            unshifted: None,
            curvature: Vec::new(),
        };
        if textured {
            world.curvature = texture::curvatures(&world);
        }
        world
    }

    /// This world with the objects and lights that move at `poses`: the meshes' hierarchies
    /// and the materials stay, the top level, the spheres' hierarchy and the lights are
    /// built anew (`Geometry::subset`), as for a still scene that placed them there.
    pub fn posed(&self, poses: &Poses) -> World {
        let mut scene = self.scene.clone();
        for (thing, posed) in poses {
            match (*thing, *posed) {
                (Thing::Object(i), Posed::Object(o)) => scene.objects[i] = o,
                (Thing::Light(i), Posed::Light(l)) => scene.lights[i] = l,
                // A rig poses the kind of thing it names (`Rig::at` starts from it).
                _ => {}
            }
        }
        let world = World::with_bvhs(scene, self.bvhs.clone());
        World {
            point_sampled: self.point_sampled,
            ..world
        }
    }

    /// Whether some object is a mesh (shading then lifts secondary rays off triangles).
    pub fn has_meshes(&self) -> bool {
        !self.bvhs.is_empty()
    }

    /// This world in coordinates whose origin is `by` (see `Scene::shifted`), its boxes
    /// widened for f32 by 2^-16 of their reach (see `Geometry::shifted`).
    pub fn shifted(&self, by: DVec3) -> World {
        const PAD: f64 = 1.0 / 65536.0;
        let scene = self.scene.shifted(by);
        World {
            clear: clear(&scene, &self.bvhs),
            cones: cone::occluders(&scene),
            scene,
            geometry: self.geometry.shifted(by, PAD),
            opaque: self.opaque.as_ref().map(|g| g.shifted(by, PAD)),
            branches: self.branches,
            bvhs: self.bvhs.clone(),
            area_lights: self.area_lights,
            textured: self.textured,
            point_sampled: self.point_sampled,
            origin: self.origin + by,
            unshifted: match (&self.unshifted, self.textured) {
                (Some(s), _) => Some(s.clone()),
                (None, true) => Some(Arc::new(self.scene.clone())),
                (None, false) => None,
            },
            curvature: self.curvature.clone(),
        }
    }

    /// Whether eye rays carry their pixels (`texture::PixelRays`): some material has a checker
    /// and textures are filtered.
    pub(crate) fn checkered(&self) -> bool {
        self.textured && !self.point_sampled && self.scene.materials.iter().any(|m| m.checkered())
    }

    /// Whether a first pass under the adaptive rule records which pixels are smooth on one
    /// object (docs/spec/tracer.md, *Smooth pixels*): a checker, filtered, and no trees.
    pub(crate) fn tracks_smooth(&self) -> bool {
        self.checkered() && !self.branches
    }

    /// This world with textures looked up at points, unfiltered: what `bench` and the tests
    /// compare filtering against.
    pub fn point_sampled(self) -> World {
        World {
            point_sampled: true,
            ..self
        }
    }

    /// Whether paths are trees (some material sends on two rays, or reflects by angle).
    pub fn trees(&self) -> bool {
        self.branches
    }

    /// The geometry shadow rays are blocked by.
    fn blockers(&self) -> &accel::Geometry {
        self.opaque.as_ref().unwrap_or(&self.geometry)
    }
}

/// The objects of `scene` that let light through, in file order.
fn clear(scene: &Scene, bvhs: &[Arc<bvh::Bvh>]) -> Vec<glass::Clear> {
    let material = |i: usize| &scene.materials[scene.objects[i].material];
    (0..scene.objects.len())
        .filter(|&i| material(i).transparent())
        .map(|i| glass::Clear::new(&scene.objects[i], i, material(i).transmission, bvhs))
        .collect()
}

/// Frame number `frame` of `world` seen with `exposure`'s cameras (panics where the system
/// refuses the memory of a mesh's triangle copy: tools and tests; runs use `render_or_stop`).
pub fn render(world: &World, exposure: &Exposure, settings: &Settings, frame: u64) -> Frame {
    render_with(Kernel::chosen(), world, exposure, settings, frame)
}

/// `render`, given up (`Ok(None)`) as soon as `stop` is set: it is checked before each band
/// of rows, each packet and each sample, so even a frame of hours stops within milliseconds;
/// an error when the system refuses the memory of a mesh's triangle copy. `want8`: a sink
/// will take the frame's 8-bit levels (`Frame::take_rgb8`), which a frame of one pass then
/// makes as it goes.
pub(crate) fn render_or_stop(
    world: &World,
    exposure: &Exposure,
    settings: &Settings,
    frame: u64,
    stop: &AtomicBool,
    want8: bool,
) -> Result<Option<Frame>, OutOfMemory> {
    render_frame(
        Kernel::chosen(),
        world,
        exposure,
        settings,
        frame,
        stop,
        want8,
    )
}

/// `render` with a given kernel (they all give the same frame; benchmarks compare them).
pub fn render_with(
    kernel: Kernel,
    world: &World,
    exposure: &Exposure,
    settings: &Settings,
    frame: u64,
) -> Frame {
    let never = AtomicBool::new(false);
    render_frame(kernel, world, exposure, settings, frame, &never, false)
        .unwrap_or_else(|e| panic!("{e}"))
        .expect("never stopped")
}

fn render_frame(
    kernel: Kernel,
    world: &World,
    exposure: &Exposure,
    settings: &Settings,
    frame: u64,
    stop: &AtomicBool,
    want8: bool,
) -> Result<Option<Frame>, OutOfMemory> {
    // What moves is posed: at the frame's time, and at each instant of an open shutter.
    let staged = exposure.motion.as_ref().map(|m| stage(world, m));
    let (world, instants) = match &staged {
        Some((at, instants)) => (at, instants.as_slice()),
        None => (world, &[][..]),
    };
    // f32 traces in coordinates relative to the frame's camera, shifted in f64: positions
    // near the camera keep their precision however far from the origin the scene lies. A
    // frame f32 cannot resolve is traced in f64 (see `precision`), as is one whose objects
    // move while the shutter is open.
    let f32_frame = settings.precision == Precision::F32
        && instants.is_empty()
        && precision::f32_limit(&world.scene, exposure, settings).is_none();
    let settings = &Settings {
        precision: if f32_frame {
            Precision::F32
        } else {
            Precision::F64
        },
        ..*settings
    };
    // The triangle copies this frame tests, and the passes' (traced in f64), made fallibly.
    world.prepare(settings.precision)?;
    if !settings.aov.is_empty() {
        world.prepare(Precision::F64)?;
    }
    let relative;
    let (world, exposure) = match settings.precision {
        Precision::F64 => (world, exposure),
        Precision::F32 => {
            let by = exposure.camera.origin;
            relative = (world.shifted(by), exposure.shifted(by));
            (&relative.0, &relative.1)
        }
    };
    let (w, h) = (settings.width as usize, settings.height as usize);
    let mut rgb = crate::frame::buffer(3 * w * h);
    let mut alpha = settings.alpha.then(|| crate::frame::buffer(w * h));
    let camera = &exposure.camera;
    let from_origin = world.geometry.from_origin(camera.origin);
    let sampled = exposure.sampled();
    // Film frames record each pixel's error estimate for the rounds and the film filter.
    let rounds =
        sampled && settings.samples > 1 && (settings.adaptive.is_some() || settings.denoise);
    let recorded = settings.adaptive.is_some() || rounds;
    let mut spread = vec![0f32; if recorded { w * h } else { 0 }];
    // Second differences along smooth checker pixels are not tested (`mark`).
    let smooth = settings.adaptive.is_some() && !rounds && !sampled && world.tracks_smooth();
    let mut smooth_on = vec![rows::NOT_SMOOTH; if smooth { w * h } else { 0 }];
    let first = Pass {
        world,
        camera,
        exposure: sampled.then_some(exposure),
        settings,
        frame,
        samples: Samples::All(settings.samples),
        rounds,
        from_origin: &from_origin,
        instants,
        stop,
        smooth,
    };
    let mut planes = Planes {
        rgb: &mut rgb,
        alpha: alpha.as_deref_mut(),
    };
    // A frame of one pass is finished band by band as each is traced, while the band is
    // still in cache: exposed, and turned into the 8-bit levels its sinks want (reading a
    // 1080p frame's 25 MB of floats back afterwards cost about a sixth of the talk's f32
    // stream). The same values as exposing and encoding the whole frame afterwards.
    let single = settings.adaptive.is_none() && !(first.rounds && settings.denoise);
    let mut levels8 = (single && want8 && !settings.alpha).then(|| crate::frame::bytes8(3 * w * h));
    let finish = single.then_some(Finish {
        stops: settings.exposure,
        levels8: levels8.as_deref_mut(),
    });
    let mut stats = run_pass(
        kernel,
        &first,
        &mut planes,
        (&mut spread, &mut smooth_on),
        finish,
    );
    if let (Some(a), true) = (settings.adaptive, first.rounds) {
        stats = stats + adaptive::rounds(kernel, &first, a, &mut planes, &mut spread);
    } else if let Some(a) = settings.adaptive {
        let smooth_on = smooth.then_some(&smooth_on[..]);
        let marked = mark(planes.rgb, (&spread, smooth_on), w, h, a.threshold);
        let more = Pass {
            samples: Samples::More {
                have: settings.samples,
                total: a.max_samples,
            },
            smooth: false,
            ..first
        };
        let marked: Vec<u32> = (0..marked.len() as u32)
            .filter(|&i| marked[i as usize])
            .collect();
        stats = stats + extend(kernel, &more, &marked, &mut planes).0;
    }
    // The film filter, before the exposure scales what the error estimates describe.
    if first.rounds && settings.denoise {
        let reach = crate::denoise::Reach::of(exposure.lens_open());
        crate::denoise::filter(&mut rgb, &spread, alpha.as_deref(), w, reach);
    }
    if settings.exposure != 0.0 && !single {
        expose(&mut rgb, settings.exposure);
    }
    let depth = settings.depth.then(|| {
        let mut depth = crate::frame::buffer(w * h);
        depth
            .par_chunks_mut(w)
            .enumerate()
            .for_each(|(row, out)| kernel.depth_row(&first, row as u32, out));
        depth
    });
    if stop.load(Ordering::Relaxed) {
        return Ok(None);
    }
    Ok(Some(Frame {
        width: settings.width,
        height: settings.height,
        rgb,
        depth,
        alpha,
        aov: None,
        encoding: settings.encoding,
        non_finite: stats.non_finite,
        samples: stats.samples,
        rays: stats.rays,
        levels8,
    }))
}

/// The world at the frame's time, and at each instant of the open shutter when something
/// moves while it is open (built in parallel; each is a pure function of its poses).
fn stage(world: &World, staged: &Staged) -> (World, Vec<World>) {
    let instants = staged.instants.par_iter().map(|p| world.posed(p)).collect();
    (world.posed(&staged.at), instants)
}

impl World {
    /// This world as frame `exposure` sees it at its time: posed when something moves.
    pub fn at_frame(&self, exposure: &Exposure) -> std::borrow::Cow<'_, World> {
        match &exposure.motion {
            Some(m) => std::borrow::Cow::Owned(self.posed(&m.at)),
            None => std::borrow::Cow::Borrowed(self),
        }
    }
}

/// Which samples a pass traces for each selected pixel.
#[derive(Clone, Copy)]
enum Samples {
    /// `n` samples from scratch, in the settings' pattern.
    All(u32),
    /// Extends a pixel that has `have` samples to `total` with R2 samples `have..total`,
    /// which are uniform over the pixel like the first ones, so the mean stays unbiased.
    More { have: u32, total: u32 },
}

/// What the last pass of a frame does to each band it has traced: `stops` of exposure, then
/// the 8-bit levels into `levels8` (3 a pixel) when there is one.
struct Finish<'a> {
    stops: f64,
    levels8: Option<&'a mut [u8]>,
}

/// Runs `pass` over every band of rows in parallel; fills `spread` (when not empty) with each
/// pixel's largest channel range and `smooth` (when not empty) with the object each pixel is
/// smooth on, and finishes each band with `finish` when given.
fn run_pass(
    kernel: Kernel,
    pass: &Pass,
    planes: &mut Planes,
    (spread, smooth): (&mut [f32], &mut [u32]),
    finish: Option<Finish>,
) -> RowStats {
    let rows = kernel.band_rows(pass.settings.precision);
    let w = pass.settings.width as usize;
    let bands = (pass.settings.height as usize).div_ceil(rows);
    let mut spreads = in_bands((!spread.is_empty()).then_some(spread), w * rows, bands);
    let mut smooths = in_bands((!smooth.is_empty()).then_some(smooth), w * rows, bands);
    let mut alphas = in_bands(planes.alpha.as_deref_mut(), w * rows, bands);
    let stops = finish.as_ref().map(|f| f.stops);
    let mut levels = in_bands(finish.and_then(|f| f.levels8), 3 * w * rows, bands);
    planes
        .rgb
        .par_chunks_mut(3 * w * rows)
        .zip(spreads.par_iter_mut())
        .zip(alphas.par_iter_mut())
        .zip(levels.par_iter_mut())
        .zip(smooths.par_iter_mut())
        .enumerate()
        .map(|(band, ((((rgb, spread), alpha), levels), smooth))| {
            let out = RowOut {
                rgb: &mut *rgb,
                spread: spread.as_deref_mut(),
                alpha: alpha.as_deref_mut(),
                smooth: smooth.as_deref_mut(),
            };
            let stats = kernel.band(pass, (band * rows) as u32, out);
            if let Some(stops) = stops.filter(|&s| s != 0.0) {
                expose(rgb, stops);
            }
            if let Some(levels) = levels {
                crate::frame::levels8(rgb, levels, pass.settings.encoding);
            }
            stats
        })
        .reduce(RowStats::default, |a, b| a + b)
}

/// A per-pixel buffer cut into the bands' parts, or `bands` Nones without one.
fn in_bands<T>(buffer: Option<&mut [T]>, band: usize, bands: usize) -> Vec<Option<&mut [T]>> {
    match buffer {
        Some(b) => b.chunks_mut(band).map(Some).collect(),
        None => (0..bands).map(|_| None).collect(),
    }
}

/// Adds samples to the pixels `pixels` (row-major indices, ascending), packed in raster
/// order across rows so packets stay full however sparse they are; returns what the pass
/// recorded of each (its samples' variance in rounds, else 0).
fn extend(
    kernel: Kernel,
    pass: &Pass,
    pixels: &[u32],
    planes: &mut Planes,
) -> (RowStats, Vec<f32>) {
    let mut means = vec![[0f32; 5]; pixels.len()];
    let (rgb, alpha) = (&*planes.rgb, planes.alpha.as_deref());
    // Tasks of 256 pixels: a whole number of packets of every width.
    let stats = means
        .par_chunks_mut(256)
        .zip(pixels.par_chunks(256))
        .map(|(out, pixels)| kernel.marked(pass, pixels, (rgb, alpha), out))
        .reduce(RowStats::default, |a, b| a + b);
    for (&p, m) in pixels.iter().zip(&means) {
        planes.rgb[3 * p as usize..][..3].copy_from_slice(&m[..3]);
        if let Some(alpha) = planes.alpha.as_deref_mut() {
            alpha[p as usize] = m[3];
        }
    }
    (stats, means.iter().map(|m| m[4]).collect())
}

/// 2^stops (libm's exp2, rounded to f32) times every channel, in f32; a product beyond f32
/// stays at f32::MAX, as the tracer's own colours do.
fn expose(rgb: &mut [f32], stops: f64) {
    let scale = libm::exp2(stops) as f32;
    for c in rgb {
        *c = (*c * scale).clamp(-f32::MAX, f32::MAX);
    }
}

/// Pixels that need more samples: their own samples disagree, or they stand out from their
/// neighbours along a row or column (a second difference, so smooth shading gradients, which
/// antialiasing cannot improve, are left alone while edges and thin features are caught),
/// except across pixels `smooth` on one object (docs/spec/tracer.md, *Smooth pixels*).
fn mark(
    rgb: &[f32],
    (spread, smooth): (&[f32], Option<&[u32]>),
    w: usize,
    h: usize,
    threshold: f32,
) -> Vec<bool> {
    // Three pixels smooth on one object differ only by smooth shading and a checker's exact
    // pixel means: their second difference is not an edge more samples would resolve.
    let exempt = |a: usize, i: usize, b: usize| match smooth {
        Some(s) => s[i] != rows::NOT_SMOOTH && s[a] == s[i] && s[b] == s[i],
        None => false,
    };
    let bumps = |a: usize, i: usize, b: usize| {
        !exempt(a, i, b)
            && (0..3).any(|c| {
                (2.0 * rgb[3 * i + c] - rgb[3 * a + c] - rgb[3 * b + c]).abs() > 2.0 * threshold
            })
    };
    // Row by row: per pixel, the index's division and rayon's per-item collection cost more
    // than the test.
    let mut marks = vec![false; w * h];
    marks
        .par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(row, line)| {
            for (col, m) in line.iter_mut().enumerate() {
                let i = row * w + col;
                *m = spread[i] > threshold
                    || (col > 0 && col + 1 < w && bumps(i - 1, i, i + 1))
                    || (row > 0 && row + 1 < h && bumps(i - w, i, i + w));
            }
        });
    marks
}

/// The last guard before a pixel: a numerical surprise, or a colour beyond f32, never writes
/// NaN or Inf (`Frame::non_finite` counts how often it had to step in).
#[inline]
fn finite(c: [f32; 3]) -> [f32; 3] {
    c.map(|v| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-f32::MAX, f32::MAX)
        }
    })
}

#[cfg(test)]
mod finish_tests {
    use super::*;
    use crate::sequence;
    use crate::transfer::Encoding;
    use std::path::Path;

    const SCENE: &str = "
render: { width: 61, height: 37, samples: 1 }
camera: { position: [0, 0.2, 2], look_at: [0, 0, 0], fov: 60 }
materials:
  red: { diffuse: [0.9, 0.1, 0.1], specular: [1, 1, 1], shininess: 50, reflection: 0.4 }
objects:
  - sphere: { center: [0, 0, 0], radius: 0.6, material: red }
  - plane: { point: [0, -0.6, 0], normal: [0, 1, 0], material: red }
lights:
  - point: { position: [3, 4, 5], diffuse: [2, 2, 2], specular: [1, 1, 1] }
";

    /// The levels made band by band as the frame is traced are the whole frame's, exposed
    /// and encoded afterwards, in both precisions and encodings, with and without exposure.
    #[test]
    fn levels_made_per_band_are_the_frames_own() {
        let seq = sequence::parse(Path::new("finish.yaml"), SCENE).unwrap();
        let world = World::new(seq.scene.clone());
        let exposure = Exposure::of_frame(&seq.timeline, None, 0).unwrap();
        let never = AtomicBool::new(false);
        for precision in [Precision::F32, Precision::F64] {
            for encoding in [Encoding::Srgb, Encoding::Linear] {
                for stops in [0.0, 0.7, -1.3] {
                    let settings = Settings {
                        precision,
                        encoding,
                        exposure: stops,
                        ..seq.settings
                    };
                    let render = |want8| {
                        render_frame(
                            Kernel::chosen(),
                            &world,
                            &exposure,
                            &settings,
                            0,
                            &never,
                            want8,
                        )
                        .unwrap()
                        .unwrap()
                    };
                    let (mut fused, whole) = (render(true), render(false));
                    assert!(fused.levels8.is_some() && whole.levels8.is_none());
                    assert_eq!(fused.rgb, whole.rgb, "{precision:?} {stops}");
                    assert_eq!(fused.take_rgb8(), whole.to_rgb8(), "{precision:?} {stops}");
                }
            }
        }
    }
}

#[cfg(test)]
mod discs_tests {
    use super::*;
    use crate::sequence;
    use std::path::Path;

    /// A sphere light and a one-sided rect light over mirrors, glass and a floor partly behind
    /// the rect's plane (lanes its first surfaces leave unlit that later ones light), seen
    /// through a lens so that paths branch.
    const SCENE: &str = "
render: { width: 47, height: 29, samples: 3, max_depth: 4 }
camera: { position: [0, 0.4, 2.2], look_at: [0, 0, 0], fov: 70, aperture: 0.05, focus_distance: 2.2 }
materials:
  mirror: { diffuse: [0.2, 0.2, 0.2], specular: [1, 1, 1], shininess: 40, reflection: 0.6 }
  floor: { diffuse: [0.7, 0.7, 0.6], specular: [0.3, 0.3, 0.3], shininess: 20, reflection: 0.3 }
  glass: { diffuse: [0, 0, 0], specular: [1, 1, 1], shininess: 300, transmission: [0.9, 0.95, 1], ior: 1.5, fresnel: true }
objects:
  - sphere: { center: [-0.5, 0, 0], radius: 0.45, material: mirror }
  - sphere: { center: [0.55, -0.1, 0.2], radius: 0.35, material: glass }
  - plane: { point: [0, -0.45, 0], normal: [0, 1, 0], material: floor }
lights:
  - sphere: { center: [2, 3, 2], radius: 0.6, diffuse: [0.8, 0.8, 0.8], specular: [1, 1, 1], samples: 7 }
  - rect: { corner: [-1, 1.5, -1], edge_u: [0, 0, 2.5], edge_v: [0, 1.5, 0], diffuse: [0.5, 0.4, 0.3], specular: [0.5, 0.5, 0.5], samples: 5 }
";

    /// The points' coordinates a packet keeps for its sample's paths give every byte the
    /// recomputed ones give, in both precisions.
    #[test]
    fn kept_light_points_change_no_byte() {
        let seq = sequence::parse(Path::new("discs.yaml"), SCENE).unwrap();
        let world = World::new(seq.scene.clone());
        let exposure = Exposure::of_frame(&seq.timeline, None, 0).unwrap();
        let never = AtomicBool::new(false);
        for precision in [Precision::F32, Precision::F64] {
            let settings = Settings {
                precision,
                ..seq.settings
            };
            let render = |keep| {
                area::KEEP.store(keep, Ordering::Relaxed);
                let f = render_frame(
                    Kernel::chosen(),
                    &world,
                    &exposure,
                    &settings,
                    0,
                    &never,
                    false,
                );
                area::KEEP.store(true, Ordering::Relaxed);
                f.unwrap().unwrap()
            };
            let (kept, made) = (render(true), render(false));
            assert_eq!(kept.rgb, made.rgb, "{precision:?}");
        }
    }
}

#[cfg(test)]
mod mark_tests {
    use super::*;

    /// A 5×3 grey frame whose middle row has a bright pixel at column 2: second differences
    /// mark it and its row neighbours unless their triples are smooth on one object.
    fn frame() -> Vec<f32> {
        let mut rgb = vec![0.5f32; 3 * 5 * 3];
        rgb[3 * (5 + 2)..][..3].copy_from_slice(&[0.9, 0.9, 0.9]);
        rgb
    }

    #[test]
    fn smooth_triples_on_one_object_skip_the_second_difference() {
        let (rgb, spread) = (frame(), vec![0f32; 15]);
        let marked = |smooth: Option<&[u32]>| mark(&rgb, (&spread, smooth), 5, 3, 0.03);
        let plain = marked(None);
        assert!(plain[5 + 1] && plain[5 + 2] && plain[5 + 3], "{plain:?}");
        // Every pixel smooth on object 4: nothing is marked.
        let all = vec![4u32; 15];
        assert!(marked(Some(&all)).iter().all(|&m| !m));
        // Column 3 smooth on another object: the row triples through it are tested again
        // (centred on columns 2 and 3 of the middle row); column 1's stays exempt.
        let mut other = all.clone();
        for row in 0..3 {
            other[5 * row + 3] = 7;
        }
        let m = marked(Some(&other));
        assert!(m[5 + 2] && m[5 + 3] && !m[5 + 1], "{m:?}");
        // A pixel smooth on no object is tested.
        let mut none = all.clone();
        none[5 + 1] = rows::NOT_SMOOTH;
        let m = marked(Some(&none));
        assert!(m[5 + 1] && m[5 + 2] && !m[5 + 3], "{m:?}");
        // The spread rule is unchanged.
        let mut spread = spread.clone();
        spread[0] = 0.5;
        assert!(mark(&rgb, (&spread, Some(&all)), 5, 3, 0.03)[0]);
    }
}
