//! One typed job from the sequence file and the job arguments, in one step: the file is read
//! and checked by `sequence::load` alone, then the command line's values replace the file's
//! (clap has already checked each of them), the frame spec and shard become this task's
//! frames, and the output pattern and format become the file sink.

use super::{BitDepth, JobArgs, RenderArgs, ShardSpec, resolve_shard};
use crate::frameset::FrameSet;
use crate::output::{FileFormat, Files};
use crate::sequence::{self, LoadError, Quality, Sequence, output_pattern};
use crate::settings::Aovs;

/// Why the arguments make no job: the file is wrong, or the command line asks for something
/// impossible (both exit 2).
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error("{0}")]
    Usage(String),
}

/// A sequence with the command line applied, and the frames this task renders.
#[derive(Debug)]
pub struct Job {
    pub seq: Sequence,
    pub(crate) frames: FrameSet,
    /// `--output` was given (with `--pipe`, files are written only then).
    pub(crate) output_given: bool,
    pub(crate) sixteen_bit: bool,
}

impl Job {
    /// Loads the file and applies the arguments.
    pub fn new(args: &JobArgs) -> Result<Job, JobError> {
        Job::load(args, false)
    }

    /// `new` for `status`, the final check of a whole farm job: `--shard auto` outside a job
    /// array (no scheduler index set) means every shard, so the array script's own line can
    /// be repeated with `status` after the array ends.
    pub(crate) fn for_status(args: &JobArgs) -> Result<Job, JobError> {
        Job::load(args, true)
    }

    fn load(args: &JobArgs, every_shard: bool) -> Result<Job, JobError> {
        let assets = super::asset_folders(&args.assets).map_err(JobError::Usage)?;
        let mut seq = sequence::load_with(&args.file, &assets)?;
        apply(&mut seq, args)?;
        let frames = frames(&seq, args, every_shard)?;
        Ok(Job {
            seq,
            frames,
            output_given: args.output.is_some(),
            sixteen_bit: args.bit_depth == BitDepth::Sixteen,
        })
    }

    /// The file pattern and format. A pattern without a frame number holds one frame: the
    /// one selected.
    pub(crate) fn files(&self, args: &JobArgs) -> Result<Files, JobError> {
        let seq = &self.seq;
        let mut pattern =
            output_pattern(&seq.output, seq.timeline.last_frame()).map_err(JobError::Usage)?;
        if pattern.is_single() {
            if self.frames.len() != 1 {
                return Err(JobError::Usage(format!(
                    "output `{}` has no `#` run or %04d for the frame number, so it holds one frame, but {} frames are selected (select one with --frames, or use a pattern such as frame_####.png)",
                    seq.output,
                    self.frames.len()
                )));
            }
            pattern = pattern.holding(self.frames.iter().next().unwrap_or_default());
        }
        let format = FileFormat::for_extension(
            &pattern.extension(),
            self.sixteen_bit,
            args.png_compression,
            args.exr_precision,
        )
        .map_err(|e| JobError::Usage(format!("output `{}`: {e}", seq.output)))?;
        let exr = matches!(format, FileFormat::Exr { .. });
        if exr && self.sixteen_bit {
            return Err(JobError::Usage(
                "--bit-depth 16 applies to PNG files and streams; EXR frames are float".into(),
            ));
        }
        if seq.settings.depth && !exr {
            return Err(JobError::Usage(format!(
                "--depth (render.depth) needs EXR frames to hold the Z channel; `{}` is not .exr",
                seq.output
            )));
        }
        if !seq.settings.aov.is_empty() && !exr {
            return Err(JobError::Usage(format!(
                "--aov (render.aov) writes its passes as extra EXR channels; `{}` is not .exr (use a pattern such as frame_####.exr)",
                seq.output
            )));
        }
        Ok(Files { pattern, format })
    }

    /// The file sink of a render: with `--pipe` or `--video` the stream is the product, and files are
    /// written too only when `--output` asks for them; `--claim` shares files, so it takes
    /// no stream.
    pub(crate) fn render_files(&self, args: &RenderArgs) -> Result<Option<Files>, JobError> {
        let streaming = args.pipe.is_some() || args.video.is_some();
        let files = match !streaming || self.output_given {
            true => Some(self.files(&args.job)?),
            false => None,
        };
        if files.is_none() && !self.seq.settings.aov.is_empty() {
            return Err(JobError::Usage(
                "--aov (render.aov) writes its passes as extra EXR channels, which the --pipe stream cannot carry; add -o frame_####.exr to write EXR files beside the stream".into(),
            ));
        }
        if args.claim && (files.is_none() || args.pipe.is_some()) {
            return Err(JobError::Usage(
                "--claim shares frame files between processes; it cannot be combined with --pipe"
                    .into(),
            ));
        }
        Ok(files)
    }
}

/// The command line's values replace the file's. A preset fills only the sampling values the
/// file left unset (it never replaces `render.samples`, `render.adaptive` or
/// `render.max_depth`); the flags that set a value replace it.
fn apply(seq: &mut Sequence, o: &JobArgs) -> Result<(), JobError> {
    if let Some(q) = o.quality {
        let (glass, film) = (seq.scene.has_glass(), seq.film());
        seq.explicit.preset(&mut seq.settings, q, glass, film);
        // The preset's first pass may reach the file's own most samples: nothing is left
        // to extend.
        let s = &mut seq.settings;
        if s.adaptive.is_some_and(|a| a.max_samples <= s.samples) {
            s.adaptive = None;
        }
    }
    let draft = o.quality.or(seq.quality) == Some(Quality::Draft);
    if draft && o.size.is_none() {
        seq.settings.width = seq.settings.width.div_ceil(2);
        seq.settings.height = seq.settings.height.div_ceil(2);
    }
    if let Some(n) = o.samples {
        // `--samples N` means N uniform samples, whatever the file or preset chose.
        seq.settings.samples = n;
        seq.settings.adaptive = None;
    }
    if let Some((w, h)) = o.size {
        (seq.settings.width, seq.settings.height) = (w, h);
    }
    if let Some(d) = o.max_depth {
        seq.settings.max_depth = d;
    }
    if let Some(n) = o.first_frame {
        seq.timeline.clock.first_frame = n;
    }
    if let Some(out) = &o.output {
        seq.output = out.clone();
    }
    if draft {
        seq.output = draft_output(&seq.output);
    }
    seq.settings.depth |= o.depth;
    seq.settings.alpha |= o.alpha;
    seq.settings.aov = seq.settings.aov.union(Aovs::of(&o.aov));
    if let Some(e) = o.encoding {
        seq.settings.encoding = e;
    }
    if let Some(p) = o.precision {
        seq.settings.precision = p;
    }
    if let Some(d) = o.denoise {
        seq.settings.denoise = sequence::denoise(Some(d == super::Switch::On), seq.film());
    }
    if let Some(e) = o.exposure {
        seq.settings.exposure =
            sequence::exposure(e).map_err(|m| JobError::Usage(format!("--exposure: {m}")))?;
    }
    output_pattern(&seq.output, seq.timeline.last_frame())
        .map_err(|m| JobError::Usage(format!("--output: {m}")))?;
    Ok(())
}

/// Where draft frames go: a `draft/` folder beside the output's file name
/// (`frames/orbit/frame_####.png` → `frames/orbit/draft/frame_####.png`), so a draft, made
/// at half the size and one sample, never meets the finished frames.
pub(crate) fn draft_output(output: &str) -> String {
    match output.rfind('/') {
        Some(i) => format!("{}/draft/{}", &output[..i], &output[i + 1..]),
        None => format!("draft/{output}"),
    }
}

/// This task's frames: the spec's (default all), then the shard's share (`every_shard`: all
/// of them when `--shard auto` finds no scheduler index).
fn frames(seq: &Sequence, args: &JobArgs, every_shard: bool) -> Result<FrameSet, JobError> {
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    let mut frames = match &args.frames {
        Some(spec) => spec
            .frames(first, last)
            .map_err(|e| JobError::Usage(format!("--frames: {e}")))?,
        None => FrameSet::range(first, last, 1),
    };
    let env = |name: &str| std::env::var(name).ok();
    let unscheduled = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"]
        .iter()
        .all(|v| env(v).is_none());
    let shard = match args.shard {
        Some(ShardSpec::Auto) if every_shard && unscheduled => None,
        other => other,
    };
    if let Some(spec) = shard {
        let (k, n) = resolve_shard(spec, args.shard_count, &env)
            .map_err(|e| JobError::Usage(format!("--shard: {e}")))?;
        frames = frames.shard(k, n);
    }
    Ok(frames)
}
