//! `render` and `status`: the same job description (sequence, overrides, frames, shard,
//! format) either rendered or only inspected.

use super::video::{
    FromFiles, encode_files, end_video, ffmpeg_line, start_video, video_job, video_notes,
};
use super::{Error, out, shown};
use crate::claim::{self, Claims, Held};
use crate::cli::job::Job;
use crate::cli::{ProgressFormat, RenderArgs};
use crate::frameset::FrameSet;
use crate::output::{self, Files, video::VideoJob};
use crate::plan::{self, Plan, Resume, State};
use crate::progress::Progress;
use crate::schedule::{self, Batch, Outcome, RunError, Task};
use crate::sequence::Sequence;
use crate::signals;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Makes the frames' directory, checks that files can be written there (before anything
/// renders), and removes this job's temporaries that processes which are gone left there.
fn prepare(files: &Files, frames: &FrameSet) -> Result<(), Error> {
    let dir = plan::directory(&files.frame_path(0));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    output::atomic::probe_writable(&dir).map_err(|e| {
        Error::Failed(format!(
            "{}: cannot write files in this directory: {e}",
            dir.display()
        ))
    })?;
    output::atomic::clean_leftovers(&dir, &files.pattern, frames);
    Ok(())
}

pub(crate) fn render(args: RenderArgs) -> Result<(), Error> {
    // From here on every line on stderr is one JSON object, errors included.
    crate::console::set_json(args.progress == ProgressFormat::Json);
    let spec = Job::new(&args.job)?;
    let sixteen_bit = spec.sixteen_bit;
    let warnings = crate::warnings::for_sequence(&spec.seq);
    let files = spec.render_files(&args)?;
    let video = video_job(&args, &spec.seq, sixteen_bit)?;
    let reusable = match (&video, &files) {
        (Some(_), None) => super::video::finished_elsewhere(&spec, &args.job),
        _ => None,
    };
    if let (Some(note), false) = (&reusable, args.quiet) {
        crate::console::note(&format!("note: {note}"));
    }
    let Job { seq, frames, .. } = spec;
    if args.dry_run {
        let job = (&seq, &frames, sixteen_bit);
        return dry_run(&args, job, files.as_ref(), video.as_ref(), &warnings);
    }
    let (pool, threads) = workers(args.threads)?;
    if let Some(video) = &video {
        video.preflight().map_err(Error::Failed)?;
    }
    if let Some(files) = &files {
        prepare(files, &frames)?;
    }
    // With -o, `--video` renders what the files lack and then encodes the files.
    let from_files = video.is_some() && files.is_some();
    let stream = match &video {
        Some(video) if !from_files => Some(video.stream()),
        Some(_) => None,
        None => args.pipe.map(|p| (p, sixteen_bit)),
    };
    let plan = files
        .as_ref()
        .map(|f| plan::plan(&seq, &frames, f, args.resume()));
    let tasks = tasks(&frames, plan.as_ref(), stream.is_some());
    let mut progress = progress_for(&args, tasks.len() as u64, seq.timeline.frame_count);
    start(&progress, &warnings, plan.as_ref(), frames.len());
    if let (Some(plan), Some(files)) = (&plan, &files) {
        report_skipped(&progress, plan, files);
    }
    match &video {
        Some(video) if args.print_ffmpeg => progress.command(&video.command_line()),
        Some(video) if !from_files => progress.note(&super::video::nothing_kept(&video.path)),
        Some(_) => {}
        None => video_notes(&progress, &seq, stream, files.as_ref(), args.print_ffmpeg),
    }
    let streamed_video = video.as_ref().filter(|_| !from_files);
    let mut encoder = start_video(streamed_video, &mut progress)?;
    let stream_out = encoder.as_mut().and_then(|e| e.take_input());
    let claims = args
        .claim
        .then(|| Arc::new(Claims::new(Duration::from_secs(args.claim_timeout))));
    let sequence = Arc::new(seq);
    let files_kept = files.clone();
    let batch = Batch {
        sequence: Arc::clone(&sequence),
        tasks,
        files,
        stream,
        stream_out: stream_out.map(|s| Box::new(s) as Box<dyn std::io::Write + Send>),
        threads,
        claims,
    };
    let outcome = run_job(
        &pool,
        batch,
        (&frames, args.resume().unforced()),
        &mut progress,
    )?;
    let outcome = match encoder.take() {
        Some(encoder) => end_video(encoder, outcome)?,
        None => outcome,
    };
    let (seq, files) = (Arc::clone(&sequence), files_kept);
    match (video.filter(|_| from_files), files) {
        (Some(video), Some(files)) => {
            let encode = FromFiles {
                seq: &seq,
                frames: &frames,
                files: &files,
                resume: args.resume().unforced(),
                quiet: args.quiet,
                json: args.progress == ProgressFormat::Json,
            };
            finish(outcome, plan.as_ref(), false, true)?;
            encode_files(&video, &encode)
        }
        _ => finish(outcome, plan.as_ref(), stream.is_some(), false),
    }
}

/// `--dry-run`: the warnings, the ffmpeg line if asked for, and the plan; nothing is made.
fn dry_run(
    args: &RenderArgs,
    (seq, frames, sixteen_bit): (&Sequence, &FrameSet, bool),
    files: Option<&Files>,
    video: Option<&VideoJob>,
    warnings: &[String],
) -> Result<(), Error> {
    warnings
        .iter()
        .for_each(|w| crate::console::warning(&format!("warning: {w}")));
    let plan = files.map(|f| plan::plan(seq, frames, f, args.resume()));
    if args.print_ffmpeg {
        let stream = args.pipe.map(|p| (p, sixteen_bit));
        let line = match video {
            Some(video) => Some(video.command_line()),
            None => ffmpeg_line(seq, stream, files),
        };
        line.iter().for_each(|l| crate::console::note(l));
    }
    let video = video.map(|v| v.path.as_path());
    print_dry_run(
        seq,
        (plan.as_ref(), video, files),
        (frames, args.threads),
        args.pipe.is_some(),
    )
}

/// Progress as `--progress` and `--quiet` ask: `total` frames to render of `frame_count`.
fn progress_for(args: &RenderArgs, total: u64, frame_count: u64) -> Progress {
    match args.progress {
        ProgressFormat::Json if !args.quiet => Progress::json(total, frame_count),
        _ => Progress::new(total, frame_count, args.quiet),
    }
}

/// The warnings, then the plan (or the selection when streaming without files).
fn start(progress: &Progress, warnings: &[String], plan: Option<&Plan>, selected: u64) {
    for w in warnings {
        progress.warn(&format!("warning: {w}"));
    }
    let planned = plan.map(|p| (p.summary(), p.counts()));
    let planned = planned
        .as_ref()
        .map(|(summary, counts)| (summary.as_str(), &counts[..]));
    progress.start(planned, selected);
    plan.iter()
        .flat_map(|p| p.reasons())
        .for_each(|r| progress.note(&r));
}

/// The worker threads, started before anything else happens: a count the machine cannot
/// start is refused at once (exit 2 when it was asked for with --threads).
fn workers(asked: Option<u16>) -> Result<(rayon::ThreadPool, usize), Error> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = asked.map_or(cores, usize::from);
    let pool = schedule::worker_pool(threads).map_err(|e| match asked {
        Some(_) => Error::Usage(format!(
            "--threads {threads}: {e}; this machine has {cores} cores, and more threads than cores do not render faster"
        )),
        None => Error::Run(e),
    })?;
    Ok((pool, threads))
}

/// Runs the batch (cooperating through claims if asked), then checks what it wrote.
fn run_job(
    pool: &rayon::ThreadPool,
    batch: Batch,
    frames: (&FrameSet, Resume),
    progress: &mut Progress,
) -> Result<Result<Outcome, RunError>, Error> {
    let mut written = FrameSet::new();
    batch
        .tasks
        .iter()
        .filter(|t| t.write_file)
        .for_each(|t| written.push(t.frame));
    let (seq, files) = (Arc::clone(&batch.sequence), batch.files.clone());
    signals::install_interrupt_handler();
    let outcome = match batch.claims.is_some() {
        true => cooperate(pool, batch, frames, progress),
        false => schedule::run_on(pool, batch, progress),
    };
    progress.finish(matches!(outcome, Ok(Outcome::Interrupted { .. })));
    if let (Ok(Outcome::Complete { .. }), Some(files)) = (&outcome, &files) {
        verify(&seq, &written, files)?;
    }
    Ok(outcome)
}

/// After a complete run, every frame it wrote must still be there and intact: a file that
/// vanished or was replaced meanwhile (another program, a full disk elsewhere) is reported
/// rather than assumed done.
fn verify(seq: &Sequence, written: &FrameSet, files: &Files) -> Result<(), Error> {
    let check = plan::plan(seq, written, files, Resume::Normal);
    let mut bad: Vec<(u64, State)> = check
        .why
        .into_iter()
        .map(|(n, why)| (n, State::Corrupt(why)))
        .collect();
    for (set, state) in [
        (&check.stale, State::Stale(String::new())),
        (&check.kept, State::Stale(String::new())),
        (&check.missing, State::Missing),
    ] {
        bad.extend(set.iter().map(|n| (n, state.clone())));
    }
    bad.extend(
        check
            .why_foreign
            .into_iter()
            .map(|(n, why)| (n, State::Foreign(why))),
    );
    if bad.is_empty() {
        return Ok(());
    }
    bad.sort_by_key(|(n, _)| *n);
    let bad: Vec<String> = bad
        .iter()
        .map(|(n, s)| format!("{} ({})", files.frame_path(*n).display(), describe(s)))
        .collect();
    Err(Error::Failed(format!(
        "frames written by this run changed before it ended: {}; run the same command again to render them",
        bad.join(", ")
    )))
}

fn describe(s: &State) -> String {
    match s {
        State::UpToDate => "up to date".into(),
        State::Stale(_) | State::Kept(_) => "replaced by a different render".into(),
        State::Missing => "vanished".into(),
        State::Corrupt(why) => format!("now corrupt: {why}"),
        State::Foreign(why) => format!("replaced by something rayreel did not write: {why}"),
    }
}

/// Claim mode: render what can be claimed, then keep re-planning until every frame is up to
/// date, waiting on frames other live processes hold (and saying so) and taking over those
/// whose owner died or went silent.
fn cooperate(
    pool: &rayon::ThreadPool,
    mut batch: Batch,
    (frames, resume): (&FrameSet, Resume),
    progress: &mut Progress,
) -> Result<Outcome, RunError> {
    let mut written = 0;
    let mut told: Option<Instant> = None;
    loop {
        let outcome = schedule::run_on(
            pool,
            Batch {
                tasks: std::mem::take(&mut batch.tasks),
                claims: batch.claims.clone(),
                files: batch.files.clone(),
                sequence: Arc::clone(&batch.sequence),
                stream: None,
                stream_out: None,
                threads: batch.threads,
            },
            progress,
        )?;
        let held = match outcome {
            Outcome::Complete { written: w, held } => {
                written += w;
                held
            }
            // A signal while waiting on other processes' claims stops the pass that follows:
            // what the earlier passes wrote counts too.
            Outcome::Interrupted {
                written: w,
                streamed,
            } => {
                return Ok(Outcome::Interrupted {
                    written: written + w,
                    streamed,
                });
            }
            other => return Ok(other),
        };
        if signals::interrupted() {
            return Ok(Outcome::Interrupted {
                written,
                streamed: 0,
            });
        }
        let files = batch.files.as_ref().expect("claim mode has files");
        if !held.is_empty() {
            if told.is_none_or(|t| t.elapsed() >= WAITING_REPORT_EVERY) {
                report_waiting(progress, files, &held);
                told = Some(Instant::now());
            }
            std::thread::sleep(Duration::from_millis(500));
        }
        let plan = plan::plan(&batch.sequence, frames, files, resume);
        batch.tasks = tasks(frames, Some(&plan), false);
        if batch.tasks.is_empty() {
            return Ok(Outcome::Complete {
                written,
                held: Vec::new(),
            });
        }
        if held.is_empty() {
            progress.add_total(batch.tasks.len() as u64);
        }
    }
}

/// How often a waiting process repeats what it waits for.
const WAITING_REPORT_EVERY: Duration = Duration::from_secs(30);

/// Which frames other processes hold, with the first few claims' paths and owners.
fn report_waiting(progress: &Progress, files: &Files, held: &[u64]) {
    let mut set = FrameSet::new();
    held.iter().for_each(|&n| set.push(n));
    let claims: Vec<Held> = held
        .iter()
        .take(3)
        .map(|&n| claim::held(&files.frame_path(n)))
        .collect();
    progress.waiting(&set.to_string(), held.len(), &claims);
}

/// The plan on stdout, or on stderr when stdout is the stream (`--pipe`): what reads the
/// stream must never get text.
fn print_dry_run(
    seq: &Sequence,
    (plan, video, files): (Option<&Plan>, Option<&std::path::Path>, Option<&Files>),
    (frames, threads): (&FrameSet, Option<u16>),
    piping: bool,
) -> Result<(), Error> {
    let (text, rendering) = match (plan, video) {
        // Without files a video takes every selected frame straight from the tracer.
        (None, Some(video)) => {
            let text = format!(
                "would render frames {frames} straight into {}\nnote: {}\n",
                shown(video),
                super::video::nothing_kept(video)
            );
            (text, frames.clone())
        }
        (Some(plan), video) => {
            let render = match piping {
                true => frames.clone(),
                false => plan.to_render(),
            };
            let reasons: String = plan.reasons().iter().map(|r| format!("{r}\n")).collect();
            let what = match render.is_empty() {
                true => "nothing: every selected frame is finished".to_string(),
                false => render.to_string(),
            };
            let mut text = format!("{}\n{reasons}would render: {what}\n", plan.summary());
            if let (Some(video), Some(files)) = (video, files) {
                text += &format!(
                    "then would encode frames {frames} from {} into {}\n",
                    files.pattern.ffmpeg(),
                    shown(video)
                );
            }
            (text, render)
        }
        (None, None) => (format!("would stream frames: {frames}\n"), frames.clone()),
    };
    let threads = threads.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        usize::from,
    );
    let format = match piping {
        true => None,
        false => files.map(|f| &f.format),
    };
    let super::check::Cost {
        line: cost,
        warning,
        ..
    } = super::check::cost(seq, &rendering, threads, format, " ")?;
    if let Some(w) = warning {
        crate::console::warning(&w);
    }
    let s = &seq.settings;
    let text = format!(
        "{text}settings: {}x{}, max_depth {}, {}, {}\ncost: {cost}\n",
        s.width,
        s.height,
        s.max_depth,
        super::check::picture(s),
        s.precision.name()
    );
    if !piping {
        return out(&text);
    }
    text.lines().for_each(crate::console::note);
    Ok(())
}

/// Every selected frame when streaming (files written only where the plan says), otherwise
/// just the frames the plan renders.
fn tasks(frames: &FrameSet, plan: Option<&Plan>, streaming: bool) -> Vec<Task> {
    let task = |frame, write_file| Task { frame, write_file };
    match plan {
        None => frames.iter().map(|n| task(n, false)).collect(),
        Some(plan) if streaming => {
            let render = plan.to_render();
            frames.iter().map(|n| task(n, render.contains(n))).collect()
        }
        Some(plan) => plan.to_render().iter().map(|n| task(n, true)).collect(),
    }
}

fn report_skipped(progress: &Progress, plan: &Plan, files: &Files) {
    if plan.force {
        return;
    }
    let path = |n| files.frame_path(n).display().to_string();
    if progress.reports_skipped() {
        for n in plan.up_to_date.iter() {
            progress.frame_skipped(n, &path(n), "up-to-date");
        }
        for n in plan.kept.iter() {
            progress.frame_skipped(n, &path(n), "kept");
        }
    }
    for (n, why) in &plan.why_foreign {
        progress.frame_skipped(*n, &path(*n), "foreign");
        progress.warn(&format!(
            "{}: {why}; leaving it alone (use --force to overwrite)",
            path(*n)
        ));
    }
}

/// `interrupted: 3 frames written and 14 streamed to stdout in this run; …`.
fn interrupted_summary(
    written: usize,
    streamed: usize,
    plan: Option<&Plan>,
    streaming: bool,
) -> String {
    let frames = |n: usize| format!("{n} frame{}", if n == 1 { "" } else { "s" });
    let done = match (plan.is_some(), streaming) {
        (true, true) => format!(
            "{} written and {streamed} streamed to stdout",
            frames(written)
        ),
        (false, _) => format!("{} streamed to stdout", frames(streamed)),
        (true, false) => format!("{} written", frames(written)),
    };
    format!("interrupted: {done} in this run; run the same command again to render the rest")
}

/// What the run came to; `encoding_next` when `--video` encodes the files once they are all
/// rendered (an interruption then says that no video was made).
fn finish(
    outcome: Result<Outcome, RunError>,
    plan: Option<&Plan>,
    streaming: bool,
    encoding_next: bool,
) -> Result<(), Error> {
    match outcome? {
        Outcome::Complete { .. } => {
            let blocked = plan.map(Plan::blocked).unwrap_or_default();
            if blocked.is_empty() {
                return Ok(());
            }
            Err(Error::Failed(format!(
                "{} not written: files rayreel did not write are in the way (use --force to overwrite them)",
                match blocked.len() {
                    1 => format!("frame {blocked} was"),
                    _ => format!("frames {blocked} were"),
                }
            )))
        }
        Outcome::Interrupted { written, .. } if encoding_next => Err(Error::Interrupted(
            format!(
                "interrupted: {} in this run, and they stay; no video was made yet: run the same command again to render the rest and encode it",
                plural(written as u64, "frame file") + " written"
            ),
            signals::interrupt_code(),
        )),
        Outcome::Interrupted { written, streamed } => Err(Error::Interrupted(
            interrupted_summary(written, streamed, plan, streaming),
            signals::interrupt_code(),
        )),
        // Ctrl-C in `rayreel … | ffmpeg …` reaches both: ffmpeg closing the pipe is then
        // the interruption, not a reader that had enough.
        Outcome::ReaderClosed { streamed } if reader_was_interrupted() => Err(Error::Interrupted(
            interrupted_summary(0, streamed, None, true),
            signals::interrupt_code(),
        )),
        Outcome::ReaderClosed { streamed } => {
            crate::console::note(&format!(
                "rayreel: the reader closed the stream after {}; stopping",
                plural(streamed as u64, "frame")
            ));
            Ok(())
        }
    }
}

/// Whether a signal came with the reader's end: the terminal sends Ctrl-C to every process
/// of the pipeline, and the reader may exit a moment before the signal is noticed here.
fn reader_was_interrupted() -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(200) {
        if signals::interrupted() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    signals::interrupted()
}

/// `1 frame`, `3 frames`.
pub(crate) fn plural(n: u64, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// `rayreel status`: the completeness of the output against the sequence; exit 0 only when
/// every selected frame is up to date.
pub(crate) fn status(args: RenderArgs) -> Result<(), Error> {
    let spec = Job::for_status(&args.job)?;
    let files = spec.files(&args.job)?;
    let (seq, frames) = (spec.seq, spec.frames);
    let plan = plan::plan(&seq, &frames, &files, args.resume().unforced());
    let dir = plan::directory(&files.frame_path(0));
    let mut lines = vec![format!("{}: {}", shown(&dir), plan.status_line())];
    for (label, set) in plan.by_state() {
        if !set.is_empty() {
            lines.push(format!("  {label:<11} {set}"));
        }
    }
    lines.extend(plan.reasons().iter().map(|r| format!("  {r}")));
    // A closed stdout ends the listing, not the verdict: the exit code still says whether
    // every frame is up to date.
    out(&format!("{}\n", lines.join("\n")))?;
    // Kept frames are done: `render` would leave them as they are.
    let done = plan.up_to_date.len() + plan.kept.len();
    let selected = plan.selected_count();
    if done == selected {
        Ok(())
    } else {
        Err(Error::Incomplete(format!(
            "{} of {selected} frames are not up to date",
            selected - done
        )))
    }
}
