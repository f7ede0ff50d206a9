//! What decides a frame besides the scene and the camera: size, depth, sampling, alpha,
//! exposure, encoding, shutter and the tracer's arithmetic. Plain data that `sequence` fills in
//! from the file, the job overrides from the command line, the tracer renders with and the
//! fingerprint encodes; it lives here, below all of them, so none imports another for it.

use crate::shutter::{FrameView, Shutter};
use crate::transfer::Encoding;

/// What decides a frame besides the scene and the camera.
#[derive(Clone, Copy, PartialEq)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Surfaces one path may visit: 1 = no reflections.
    pub max_depth: u32,
    /// Also record the eye-ray distance to the first hit.
    pub depth: bool,
    /// Eye rays per pixel (uniform sampling), or the first pass of adaptive sampling.
    pub samples: u32,
    pub adaptive: Option<Adaptive>,
    pub sampler: Sampler,
    /// Record coverage (alpha): eye rays that miss add nothing instead of the background.
    pub alpha: bool,
    /// Stops: the colour is multiplied by 2^exposure.
    pub exposure: f64,
    /// How the frame's integer values encode its colour (the tracer only passes it on).
    pub encoding: Encoding,
    /// Motion blur: None when `render.shutter` is 0.
    pub shutter: Option<Shutter>,
    /// The arithmetic of the lanes: f64 (the reference) or f32 (twice the lanes per
    /// instruction, camera-relative coordinates).
    pub precision: Precision,
    /// Compositing passes written beside the colour (`render.aov`, `--aov`); none by default.
    pub aov: Aovs,
    /// Film frames go through the film filter (`render.denoise`, `--denoise`): true by
    /// default on film, always false where no frame is film (it would change nothing).
    pub denoise: bool,
}

/// The float type the tracer's lanes compute in (`render.precision`, `--precision`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// IEEE double precision: the reference every other setting is measured against.
    #[default]
    F64,
    /// IEEE single precision, in coordinates relative to the frame's camera.
    F32,
}

impl Precision {
    pub fn name(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }
}

/// The derived form without `shutter`, whose effect shows in each frame's cameras (see
/// `shutter::Exposure`); the fingerprint does not use this text (see `output::fingerprint::Canon`).
impl std::fmt::Debug for Settings {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.debug_struct("Settings")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("max_depth", &self.max_depth)
            .field("depth", &self.depth)
            .field("samples", &self.samples)
            .field("adaptive", &self.adaptive)
            .field("sampler", &self.sampler)
            .field("alpha", &self.alpha)
            .field("exposure", &self.exposure)
            .field("encoding", &self.encoding)
            .field("precision", &self.precision)
            .field("aov", &self.aov)
            .field("denoise", &self.denoise)
            .finish()
    }
}

/// One compositing pass (AOV): extra EXR channels computed at each pixel centre's first hit
/// (`tracer::aov`, docs/spec/output.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    /// World-space shading normal, facing the camera: `N.X`, `N.Y`, `N.Z`.
    Normal,
    /// Diffuse colour of the surface (its texture's where it has one): `albedo.R/G/B`.
    Albedo,
    /// The object's index in `objects:` (−1 for background): `objectId`.
    Id,
    /// Where the surface point is one frame later minus where it is now, in pixels:
    /// `forward.u`, `forward.v` (Nuke's convention, v up).
    Motion,
    /// World-space position of the hit: `P.X`, `P.Y`, `P.Z`.
    Position,
}

impl Aov {
    pub const ALL: [Aov; 5] = [
        Aov::Normal,
        Aov::Albedo,
        Aov::Id,
        Aov::Motion,
        Aov::Position,
    ];

    /// How many channels the pass writes.
    pub const fn channels(self) -> u64 {
        match self {
            Aov::Id => 1,
            Aov::Motion => 2,
            _ => 3,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Aov::Normal => "normal",
            Aov::Albedo => "albedo",
            Aov::Id => "id",
            Aov::Motion => "motion",
            Aov::Position => "position",
        }
    }
}

/// A set of passes, in the fixed order of `Aov::ALL` whatever order they were asked in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Aovs(u8);

impl Aovs {
    /// The passes of `list` (repeats count once).
    pub fn of(list: &[Aov]) -> Aovs {
        list.iter().fold(Aovs::default(), |s, &a| s.with(a))
    }

    pub fn with(self, a: Aov) -> Aovs {
        Aovs(self.0 | 1 << a as u8)
    }

    pub fn union(self, o: Aovs) -> Aovs {
        Aovs(self.0 | o.0)
    }

    pub fn has(self, a: Aov) -> bool {
        self.0 >> a as u8 & 1 == 1
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// One bit per pass, bit i for `Aov::ALL[i]` (what the fingerprint records).
    pub fn bits(self) -> u8 {
        self.0
    }

    pub fn iter(self) -> impl Iterator<Item = Aov> {
        Aov::ALL.into_iter().filter(move |&a| self.has(a))
    }
}

/// Adaptive sampling: every pixel gets `samples`; pixels whose samples disagree, or whose
/// neighbours differ, by more than `threshold` are rendered again with `max_samples`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive {
    pub threshold: f32,
    pub max_samples: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampler {
    /// Jittered n×n grid, or R2 low-discrepancy for other counts.
    Stratified,
    /// Independent uniform positions, kept to measure what stratification buys.
    Random,
}

impl Settings {
    /// Frame `n` of `timeline` as these settings render it: through their shutter, and with
    /// the next frame's camera when the motion pass is asked for.
    pub(crate) fn frame_view(&self, timeline: &crate::timeline::Timeline, n: u64) -> FrameView {
        FrameView::with_next(timeline, self.shutter, self.aov.has(Aov::Motion), n)
    }
}
