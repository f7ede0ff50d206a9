//! The command line: clap's definitions (the raw arguments, each checked as clap parses it:
//! ranges, choices, sizes, frame specs) in this file, the small languages of frame specs,
//! shards and sizes in `spec.rs`, and `job.rs`, which turns a sequence file and the job
//! arguments into one typed job in one step.

pub mod job;
pub(crate) mod spec;

pub use spec::{FrameSpec, SpecError, parse_frame_spec, parse_size};
pub(crate) use spec::{ShardSpec, parse_shard, resolve_shard};

use crate::output::stream::StreamFormat;
use crate::output::{Compression, ExrPrecision};
use crate::sequence::{MAX_DEPTH, MAX_FIRST_FRAME, MAX_SAMPLES, Quality};
use crate::transfer::Encoding;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  rayreel render sequences/orbit.yaml
  rayreel render sequences/talk.yaml --size 640x360 --output /tmp/talk/frame_####.png
  rayreel render sequences/orbit.yaml --frames 24 --output still.png
  rayreel render sequences/orbit.yaml --frames 0-47:2 --threads 2
  rayreel render sequences/orbit.yaml --output frames/orbit/frame_%04d.exr --depth
  rayreel render sequences/orbit.yaml --video orbit.mp4
  rayreel render sequences/orbit.yaml --pipe png --quiet | ffmpeg -f image2pipe -framerate 24 -i - -c:v libx264 -pix_fmt yuv420p orbit.mp4
  rayreel render sequences/orbit.yaml --dry-run
  rayreel render sequences/orbit.yaml --shard 2/4
  rayreel status sequences/orbit.yaml
  rayreel check sequences/flyby.yaml
  rayreel measure sequences/orbit.yaml --frame 0
  rayreel bench
  rayreel preview sequences/flyby.yaml --out /tmp/preview
  rayreel camera sequences/flyby.yaml --format json";

#[derive(Debug, Parser)]
#[command(name = "rayreel", version, about = "Render camera fly-through animations with a Whitted ray tracer", after_help = EXAMPLES)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a sequence file to numbered frames.
    #[command(after_help = EXAMPLES)]
    Render(RenderArgs),
    /// Validate a sequence file and print a one-screen summary.
    Check(CheckArgs),
    /// Report which frames of an output directory are up to date, stale, missing, corrupt or
    /// foreign; exit 0 only when every selected frame is up to date. Takes every render
    /// option, so the render command line can be repeated with `status`.
    Status(RenderArgs),
    /// Draw the camera path (top and side views) and a contact sheet of draft frames.
    Preview(PreviewArgs),
    /// Print every frame's camera: time, position, look_at, up, fov, speed and focus distance.
    Camera(CameraArgs),
    /// Measure what each speed/accuracy setting costs and buys on one frame.
    Measure(MeasureArgs),
    /// Benchmark this machine: rays/s and frames/s, thread scaling, sphere-count scaling,
    /// and the comparison with POV-Ray when it is installed.
    Bench(BenchArgs),
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The sequence file (YAML; `-` reads standard input).
    pub(crate) file: PathBuf,
    /// List every mesh file, placement, texture, area light note and warning, where the
    /// summary shows the first few of each and counts the rest.
    #[arg(long)]
    pub(crate) full: bool,
    /// A model library: a folder where mesh and image files the sequence names are also
    /// looked for, after the sequence file's folder (repeatable; RAYREEL_ASSETS adds more,
    /// separated by `:`).
    #[arg(long, value_name = "DIR")]
    pub(crate) assets: Vec<PathBuf>,
}

#[derive(Debug, Args)]
pub struct CameraArgs {
    /// The sequence file (YAML; `-` reads standard input).
    pub(crate) file: PathBuf,
    /// A model library: a folder where mesh and image files the sequence names are also
    /// looked for, after the sequence file's folder (repeatable; RAYREEL_ASSETS adds more,
    /// separated by `:`).
    #[arg(long, value_name = "DIR")]
    pub(crate) assets: Vec<PathBuf>,
    /// `csv` (a header line, then one line per frame), `json` (one object per line) or `chan`.
    #[arg(long, value_enum, default_value_t = CameraFormat::Csv)]
    pub(crate) format: CameraFormat,
    /// Frames to print, e.g. 0-23 (default: all).
    #[arg(long, value_name = "SPEC", value_parser = parse_frame_spec)]
    pub(crate) frames: Option<FrameSpec>,
    /// Print this moving object's poses instead of the camera: its index in `objects:` (from
    /// 0, as `check` lists it) or its `name:`.
    #[arg(long, value_name = "INDEX|NAME", conflicts_with = "light")]
    pub(crate) object: Option<String>,
    /// Print this moving light's poses instead of the camera: its index in `lights:` (from 0).
    #[arg(long, value_name = "INDEX")]
    pub(crate) light: Option<usize>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum CameraFormat {
    Csv,
    Json,
    /// Nuke's channel file: `frame tx ty tz rx ry rz vfov`, rotations in degrees, order ZXY.
    Chan,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Runs per figure (the median is reported, with min and max).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub(crate) runs: u64,
    /// Only this figure: kernels, mesh, motion, texture, render, threads, reflections, glass,
    /// sequence, scaling or povray.
    #[arg(long, value_parser = ["kernels", "mesh", "motion", "texture", "render", "threads", "reflections", "glass", "sequence", "scaling", "povray"])]
    pub(crate) only: Option<String>,
    /// Small sizes and scenes, to check the command quickly.
    #[arg(long)]
    pub(crate) quick: bool,
}

#[derive(Debug, Args)]
pub struct MeasureArgs {
    /// The sequence file (YAML; `-` reads standard input).
    pub(crate) file: PathBuf,
    /// A model library: a folder where mesh and image files the sequence names are also
    /// looked for, after the sequence file's folder (repeatable; RAYREEL_ASSETS adds more,
    /// separated by `:`).
    #[arg(long, value_name = "DIR")]
    pub(crate) assets: Vec<PathBuf>,
    /// The frame to measure.
    #[arg(long, default_value_t = 0)]
    pub(crate) frame: u64,
    /// Measurement size (default: the sequence's aspect ratio at 320 pixels wide).
    #[arg(long, value_parser = parse_size, value_name = "WxH")]
    pub(crate) size: Option<(u32, u32)>,
    /// Timed runs per setting; the median is reported, with min and max.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    pub(crate) runs: u64,
    /// Encoding of the 8-bit values errors are measured on (default: the sequence's).
    #[arg(long, value_enum)]
    pub(crate) encoding: Option<Encoding>,
    /// Directory for measure.csv, measure.json, measure.svg and reference.png (default:
    /// frames/NAME/measure).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Samples per pixel of the reference (default: 1024, or 256 where paths branch).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub(crate) reference_samples: Option<u32>,
    /// max_depth of the reference (default: 16, or 12 where paths branch); give the file's
    /// own to measure sampling alone.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10000))]
    pub(crate) reference_depth: Option<u32>,
    /// Samples of the render, with other seeds, that the reference is checked against
    /// (default: half the reference's).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub(crate) check_samples: Option<u32>,
    /// Keep references in DIR and take them from there when the same frame, scene and
    /// reference settings come again.
    #[arg(long, value_name = "DIR")]
    pub(crate) reference_cache: Option<PathBuf>,
    /// Only these groups of rows, comma-separated: uniform, adaptive, depth, preset,
    /// sampler, default, denoise, lights, precision.
    #[arg(long, value_name = "GROUPS", value_delimiter = ',',
          value_parser = clap::builder::PossibleValuesParser::new(crate::tools::measure::GROUPS))]
    pub(crate) only: Option<Vec<String>>,
}

#[derive(Debug, Args)]
pub struct PreviewArgs {
    /// The sequence file (YAML; `-` reads standard input).
    pub(crate) file: PathBuf,
    /// A model library: a folder where mesh and image files the sequence names are also
    /// looked for, after the sequence file's folder (repeatable; RAYREEL_ASSETS adds more,
    /// separated by `:`).
    #[arg(long, value_name = "DIR")]
    pub(crate) assets: Vec<PathBuf>,
    /// Directory for NAME_path.png and NAME_sheet.png (default: a `preview` folder beside
    /// the frames, e.g. frames/NAME/preview).
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Frames on the contact sheet, e.g. 0-100:10 (default: --tiles frames evenly spaced).
    #[arg(long, value_name = "SPEC", value_parser = parse_frame_spec)]
    pub(crate) frames: Option<FrameSpec>,
    /// Number of evenly spaced frames on the contact sheet.
    #[arg(long, value_name = "N", default_value_t = crate::tools::preview::DEFAULT_TILES,
          value_parser = clap::value_parser!(u64).range(1..=crate::tools::preview::MAX_TILES))]
    pub(crate) tiles: u64,
}

/// Bits per channel of PNG files and raw streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum BitDepth {
    #[value(name = "8")]
    Eight,
    #[value(name = "16")]
    Sixteen,
}

/// What decides a run's frames and files: shared by `render` and `status`, so a farm's final
/// check repeats the render command line with `status` in place of `render`.
#[derive(Debug, Args)]
pub struct JobArgs {
    /// The sequence file (YAML; `-` reads standard input).
    pub(crate) file: PathBuf,
    /// A model library: a folder where mesh and image files the sequence names are also
    /// looked for, after the sequence file's folder (repeatable; RAYREEL_ASSETS adds more,
    /// separated by `:`).
    #[arg(long, value_name = "DIR")]
    pub(crate) assets: Vec<PathBuf>,
    /// Image size, e.g. 640x360 (overrides render.width/height).
    #[arg(long, value_parser = parse_size, value_name = "WxH")]
    pub(crate) size: Option<(u32, u32)>,
    /// Output pattern: a run of '#' or ffmpeg's %04d becomes the zero-padded frame number; a
    /// name with neither holds the one frame selected (still.png).
    #[arg(long, short, value_name = "PATTERN")]
    pub(crate) output: Option<String>,
    /// Surfaces one path may visit (1 = no reflections).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    pub(crate) max_depth: Option<u32>,
    /// Uniform samples per pixel (replaces render.samples and turns adaptive sampling off).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES as i64))]
    pub(crate) samples: Option<u32>,
    /// Quality preset: draft (1 sample, depth 2, half size), preview (4 samples), final
    /// (adaptive 4-64 samples, depth 5); explicit flags override it.
    #[arg(long, value_enum)]
    pub(crate) quality: Option<Quality>,
    /// Frames, e.g. 7, 0-23, 1..10, 5-, last, 0-100:5, 1-100x2, 1,3,10-12 (default: all).
    #[arg(long, value_name = "SPEC", value_parser = parse_frame_spec)]
    pub(crate) frames: Option<FrameSpec>,
    /// The number of the first frame (replaces timeline.first_frame; studios start at 1001).
    #[arg(long, alias = "frame-offset", value_name = "N",
          value_parser = clap::value_parser!(u64).range(0..=MAX_FIRST_FRAME))]
    pub(crate) first_frame: Option<u64>,
    /// This task's share of the frames: K/N (K from 1 to N, interleaved), or `auto` to read
    /// SLURM_ARRAY_TASK_ID/MIN/COUNT or JOB_COMPLETION_INDEX with --shard-count.
    #[arg(long, value_name = "K/N|auto", value_parser = parse_shard)]
    pub(crate) shard: Option<ShardSpec>,
    /// Number of shards for `--shard auto` under Kubernetes Indexed Jobs.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) shard_count: Option<u64>,
    /// Bits per channel of PNG files and streams.
    #[arg(long, value_name = "BITS", value_enum, default_value_t = BitDepth::Eight)]
    pub(crate) bit_depth: BitDepth,
    /// Float precision of the R, G, B channels of EXR files.
    #[arg(long, value_name = "PRECISION", value_enum, default_value_t = ExrPrecision::Half)]
    pub(crate) exr_precision: ExrPrecision,
    /// PNG compression level.
    #[arg(long, value_name = "LEVEL", value_enum, default_value_t = Compression::Fast)]
    pub(crate) png_compression: Compression,
    /// Add a Z channel (planar depth) to EXR files (same as render.depth: true).
    #[arg(long)]
    pub(crate) depth: bool,
    /// How PNG and stream values encode the linear colour (replaces render.encoding).
    #[arg(long, value_enum)]
    pub(crate) encoding: Option<Encoding>,
    /// Exposure in stops: the colour is multiplied by 2^STOPS (replaces render.exposure).
    #[arg(long, value_name = "STOPS", allow_negative_numbers = true)]
    pub(crate) exposure: Option<f64>,
    /// Coverage as alpha: RGBA PNGs and streams, an A channel in EXR (as render.alpha: true).
    #[arg(long)]
    pub(crate) alpha: bool,
    /// Arithmetic of the tracer: f64, or f32 at about twice the speed (replaces
    /// render.precision).
    #[arg(long, value_enum)]
    pub(crate) precision: Option<crate::settings::Precision>,
    /// Compositing passes as extra EXR channels, e.g. normal,albedo,id,motion,position (added
    /// to render.aov).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "PASSES")]
    pub(crate) aov: Vec<crate::settings::Aov>,
    /// The film filter on frames with motion blur or depth of field (replaces
    /// render.denoise; on by default): off keeps the samples' means as they are.
    #[arg(long, value_enum, value_name = "on|off")]
    pub(crate) denoise: Option<Switch>,
}

/// A setting turned on or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Switch {
    On,
    Off,
}

/// `render`'s options; `status` takes them too and ignores those that only shape a run.
#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub job: JobArgs,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u16).range(1..=MAX_THREADS as i64))]
    pub(crate) threads: Option<u16>,
    /// No progress bar and no per-frame lines.
    #[arg(long, short)]
    pub(crate) quiet: bool,
    /// Progress format on stderr: a bar or lines (`human`), or one JSON object per line.
    #[arg(long, value_enum, default_value_t = ProgressFormat::Human)]
    pub(crate) progress: ProgressFormat,
    /// Stream frames to stdout (raw rgb24/rgb48le or PNGs) for ffmpeg; files are then only
    /// written when --output is given too.
    #[arg(long, value_name = "FORMAT")]
    pub(crate) pipe: Option<StreamFormat>,
    /// Render and encode a video in one step with the system's ffmpeg: .mp4, .mov or .mkv
    /// (H.264 yuv420p; ProRes 4444 with alpha in .mov/.mkv), at the job's size and exact
    /// frame rate. Written under a temporary name and renamed when ffmpeg succeeds; an
    /// existing file is replaced only with --force. Frame files are written too only when
    /// --output is given.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["pipe", "claim", "shard"])]
    pub(crate) video: Option<PathBuf>,
    /// Extra ffmpeg output options for --video, split at spaces (e.g. "-crf 18 -preset
    /// slow"); they come after rayreel's own, so they replace them.
    #[arg(
        long,
        value_name = "ARGS",
        requires = "video",
        allow_hyphen_values = true
    )]
    pub(crate) video_args: Option<String>,
    /// Print (on stderr) the ffmpeg command that reads the --pipe stream, or the frame files,
    /// for the job's own size and rate; with --video, the command it runs. With --dry-run it
    /// prints without rendering.
    #[arg(long)]
    pub(crate) print_ffmpeg: bool,
    /// Print which frames are up to date, stale, missing, corrupt or foreign, and render nothing.
    #[arg(long)]
    pub(crate) dry_run: bool,
    /// Render and overwrite every selected frame, even up-to-date ones, frames made at other
    /// quality and files rayreel did not write.
    #[arg(long)]
    pub(crate) force: bool,
    /// Keep every complete frame of the job's size and channels, whatever settings made it;
    /// render only missing and corrupt frames.
    #[arg(long, conflicts_with = "force")]
    pub(crate) skip_existing: bool,
    /// Share the frames with other rayreel processes on the same directory through claim
    /// files; a claim whose owner died or went silent is taken over.
    #[arg(long)]
    pub(crate) claim: bool,
    /// Seconds without a heartbeat after which another host's claim is taken over.
    #[arg(long, value_name = "SECONDS", default_value_t = 120, value_parser = clap::value_parser!(u64).range(2..))]
    pub(crate) claim_timeout: u64,
}

impl RenderArgs {
    /// What to do with frames that exist, as `--force` and `--skip-existing` say.
    pub(crate) fn resume(&self) -> crate::plan::Resume {
        use crate::plan::Resume;
        match (self.force, self.skip_existing) {
            (true, _) => Resume::Force,
            (_, true) => Resume::SkipExisting,
            _ => Resume::Normal,
        }
    }
}

/// Most worker threads `--threads` may ask for: more than machines have cores, few enough to
/// start in moments.
pub(crate) const MAX_THREADS: u16 = 1024;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ProgressFormat {
    Human,
    Json,
}

/// The model libraries of a command: its `--assets` folders, then those of RAYREEL_ASSETS
/// (`:`-separated), each of which must be a directory.
pub(crate) fn asset_folders(flags: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let from_env = std::env::var_os("RAYREEL_ASSETS").unwrap_or_default();
    let env: Vec<PathBuf> = std::env::split_paths(&from_env)
        .filter(|p| !p.as_os_str().is_empty())
        .collect();
    let named = flags
        .iter()
        .map(|f| (f, "--assets"))
        .chain(env.iter().map(|f| (f, "RAYREEL_ASSETS")));
    let mut out = Vec::new();
    for (folder, from) in named {
        if !folder.is_dir() {
            return Err(format!(
                "{from} {}: not a directory (a model library is a folder of mesh and image files)",
                crate::console::printable(&folder.display().to_string())
            ));
        }
        out.push(folder.clone());
    }
    Ok(out)
}
