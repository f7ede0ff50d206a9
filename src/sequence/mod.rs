//! `load(path) → Sequence`: reads the YAML, checks every field, and resolves names, defaults
//! and the timeline. Every rejection names `FILE:LINE:COL: field.path: what is wrong (got X)`.
//!
//! serde_yaml reports syntax, type, unknown-key and missing-key errors with their position.
//! The checks below work on the parsed structs and name the field by its path; `locate` then
//! finds that path's line and column by walking the document once more.

mod guard;
mod locate;
pub mod raw;
mod timeline;

pub use guard::nesting_depth;

use crate::camera::{Camera, Degenerate, Pose};
use crate::exposure::Shutter;
use crate::output::{atomic, pattern::Pattern};
use crate::scene::{Intensity, Light, Material, Object, Scene, Shape};
use crate::timeline::{Ease, Key, Timeline};
use crate::tracer::{Adaptive, Sampler, Settings};
use crate::transfer::Encoding;
use glam::DVec3;
pub use raw::Quality;
use std::fmt::Display;
use std::path::{Path, PathBuf};

/// Largest width or height accepted, in pixels.
pub const MAX_DIMENSION: u64 = 16384;
/// Largest width × height: a frame in flight takes 12 bytes a pixel (16 with depth), and a
/// run keeps a few in flight.
pub const MAX_PIXELS: u64 = 1 << 26;
/// Largest number of objects in a scene.
pub const MAX_OBJECTS: usize = 1_000_000;
/// Largest `max_depth` accepted.
pub const MAX_DEPTH: u64 = 10_000;
/// Largest shininess accepted (the exponent is shininess / 4).
pub const MAX_SHININESS: f64 = 1e6;
/// Largest colour component or intensity accepted.
pub const MAX_COLOR: f64 = 1e6;
/// Largest number of frames a timeline may have.
pub const MAX_FRAMES: u64 = 10_000_000;
/// A camera that rolls more than this between consecutive frames is flipping over.
pub const MAX_ROLL_PER_FRAME_DEGREES: f64 = 60.0;
/// Largest magnitude of any number: lengths get squared, and f64 squares overflow near 1e154.
pub const MAX_MAGNITUDE: f64 = 1e100;
/// Smallest sphere radius: its square must stay a normal f64.
pub const MIN_RADIUS: f64 = 1e-100;
/// Largest frames per second accepted.
pub const MAX_FPS: f64 = 1000.0;
/// Largest sequence file accepted, in bytes; larger files are refused before they are read.
/// serde_yaml holds a whole document as events before checking it, 35 to 100 bytes of memory
/// per byte of YAML (a 16 MiB scene takes 0.6 GB), so this bounds what a file can allocate.
pub const MAX_FILE_BYTES: u64 = 16 << 20;
/// Collections may nest this deep for sure (a sequence file needs 6 levels): a linear pre-scan
/// (`guard`) refuses text before parsing when its bound, at most twice the real depth plus one,
/// passes twice this plus one. libyaml takes time quadratic in the depth of `[[[[…`.
pub const MAX_NESTING: usize = 32;

/// A validated sequence file: everything needed to render any of its frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    /// The file's stem, used in the default output pattern.
    pub name: String,
    pub scene: Scene,
    pub timeline: Timeline,
    pub settings: Settings,
    /// Output pattern; a run of `#` stands for the zero-padded frame number.
    pub output: String,
    /// The file's `render.quality`, if any (draft also halves the resolution).
    pub quality: Option<Quality>,
    /// What is valid but probably not meant (keys after the end of the film), one line each.
    pub warnings: Vec<String>,
}

/// Values given on the command line; they replace the file's.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub size: Option<(u64, u64)>,
    pub max_depth: Option<u64>,
    pub output: Option<String>,
    pub depth: bool,
    pub samples: Option<u64>,
    pub quality: Option<Quality>,
    pub encoding: Option<Encoding>,
    pub exposure: Option<f64>,
    pub alpha: bool,
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
    #[error("{flag}: {message}")]
    Flag { flag: &'static str, message: String },
    #[error("{file}: {size}; sequence files are limited to {} MiB", MAX_FILE_BYTES >> 20)]
    TooLarge { file: PathBuf, size: String },
}

/// A rejected value: the YAML path of the field and what is wrong with it.
#[derive(Debug)]
struct Invalid {
    path: String,
    message: String,
}

type Check<T> = Result<T, Invalid>;

fn invalid<T>(path: impl Into<String>, message: impl Into<String>) -> Check<T> {
    Err(Invalid {
        path: path.into(),
        message: message.into(),
    })
}

pub fn load(file: &Path, overrides: &Overrides) -> Result<Sequence, LoadError> {
    parse(file, &read(file)?, overrides)
}

/// `load`, except that a file whose every field is valid but whose camera cannot be built at
/// some key or frame still loads: that error comes back beside the sequence, for `preview` to
/// draw the path it describes.
pub fn load_drawable(
    file: &Path,
    overrides: &Overrides,
) -> Result<(Sequence, Option<LoadError>), LoadError> {
    parse_drawable(file, &read(file)?, overrides)
}

fn read(file: &Path) -> Result<String, LoadError> {
    use std::io::Read;
    let io = |source| LoadError::Io {
        file: file.to_owned(),
        source,
    };
    let f = std::fs::File::open(file).map_err(io)?;
    if let Ok(meta) = f.metadata()
        && meta.len() > MAX_FILE_BYTES
    {
        return Err(too_large(file, meta.len()));
    }
    // Pipes and special files have no length up front: read one byte past the limit at most.
    let mut bytes = Vec::new();
    f.take(MAX_FILE_BYTES + 1)
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
pub fn parse(file: &Path, text: &str, overrides: &Overrides) -> Result<Sequence, LoadError> {
    match parse_drawable(file, text, overrides)? {
        (_, Some(problem)) => Err(problem),
        (seq, None) => Ok(seq),
    }
}

/// `load_drawable` for text already in memory.
pub fn parse_drawable(
    file: &Path,
    text: &str,
    overrides: &Overrides,
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
    let raw: raw::Sequence = serde_yaml::from_str(text).map_err(|e| yaml_error(file, &e))?;
    let name = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "sequence".into());
    let located = |e: Invalid| {
        let (line, col) = locate::locate(text, &e.path);
        let message = clip(format!("{}: {}", e.path, e.message));
        LoadError::Invalid {
            file: file.to_owned(),
            line,
            col,
            message,
        }
    };
    let (mut seq, problem) = validate(raw, &name).map_err(located)?;
    apply(&mut seq, overrides)?;
    Ok((seq, problem.map(located)))
}

fn yaml_error(file: &Path, e: &serde_yaml::Error) -> LoadError {
    let (line, col) = e.location().map_or((1, 1), |l| (l.line(), l.column()));
    let text = e.to_string();
    // serde_yaml appends " at line L column C" (and libyaml "..., while parsing ... at ...");
    // the position is already in front, so keep only the first clause.
    let message = match text.find(" at line ") {
        Some(i) => text[..i].to_string(),
        None => text,
    };
    // serde_yaml's two guards against hostile documents say little on their own.
    let message = match message.as_str() {
        "" => "invalid YAML".into(),
        "recursion limit exceeded" => {
            "nested too deeply, counting what aliases repeat (recursion limit exceeded)".into()
        }
        "repetition limit exceeded" => {
            "aliases repeat too many nodes (repetition limit exceeded)".into()
        }
        _ => out_of_range(&message)
            .or_else(|| tagged_number(&message))
            .unwrap_or(message),
    };
    LoadError::Invalid {
        file: file.to_owned(),
        line,
        col,
        message: clip(message),
    }
}

/// serde_yaml reads a number beyond f64 (`1e400`) as a string and one beyond 64 bits as an
/// i128/u128, then reports a type error; say instead that the number is out of range.
fn out_of_range(message: &str) -> Option<String> {
    let (field, rest) = match message.split_once(": invalid type: ") {
        Some((field, rest)) => (format!("{field}: "), rest),
        None => (String::new(), message.strip_prefix("invalid type: ")?),
    };
    if let Some(s) = rest.strip_prefix("string \"") {
        let s = s.strip_suffix("\", expected f64")?;
        let digits = s
            .bytes()
            .all(|b| b.is_ascii_digit() || b"+-.eE".contains(&b));
        s.parse::<f64>()
            .ok()
            .filter(|v| digits && v.is_infinite())?;
        return Some(format!(
            "{field}must be within ±{MAX_MAGNITUDE:e} (lengths are squared) (got {s})"
        ));
    }
    let s = rest.strip_prefix("integer `")?;
    let s = ["u128", "i128"]
        .iter()
        .flat_map(|t| ["u64", "i64"].map(|e| format!("` as {t}, expected {e}")))
        .find_map(|suffix| s.strip_suffix(suffix.as_str()))?;
    Some(format!("{field}number out of range (got {s})"))
}

/// serde_yaml reads a tagged, quoted number (`fps: !!float "24"`) as a number and then refuses
/// it for the very type it is (`invalid type: floating point `24.0`, expected f64`): say what
/// to write instead.
fn tagged_number(message: &str) -> Option<String> {
    let (field, rest) = message.split_once(": invalid type: ")?;
    let value = match rest.strip_prefix("floating point `") {
        Some(r) => r.strip_suffix("`, expected f64")?,
        None => {
            let (value, expected) = rest.strip_prefix("integer `")?.split_once("`, expected ")?;
            ["f64", "u64", "i64"].contains(&expected).then_some(value)?
        }
    };
    let value = value.parse::<f64>().map_or(value.to_string(), num);
    // `timeline.fps` → `fps: 24`; a list element (`center[1]`) → `0`.
    let plain = match field.ends_with(']') {
        true => value.clone(),
        false => format!("{}: {value}", field.rsplit('.').next().unwrap_or(field)),
    };
    Some(format!(
        "{field}: a tagged, quoted number such as `!!float \"{value}\"` is not read as a number; write it plainly, without tag or quotes: `{plain}`"
    ))
}

/// Longest error message shown whole; longer ones quote some huge value from the file.
const MAX_MESSAGE: usize = 400;

/// `message`, cut in the middle when it is too long to read.
fn clip(message: String) -> String {
    if message.len() <= MAX_MESSAGE {
        return message;
    }
    let mut head = MAX_MESSAGE / 2;
    while !message.is_char_boundary(head) {
        head -= 1;
    }
    let mut tail = message.len() - MAX_MESSAGE / 4;
    while !message.is_char_boundary(tail) {
        tail += 1;
    }
    format!(
        "{} [… {} bytes …] {}",
        &message[..head],
        tail - head,
        &message[tail..]
    )
}

fn apply(seq: &mut Sequence, o: &Overrides) -> Result<(), LoadError> {
    let flag = |flag, message: String| LoadError::Flag { flag, message };
    if let Some(q) = o.quality {
        preset(&mut seq.settings, q);
    }
    let draft = o.quality.or(seq.quality) == Some(Quality::Draft);
    if draft && o.size.is_none() {
        seq.settings.width = seq.settings.width.div_ceil(2);
        seq.settings.height = seq.settings.height.div_ceil(2);
    }
    if let Some(n) = o.samples {
        // `--samples N` means N uniform samples, whatever the file or preset chose.
        seq.settings.samples = samples(n).map_err(|m| flag("--samples", m))?;
        seq.settings.adaptive = None;
    }
    if let Some((w, h)) = o.size {
        seq.settings.width = dimension(w).map_err(|m| flag("--size", format!("width {m}")))?;
        seq.settings.height = dimension(h).map_err(|m| flag("--size", format!("height {m}")))?;
        pixels(seq.settings.width, seq.settings.height).map_err(|m| flag("--size", m))?;
    }
    if let Some(d) = o.max_depth {
        seq.settings.max_depth = max_depth(d).map_err(|m| flag("--max-depth", m))?;
    }
    if let Some(out) = &o.output {
        output_pattern(out, seq.timeline.frame_count).map_err(|m| flag("--output", m))?;
        seq.output = out.clone();
    }
    seq.settings.depth |= o.depth;
    seq.settings.alpha |= o.alpha;
    if let Some(e) = o.encoding {
        seq.settings.encoding = e;
    }
    if let Some(e) = o.exposure {
        seq.settings.exposure = exposure(e).map_err(|m| flag("--exposure", m))?;
    }
    Ok(())
}

/// Longest path the kernel takes, in bytes (PATH_MAX less its NUL).
const MAX_PATH_BYTES: usize = 4095;

/// A pattern that names frames of a type rayreel writes, in paths the file system can take.
fn output_pattern(output: &str, frame_count: u64) -> Result<Pattern, String> {
    if output.contains('\0') {
        return Err(format!(
            "contains a NUL byte, which no file name may hold (got `{}`)",
            output.replace('\0', "\\0")
        ));
    }
    let pattern = Pattern::new(output, frame_count)?;
    // Every frame's path is as long as the last one's (the numbers are padded to one width).
    let last = pattern.frame_path(frame_count.saturating_sub(1));
    for part in last.iter() {
        let part = part.to_string_lossy();
        if part.len() > atomic::NAME_MAX {
            return Err(format!(
                "the name `{}` is {} bytes; a file or directory name may have at most {}",
                abbreviated(&part),
                part.len(),
                atomic::NAME_MAX
            ));
        }
    }
    if last.as_os_str().len() > MAX_PATH_BYTES {
        return Err(format!(
            "a frame's path is {} bytes (`{}`); a path may have at most {MAX_PATH_BYTES}",
            last.as_os_str().len(),
            abbreviated(&last.to_string_lossy())
        ));
    }
    match pattern.extension().as_str() {
        "png" | "exr" => Ok(pattern),
        other => Err(format!(
            "unsupported file type `.{other}`; frames are .png or .exr (got `{output}`)"
        )),
    }
}

/// `s` cut in the middle when long: `aaaaaaaaaaaaaaaaaaaa…aaaaaaaa_0001.png`.
fn abbreviated(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    if chars.len() <= 48 {
        return s.to_string();
    }
    let head: String = chars[..24].iter().collect();
    let tail: String = chars[chars.len() - 20..].iter().collect();
    format!("{head}…{tail}")
}

/// A sequence file may come from someone else, so its `output` stays below the current
/// directory; the user can still write anywhere with `--output`, which they typed themselves.
fn contained(path: &str, output: &str) -> Check<()> {
    let p = Path::new(output);
    let climbs = p
        .components()
        .any(|c| matches!(c, std::path::Component::ParentDir));
    if p.is_absolute() || climbs || output.starts_with('~') {
        return invalid(
            path,
            format!(
                "a sequence file may only write below the current directory, so an absolute path or `..` is refused here (got `{output}`); if you mean it, give it on the command line with --output"
            ),
        );
    }
    if let Some(dir) = escapes(output) {
        return invalid(
            path,
            format!(
                "`{output}` leads outside the current directory: its directory is {} once symbolic links are followed; a sequence file may only write below the current directory (if you mean it, give it on the command line with --output)",
                dir.display()
            ),
        );
    }
    Ok(())
}

/// Where the directory of a relative `output` really is when it is not below the current
/// directory (a symbolic link on the way leads elsewhere, or leads nowhere); `None` when it is
/// inside. The part that does not exist yet will be created as plain directories.
pub fn escapes(output: &str) -> Option<PathBuf> {
    let cwd = std::fs::canonicalize(".").ok()?;
    let mut existing = Path::new(output).parent().unwrap_or(Path::new(""));
    let mut missing = Vec::new();
    while !existing.as_os_str().is_empty() && std::fs::symlink_metadata(existing).is_err() {
        missing.push(existing.file_name()?);
        existing = existing.parent().unwrap_or(Path::new(""));
    }
    let base = match existing.as_os_str().is_empty() {
        true => cwd.clone(),
        // An entry that exists but does not resolve is a link that leads nowhere.
        false => std::fs::canonicalize(existing).unwrap_or_else(|_| existing.to_path_buf()),
    };
    let dir = missing.iter().rev().fold(base, |d, part| d.join(part));
    (!dir.starts_with(&cwd)).then_some(dir)
}

fn pixels(w: u32, h: u32) -> Result<(), String> {
    let n = u64::from(w) * u64::from(h);
    if n > MAX_PIXELS {
        return Err(format!(
            "{w}x{h} is {n} pixels; a frame may have at most {MAX_PIXELS} (e.g. 8192x8192)"
        ));
    }
    Ok(())
}

fn dimension(v: u64) -> Result<u32, String> {
    if (1..=MAX_DIMENSION).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!("must be 1 to {MAX_DIMENSION} pixels (got {v})"))
    }
}

fn max_depth(v: u64) -> Result<u32, String> {
    if (1..=MAX_DEPTH).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!(
            "must be 1 (no reflections) to {MAX_DEPTH} (got {v})"
        ))
    }
}

/// The sequence, and the first key or frame whose camera cannot be built (see `load_drawable`).
fn validate(raw: raw::Sequence, name: &str) -> Check<(Sequence, Option<Invalid>)> {
    let settings = render_settings(&raw.render)?;
    let background = color(
        "render.background",
        raw.render.background.unwrap_or_default(),
    )?;
    let mut materials = Vec::new();
    for (name, m) in &raw.materials.0 {
        materials.push(material(&format!("materials.{name}"), m)?);
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
    for (i, o) in raw.objects.iter().enumerate() {
        objects.push(object(&format!("objects[{i}]"), o, &names, &mut materials)?);
    }
    let mut lights = Vec::new();
    for (i, l) in raw.lights.iter().enumerate() {
        lights.push(light(&format!("lights[{i}]"), l)?);
    }
    let camera = raw.camera.as_ref().map(camera_key).transpose()?;
    let loaded = match (&raw.timeline, camera) {
        (Some(t), camera) => timeline::timeline(t, camera, settings.shutter)?,
        (None, Some(key)) => timeline::Loaded {
            timeline: Timeline::still(key),
            warnings: Vec::new(),
            problem: None,
        },
        (None, None) => return invalid("camera", "a sequence needs a `camera:` or a `timeline:`"),
    };
    let timeline = loaded.timeline;
    let seq = Sequence {
        name: name.to_string(),
        scene: Scene {
            objects,
            materials,
            lights,
            background,
        },
        settings,
        output: match raw.output {
            Some(o) => {
                output_pattern(&o, timeline.frame_count).or_else(|m| invalid("output", m))?;
                contained("output", &o)?;
                o
            }
            None => format!("frames/{name}/frame_####.png"),
        },
        quality: raw.render.quality,
        timeline,
        warnings: loaded.warnings,
    };
    Ok((seq, loaded.problem))
}

fn render_settings(r: &raw::Render) -> Check<Settings> {
    let check = |path: &str, r: Result<u32, String>| r.or_else(|m| invalid(path, m));
    let mut s = Settings {
        width: check("render.width", dimension(r.width.unwrap_or(1280)))?,
        height: check("render.height", dimension(r.height.unwrap_or(720)))?,
        max_depth: 3,
        depth: r.depth.unwrap_or(false),
        samples: 1,
        adaptive: None,
        sampler: match r.sampler {
            Some(raw::Sampler::Random) => Sampler::Random,
            _ => Sampler::Stratified,
        },
        alpha: r.alpha.unwrap_or(false),
        exposure: match r.exposure {
            Some(e) => exposure(e).or_else(|m| invalid("render.exposure", m))?,
            None => 0.0,
        },
        encoding: r.encoding.unwrap_or_default(),
        shutter: shutter(r)?,
    };
    if r.quality.is_none() && r.samples.is_none() && r.adaptive.is_none() {
        default_sampling(&mut s);
    }
    pixels(s.width, s.height).or_else(|m| invalid("render.width", m))?;
    if let Some(q) = r.quality {
        preset(&mut s, q);
    }
    if let Some(d) = r.max_depth {
        s.max_depth = check("render.max_depth", max_depth(d))?;
    }
    if let Some(n) = r.samples {
        s.samples = check("render.samples", samples(n))?;
    }
    if let Some(a) = &r.adaptive {
        let threshold = a.threshold.unwrap_or(DEFAULT_THRESHOLD);
        in_range(
            "render.adaptive.threshold",
            threshold,
            0.0,
            1.0,
            "in (0, 1]",
        )?;
        if threshold == 0.0 {
            return invalid(
                "render.adaptive.threshold",
                "must be greater than 0 (got 0)",
            );
        }
        let max_samples = check(
            "render.adaptive.max_samples",
            samples(a.max_samples.unwrap_or(DEFAULT_MAX_SAMPLES)),
        )?;
        s.adaptive = Some(Adaptive {
            threshold: threshold as f32,
            max_samples,
        });
    }
    if let Some(a) = s.adaptive
        && a.max_samples <= s.samples
    {
        return invalid(
            "render.adaptive.max_samples",
            format!(
                "must exceed render.samples ({}) {}",
                s.samples,
                got(a.max_samples)
            ),
        );
    }
    Ok(s)
}

/// Largest |render.exposure|, in stops: 2^64 times the brightest colour still fits an f32.
pub const MAX_EXPOSURE: f64 = 64.0;

fn exposure(v: f64) -> Result<f64, String> {
    if v.is_finite() && v.abs() <= MAX_EXPOSURE {
        Ok(v)
    } else {
        Err(format!(
            "must be within ±{MAX_EXPOSURE} stops {}",
            got_num(v)
        ))
    }
}

/// Sampling of a file that sets none (no `samples`, `adaptive` or `quality`): antialiased
/// frames at about the cost one sample had before the packet tracer (see the README).
fn default_sampling(s: &mut Settings) {
    s.samples = DEFAULT_SAMPLES;
    s.adaptive = Some(Adaptive {
        threshold: DEFAULT_THRESHOLD as f32,
        max_samples: DEFAULT_SAMPLING_MAX,
    });
}

/// `render.samples` when a file sets no sampling.
pub const DEFAULT_SAMPLES: u32 = 2;
/// `render.adaptive.max_samples` when a file sets no sampling.
pub const DEFAULT_SAMPLING_MAX: u32 = 8;

/// `render.shutter` and `render.shutter_offset`; None when the shutter angle is 0.
fn shutter(r: &raw::Render) -> Check<Option<Shutter>> {
    let angle = in_range(
        "render.shutter",
        r.shutter.unwrap_or(0.0),
        0.0,
        360.0,
        "an angle in [0, 360] degrees (0: no motion blur, 180: film)",
    )?;
    let offset = in_range(
        "render.shutter_offset",
        r.shutter_offset.unwrap_or(0.0),
        -0.5,
        0.5,
        "in [-0.5, 0.5] (0: open interval centred on the frame time, 0.5: opening at it, -0.5: closing at it)",
    )?;
    Ok((angle > 0.0).then_some(Shutter { angle, offset }))
}

/// Default `render.adaptive.threshold`: a linear colour difference of about 8/255.
pub const DEFAULT_THRESHOLD: f64 = 0.03;
/// Default `render.adaptive.max_samples`.
pub const DEFAULT_MAX_SAMPLES: u64 = 32;
/// Largest samples per pixel accepted.
pub const MAX_SAMPLES: u64 = 4096;

/// What a quality preset sets; explicit settings at the same or a later level override it.
pub fn preset(s: &mut Settings, q: Quality) {
    let (samples, adaptive, depth) = match q {
        Quality::Draft => (1, None, 2),
        Quality::Preview => (4, None, 3),
        Quality::Final => (
            4,
            Some(Adaptive {
                threshold: DEFAULT_THRESHOLD as f32,
                max_samples: 64,
            }),
            5,
        ),
    };
    s.samples = samples;
    s.adaptive = adaptive;
    s.max_depth = depth;
}

fn samples(v: u64) -> Result<u32, String> {
    if (1..=MAX_SAMPLES).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!(
            "must be 1 to {MAX_SAMPLES} samples per pixel (got {v})"
        ))
    }
}

fn got(v: impl Display) -> String {
    format!("(got {v})")
}

/// `(got X)` for a number, short (see `num`).
pub(super) fn got_num(v: f64) -> String {
    got(num(v))
}

/// A number as messages show it: exactly as written when that takes at most 6 significant
/// digits (`0.35`, `10000000`), otherwise rounded to 6, plain from 1e-4 up to 1e6 and in
/// exponent form beyond (`1e-300`, never 300 digits).
pub fn num(v: f64) -> String {
    let exact = format!("{v}");
    let significant = exact
        .trim_start_matches('-')
        .replace('.', "")
        .trim_matches('0')
        .len();
    if v == 0.0 || !v.is_finite() || ((1e-4..1e16).contains(&v.abs()) && significant <= 6) {
        return exact;
    }
    let exponent = v.abs().log10().floor() as i32;
    if (-4..6).contains(&exponent) {
        let decimals = (5 - exponent).max(0) as usize;
        return trim_zeros(&format!("{v:.decimals$}")).to_string();
    }
    let text = format!("{v:.5e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    format!("{}e{exponent}", trim_zeros(mantissa))
}

/// `1.500` → `1.5`, `2.000` → `2`; whole numbers without a point stay as they are.
fn trim_zeros(s: &str) -> &str {
    match s.contains('.') {
        true => s.trim_end_matches('0').trim_end_matches('.'),
        false => s,
    }
}

/// `[x, y, z]` with each number short (see `num`).
fn num3(v: DVec3) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

fn number(path: &str, v: f64) -> Check<f64> {
    if !v.is_finite() {
        invalid(path, format!("must be a finite number {}", got_num(v)))
    } else if v.abs() > MAX_MAGNITUDE {
        invalid(
            path,
            format!(
                "must be within ±{MAX_MAGNITUDE:e} (lengths are squared) {}",
                got_num(v)
            ),
        )
    } else {
        Ok(v)
    }
}

fn vector(path: &str, v: raw::V3) -> Check<DVec3> {
    for (i, x) in v.iter().enumerate() {
        number(&format!("{path}[{i}]"), *x)?;
    }
    Ok(DVec3::from(v))
}

fn fmt3(v: raw::V3) -> String {
    num3(DVec3::from(v))
}

fn unit(path: &str, v: raw::V3) -> Check<DVec3> {
    direction(path, v).map(|d| d.normalize())
}

/// A vector that has a direction, kept as written: a camera's `up` is used exactly as printed
/// by `rayreel camera`, so a still camera given those numbers renders the same frame.
fn direction(path: &str, v: raw::V3) -> Check<DVec3> {
    let d = vector(path, v)?;
    let n = d.normalize_or_zero();
    if n == DVec3::ZERO || !n.is_finite() {
        return invalid(
            path,
            format!("must have a non-zero length {}", got(fmt3(v))),
        );
    }
    Ok(d)
}

fn color(path: &str, v: raw::V3) -> Check<DVec3> {
    let c = vector(path, v)?;
    if c.min_element() < 0.0 || c.max_element() > MAX_COLOR {
        return invalid(
            path,
            format!("components must be in [0, {MAX_COLOR}] {}", got(fmt3(v))),
        );
    }
    Ok(c)
}

fn in_range(path: &str, v: f64, lo: f64, hi: f64, what: &str) -> Check<f64> {
    number(path, v)?;
    if v < lo || v > hi {
        return invalid(path, format!("must be {what} {}", got_num(v)));
    }
    Ok(v)
}

fn positive(path: &str, v: f64) -> Check<f64> {
    if number(path, v)? <= 0.0 {
        return invalid(path, format!("must be greater than 0 {}", got_num(v)));
    }
    Ok(v)
}

fn fov(path: &str, v: f64) -> Check<f64> {
    number(path, v)?;
    if !(v > 0.0 && v < 180.0) {
        return invalid(
            path,
            format!(
                "must be between 0 and 180 degrees, exclusive {}",
                got_num(v)
            ),
        );
    }
    Ok(v)
}

fn material(path: &str, m: &raw::Material) -> Check<Material> {
    let shininess = m.shininess.unwrap_or(100.0);
    let exponent = shininess / 4.0;
    Ok(Material {
        // x^e < 1e-30 ⇔ x < exp(−69.08 / e).
        specular_floor: if exponent > 0.0 {
            libm::exp(-69.08 / exponent)
        } else {
            0.0
        },
        ambient: color(&format!("{path}.ambient"), m.ambient)?,
        diffuse: color(&format!("{path}.diffuse"), m.diffuse)?,
        specular: color(&format!("{path}.specular"), m.specular)?,
        exponent: in_range(
            &format!("{path}.shininess"),
            shininess,
            0.0,
            MAX_SHININESS,
            &format!("in [0, {MAX_SHININESS}]"),
        )? / 4.0,
        reflection: in_range(
            &format!("{path}.reflection"),
            m.reflection.unwrap_or(0.0),
            0.0,
            1.0,
            "in [0, 1]",
        )?,
        transmission: transmission(path, m)?,
        ior: in_range(
            &format!("{path}.ior"),
            m.ior.unwrap_or(1.5),
            1.0,
            MAX_IOR,
            &format!("in [1, {MAX_IOR}]"),
        )?,
        fresnel: m.fresnel,
    })
}

/// Glass refracts at most as much as diamond's 2.42 several times over; beyond this an index
/// means nothing physical.
const MAX_IOR: f64 = 100.0;

/// The transmission filter: each channel in [0, 1], and with the reflection at most 1, since
/// a surface cannot pass on more light than it receives (Fresnel shares it out itself).
fn transmission(path: &str, m: &raw::Material) -> Check<DVec3> {
    if m.fresnel && m.reflection.is_some() {
        return invalid(
            format!("{path}.reflection"),
            "with `fresnel: true` the Fresnel term decides how much is reflected; remove `reflection`",
        );
    }
    let field = format!("{path}.transmission");
    let Some(raw::Filter(v)) = m.transmission else {
        return Ok(DVec3::ZERO);
    };
    let t = vector(&field, v)?;
    if t.min_element() < 0.0 || t.max_element() > 1.0 {
        return invalid(&field, format!("must be in [0, 1] {}", got(fmt3(v))));
    }
    let r = m.reflection.unwrap_or(0.0);
    if !m.fresnel && r + t.max_element() > 1.0 {
        return invalid(
            &field,
            format!(
                "reflection + transmission must not exceed 1 in any channel: a surface cannot pass on more light than it receives {}",
                got(format!("{} + {}", num(r), fmt3(v)))
            ),
        );
    }
    Ok(t)
}

fn material_ref(
    path: &str,
    r: &raw::MaterialRef,
    names: &[&str],
    materials: &mut Vec<Material>,
) -> Check<usize> {
    match r {
        raw::MaterialRef::Named(n) => names.iter().position(|m| m == n).map_or_else(
            || {
                let known = if names.is_empty() {
                    "no materials are defined under `materials:`".to_string()
                } else {
                    format!("defined: {}", names.join(", "))
                };
                invalid(path, format!("unknown material `{n}` ({known})"))
            },
            Ok,
        ),
        raw::MaterialRef::Inline(m) => {
            materials.push(material(path, m)?);
            Ok(materials.len() - 1)
        }
    }
}

fn exactly_one<T>(path: &str, options: &[(&str, Option<T>)]) -> Check<T>
where
    T: Copy,
{
    let given: Vec<&(&str, Option<T>)> = options.iter().filter(|(_, v)| v.is_some()).collect();
    let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
    match given.as_slice() {
        [(_, Some(v))] => Ok(*v),
        [] => invalid(path, format!("needs one of: {}", names.join(", "))),
        many => invalid(
            path,
            format!(
                "give exactly one of {} per entry (got {})",
                names.join(", "),
                many.iter()
                    .map(|(n, _)| *n)
                    .collect::<Vec<_>>()
                    .join(" and ")
            ),
        ),
    }
}

fn object(
    path: &str,
    o: &raw::Object,
    names: &[&str],
    materials: &mut Vec<Material>,
) -> Check<Object> {
    let which = exactly_one(
        path,
        &[
            ("sphere", o.sphere.as_ref().map(|_| 0)),
            ("plane", o.plane.as_ref().map(|_| 1)),
        ],
    )?;
    if which == 0 {
        let s = o.sphere.as_ref().expect("checked");
        let p = format!("{path}.sphere");
        Ok(Object {
            shape: Shape::Sphere {
                center: vector(&format!("{p}.center"), s.center)?,
                radius: in_range(
                    &format!("{p}.radius"),
                    s.radius,
                    MIN_RADIUS,
                    MAX_MAGNITUDE,
                    "a positive length in [1e-100, 1e100]",
                )?,
            },
            material: material_ref(&format!("{p}.material"), &s.material, names, materials)?,
        })
    } else {
        let s = o.plane.as_ref().expect("checked");
        let p = format!("{path}.plane");
        Ok(Object {
            shape: Shape::Plane {
                point: vector(&format!("{p}.point"), s.point)?,
                normal: unit(&format!("{p}.normal"), s.normal)?,
            },
            material: material_ref(&format!("{p}.material"), &s.material, names, materials)?,
        })
    }
}

fn intensity(
    path: &str,
    ambient: raw::V3,
    diffuse: raw::V3,
    specular: raw::V3,
) -> Check<Intensity> {
    Ok(Intensity {
        ambient: color(&format!("{path}.ambient"), ambient)?,
        diffuse: color(&format!("{path}.diffuse"), diffuse)?,
        specular: color(&format!("{path}.specular"), specular)?,
    })
}

fn light(path: &str, l: &raw::Light) -> Check<Light> {
    let which = exactly_one(
        path,
        &[
            ("point", l.point.as_ref().map(|_| 0)),
            ("directional", l.directional.as_ref().map(|_| 1)),
            ("spot", l.spot.as_ref().map(|_| 2)),
            ("ambient", l.ambient.as_ref().map(|_| 3)),
        ],
    )?;
    Ok(match which {
        0 => {
            let p = l.point.as_ref().expect("checked");
            let path = format!("{path}.point");
            Light::Point {
                position: vector(&format!("{path}.position"), p.position)?,
                intensity: intensity(&path, p.ambient, p.diffuse, p.specular)?,
            }
        }
        1 => {
            let d = l.directional.as_ref().expect("checked");
            let path = format!("{path}.directional");
            Light::Directional {
                to_light: -unit(&format!("{path}.direction"), d.direction)?,
                intensity: intensity(&path, d.ambient, d.diffuse, d.specular)?,
            }
        }
        2 => spot(&format!("{path}.spot"), l.spot.as_ref().expect("checked"))?,
        _ => Light::Ambient {
            color: color(
                &format!("{path}.ambient.color"),
                l.ambient.as_ref().expect("checked").color,
            )?,
        },
    })
}

fn spot(path: &str, s: &raw::SpotLight) -> Check<Light> {
    let angle = |name: &str, v: f64| {
        in_range(
            &format!("{path}.{name}"),
            v,
            0.0,
            180.0,
            "an angle in [0, 180] degrees",
        )
    };
    let inner = angle("inner_angle", s.inner_angle)?;
    let outer = angle("outer_angle", s.outer_angle)?;
    if inner > outer {
        return invalid(
            format!("{path}.inner_angle"),
            format!(
                "must not exceed outer_angle ({}) {}",
                num(outer),
                got_num(inner)
            ),
        );
    }
    Ok(Light::Spot {
        position: vector(&format!("{path}.position"), s.position)?,
        axis: unit(&format!("{path}.direction"), s.direction)?,
        cos_inner: libm::cos(inner.to_radians()),
        cos_outer: libm::cos(outer.to_radians()),
        intensity: intensity(path, s.ambient, s.diffuse, s.specular)?,
    })
}

/// `camera:` as a key at time 0: a still camera, or what the first keyframe starts from.
fn camera_key(c: &raw::Camera) -> Check<Key> {
    let pose = Pose {
        position: vector("camera.position", c.position)?,
        look_at: vector("camera.look_at", c.look_at)?,
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
