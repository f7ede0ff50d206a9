//! The subcommands: each turns validated arguments into calls down the pipeline.

mod camera;
mod render;

use crate::Error;
use crate::cli::{BenchArgs, CheckArgs, Cli, Command, MeasureArgs, PreviewArgs};
use crate::output;
use crate::scene::{Light, Shape};
use crate::sequence::{self, Overrides, Sequence};
use crate::timeline::{Ease, Path as TimelinePath, Speed, Timeline};
use std::path::Path;

pub fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Render(args) => render::render(args),
        Command::Status(args) => render::status(args),
        Command::Check(args) => check(args),
        Command::Preview(args) => preview(args),
        Command::Camera(args) => camera::camera(args),
        Command::Measure(args) => measure(args),
        Command::Bench(args) => bench(args),
    }
}

/// What a valid sequence still deserves a warning for: keys the film never shows, frames with
/// the camera inside an object.
fn warnings(seq: &Sequence) -> Vec<String> {
    let mut all = seq.warnings.clone();
    all.extend(crate::preview::inside_warnings(seq));
    all
}

fn print_warnings(seq: &Sequence) {
    for w in warnings(seq) {
        eprintln!("warning: {w}");
    }
}

/// Writes DIR/NAME_path.png and DIR/NAME_sheet.png, printing their paths; warnings about the
/// camera path go to stderr. A path whose camera cannot be built somewhere is still drawn,
/// with the reason, and then reported as the load error it is (exit 2).
fn preview(args: PreviewArgs) -> Result<(), Error> {
    use crate::preview;
    let (seq, problem) = sequence::load_drawable(&args.file, &Overrides::default())?;
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
    let reason = problem.as_ref().map(|p| p.to_string());
    let (plot, warnings) = preview::path_plot(&seq, reason.as_deref());
    for w in seq.warnings.iter().chain(&warnings) {
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
    problem.map_or(Ok(()), |p| Err(Error::Load(p)))
}

fn check(args: CheckArgs) -> Result<(), Error> {
    let seq = sequence::load(&args.file, &Overrides::default())?;
    print_warnings(&seq);
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
        TimelinePath::Keys(k) if k.keys.len() == 1 => "still camera".to_string(),
        TimelinePath::Keys(k) => format!(
            "{} keyframes, {:?} interpolation",
            k.keys.len(),
            k.interpolation
        )
        .to_lowercase(),
    };
    let s = &seq.settings;
    format!(
        "{file}: ok\n  objects:    {} ({spheres} spheres, {planes} planes)\n  materials:  {}\n  lights:     {} ({})\n  resolution: {}x{}, max_depth {}\n  frames:     {} at {} fps ({:.2} s), {camera}\n{}  output:     {}\n",
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
        timing(t),
        seq.output
    )
}

/// The `timing:` line of a keyframed move: stops, or what constant speed does to key times.
fn timing(t: &Timeline) -> String {
    let TimelinePath::Keys(k) = &t.path else {
        return String::new();
    };
    let inner = 1..k.keys.len().saturating_sub(1);
    let line = match k.speed {
        Speed::Constant => {
            let passed: Vec<String> = inner
                .clone()
                .map(|i| format!("{i} at {:.3} s", k.passes[i]))
                .collect();
            let rate = t.speed_at(k.passes[0]);
            let ignored = match passed.is_empty() {
                true => String::new(),
                false => format!(
                    "; the times of keyframes between the first and last are ignored: passed {}",
                    passed.join(", ")
                ),
            };
            format!("constant speed, {rate:.4} units/s{ignored}")
        }
        Speed::Keys if k.keys.len() < 2 => return String::new(),
        Speed::Keys => {
            let stops: Vec<String> = (0..k.keys.len())
                .filter(|&i| k.keys[i].ease == Ease::Stop)
                .map(|i| i.to_string())
                .collect();
            match stops.is_empty() {
                true => "each keyframe at its time".to_string(),
                false => format!(
                    "each keyframe at its time, stopping at keyframe{} {}",
                    if stops.len() == 1 { "" } else { "s" },
                    stops.join(", ")
                ),
            }
        }
    };
    format!("  timing:     {line}\n")
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

fn bench(args: BenchArgs) -> Result<(), Error> {
    let options = crate::bench::Options {
        runs: args.runs as usize,
        only: args.only,
        quick: args.quick,
    };
    crate::bench::run(&options, &mut |line| println!("{line}")).map_err(Error::Failed)
}
