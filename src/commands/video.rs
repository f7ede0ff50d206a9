//! `render --video` and `--print-ffmpeg`: the job's video from the command line, ffmpeg
//! started before the first frame and finished (or stopped) after the last, and the ffmpeg
//! command that reads the stream or the frame files.

use super::render::plural;
use super::{Error, shown};
use crate::cli::RenderArgs;
use crate::cli::job::Job;
use crate::frameset::FrameSet;
use crate::output::video::{Encoder, VideoJob};
use crate::output::{self, Expected, Files, reread, stream::StreamFormat};
use crate::plan::{self, Resume};
use crate::progress::Progress;
use crate::schedule::{Outcome, RunError};
use crate::sequence::Sequence;
use crate::signals;
use std::path::Path;

/// ffmpeg started for `--video` (frame lines then say `to ffmpeg`), before any frame renders.
pub(super) fn start_video(
    video: Option<&VideoJob>,
    progress: &mut Progress,
) -> Result<Option<output::video::Encoder>, Error> {
    let Some(video) = video else {
        return Ok(None);
    };
    progress.stream_to = "to ffmpeg";
    video.start().map(Some).map_err(Error::Failed)
}

/// `--video`'s job from the command line and the sequence as applied (size, alpha, rate).
pub(super) fn video_job(
    args: &RenderArgs,
    seq: &Sequence,
    sixteen_bit: bool,
) -> Result<Option<VideoJob>, Error> {
    let Some(path) = &args.video else {
        return Ok(None);
    };
    let extra = args
        .video_args
        .as_deref()
        .unwrap_or("")
        .split_whitespace()
        .map(String::from)
        .collect();
    let t = &seq.timeline;
    let picture = output::video::Picture {
        alpha: seq.settings.alpha,
        sixteen_bit,
        size: (seq.settings.width, seq.settings.height),
        fps: output::video::exact_rate(t.clock.fraction, t.fps),
    };
    VideoJob::new(path.clone(), picture, extra, args.force)
        .map(Some)
        .map_err(|e| Error::Usage(format!("--video: {e}")))
}

/// After the run: a finished stream (or one ffmpeg ended on its own) is encoded and the video
/// published, or ffmpeg's failure reported; any other end drops the encoder, which stops
/// ffmpeg and removes its temporary (a signal says that no video was made).
pub(super) fn end_video(
    encoder: output::video::Encoder,
    outcome: Result<Outcome, RunError>,
) -> Result<Result<Outcome, RunError>, Error> {
    match outcome {
        Ok(Outcome::Complete { .. } | Outcome::ReaderClosed { .. }) => {
            let whole_stream = matches!(outcome, Ok(Outcome::Complete { .. }));
            encoder.finish(whole_stream).map_err(Error::Failed)?;
            Ok(outcome)
        }
        Ok(Outcome::Interrupted { written, .. }) => {
            drop(encoder);
            let files = match written {
                0 => String::new(),
                n => format!(" ({} written)", plural(n as u64, "frame file")),
            };
            Err(Error::Interrupted(
                format!(
                    "interrupted: no video was made{files}; run the same command again to make it"
                ),
                signals::interrupt_code(),
            ))
        }
        other => Ok(other),
    }
}

/// The ffmpeg command for the stream, or else for the files (`--print-ffmpeg`), and the
/// warning that yuv420p video needs even sizes.
pub(super) fn video_notes(
    progress: &Progress,
    seq: &Sequence,
    stream: Option<(StreamFormat, bool)>,
    files: Option<&Files>,
    print: bool,
) {
    use output::stream::PAD;
    let (w, h) = (seq.settings.width, seq.settings.height);
    let Some(line) = ffmpeg_line(seq, stream, files) else {
        return;
    };
    if print {
        progress.command(&line);
    }
    // ProRes 4444, which alpha frames go to, takes odd sizes.
    if (w % 2 == 1 || h % 2 == 1) && !seq.settings.alpha {
        let text = format!(
            "note: {w}x{h} is odd, and yuv420p video needs even sizes: give ffmpeg -vf '{PAD}'"
        );
        // A stream goes to ffmpeg now, so even --quiet says it; files may never become video.
        match stream {
            Some(_) => progress.warn(&text),
            None => progress.note(&text),
        }
    }
}

/// The ffmpeg command that reads the stream, or else the frame files, for the job as given
/// (its size after presets, its frame rate); `None` when there is neither.
pub(super) fn ffmpeg_line(
    seq: &Sequence,
    stream: Option<(StreamFormat, bool)>,
    files: Option<&Files>,
) -> Option<String> {
    use output::stream::{Source, ffmpeg_command};
    let pattern = files.map(|f| f.pattern.ffmpeg());
    let source = match (stream, &pattern) {
        (Some((format, sixteen_bit)), _) => Source::Stream {
            format,
            sixteen_bit,
        },
        (None, Some(pattern)) => Source::Files {
            pattern,
            first: seq.timeline.first_frame(),
        },
        (None, None) => return None,
    };
    let out = format!("{}.mp4", seq.name);
    let (size, alpha) = (
        (seq.settings.width, seq.settings.height),
        seq.settings.alpha,
    );
    Some(ffmpeg_command(
        source,
        alpha,
        size,
        &seq.timeline.fps_text(),
        &out,
    ))
}

/// What `--video` with `-o` encodes once every frame is rendered: the job's frames, from
/// its files.
pub(super) struct FromFiles<'a> {
    pub(super) seq: &'a Sequence,
    pub(super) frames: &'a FrameSet,
    pub(super) files: &'a Files,
    pub(super) resume: Resume,
    pub(super) quiet: bool,
    pub(super) json: bool,
}

/// The note a `--video` run without `-o` starts with: what an interruption keeps.
pub(super) fn nothing_kept(video: &Path) -> String {
    format!(
        "no frame file is written (each frame is encoded as it renders), so an interruption keeps nothing of {}; with -o PATTERN the frames are kept, a rerun renders only what is missing, and the video is encoded from the files",
        shown(video)
    )
}

/// Encodes the video from the job's frame files, which must all be finished (up to date, or
/// kept as the plan keeps them): each file is read back as the raw stream's bytes and fed to
/// the same ffmpeg command a stream would get. Ctrl-C stops it with no video made and every
/// frame still on disk.
pub(super) fn encode_files(video: &VideoJob, job: &FromFiles) -> Result<(), Error> {
    let (seq, files) = (job.seq, job.files);
    let plan = plan::plan(seq, job.frames, files, job.resume);
    let unfinished = FrameSet::union(&[&plan.to_render(), &plan.foreign]);
    if !unfinished.is_empty() {
        return Err(Error::Failed(format!(
            "{}: not made: frames {unfinished} are not finished in {} ({}); run the same command again to render them",
            shown(&video.path),
            shown(&plan::directory(&files.frame_path(0))),
            plan.status_line()
        )));
    }
    let total = job.frames.len();
    let mut progress = match job.json {
        true if !job.quiet => Progress::json(total, seq.timeline.frame_count),
        _ => Progress::new(total, seq.timeline.frame_count, job.quiet),
    };
    progress.stream_to = "to ffmpeg";
    progress.verb = "encoded";
    progress.note(&format!(
        "encoding {} from {} into {}",
        plural(total, "frame"),
        files.pattern.ffmpeg(),
        shown(&video.path)
    ));
    let mut encoder = video.start().map_err(Error::Failed)?;
    let fed = feed(&mut encoder, job, &mut progress);
    progress.finish(matches!(fed, Err(Error::Interrupted(..))));
    let whole_stream = fed?;
    encoder.finish(whole_stream).map_err(Error::Failed)
}

/// Writes every frame file's stream bytes into ffmpeg, in frame order; whether ffmpeg took
/// them all. A closed pipe means ffmpeg stopped: `finish` then reports what it said.
fn feed(encoder: &mut Encoder, job: &FromFiles, progress: &mut Progress) -> Result<bool, Error> {
    use std::io::Write;
    let Some(mut input) = encoder.take_input() else {
        return Ok(false);
    };
    let s = &job.seq.settings;
    let expected = Expected {
        width: s.width,
        height: s.height,
        format: job.files.format,
        alpha: s.alpha,
    };
    for n in job.frames.iter() {
        if signals::interrupted() {
            return Err(Error::Interrupted(
                "interrupted while encoding: no video was made; every frame is on disk, so the same command again only encodes".into(),
                signals::interrupt_code(),
            ));
        }
        let start = std::time::Instant::now();
        let path = job.files.frame_path(n);
        let bytes = reread::raw_frame(&path, &expected, s.encoding)
            .map_err(|e| Error::Failed(format!("{}: {e}; no video was made", shown(&path))))?;
        if input.write_all(&bytes).is_err() {
            return Ok(false);
        }
        progress.frame_done(n, "to ffmpeg", start.elapsed().as_secs_f64());
    }
    Ok(true)
}

/// For `--video` without `-o`: a note when frames of the job are already finished at the
/// sequence's own output, naming the `-o` that encodes them instead of rendering them again.
pub(super) fn finished_elsewhere(job: &Job, args: &crate::cli::JobArgs) -> Option<String> {
    let files = job.files(args).ok()?;
    let plan = plan::plan(&job.seq, &job.frames, &files, Resume::Normal);
    let finished = plan.up_to_date.len() + plan.kept.len();
    (finished > 0).then(|| {
        let pattern = crate::output::stream::shell_quote(&job.seq.output);
        format!(
            "{finished} of the {} selected frames are finished in {}: add -o {pattern} to encode the video from them and render only the rest",
            job.frames.len(),
            shown(&plan::directory(&files.frame_path(0))),
        )
    })
}
