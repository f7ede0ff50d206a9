//! `render --video` and `--print-ffmpeg`: the job's video from the command line, ffmpeg
//! started before the first frame and finished (or stopped) after the last, and the ffmpeg
//! command that reads the stream or the frame files.

use super::Error;
use super::render::plural;
use crate::cli::RenderArgs;
use crate::output::{self, Files, stream::StreamFormat, video::VideoJob};
use crate::progress::Progress;
use crate::schedule::{Outcome, RunError};
use crate::sequence::Sequence;
use crate::signals;

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
