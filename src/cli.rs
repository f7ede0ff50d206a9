//! Command-line definitions (clap) and frame specs (`7`, `0-23`, `0-100:5`, `1-100x2`, `1,3,7-9`).

use crate::frameset::{FrameSet, Run};
use crate::output::exr::Precision;
use crate::output::png::Compression;
use crate::output::stream::StreamFormat;
use crate::sequence::Quality;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  rayreel render sequences/orbit.yaml
  rayreel render sequences/talk.yaml --size 640x360 --output /tmp/talk/frame_####.png
  rayreel render sequences/orbit.yaml --frames 0-47:2 --threads 2
  rayreel render sequences/orbit.yaml --output frames/orbit/frame_####.exr --depth
  rayreel render sequences/orbit.yaml --pipe raw --quiet | ffmpeg -f rawvideo -pix_fmt rgb24 -s 1280x720 -r 24 -i - -c:v libx264 -pix_fmt yuv420p orbit.mp4
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
    /// foreign; exit 0 only when every selected frame is up to date. Takes render's options.
    Status(StatusArgs),
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
pub struct StatusArgs {
    #[command(flatten)]
    pub job: JobArgs,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// The sequence file (YAML).
    pub file: PathBuf,
}

#[derive(Debug, Args)]
pub struct CameraArgs {
    /// The sequence file (YAML).
    pub file: PathBuf,
    /// `csv` (a header line, then one line per frame) or `json` (one object per line).
    #[arg(long, value_enum, default_value_t = CameraFormat::Csv)]
    pub format: CameraFormat,
    /// Frames to print, e.g. 0-23 (default: all).
    #[arg(long, value_name = "SPEC", value_parser = parse_frame_spec)]
    pub frames: Option<FrameSpec>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CameraFormat {
    Csv,
    Json,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Runs per figure (the median is reported, with min and max).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub runs: u64,
    /// Only this figure: kernels, render, threads, reflections, sequence, scaling or povray.
    #[arg(long, value_parser = ["kernels", "render", "threads", "reflections", "sequence", "scaling", "povray"])]
    pub only: Option<String>,
    /// Small sizes and scenes, to check the command quickly.
    #[arg(long)]
    pub quick: bool,
}

#[derive(Debug, Args)]
pub struct MeasureArgs {
    /// The sequence file (YAML).
    pub file: PathBuf,
    /// The frame to measure.
    #[arg(long, default_value_t = 0)]
    pub frame: u64,
    /// Measurement size (default: the sequence's aspect ratio at 320 pixels wide).
    #[arg(long, value_parser = parse_size, value_name = "WxH")]
    pub size: Option<(u64, u64)>,
    /// Timed runs per setting; the median is reported, with min and max.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100))]
    pub runs: u64,
    /// Directory for measure.csv, measure.json and measure.svg (default: frames/NAME/measure).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct PreviewArgs {
    /// The sequence file (YAML).
    pub file: PathBuf,
    /// Directory for NAME_path.png and NAME_sheet.png (default: frames/NAME/preview).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Frames on the contact sheet, e.g. 0-100:10 (default: --tiles frames evenly spaced).
    #[arg(long, value_name = "SPEC", value_parser = parse_frame_spec)]
    pub frames: Option<FrameSpec>,
    /// Number of evenly spaced frames on the contact sheet.
    #[arg(long, value_name = "N", default_value_t = crate::tools::preview::DEFAULT_TILES,
          value_parser = clap::value_parser!(u64).range(1..=crate::tools::preview::MAX_TILES))]
    pub tiles: u64,
}

/// What decides a run's frames and files: shared by `render` and `status`, so a farm's final
/// check repeats the render command line with `status` in place of `render`.
#[derive(Debug, Args)]
pub struct JobArgs {
    /// The sequence file (YAML).
    pub file: PathBuf,
    /// Image size, e.g. 640x360 (overrides render.width/height).
    #[arg(long, value_parser = parse_size, value_name = "WxH")]
    pub size: Option<(u64, u64)>,
    /// Output pattern; a run of '#' becomes the zero-padded frame number.
    #[arg(long, short, value_name = "PATTERN")]
    pub output: Option<String>,
    /// Surfaces one path may visit (1 = no reflections).
    #[arg(long, value_name = "N")]
    pub max_depth: Option<u64>,
    /// Uniform samples per pixel (replaces render.samples and turns adaptive sampling off).
    #[arg(long, value_name = "N")]
    pub samples: Option<u64>,
    /// Quality preset: draft (1 sample, depth 2, half size), preview (4 samples), final
    /// (adaptive 4-64 samples, depth 5); explicit flags override it.
    #[arg(long, value_enum)]
    pub quality: Option<Quality>,
    /// Frames, e.g. 7, 0-23, 0-100:5, 1-100x2, 1,3,10-12 (default: all).
    #[arg(long, value_name = "SPEC", value_parser = parse_frame_spec)]
    pub frames: Option<FrameSpec>,
    /// This task's share of the frames: K/N (K from 1 to N, interleaved), or `auto` to read
    /// SLURM_ARRAY_TASK_ID/MIN/COUNT or JOB_COMPLETION_INDEX with --shard-count.
    #[arg(long, value_name = "K/N|auto", value_parser = parse_shard)]
    pub shard: Option<ShardSpec>,
    /// Number of shards for `--shard auto` under Kubernetes Indexed Jobs.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub shard_count: Option<u64>,
    /// Bits per channel of PNG files and streams.
    #[arg(long, value_name = "BITS", default_value = "8", value_parser = ["8", "16"])]
    pub bit_depth: String,
    /// Float precision of the R, G, B channels of EXR files.
    #[arg(long, value_name = "PRECISION", value_enum, default_value_t = Precision::Half)]
    pub exr_precision: Precision,
    /// PNG compression level.
    #[arg(long, value_name = "LEVEL", value_enum, default_value_t = Compression::Fast)]
    pub png_compression: Compression,
    /// Add a Z channel (eye-ray distance) to EXR files (same as render.depth: true).
    #[arg(long)]
    pub depth: bool,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub job: JobArgs,
    /// Worker threads (default: all cores; at most 1024).
    #[arg(long, short = 'j', value_name = "N", value_parser = clap::value_parser!(u16).range(1..=MAX_THREADS as i64))]
    pub threads: Option<u16>,
    /// No progress bar and no per-frame lines.
    #[arg(long, short)]
    pub quiet: bool,
    /// Progress format on stderr: a bar or lines (`human`), or one JSON object per frame.
    #[arg(long, value_enum, default_value_t = ProgressFormat::Human)]
    pub progress: ProgressFormat,
    /// Stream frames to stdout (raw rgb24/rgb48le or PNGs) for ffmpeg; files are then only
    /// written when --output is given too.
    #[arg(long, value_name = "FORMAT")]
    pub pipe: Option<StreamFormat>,
    /// Print (on stderr) the ffmpeg command that reads the --pipe stream.
    #[arg(long)]
    pub print_ffmpeg: bool,
    /// Print which frames are up to date, stale, missing, corrupt or foreign, and render nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// Render and overwrite every selected frame, even up-to-date ones and files rayreel did
    /// not write.
    #[arg(long)]
    pub force: bool,
    /// Share the frames with other rayreel processes on the same directory through claim
    /// files; a claim whose owner died or went silent is taken over.
    #[arg(long)]
    pub claim: bool,
    /// Seconds without a heartbeat after which another host's claim is taken over.
    #[arg(long, value_name = "SECONDS", default_value_t = 120, value_parser = clap::value_parser!(u64).range(2..))]
    pub claim_timeout: u64,
}

/// Most worker threads `--threads` may ask for: more than machines have cores, few enough to
/// start in moments.
pub const MAX_THREADS: u16 = 1024;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProgressFormat {
    Human,
    Json,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShardSpec {
    /// 1-based task number and task count.
    Fixed(u64, u64),
    Auto,
}

pub fn parse_shard(s: &str) -> Result<ShardSpec, String> {
    if s == "auto" {
        return Ok(ShardSpec::Auto);
    }
    let bad = || format!("expected K/N with 1 ≤ K ≤ N, such as 2/4, or `auto` (got `{s}`)");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u64, u64) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok(ShardSpec::Fixed(k, n))
}

/// Turns `--shard auto` into K/N from the scheduler's environment.
pub fn resolve_shard(
    spec: ShardSpec,
    shard_count: Option<u64>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(u64, u64), String> {
    if let ShardSpec::Fixed(k, n) = spec {
        return Ok((k, n));
    }
    let num = |name: &str| -> Result<Option<u64>, String> {
        env(name)
            .map(|v| {
                v.trim()
                    .parse::<u64>()
                    .map_err(|_| format!("{name}={v} is not a whole number"))
            })
            .transpose()
    };
    if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
        let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let count = num("SLURM_ARRAY_TASK_COUNT")?
            .ok_or("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
        if id < min || id - min >= count {
            return Err(format!(
                "SLURM_ARRAY_TASK_ID={id} is outside MIN={min}, COUNT={count} (use a contiguous array such as --array=0-3)"
            ));
        }
        return Ok((id - min + 1, count));
    }
    if let Some(index) = num("JOB_COMPLETION_INDEX")? {
        let count = shard_count
            .ok_or("JOB_COMPLETION_INDEX is set: give --shard-count N (the job's completions)")?;
        if index >= count {
            return Err(format!(
                "JOB_COMPLETION_INDEX={index} is not below --shard-count {count}"
            ));
        }
        return Ok((index + 1, count));
    }
    Err("--shard auto needs SLURM_ARRAY_TASK_ID (a Slurm job array) or JOB_COMPLETION_INDEX with --shard-count (a Kubernetes Indexed Job); neither is set".into())
}

/// `WxH` with both parts positive integers.
pub fn parse_size(s: &str) -> Result<(u64, u64), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT such as 640x360 (got `{s}`)"))?;
    let num = |p: &str| {
        p.trim().parse::<u64>().map_err(|_| {
            format!("expected WIDTHxHEIGHT with whole numbers such as 640x360 (got `{s}`)")
        })
    };
    Ok((num(w)?, num(h)?))
}

/// A union of inclusive ranges with steps, kept unexpanded until the frame count is known.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameSpec {
    ranges: Vec<(u64, u64, u64)>,
}

impl FrameSpec {
    /// The selected frames, or the first one out of range. Repeated and overlapping ranges
    /// are joined as ranges, so `0-9999999` costs one run, however often it is repeated.
    pub fn frames(&self, frame_count: u64) -> Result<FrameSet, String> {
        for &(_, end, _) in &self.ranges {
            if end >= frame_count {
                return Err(format!(
                    "frame {end} is outside the timeline, which has frames 0-{}",
                    frame_count.saturating_sub(1)
                ));
            }
        }
        let runs = self.ranges.iter().map(|&(a, b, step)| Run::new(a, b, step));
        Ok(FrameSet::from_runs(runs.collect()))
    }
}

pub fn parse_frame_spec(s: &str) -> Result<FrameSpec, String> {
    let bad = |part: &str, why: &str| {
        format!(
            "`{part}` in frame spec `{s}`: {why}; use forms like 7, 0-23, 0-100:5, 1-100x2, 1,3,10-12"
        )
    };
    // Farm managers hand out one range or a few; a bound keeps expansion time bounded too.
    const MAX_ENTRIES: usize = 64;
    if s.split(',').count() > MAX_ENTRIES {
        return Err(format!(
            "frame spec has more than {MAX_ENTRIES} comma-separated entries"
        ));
    }
    let mut ranges = Vec::new();
    for part in s.split(',') {
        let part = part.trim();
        if part.is_empty() {
            return Err(bad(part, "empty entry"));
        }
        let (range, step) = match part.split_once([':', 'x']) {
            Some((r, st)) => (r, Some(st)),
            None => (part, None),
        };
        let num = |t: &str| {
            t.trim()
                .parse::<u64>()
                .map_err(|_| bad(part, "not a whole number"))
        };
        let (start, end) = match range.split_once('-') {
            Some((a, b)) => (num(a)?, num(b)?),
            None => {
                let n = num(range)?;
                (n, n)
            }
        };
        if start > end {
            return Err(bad(part, "the range runs backwards"));
        }
        let step = match step {
            Some(st) => num(st)?,
            None => 1,
        };
        if step == 0 || step > usize::MAX as u64 {
            return Err(bad(part, "the step must be at least 1"));
        }
        ranges.push((start, end, step));
    }
    Ok(FrameSpec { ranges })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(s: &str, count: u64) -> Result<Vec<u64>, String> {
        Ok(parse_frame_spec(s)?.frames(count)?.iter().collect())
    }

    #[test]
    fn specs_expand() {
        assert_eq!(frames("7", 10).unwrap(), vec![7]);
        assert_eq!(frames("0-3", 10).unwrap(), vec![0, 1, 2, 3]);
        assert_eq!(frames("0-10:5", 11).unwrap(), vec![0, 5, 10]);
        assert_eq!(frames("1-9x4", 11).unwrap(), vec![1, 5, 9]);
        assert_eq!(frames("1,3,10-12", 13).unwrap(), vec![1, 3, 10, 11, 12]);
        assert_eq!(frames("3,1-3", 13).unwrap(), vec![1, 2, 3]);
    }

    #[test]
    fn garbage_is_rejected_clearly() {
        for bad in ["", "a", "1-", "-3", "5-2", "1-9:0", "1,,2", "1.5", "0-3:x"] {
            let err = frames(bad, 100).unwrap_err();
            assert!(
                err.contains("frame spec") || err.contains("outside"),
                "{bad}: {err}"
            );
        }
        let err = frames("0-100", 48).unwrap_err();
        assert!(
            err.contains("frame 100 is outside the timeline, which has frames 0-47"),
            "{err}"
        );
        // A huge range is refused before anything is expanded.
        assert!(frames("0-18446744073709551615", 48).is_err());
        // Repeated ranges are joined as ranges (this once took 80 MB a copy).
        let spec = vec!["4-8888885"; 16].join(",");
        let set = parse_frame_spec(&spec).unwrap().frames(10_000_000).unwrap();
        assert_eq!((set.len(), set.runs().len()), (8_888_882, 1));
        assert!(
            frames(&vec!["1"; 65].join(","), 10)
                .unwrap_err()
                .contains("more than 64")
        );
    }

    #[test]
    fn shards_parse_and_resolve() {
        assert_eq!(parse_shard("2/4"), Ok(ShardSpec::Fixed(2, 4)));
        for bad in ["0/4", "5/4", "2", "a/b", "1/0"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
        let slurm = |name: &str| match name {
            "SLURM_ARRAY_TASK_ID" => Some("7".to_string()),
            "SLURM_ARRAY_TASK_MIN" => Some("5".to_string()),
            "SLURM_ARRAY_TASK_COUNT" => Some("4".to_string()),
            _ => None,
        };
        assert_eq!(resolve_shard(ShardSpec::Auto, None, &slurm), Ok((3, 4)));
        let k8s = |name: &str| (name == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(resolve_shard(ShardSpec::Auto, Some(3), &k8s), Ok((1, 3)));
        assert!(
            resolve_shard(ShardSpec::Auto, None, &k8s)
                .unwrap_err()
                .contains("--shard-count")
        );
        assert!(
            resolve_shard(ShardSpec::Auto, None, &|_| None)
                .unwrap_err()
                .contains("neither is set")
        );
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("640x360"), Ok((640, 360)));
        assert!(parse_size("640").is_err());
        assert!(parse_size("-1x3").is_err());
    }
}
