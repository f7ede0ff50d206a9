//! `load(path) → Sequence`: reads the YAML, checks every field, and resolves names, defaults
//! and the timeline. Every rejection names `FILE:LINE:COL: field.path: what is wrong (got X)`.
//!
//! serde_yaml reports syntax, type, unknown-key and missing-key errors with their position.
//! The checks below work on the parsed structs and name the field by its path; `locate` then
//! finds that path's line and column by walking the document once more.

mod aim;
mod fields;
mod guard;
mod locate;
pub mod mesh;
mod meshes;
mod messages;
mod motion;
pub(crate) mod raw;
mod scene;
mod settings;
mod textures;
mod timeline;

use fields::*;
use messages::*;
use scene::*;
use settings::*;

pub use guard::nesting_depth;
pub use meshes::Folders;
pub(crate) use messages::num;
pub use settings::{
    DEFAULT_MAX_SAMPLES, DEFAULT_SAMPLES, DEFAULT_SAMPLING_MAX, DEFAULT_THRESHOLD, FILM_FINAL_MAX,
    FILM_FINAL_THRESHOLD, FILM_SAMPLING_MAX, LENS_SAMPLES, LENS_THRESHOLD, SHUTTER_SAMPLES,
    SHUTTER_THRESHOLD,
};
pub(crate) use settings::{
    Explicit, MAX_SAMPLES, default_sampling, denoise, exposure, output_pattern, preset,
};
pub(crate) use textures::decode as decode_texture;
pub(crate) use timeline::{MAX_FIRST_FRAME, rolls_over};

use crate::camera::{Camera, Degenerate, Pose};
use crate::scene::{Intensity, Light, Material, Object, Scene, Shape};
use crate::settings::{Adaptive, Aovs, Sampler, Settings};
use crate::shutter::Shutter;
use crate::timeline::{Ease, Key, Timeline};
use glam::DVec3;
pub use raw::Quality;
use std::fmt::Display;
use std::path::{Path, PathBuf};

/// Largest width or height accepted, in pixels.
pub(crate) const MAX_DIMENSION: u64 = 16384;
/// Largest width × height: a frame in flight takes 12 bytes a pixel (16 with depth, up to 48
/// more with every compositing pass), and a run keeps a few in flight.
pub(crate) const MAX_PIXELS: u64 = 1 << 26;
/// Largest number of objects in a scene.
pub(crate) const MAX_OBJECTS: usize = 1_000_000;
/// Largest `max_depth` accepted.
pub(crate) const MAX_DEPTH: u64 = 10_000;
/// Largest shininess accepted (the exponent is shininess / 4).
pub(crate) const MAX_SHININESS: f64 = 1e6;
/// Largest colour component or intensity accepted.
pub(crate) const MAX_COLOR: f64 = 1e6;
/// Largest number of frames a timeline may have.
pub(crate) const MAX_FRAMES: u64 = 10_000_000;
/// A camera that rolls more than this between consecutive frames is flipping over.
pub(crate) const MAX_ROLL_PER_FRAME_DEGREES: f64 = 60.0;
/// Largest magnitude of any number: lengths get squared, and f64 squares overflow near 1e154.
pub(crate) const MAX_MAGNITUDE: f64 = 1e100;
/// Smallest sphere radius: its square must stay a normal f64.
pub(crate) const MIN_RADIUS: f64 = 1e-100;
/// Largest frames per second accepted.
pub(crate) const MAX_FPS: f64 = 1000.0;
/// Largest sequence file accepted, in bytes; larger files are refused before they are read.
/// serde_yaml holds a whole document as events before checking it, 35 to 100 bytes of memory
/// per byte of YAML (a 16 MiB scene takes 0.6 GB), so this bounds what a file can allocate.
pub(crate) const MAX_FILE_BYTES: u64 = 16 << 20;
/// Collections may nest this deep for sure (a sequence file needs 6 levels): a linear pre-scan
/// (`guard`) refuses text before parsing when its bound, at most twice the real depth plus one,
/// passes twice this plus one. libyaml takes time quadratic in the depth of `[[[[…`.
pub(crate) const MAX_NESTING: usize = 32;

/// A validated sequence file: everything needed to render any of its frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    /// The file's stem, used in the default output pattern.
    pub(crate) name: String,
    pub scene: Scene,
    pub timeline: Timeline,
    pub settings: Settings,
    /// The names of `materials:`, in the order of the first `Scene::materials` (those written
    /// inline in objects follow them there, unnamed).
    pub(crate) material_names: Vec<String>,
    /// Each object's `name:`, if it has one, in `objects:` order.
    pub(crate) object_names: Vec<Option<String>>,
    /// Output pattern; a run of `#` stands for the zero-padded frame number.
    pub(crate) output: String,
    /// The file's `render.quality`, if any (draft also halves the resolution).
    pub quality: Option<Quality>,
    /// The sampling values the file set itself, which no preset replaces.
    pub(crate) explicit: Explicit,
    /// What is valid but probably not meant (keys after the end of the film), one line each.
    pub(crate) warnings: Vec<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}:{line}:{col}: {message}")]
    Invalid {
        file: PathBuf,
        line: usize,
        col: usize,
        message: String,
    },
    #[error("{file}: {size}; sequence files are limited to {} MiB", MAX_FILE_BYTES >> 20)]
    TooLarge { file: PathBuf, size: String },
    /// A texture or mesh the file names does not fit in the memory the process may take: the
    /// file is valid, the machine (or its limit) too small, so the exit code is 1, not 2.
    #[error("{file}:{line}:{col}: {message}")]
    Memory {
        file: PathBuf,
        line: usize,
        col: usize,
        message: String,
    },
}

/// A rejected value: the YAML path of the field and what is wrong with it.
#[derive(Debug)]
struct Invalid {
    path: String,
    message: String,
    /// Refused for want of memory (`crate::budget`), not for what the file says.
    memory: bool,
}

type Check<T> = Result<T, Invalid>;

fn invalid<T>(path: impl Into<String>, message: impl Into<String>) -> Check<T> {
    Err(Invalid {
        path: path.into(),
        message: message.into(),
        memory: false,
    })
}

/// `invalid`, for a value the file may hold but this process has no memory for.
fn no_memory<T>(path: impl Into<String>, message: impl Into<String>) -> Check<T> {
    Err(Invalid {
        path: path.into(),
        message: message.into(),
        memory: true,
    })
}

/// Reads and validates the sequence file at `file` (`-` reads standard input). Only the file
/// decides the result: the command line's settings are applied afterwards, by the job.
pub fn load(file: &Path) -> Result<Sequence, LoadError> {
    load_with(file, &[])
}

/// `load`, with mesh and image files also looked for in the model libraries `assets` (after
/// the sequence file's folder; see `Folders`).
pub fn load_with(file: &Path, assets: &[PathBuf]) -> Result<Sequence, LoadError> {
    match parse_drawable(file, &read(file)?, assets)? {
        (_, Some(problem)) => Err(problem),
        (seq, None) => Ok(seq),
    }
}

/// `load_with`, except that a file whose every field is valid but whose camera cannot be
/// built at some key or frame still loads: that error comes back beside the sequence, for
/// `preview` to draw the path it describes.
pub(crate) fn load_drawable(
    file: &Path,
    assets: &[PathBuf],
) -> Result<(Sequence, Option<LoadError>), LoadError> {
    parse_drawable(file, &read(file)?, assets)
}

/// Whether `file` names standard input (`-`).
pub(crate) fn is_stdin(file: &Path) -> bool {
    file.as_os_str() == "-"
}

fn read(file: &Path) -> Result<String, LoadError> {
    use std::io::Read;
    let io = |source| LoadError::Io {
        file: file.to_owned(),
        source,
    };
    let input: Box<dyn Read> = match is_stdin(file) {
        true => Box::new(std::io::stdin().lock()),
        false => {
            let f = std::fs::File::open(file).map_err(io)?;
            if let Ok(meta) = f.metadata()
                && meta.len() > MAX_FILE_BYTES
            {
                return Err(too_large(file, meta.len()));
            }
            Box::new(f)
        }
    };
    // Pipes and special files have no length up front: read one byte past the limit at most.
    let mut bytes = Vec::new();
    input
        .take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(LoadError::TooLarge {
            file: file.to_owned(),
            size: "the input goes on past the limit".into(),
        });
    }
    let text = String::from_utf8(bytes).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        ))
    })?;
    Ok(text)
}

fn too_large(file: &Path, len: u64) -> LoadError {
    LoadError::TooLarge {
        file: file.to_owned(),
        size: format!(
            "the file is {:.1} MiB ({len} bytes)",
            len as f64 / (1u64 << 20) as f64
        ),
    }
}

/// `load` for text already in memory; `file` is only used to name things.
pub fn parse(file: &Path, text: &str) -> Result<Sequence, LoadError> {
    match parse_drawable(file, text, &[])? {
        (_, Some(problem)) => Err(problem),
        (seq, None) => Ok(seq),
    }
}

/// `load_drawable` for text already in memory.
pub(crate) fn parse_drawable(
    file: &Path,
    text: &str,
    assets: &[PathBuf],
) -> Result<(Sequence, Option<LoadError>), LoadError> {
    // Editors on Windows start UTF-8 files with a byte-order mark; libyaml would take it for
    // the start of a second document.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(too_large(file, text.len() as u64));
    }
    if let Some((line, col)) = guard::first_too_deep(text, 2 * MAX_NESTING + 1) {
        return Err(LoadError::Invalid {
            file: file.to_owned(),
            line,
            col,
            message: format!(
                "collections nested too deeply here (a sequence file needs 6 levels; over {MAX_NESTING} are refused)"
            ),
        });
    }
    let raw: raw::Sequence = serde_yaml::from_str(text).map_err(|e| yaml_error(file, text, &e))?;
    let name = match is_stdin(file) {
        true => "stdin".into(),
        false => file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "sequence".into()),
    };
    let located = |e: Invalid| {
        let (line, col) = locate::locate(text, &e.path);
        let message = clip(format!("{}: {}", e.path, e.message));
        match e.memory {
            true => LoadError::Memory {
                file: file.to_owned(),
                line,
                col,
                message,
            },
            false => LoadError::Invalid {
                file: file.to_owned(),
                line,
                col,
                message,
            },
        }
    };
    let base = match is_stdin(file) {
        true => Path::new(""),
        false => file.parent().unwrap_or(Path::new("")),
    };
    let cut = comment_cut(text);
    // An output the comment cut short may be refused for what is left of it (no file type):
    // the comment is the cause to name.
    let located = |e: Invalid| match (&cut, e.path == "output") {
        (Some(cut), true) => located(Invalid {
            message: cut.explain(&format!("what is left, `{}`, is refused", cut.kept)),
            ..e
        }),
        _ => located(e),
    };
    let folders = Folders::new(base, assets);
    let (mut seq, problem) = validate(raw, &name, &folders).map_err(located)?;
    if let Some(cut) = &cut {
        let at = format!("{}:{}:{}", file.display(), cut.line, cut.col);
        let what = format!("frames go to `{}`", seq.output);
        seq.warnings
            .push(format!("{at}: output: {}", cut.explain(&what)));
    }
    Ok((seq, problem.map(located)))
}

/// `output: ####.png` unquoted: YAML reads a `#` after a space as the start of a comment, so
/// the pattern is lost (and the default used, or what is left refused) without a word; the
/// loader says what was meant.
struct CommentCut {
    line: usize,
    col: usize,
    /// What YAML kept, what it dropped, and the whole value as written.
    kept: String,
    lost: String,
    whole: String,
}

impl CommentCut {
    /// `` `#` after a space starts a YAML comment, so `####.png` was dropped and WHAT; quote
    /// the pattern: output: "frames/####.png" ``.
    fn explain(&self, what: &str) -> String {
        format!(
            "`#` after a space starts a YAML comment, so `{}` was dropped and {what}; quote the pattern: output: \"{}\"",
            self.lost, self.whole
        )
    }
}

/// The top-level `output:` line when a comment cut a pattern-like text off its value.
fn comment_cut(text: &str) -> Option<CommentCut> {
    let (n, line) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.starts_with("output:"))?;
    let value = &line["output:".len()..];
    if value.trim_start().starts_with(['"', '\'']) {
        return None;
    }
    let comment = value
        .find(" #")
        .map(|i| i + 1)
        .or(value.starts_with('#').then_some(0))?;
    let lost = value[comment + 1..].trim();
    let pattern_like = lost.starts_with('#') || [".png", ".exr"].iter().any(|e| lost.contains(e));
    pattern_like.then(|| CommentCut {
        line: n + 1,
        col: "output:".len() + comment + 1,
        kept: value[..comment].trim().to_string(),
        lost: value[comment..].trim().to_string(),
        whole: value.trim().to_string(),
    })
}

impl Sequence {
    /// What the frames integrate besides the pixel (see `Film`).
    pub(crate) fn film(&self) -> Film {
        film(&self.settings, &self.timeline)
    }
}

/// What a sequence's frames integrate besides the pixel: a pinhole's instant, the open
/// shutter of a camera that can move (an orbit, or more than one key), or a lens some key
/// opens (with or without a shutter). Film (the last two) samples differently.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Film {
    Pinhole,
    Shutter,
    Lens,
}

fn film(s: &Settings, timeline: &Timeline) -> Film {
    if timeline.widest_aperture() > 0.0 {
        Film::Lens
    } else if s.shutter.is_some() && (timeline.moves() || !timeline.motion.is_empty()) {
        Film::Shutter
    } else {
        Film::Pinhole
    }
}

/// The sequence, and the first key or frame whose camera cannot be built (see `load_drawable`).
fn validate(
    mut raw: raw::Sequence,
    name: &str,
    folders: &Folders,
) -> Check<(Sequence, Option<Invalid>)> {
    let (mut settings, explicit) = render_settings(&raw.render)?;
    let object_names = aim::names(&raw.objects)?;
    let (scene, mut warnings) = scene_of(&raw, folders)?;
    aim::resolve(&mut raw, &scene, &object_names)?;
    let camera = raw.camera.as_ref().map(camera_key).transpose()?;
    let interpolation = raw.timeline.as_ref().and_then(|t| t.interpolation).map_or(
        crate::timeline::Interpolation::Smooth,
        motion::interpolation_of,
    );
    let things = |frames: timeline::Frames| motion::rigs(&raw, &scene, frames, interpolation);
    let loaded = match (&raw.timeline, camera) {
        (Some(t), camera) => timeline::timeline(t, camera, settings.shutter, &things)?,
        (None, Some(key)) => still_film(key, &things)?,
        (None, None) => return invalid("camera", "a sequence needs a `camera:` or a `timeline:`"),
    };
    let timeline = loaded.timeline;
    // Glass needs a preset's depth, film its sampling.
    let film = film(&settings, &timeline);
    explicit.settle(&mut settings, raw.render.quality, scene.has_glass(), film);
    settings.denoise = denoise(raw.render.denoise, film);
    let seq = Sequence {
        name: name.to_string(),
        scene,
        settings,
        material_names: raw.materials.0.iter().map(|(n, _)| n.clone()).collect(),
        object_names,
        output: output_of(raw.output, name, &timeline)?,
        quality: raw.render.quality,
        explicit,
        timeline,
        warnings: {
            warnings.extend(loaded.warnings);
            warnings
        },
    };
    Ok((seq, loaded.problem))
}

/// A film without `timeline:`: one frame of a still camera, or, when objects or lights have
/// keys, frames at 24 fps from 0 to their last key.
fn still_film(key: Key, things: timeline::Things) -> Check<timeline::Loaded> {
    let mut still = Timeline::still(key);
    still.motion = things((&still.clock, still.fps))?;
    if let Some(last) = timeline::last_thing_key(&still.motion) {
        still.frame_count = timeline::keyed_frames(last, still.fps)?;
        still.clock.duration = Some(last);
    }
    Ok(timeline::Loaded {
        timeline: still,
        warnings: Vec::new(),
        problem: None,
    })
}

/// The background, materials, objects (meshes read from below `folders`) and lights, checked
/// in that order, with the meshes' warnings.
fn scene_of(raw: &raw::Sequence, folders: &Folders) -> Check<(Scene, Vec<String>)> {
    let mut textures = textures::Textures::new(folders);
    let (background, sky) = textures.background(raw.render.background.as_ref())?;
    let mut materials = Vec::new();
    for (name, m) in &raw.materials.0 {
        materials.push(material(&format!("materials.{name}"), m, &mut textures)?);
    }
    let names: Vec<&str> = raw.materials.0.iter().map(|(n, _)| n.as_str()).collect();
    let mut objects = Vec::new();
    if raw.objects.len() > MAX_OBJECTS {
        return invalid(
            "objects",
            format!(
                "at most {MAX_OBJECTS} objects are accepted (got {})",
                raw.objects.len()
            ),
        );
    }
    let mut meshes = meshes::Meshes::new(folders);
    for (i, o) in raw.objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        let files = (&mut meshes, &mut textures);
        objects.push(object(&path, o, &names, &mut materials, files)?);
    }
    let (meshes, warnings) = meshes.finish();
    let mut lights = Vec::new();
    for (i, l) in raw.lights.iter().enumerate() {
        lights.push(light(&format!("lights[{i}]"), l)?);
    }
    let scene = Scene {
        objects,
        meshes,
        materials,
        lights,
        background,
        sky,
    };
    Ok((scene, warnings))
}

/// `output:` checked against the timeline (a one-file name holds one frame), or the default
/// `frames/NAME/frame_####.png`.
fn output_of(output: Option<String>, name: &str, timeline: &Timeline) -> Check<String> {
    let Some(o) = output else {
        return Ok(format!("frames/{name}/frame_####.png"));
    };
    let pattern = output_pattern(&o, timeline.last_frame());
    let pattern = pattern.or_else(|m| invalid("output", m))?;
    if pattern.is_single() && timeline.frame_count > 1 {
        return invalid(
            "output",
            format!(
                "output pattern `{o}` has no `#` run for the frame number, but the sequence has {} frames (e.g. frame_####.png)",
                timeline.frame_count
            ),
        );
    }
    contained("output", &o)?;
    Ok(o)
}

/// `camera:` as a key at time 0: a still camera, or what the first keyframe starts from.
fn camera_key(c: &raw::Camera) -> Check<Key> {
    let pose = Pose {
        position: vector("camera.position", c.position)?,
        look_at: vector("camera.look_at", c.look_at.point())?,
        up: direction("camera.up", c.up.unwrap_or([0.0, 1.0, 0.0]))?,
        fov: fov("camera.fov", c.fov.unwrap_or(90.0))?,
    };
    check_pose("camera", &pose)?;
    Ok(Key {
        time: 0.0,
        pose,
        ease: Ease::Pass,
        aperture: aperture("camera.aperture", c.aperture.unwrap_or(0.0))?,
        focus_distance: c
            .focus_distance
            .map(|f| focus_distance("camera.focus_distance", f))
            .transpose()?,
    })
}

/// A lens diameter: 0 (a pinhole) or more.
fn aperture(path: &str, v: f64) -> Check<f64> {
    if number(path, v)? < 0.0 {
        return invalid(
            path,
            format!(
                "must be 0 (a pinhole) or a positive lens diameter {}",
                got_num(v)
            ),
        );
    }
    Ok(v)
}

/// A distance in focus, along the view axis.
fn focus_distance(path: &str, v: f64) -> Check<f64> {
    if number(path, v)? <= 0.0 {
        return invalid(
            path,
            format!(
                "must be a distance greater than 0 from the camera to the plane in focus {}",
                got_num(v)
            ),
        );
    }
    Ok(v)
}

/// `path` is the mapping holding the pose; the error names the field to change.
fn check_pose(path: &str, pose: &Pose) -> Check<()> {
    Camera::new(pose).map(|_| ()).or_else(|e| {
        let field = match e {
            Degenerate::NoViewDirection => "look_at",
            Degenerate::UpParallel | Degenerate::Flip => "up",
            Degenerate::Fov => "fov",
        };
        invalid(
            format!("{path}.{field}"),
            format!(
                "{e} (position {}, look_at {}, up {})",
                num3(pose.position),
                num3(pose.look_at),
                num3(pose.up)
            ),
        )
    })
}
