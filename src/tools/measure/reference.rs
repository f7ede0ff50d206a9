//! The converged image `measure` compares against: rendered with seeds of its own (so the
//! rows' samples are not a prefix of its own, which would flatter them), and kept in a cache
//! directory when asked, since a reference at full size can take minutes.

use crate::frame::Frame;
use crate::output::fingerprint::{self, Hasher};
use crate::output::format::{ExrPrecision, FileFormat};
use crate::schedule::{RunError, render_seeded};
use crate::sequence::Sequence;
use crate::tracer::{Settings, World};
use std::path::{Path, PathBuf};

/// What the seeds of the reference and of the convergence check are xored with: any frame's
/// own seeds stay apart from these (frame numbers are far below 2^62).
const REFERENCE_SALT: u64 = 1 << 63;
const CHECK_SALT: u64 = 1 << 62;

/// Where and how a reference is rendered.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Samples per pixel (default: `REFERENCE_SAMPLES`, `TREE_REFERENCE_SAMPLES` for trees).
    pub samples: Option<u32>,
    /// max_depth (default: `REFERENCE_DEPTH`, `TREE_REFERENCE_DEPTH` for trees).
    pub depth: Option<u32>,
    /// Samples of the second render the reference is checked against (default: half).
    pub check_samples: Option<u32>,
    /// A directory where references are kept and found again.
    pub cache: Option<PathBuf>,
}

/// The reference of frame `n` with `settings`, from the cache when it holds it; the seconds
/// it took to render (0 from the cache).
pub(super) fn reference(
    world: &World,
    seq: &Sequence,
    n: u64,
    settings: &Settings,
    cache: Option<&Path>,
    check: bool,
) -> Result<(Frame, f64), RunError> {
    let salt = if check { CHECK_SALT } else { REFERENCE_SALT };
    let file = cache.map(|dir| dir.join(format!("{}.ref", key(seq, n, settings, salt))));
    if let Some(frame) = file.as_deref().and_then(|f| load(f, settings)) {
        return Ok((frame, 0.0));
    }
    let start = std::time::Instant::now();
    let frame = render_seeded(world, seq, n, n ^ salt, settings)?;
    let seconds = start.elapsed().as_secs_f64();
    if let Some(file) = file {
        let _ = std::fs::create_dir_all(file.parent().unwrap_or(Path::new(".")));
        let _ = crate::output::atomic::write_atomic(&file, &bytes(&frame));
    }
    Ok((frame, seconds))
}

/// The cache's name for a reference: the frame's fingerprint for a float EXR of these
/// settings, and the seeds' salt.
fn key(seq: &Sequence, n: u64, settings: &Settings, salt: u64) -> String {
    let format = FileFormat::Exr {
        precision: ExrPrecision::Float,
    };
    let mut run = fingerprint::of_run(&seq.scene, settings, &format);
    run.write(b"measure reference").write(&salt.to_le_bytes());
    let view = settings.frame_view(&seq.timeline, n);
    let mut h = Hasher::new();
    h.write(fingerprint::of_frame(&run, &view).as_bytes());
    format!("{}-{n}-{}", seq.name, h.hex())
}

/// Width, height, then the linear f32 colour, little-endian.
fn bytes(frame: &Frame) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + 4 * frame.rgb.len());
    out.extend(frame.width.to_le_bytes());
    out.extend(frame.height.to_le_bytes());
    out.extend(frame.rgb.iter().flat_map(|v| v.to_le_bytes()));
    out
}

/// A cached reference of `settings`' size, or None (missing, short, another size).
fn load(file: &Path, settings: &Settings) -> Option<Frame> {
    let bytes = std::fs::read(file).ok()?;
    let word = |i: usize| Some(u32::from_le_bytes(bytes.get(i..i + 4)?.try_into().ok()?));
    let len = 3 * settings.width as usize * settings.height as usize;
    let fits = [word(0), word(4)] == [Some(settings.width), Some(settings.height)];
    if !fits || bytes.len() != 8 + 4 * len {
        return None;
    }
    let rgb = bytes[8..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Some(Frame {
        width: settings.width,
        height: settings.height,
        rgb,
        depth: None,
        alpha: None,
        aov: None,
        encoding: settings.encoding,
        non_finite: 0,
        samples: u64::from(settings.samples) * len as u64 / 3,
        rays: 0,
        levels8: None,
    })
}
