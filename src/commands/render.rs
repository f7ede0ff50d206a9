//! `render` and `status`: the same job description (sequence, overrides, frames, shard,
//! format) either rendered or only inspected.

use super::{out, shown};
use crate::Error;
use crate::claim::Claims;
use crate::cli::{JobArgs, ProgressFormat, RenderArgs, StatusArgs, resolve_shard};
use crate::output::{self, FileFormat, pattern::Pattern, stream::StreamFormat};
use crate::plan::{self, Plan, State};
use crate::progress::Progress;
use crate::schedule::{self, Files, Job, Outcome, Task};
use crate::sequence::{self, Overrides, Sequence};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// The validated sequence and this task's frames.
fn load(job: &JobArgs) -> Result<(Sequence, Vec<u64>), Error> {
    let overrides = Overrides {
        size: job.size,
        max_depth: job.max_depth,
        output: job.output.clone(),
        depth: job.depth,
        samples: job.samples,
        quality: job.quality,
    };
    let seq = sequence::load(&job.file, &overrides)?;
    let count = seq.timeline.frame_count;
    let mut frames = match &job.frames {
        Some(spec) => spec
            .frames(count)
            .map_err(|e| Error::Usage(format!("--frames: {e}")))?,
        None => (0..count).collect(),
    };
    if let Some(spec) = job.shard {
        let env = |name: &str| std::env::var(name).ok();
        let (k, n) = resolve_shard(spec, job.shard_count, &env)
            .map_err(|e| Error::Usage(format!("--shard: {e}")))?;
        frames = plan::shard(&frames, k, n);
    }
    Ok((seq, frames))
}

/// The file pattern and format; `create` makes the directory and clears our stale temporaries.
fn file_sink(seq: &Sequence, job: &JobArgs, create: bool) -> Result<Files, Error> {
    let sixteen = job.bit_depth == "16";
    let pattern = Pattern::new(&seq.output, seq.timeline.frame_count).map_err(Error::Usage)?;
    let format = FileFormat::for_extension(
        &pattern.extension(),
        sixteen,
        job.png_compression,
        job.exr_precision,
    )
    .map_err(|e| Error::Usage(format!("output `{}`: {e}", seq.output)))?;
    let exr = matches!(format, FileFormat::Exr { .. });
    if exr && sixteen {
        return Err(Error::Usage(
            "--bit-depth 16 applies to PNG files and streams; EXR frames are float".into(),
        ));
    }
    if seq.settings.depth && !exr {
        return Err(Error::Usage(format!(
            "--depth (render.depth) needs EXR frames to hold the Z channel; `{}` is not .exr",
            seq.output
        )));
    }
    if create {
        let dir = directory(&pattern);
        std::fs::create_dir_all(&dir).map_err(|e| {
            Error::Failed(format!("{}: cannot create directory: {e}", dir.display()))
        })?;
        output::atomic::clean_leftovers(&dir);
    }
    Ok(Files { pattern, format })
}

fn directory(pattern: &Pattern) -> PathBuf {
    match pattern.frame_path(0).parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

pub fn render(args: RenderArgs) -> Result<(), Error> {
    let (seq, frames) = load(&args.job)?;
    // With --pipe the stream is the product; files come too only when asked for explicitly.
    let files = match args.pipe.is_none() || args.job.output.is_some() {
        true => Some(file_sink(&seq, &args.job, !args.dry_run)?),
        false => None,
    };
    if args.claim && (files.is_none() || args.pipe.is_some()) {
        return Err(Error::Usage(
            "--claim shares frame files between processes; it cannot be combined with --pipe"
                .into(),
        ));
    }
    let stream = args.pipe.map(|p| (p, args.job.bit_depth == "16"));
    let plan = files
        .as_ref()
        .map(|f| plan::plan(&seq, &frames, f, args.force));
    if args.dry_run {
        return print_dry_run(plan.as_ref(), &frames);
    }
    let tasks = tasks(&frames, plan.as_ref(), stream.is_some());
    let threads = match args.threads {
        Some(t) => usize::from(t),
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let count = seq.timeline.frame_count;
    let mut progress = match args.progress {
        ProgressFormat::Json if !args.quiet => Progress::json(tasks.len() as u64, count),
        _ => Progress::new(tasks.len() as u64, count, args.quiet),
    };
    if let (Some(plan), Some(files)) = (&plan, &files) {
        progress.note(&plan.summary());
        report_skipped(&progress, plan, files);
    }
    if let Some((format, sixteen)) = stream {
        stream_notes(&progress, &seq, format, sixteen, args.print_ffmpeg);
    }
    schedule::install_interrupt_handler();
    let claims = args
        .claim
        .then(|| Arc::new(Claims::new(Duration::from_secs(args.claim_timeout))));
    let job = Job {
        sequence: Arc::new(seq),
        tasks,
        files,
        stream,
        stream_out: None,
        threads,
        claims,
    };
    let written: Vec<u64> = job
        .tasks
        .iter()
        .filter(|t| t.write_file)
        .map(|t| t.frame)
        .collect();
    let (seq, files) = (Arc::clone(&job.sequence), job.files.clone());
    let outcome = match job.claims.is_some() {
        true => cooperate(job, &frames, &mut progress),
        false => schedule::run(job, &mut progress),
    };
    progress.finish();
    if let (Ok(Outcome::Complete { .. }), Some(files)) = (&outcome, &files) {
        verify(&seq, &written, files)?;
    }
    finish(outcome, plan.as_ref())
}

/// After a complete run, every frame it wrote must still be there and intact: a file that
/// vanished or was replaced meanwhile (another program, a full disk elsewhere) is reported
/// rather than assumed done.
fn verify(seq: &Sequence, written: &[u64], files: &Files) -> Result<(), Error> {
    let check = plan::plan(seq, written, files, false);
    let bad: Vec<String> = check
        .frames
        .iter()
        .filter(|(_, s)| *s != State::UpToDate)
        .map(|(n, s)| {
            format!(
                "{} ({})",
                files.pattern.frame_path(*n).display(),
                describe(s)
            )
        })
        .collect();
    if bad.is_empty() {
        return Ok(());
    }
    Err(Error::Failed(format!(
        "frames written by this run changed before it ended: {}; run the same command again to render them",
        bad.join(", ")
    )))
}

fn describe(s: &State) -> String {
    match s {
        State::UpToDate => "up to date".into(),
        State::Stale => "replaced by a different render".into(),
        State::Missing => "vanished".into(),
        State::Corrupt(why) => format!("now corrupt: {why}"),
        State::Foreign => "replaced by a file rayreel did not write".into(),
    }
}

/// Claim mode: render what can be claimed, then keep re-planning until every frame is up to
/// date, waiting on frames other live processes hold and taking over those whose owner died.
fn cooperate(mut job: Job, frames: &[u64], progress: &mut Progress) -> Result<Outcome, String> {
    let mut written = 0;
    loop {
        let outcome = schedule::run(
            Job {
                tasks: std::mem::take(&mut job.tasks),
                claims: job.claims.clone(),
                files: job.files.clone(),
                sequence: Arc::clone(&job.sequence),
                stream: None,
                stream_out: None,
                threads: job.threads,
            },
            progress,
        )?;
        let Outcome::Complete { written: w, held } = outcome else {
            return Ok(outcome);
        };
        written += w;
        if !held.is_empty() {
            std::thread::sleep(Duration::from_millis(500));
        }
        let files = job.files.as_ref().expect("claim mode has files");
        let plan = plan::plan(&job.sequence, frames, files, false);
        job.tasks = tasks(frames, Some(&plan), false);
        if job.tasks.is_empty() {
            return Ok(Outcome::Complete {
                written,
                held: Vec::new(),
            });
        }
        if held.is_empty() {
            progress.add_total(job.tasks.len() as u64);
        }
    }
}

fn print_dry_run(plan: Option<&Plan>, frames: &[u64]) -> Result<(), Error> {
    out(&match plan {
        Some(plan) => format!(
            "{}\nwould render: {}\n",
            plan.summary(),
            plan::compress(&plan.to_render())
        ),
        None => format!("would stream frames: {}\n", plan::compress(frames)),
    })
}

/// Every selected frame when streaming (files written only where the plan says), otherwise
/// just the frames the plan renders.
fn tasks(frames: &[u64], plan: Option<&Plan>, streaming: bool) -> Vec<Task> {
    let Some(plan) = plan else {
        return frames
            .iter()
            .map(|&frame| Task {
                frame,
                write_file: false,
            })
            .collect();
    };
    plan.frames
        .iter()
        .filter(|(_, s)| streaming || plan.renders(s))
        .map(|(frame, s)| Task {
            frame: *frame,
            write_file: plan.renders(s),
        })
        .collect()
}

fn report_skipped(progress: &Progress, plan: &Plan, files: &Files) {
    for (n, state) in &plan.frames {
        let path = files.pattern.frame_path(*n).display().to_string();
        match state {
            State::UpToDate if !plan.force => progress.frame_skipped(*n, &path, "up-to-date"),
            State::Foreign if !plan.force => {
                progress.frame_skipped(*n, &path, "foreign");
                progress.warn(&format!(
                    "{path}: not written by rayreel (no fingerprint); leaving it alone (use --force to overwrite)"
                ));
            }
            _ => {}
        }
    }
}

fn stream_notes(
    progress: &Progress,
    seq: &Sequence,
    format: StreamFormat,
    sixteen: bool,
    print: bool,
) {
    let (w, h) = (seq.settings.width, seq.settings.height);
    let command = output::stream::ffmpeg_command(format, sixteen, w, h, seq.timeline.fps);
    if print {
        eprintln!("{command}");
    }
    if w % 2 == 1 || h % 2 == 1 {
        progress.warn(&format!(
            "note: {w}x{h} is odd, and yuv420p video needs even sizes: give ffmpeg -vf pad=ceil(iw/2)*2:ceil(ih/2)*2"
        ));
    }
}

fn finish(outcome: Result<Outcome, String>, plan: Option<&Plan>) -> Result<(), Error> {
    match outcome.map_err(Error::Failed)? {
        Outcome::Complete { .. } => {
            let blocked = plan.map(Plan::blocked).unwrap_or_default();
            if blocked.is_empty() {
                return Ok(());
            }
            Err(Error::Failed(format!(
                "frames {} were not written: files rayreel did not write are in the way (use --force to overwrite them)",
                plan::compress(&blocked)
            )))
        }
        Outcome::Interrupted { written } => Err(Error::Interrupted(format!(
            "interrupted: {written} frame{} written in this run; run the same command again to render the rest",
            if written == 1 { "" } else { "s" }
        ))),
        Outcome::ReaderClosed { streamed } => {
            eprintln!("rayreel: the reader closed the stream after {streamed} frames; stopping");
            Ok(())
        }
    }
}

/// `rayreel status`: the completeness of the output against the sequence; exit 0 only when
/// every selected frame is up to date.
pub fn status(args: StatusArgs) -> Result<(), Error> {
    let (seq, frames) = load(&args.job)?;
    let files = file_sink(&seq, &args.job, false)?;
    let plan = plan::plan(&seq, &frames, &files, false);
    let dir = directory(&files.pattern);
    let mut lines = vec![format!("{}: {}", shown(&dir), plan.status_line())];
    for (label, pick) in [
        (
            "up to date",
            &(|s: &State| *s == State::UpToDate) as &dyn Fn(&State) -> bool,
        ),
        ("stale", &|s: &State| *s == State::Stale),
        ("missing", &|s: &State| *s == State::Missing),
        ("corrupt", &|s: &State| matches!(s, State::Corrupt(_))),
        ("foreign", &|s: &State| *s == State::Foreign),
    ] {
        let list: Vec<u64> = plan
            .frames
            .iter()
            .filter(|(_, s)| pick(s))
            .map(|(n, _)| *n)
            .collect();
        if !list.is_empty() {
            lines.push(format!("  {label:<11} {}", plan::compress(&list)));
        }
    }
    // A closed stdout ends the listing, not the verdict: the exit code still says whether
    // every frame is up to date.
    out(&format!("{}\n", lines.join("\n")))?;
    let incomplete = plan
        .frames
        .iter()
        .filter(|(_, s)| *s != State::UpToDate)
        .count();
    if incomplete == 0 {
        Ok(())
    } else {
        Err(Error::Incomplete(format!(
            "{incomplete} of {} frames are not up to date",
            plan.frames.len()
        )))
    }
}
