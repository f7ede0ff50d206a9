//! The subcommands: each turns validated arguments into calls down the pipeline.

use crate::Error;
use crate::cli::{CheckArgs, Cli, Command, MeasureArgs, PreviewArgs, RenderArgs};
use crate::output::{self, FileFormat, pattern::Pattern, stream::StreamFormat};
use crate::plan::{self, Plan};
use crate::progress::Progress;
use crate::scene::{Light, Shape};
use crate::schedule::{self, Files, Job, Outcome, Task};
use crate::sequence::{self, Overrides, Sequence};
use crate::timeline::Path as TimelinePath;
use std::path::Path;
use std::sync::Arc;

pub fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Render(args) => render(args),
        Command::Check(args) => check(args),
        Command::Preview(args) => preview(args),
        Command::Measure(args) => measure(args),
    }
}

fn render(args: RenderArgs) -> Result<(), Error> {
    let overrides = Overrides {
        size: args.size,
        max_depth: args.max_depth,
        output: args.output.clone(),
        depth: args.depth,
        samples: args.samples,
        quality: args.quality,
    };
    let seq = sequence::load(&args.file, &overrides)?;
    let count = seq.timeline.frame_count;
    let frames = match &args.frames {
        Some(spec) => spec
            .frames(count)
            .map_err(|e| Error::Usage(format!("--frames: {e}")))?,
        None => (0..count).collect(),
    };
    let sixteen = args.bit_depth == "16";
    // With --pipe the stream is the product; files come too only when asked for explicitly.
    let files = if args.pipe.is_none() || args.output.is_some() {
        Some(file_sink(&seq, &args, sixteen)?)
    } else {
        None
    };
    let stream = args.pipe.map(|p| (p, sixteen));
    let plan = files
        .as_ref()
        .map(|f| prepare(&seq, &frames, f, args.force))
        .transpose()?;
    if args.dry_run {
        print_dry_run(plan.as_ref(), &frames);
        return Ok(());
    }
    let tasks = tasks(&frames, plan.as_ref(), stream.is_some());
    let threads = match args.threads {
        Some(t) => usize::from(t),
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let mut progress = Progress::new(tasks.len() as u64, count, args.quiet);
    if let Some(plan) = &plan {
        progress.note(&plan.summary());
        warn_foreign(&progress, plan, files.as_ref().expect("plan has files"));
    }
    if let Some((format, sixteen)) = stream {
        stream_notes(&progress, &seq, format, sixteen, args.print_ffmpeg);
    }
    schedule::install_interrupt_handler();
    let job = Job {
        sequence: Arc::new(seq),
        tasks,
        files,
        stream,
        threads,
    };
    let outcome = schedule::run(job, &mut progress);
    progress.finish();
    finish(outcome, plan.as_ref())
}

/// The file pattern and format, with directories created and our stale temporaries removed.
fn file_sink(seq: &Sequence, args: &RenderArgs, sixteen: bool) -> Result<Files, Error> {
    let pattern = Pattern::new(&seq.output, seq.timeline.frame_count).map_err(Error::Usage)?;
    let format = FileFormat::for_extension(
        &pattern.extension(),
        sixteen,
        args.png_compression,
        args.exr_precision,
    )
    .map_err(|e| Error::Usage(format!("output `{}`: {e}", seq.output)))?;
    if matches!(format, FileFormat::Exr { .. }) && sixteen {
        return Err(Error::Usage(
            "--bit-depth 16 applies to PNG files and streams; EXR frames are float".into(),
        ));
    }
    if seq.settings.depth && !matches!(format, FileFormat::Exr { .. }) {
        return Err(Error::Usage(format!(
            "--depth (render.depth) needs EXR frames to hold the Z channel; `{}` is not .exr",
            seq.output
        )));
    }
    let dir = pattern
        .frame_path(0)
        .parent()
        .map(|d| d.to_path_buf())
        .unwrap_or_default();
    if !dir.as_os_str().is_empty() {
        std::fs::create_dir_all(&dir).map_err(|e| {
            Error::Failed(format!("{}: cannot create directory: {e}", dir.display()))
        })?;
    }
    output::atomic::clean_leftovers(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        &dir
    });
    Ok(Files { pattern, format })
}

fn prepare(seq: &Sequence, frames: &[u64], files: &Files, force: bool) -> Result<Plan, Error> {
    Ok(plan::plan(seq, frames, files, force))
}

fn print_dry_run(plan: Option<&Plan>, frames: &[u64]) {
    match plan {
        Some(plan) => {
            println!("{}", plan.summary());
            println!("would render: {}", plan::compress(&plan.to_render()));
        }
        None => println!("would stream frames: {}", plan::compress(frames)),
    }
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

fn warn_foreign(progress: &Progress, plan: &Plan, files: &Files) {
    for n in plan.blocked() {
        progress.warn(&format!(
            "{}: not written by rayreel (no fingerprint); leaving it alone (use --force to overwrite)",
            files.pattern.frame_path(n).display()
        ));
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
        Outcome::Complete => {
            let blocked = plan.map(Plan::blocked).unwrap_or_default();
            if blocked.is_empty() {
                Ok(())
            } else {
                Err(Error::Failed(format!(
                    "frames {} were not written: files rayreel did not write are in the way (use --force to overwrite them)",
                    plan::compress(&blocked)
                )))
            }
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

/// Writes DIR/NAME_path.png and DIR/NAME_sheet.png, printing their paths; warnings about the
/// camera path go to stderr.
fn preview(args: PreviewArgs) -> Result<(), Error> {
    use crate::preview;
    let seq = sequence::load(&args.file, &Overrides::default())?;
    let count = seq.timeline.frame_count;
    let frames = match &args.frames {
        Some(spec) => spec
            .frames(count)
            .map_err(|e| Error::Usage(format!("--frames: {e}")))?,
        None => preview::evenly_spaced(count, args.tiles),
    };
    if frames.len() as u64 > preview::MAX_TILES {
        return Err(Error::Usage(format!(
            "--frames: {} frames; a contact sheet holds at most {}",
            frames.len(),
            preview::MAX_TILES
        )));
    }
    let dir = args
        .out
        .unwrap_or_else(|| Path::new("frames").join(&seq.name).join("preview"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    let (plot, warnings) = preview::path_plot(&seq);
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let plot_file = dir.join(format!("{}_path.png", seq.name));
    preview::write_png(&plot_file, &plot).map_err(Error::Failed)?;
    println!("{}", plot_file.display());
    let (sheet, _) =
        preview::contact_sheet(&seq, &frames, preview::TILE_WIDTH).map_err(Error::Failed)?;
    let sheet_file = dir.join(format!("{}_sheet.png", seq.name));
    preview::write_png(&sheet_file, &sheet).map_err(Error::Failed)?;
    println!("{}", sheet_file.display());
    Ok(())
}

fn check(args: CheckArgs) -> Result<(), Error> {
    let seq = sequence::load(&args.file, &Overrides::default())?;
    print!("{}", summary(&args.file.display().to_string(), &seq));
    Ok(())
}

/// The one-screen description `rayreel check` prints.
pub fn summary(file: &str, seq: &Sequence) -> String {
    let scene = &seq.scene;
    let spheres = scene
        .objects
        .iter()
        .filter(|o| matches!(o.shape, Shape::Sphere { .. }))
        .count();
    let planes = scene.objects.len() - spheres;
    let mut kinds = [0usize; 4];
    for l in &scene.lights {
        kinds[match l {
            Light::Point { .. } => 0,
            Light::Directional { .. } => 1,
            Light::Spot { .. } => 2,
            Light::Ambient { .. } => 3,
        }] += 1;
    }
    let light_list: Vec<String> = ["point", "directional", "spot", "ambient"]
        .iter()
        .zip(kinds)
        .filter(|(_, n)| *n > 0)
        .map(|(k, n)| format!("{n} {k}"))
        .collect();
    let t = &seq.timeline;
    let camera = match &t.path {
        TimelinePath::Orbit(o) => format!("orbit of radius {} ({} turns)", o.radius, o.turns),
        TimelinePath::Keys { keys, .. } if keys.len() == 1 => "still camera".to_string(),
        TimelinePath::Keys {
            keys,
            interpolation,
        } => format!(
            "{} keyframes, {:?} interpolation",
            keys.len(),
            interpolation
        )
        .to_lowercase(),
    };
    let s = &seq.settings;
    format!(
        "{file}: ok\n  objects:    {} ({spheres} spheres, {planes} planes)\n  materials:  {}\n  lights:     {} ({})\n  resolution: {}x{}, max_depth {}\n  frames:     {} at {} fps ({:.2} s), {camera}\n  output:     {}\n",
        scene.objects.len(),
        scene.materials.len(),
        scene.lights.len(),
        if light_list.is_empty() {
            "none".to_string()
        } else {
            light_list.join(", ")
        },
        s.width,
        s.height,
        s.max_depth,
        t.frame_count,
        t.fps,
        t.frame_count as f64 / t.fps,
        seq.output
    )
}

fn measure(args: MeasureArgs) -> Result<(), Error> {
    let mut seq = sequence::load(&args.file, &Overrides::default())?;
    let count = seq.timeline.frame_count;
    if args.frame >= count {
        return Err(Error::Usage(format!(
            "--frame: frame {} is outside the timeline, which has frames 0-{}",
            args.frame,
            count - 1
        )));
    }
    let (w, h) = match args.size {
        Some(size) => size,
        None => {
            let s = &seq.settings;
            (
                320,
                (320.0 * f64::from(s.height) / f64::from(s.width))
                    .round()
                    .max(1.0) as u64,
            )
        }
    };
    let o = Overrides {
        size: Some((w, h)),
        ..Overrides::default()
    };
    seq = sequence::load(&args.file, &o)?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("frames").join(&seq.name).join("measure"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    eprintln!(
        "measuring frame {} of {} at {w}x{h}",
        args.frame,
        args.file.display()
    );
    let report = crate::measure::measure(&seq, args.frame, args.runs as usize, &mut |line| {
        eprintln!("  {line}")
    })
    .map_err(Error::Failed)?;
    print!("{}", report.table());
    for (name, text) in [
        ("measure.csv", report.csv()),
        ("measure.json", report.json()),
        ("measure.svg", report.svg()),
    ] {
        let path = dir.join(name);
        output::atomic::write_atomic(&path, text.as_bytes())
            .map_err(|e| Error::Failed(format!("{}: cannot write: {e}", path.display())))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
