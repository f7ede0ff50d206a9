//! `render:` and `output:` → `Settings` and the output pattern, with the limits both the file
//! and the command line are held to.

use super::*;
use crate::pattern::{NAME_MAX, Pattern};

/// The sampling values a file gives itself (`render.samples`, `render.adaptive`,
/// `render.max_depth`), checked: a preset fills only what these leave unset, whether the
/// preset comes from the file or from `--quality`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Explicit {
    pub samples: Option<u32>,
    pub adaptive: Option<Adaptive>,
    pub max_depth: Option<u32>,
}

impl Explicit {
    /// `q`'s values for what the file left unset; on a scene with glass (`glass`), at least
    /// 3 surfaces (in, out, and what is behind) so `draft` still shows through it; on film
    /// (`film`: a shutter or a lens), `final`'s film sampling.
    pub(crate) fn preset(&self, s: &mut Settings, q: Quality, glass: bool, film: Film) {
        preset(s, q, film);
        if glass {
            s.max_depth = s.max_depth.max(GLASS_DEPTH);
        }
        self.apply(s);
    }

    /// The sampling of a sequence: its preset's (`q`), or where it sets no sampling at all,
    /// the default (film's when `film`), under what the file set itself. A preset's
    /// adaptive sampling that the file's own samples already reach is dropped.
    pub(crate) fn settle(&self, s: &mut Settings, q: Option<Quality>, glass: bool, film: Film) {
        match q {
            Some(q) => self.preset(s, q, glass, film),
            None => {
                if self.samples.is_none() && self.adaptive.is_none() {
                    default_sampling(s, film);
                }
                self.apply(s);
            }
        }
        if self.adaptive.is_none() && s.adaptive.is_some_and(|a| a.max_samples <= s.samples) {
            s.adaptive = None;
        }
    }

    /// The file's own values over `s`'s.
    fn apply(&self, s: &mut Settings) {
        s.max_depth = self.max_depth.unwrap_or(s.max_depth);
        s.samples = self.samples.unwrap_or(s.samples);
        if self.adaptive.is_some() {
            s.adaptive = self.adaptive;
        }
    }
}

/// The fewest surfaces a path through glass needs to show what is behind it (entering,
/// leaving, the surface seen): a preset never sets less on a scene with glass.
pub(crate) const GLASS_DEPTH: u32 = 3;

/// The file's `render:` settings, and which sampling values it set itself.
pub(super) fn render_settings(r: &raw::Render) -> Check<(Settings, Explicit)> {
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
        shutter: shutter(r)?,
        alpha: r.alpha.unwrap_or(false),
        exposure: match r.exposure {
            Some(e) => exposure(e).or_else(|m| invalid("render.exposure", m))?,
            None => 0.0,
        },
        encoding: r.encoding.unwrap_or_default(),
        precision: r.precision.unwrap_or_default(),
        aov: Aovs::of(r.aov.as_deref().unwrap_or_default()),
        // Film is known once the timeline is: `validate` settles it (`denoise`).
        denoise: false,
    };
    pixels(s.width, s.height).or_else(|m| invalid("render.width", m))?;
    let explicit = explicit(r)?;
    // Glass and film are known once the scene and the timeline are: `validate` settles
    // the sampling again then.
    explicit.settle(&mut s, r.quality, false, Film::Pinhole);
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
    Ok((s, explicit))
}

/// `render.max_depth`, `render.samples` and `render.adaptive` where the file sets them.
fn explicit(r: &raw::Render) -> Check<Explicit> {
    let check = |path: &str, r: Result<u32, String>| r.or_else(|m| invalid(path, m));
    Ok(Explicit {
        max_depth: match r.max_depth {
            Some(d) => Some(check("render.max_depth", max_depth(d))?),
            None => None,
        },
        samples: match r.samples {
            Some(n) => Some(check("render.samples", samples(n))?),
            None => None,
        },
        adaptive: match &r.adaptive {
            Some(a) => Some(adaptive(a)?),
            None => None,
        },
    })
}

/// `render.adaptive`: its threshold in (0, 1] and its most samples, or their defaults.
fn adaptive(a: &raw::Adaptive) -> Check<Adaptive> {
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
    let max_samples = samples(a.max_samples.unwrap_or(DEFAULT_MAX_SAMPLES as i64))
        .or_else(|m| invalid("render.adaptive.max_samples", m))?;
    Ok(Adaptive {
        threshold: threshold as f32,
        max_samples,
    })
}

/// Whether film frames are filtered: the file's `render.denoise` (true unless it says
/// false), or the command line's; never where no frame is film, so pinhole sequences keep
/// their settings and fingerprints.
pub(crate) fn denoise(asked: Option<bool>, film: Film) -> bool {
    asked.unwrap_or(true) && film != Film::Pinhole
}

/// Largest |render.exposure|, in stops: 2^64 times the brightest colour still fits an f32.
pub(crate) const MAX_EXPOSURE: f64 = 64.0;

/// An exposure in stops, as the file and `--exposure` may give it.
pub(crate) fn exposure(v: f64) -> Result<f64, String> {
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
/// frames at about the cost one sample had before the packet tracer (see the README); on
/// film (a shutter or a lens), enough samples where the grain is, found in rounds
/// (docs/quality.md#motion-blur-and-depth-of-field).
pub(crate) fn default_sampling(s: &mut Settings, film: Film) {
    let (samples, threshold, max_samples) = match film {
        Film::Pinhole => (DEFAULT_SAMPLES, DEFAULT_THRESHOLD, DEFAULT_SAMPLING_MAX),
        // A lens's blur is wider than a shutter's smear: more samples before the first round.
        // A shutter's frames take a tighter threshold: the film filter's one pass there leaves
        // more of the grain than its three passes on a lens frame (docs/quality.md).
        Film::Shutter => (SHUTTER_SAMPLES, SHUTTER_THRESHOLD, FILM_SAMPLING_MAX),
        Film::Lens => (LENS_SAMPLES, LENS_THRESHOLD, FILM_SAMPLING_MAX),
    };
    s.samples = samples;
    s.adaptive = Some(Adaptive {
        threshold: threshold as f32,
        max_samples,
    });
}

/// `render.samples` when a file sets no sampling.
pub const DEFAULT_SAMPLES: u32 = 2;
/// `render.adaptive.max_samples` when a file sets no sampling.
pub const DEFAULT_SAMPLING_MAX: u32 = 8;
/// `render.samples`, `render.adaptive.threshold` and `max_samples` when a file with a
/// shutter on a moving camera (`SHUTTER_SAMPLES`, `SHUTTER_THRESHOLD`) or a lens
/// (`LENS_SAMPLES`, `LENS_THRESHOLD`) sets no sampling.
pub const SHUTTER_SAMPLES: u32 = 2;
pub const LENS_SAMPLES: u32 = 4;
pub const SHUTTER_THRESHOLD: f64 = 0.025;
pub const LENS_THRESHOLD: f64 = 0.035;
pub const FILM_SAMPLING_MAX: u32 = 64;
/// `final`'s threshold and most samples on film.
pub const FILM_FINAL_THRESHOLD: f64 = 0.01;
pub const FILM_FINAL_MAX: u32 = 256;

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
pub(crate) const MAX_SAMPLES: u64 = 4096;

/// What a quality preset sets (on film, `final` samples in rounds to a lower threshold);
/// explicit settings at the same or a later level override it.
pub(crate) fn preset(s: &mut Settings, q: Quality, film: Film) {
    let (samples, adaptive, depth) = match (q, film != Film::Pinhole) {
        (Quality::Draft, _) => (1, None, 2),
        (Quality::Preview, _) => (4, None, 3),
        (Quality::Final, false) => (
            4,
            Some(Adaptive {
                threshold: DEFAULT_THRESHOLD as f32,
                max_samples: 64,
            }),
            5,
        ),
        (Quality::Final, true) => (
            8,
            Some(Adaptive {
                threshold: FILM_FINAL_THRESHOLD as f32,
                max_samples: FILM_FINAL_MAX,
            }),
            5,
        ),
    };
    s.samples = samples;
    s.adaptive = adaptive;
    s.max_depth = depth;
}

pub(super) fn samples(v: i64) -> Result<u32, String> {
    if (1..=MAX_SAMPLES as i64).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!(
            "must be 1 to {MAX_SAMPLES} samples per pixel (got {v})"
        ))
    }
}

pub(super) fn pixels(w: u32, h: u32) -> Result<(), String> {
    let n = u64::from(w) * u64::from(h);
    if n > MAX_PIXELS {
        return Err(format!(
            "{w}x{h} is {n} pixels; a frame may have at most {MAX_PIXELS} (e.g. 8192x8192)"
        ));
    }
    Ok(())
}

pub(super) fn dimension(v: i64) -> Result<u32, String> {
    if (1..=MAX_DIMENSION as i64).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!("must be 1 to {MAX_DIMENSION} pixels (got {v})"))
    }
}

pub(super) fn max_depth(v: i64) -> Result<u32, String> {
    if (1..=MAX_DEPTH as i64).contains(&v) {
        Ok(v as u32)
    } else {
        Err(format!(
            "must be 1 (no reflections) to {MAX_DEPTH} (got {v})"
        ))
    }
}

/// Longest path the kernel takes, in bytes (PATH_MAX less its NUL).
pub(super) const MAX_PATH_BYTES: usize = 4095;

/// A pattern that names frames numbered up to `last_frame`, of a type rayreel writes, in
/// paths the file system can take.
pub(crate) fn output_pattern(output: &str, last_frame: u64) -> Result<Pattern, String> {
    if output.contains('\0') {
        return Err(format!(
            "contains a NUL byte, which no file name may hold (got `{}`)",
            output.replace('\0', "\\0")
        ));
    }
    let pattern = Pattern::new(output, last_frame).map_err(|e| e.to_string())?;
    // No frame's path is longer than the last one's (numbers are padded to one width or not).
    let last = pattern.frame_path(last_frame);
    for part in last.iter() {
        let part = part.to_string_lossy();
        if part.len() > NAME_MAX {
            return Err(format!(
                "the name `{}` is {} bytes; a file or directory name may have at most {}",
                abbreviated(&part),
                part.len(),
                NAME_MAX
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
        "" => Err(format!(
            "`{output}` has no file type; add .png or .exr (e.g. `{output}.png`)"
        )),
        other => Err(format!(
            "unsupported file type `.{other}`; frames are .png or .exr (got `{output}`)"
        )),
    }
}

/// A sequence file may come from someone else, so its `output` stays below the current
/// directory; the user can still write anywhere with `--output`, which they typed themselves.
pub(super) fn contained(path: &str, output: &str) -> Check<()> {
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
pub(crate) fn escapes(output: &str) -> Option<PathBuf> {
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
