//! The subcommands: each turns validated arguments into calls down the pipeline.

mod camera;
mod render;

use crate::cli::job::JobError;
use crate::cli::{BenchArgs, CheckArgs, Cli, Command, MeasureArgs, PreviewArgs};
use crate::console::{self, printable};
use crate::output;
use crate::scene::{Light, Shape};
use crate::schedule::RunError;
use crate::sequence::{self, LoadError, Sequence};
use crate::timeline::{Ease, Path as TimelinePath, Speed, Timeline};
use crate::warnings;
use std::path::Path;

/// The whole program behind the command line: `main` maps the error to its exit code.
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

/// Everything that ends a run early, with the exit code it maps to.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The sequence file or a flag is wrong: nothing was rendered (exit 2).
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The command line asks for something impossible (exit 2).
    #[error("{0}")]
    Usage(String),
    /// Rendering or writing failed (exit 1).
    #[error("{0}")]
    Failed(String),
    /// A run stopped short: a frame could not be rendered, encoded or written (exit 1).
    #[error(transparent)]
    Run(#[from] RunError),
    /// `status` found frames that are not up to date (exit 1).
    #[error("{0}")]
    Incomplete(String),
    /// Ctrl-C or SIGTERM: the exit code is 128 + the signal (130 for SIGINT, 143 for SIGTERM).
    #[error("{0}")]
    Interrupted(String, u8),
}

impl Error {
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Load(_) | Error::Usage(_) => 2,
            Error::Failed(_) | Error::Run(_) | Error::Incomplete(_) => 1,
            Error::Interrupted(_, code) => *code,
        }
    }
}

impl From<JobError> for Error {
    fn from(e: JobError) -> Error {
        match e {
            JobError::Load(e) => Error::Load(e),
            JobError::Usage(text) => Error::Usage(text),
        }
    }
}

fn print_warnings(seq: &Sequence) {
    for w in warnings::for_sequence(seq) {
        eprintln!("warning: {w}");
    }
}

/// Writes DIR/NAME_path.png and DIR/NAME_sheet.png, printing their paths; warnings about the
/// camera path go to stderr. A path whose camera cannot be built somewhere is still drawn,
/// with the reason, and then reported as the load error it is (exit 2).
fn preview(args: PreviewArgs) -> Result<(), Error> {
    use crate::tools::preview;
    let (seq, problem) = sequence::load_drawable(&args.file)?;
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    let frames: Vec<u64> = match &args.frames {
        Some(spec) => {
            let set = spec
                .frames(first, last)
                .map_err(|e| Error::Usage(format!("--frames: {e}")))?;
            if set.len() > preview::MAX_TILES {
                return Err(Error::Usage(format!(
                    "--frames: {} frames; a contact sheet holds at most {}",
                    set.len(),
                    preview::MAX_TILES
                )));
            }
            set.iter().collect()
        }
        None => crate::frameset::evenly_spaced(seq.timeline.frame_count, args.tiles)
            .into_iter()
            .map(|n| n + first)
            .collect(),
    };
    let dir = args.out.unwrap_or_else(|| beside_frames(&seq, "preview"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    let reason = problem.as_ref().map(|p| p.to_string());
    let (plot, warnings) = preview::path_plot(&seq, reason.as_deref());
    for w in seq.warnings.iter().chain(&warnings) {
        eprintln!("warning: {}", printable(w));
    }
    let plot_file = dir.join(format!("{}_path.png", seq.name));
    preview::write_png(&plot_file, &plot).map_err(|e| Error::Failed(e.to_string()))?;
    out(&format!("{}\n", shown(&plot_file)))?;
    let (sheet, _) = preview::contact_sheet(&seq, &frames, preview::TILE_WIDTH)
        .map_err(|e| Error::Failed(e.to_string()))?;
    let sheet_file = dir.join(format!("{}_sheet.png", seq.name));
    preview::write_png(&sheet_file, &sheet).map_err(|e| Error::Failed(e.to_string()))?;
    out(&format!("{}\n", shown(&sheet_file)))?;
    problem.map_or(Ok(()), |p| Err(Error::Load(p)))
}

fn check(args: CheckArgs) -> Result<(), Error> {
    let seq = sequence::load(&args.file)?;
    print_warnings(&seq);
    let (cost, warning) = cost(&seq, seq.timeline.frame_count);
    if let Some(w) = warning {
        eprintln!("{w}");
    }
    out(&format!(
        "{}  cost:       {cost}\n",
        summary(&shown(&args.file), &seq)
    ))
}

/// Jobs above this many rays are called enormous: about 9 hours at `RAYS_PER_SECOND`.
pub(crate) const ENORMOUS_RAYS: f64 = 1e12;
/// Rays a second of the 2-core machine measured under Performance in the README.
const RAYS_PER_SECOND: f64 = 3e7;

/// An upper bound on the rays one frame traces: pixels × samples (adaptive: its maximum) ×
/// (1 + lights that cast shadows) × max_depth, since each surface a path visits sends one ray
/// on and at most one shadow ray per light.
pub(crate) fn rays_per_frame(seq: &Sequence) -> f64 {
    let s = &seq.settings;
    let samples = s.adaptive.map_or(s.samples, |a| a.max_samples);
    let shadows = seq
        .scene
        .lights
        .iter()
        .filter(|l| !matches!(l, Light::Ambient { .. }))
        .count();
    f64::from(s.width)
        * f64::from(s.height)
        * f64::from(samples)
        * (1 + shadows) as f64
        * f64::from(s.max_depth)
}

/// `up to 2.76e9 rays a frame, 3.98e11 for 144 frames (…)`, and a warning for an enormous
/// job.
pub(crate) fn cost(seq: &Sequence, frames: u64) -> (String, Option<String>) {
    let frame = rays_per_frame(seq);
    let total = frame * frames as f64;
    let line = format!(
        "up to {frame:.2e} rays a frame, {total:.2e} for {frames} frame{} (pixels × samples × (1 + lights) × max_depth)",
        if frames == 1 { "" } else { "s" }
    );
    let warning = (total > ENORMOUS_RAYS).then(|| {
        format!(
            "warning: this job may trace up to {total:.2e} rays, about {} at {RAYS_PER_SECOND:.0e} rays/s; check the size, render.samples and render.max_depth (Ctrl-C or SIGTERM stops a render within about a second)",
            duration(total / RAYS_PER_SECOND)
        )
    });
    (line, warning)
}

/// `3.2 hours`, `41 years`.
fn duration(seconds: f64) -> String {
    let units = [
        (31_557_600.0, "years"),
        (86_400.0, "days"),
        (3600.0, "hours"),
        (60.0, "minutes"),
    ];
    match units.iter().find(|(unit, _)| seconds >= 2.0 * unit) {
        Some((unit, name)) => format!("{:.0} {name}", seconds / unit),
        None => format!("{seconds:.0} seconds"),
    }
}

/// The one-screen description `rayreel check` prints.
pub(crate) fn summary(file: &str, seq: &Sequence) -> String {
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
        TimelinePath::Orbit(o) => format!(
            "orbit of radius {} ({})",
            sequence::num(o.radius),
            noun(o.turns, "turn")
        ),
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
        "{file}: ok\n  objects:    {} ({}, {})\n  materials:  {}\n  lights:     {} ({})\n  resolution: {}x{}, max_depth {}\n  picture:    {}\n  frames:     {} at {} fps ({} s{}), {camera}\n{}{}  output:     {}\n",
        scene.objects.len(),
        noun(spheres as f64, "sphere"),
        noun(planes as f64, "plane"),
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
        picture(s),
        t.frame_count,
        t.fps_text(),
        sequence::num(t.clock.duration.unwrap_or(t.frame_count as f64 / t.fps)),
        match t.first_frame() {
            0 => String::new(),
            first => format!(", frames {first}-{}", t.last_frame()),
        },
        timing(t),
        film(seq),
        printable(&seq.output)
    )
}

/// The `picture:` line: sampling, encoding, exposure and alpha, what decides how frames look.
fn picture(s: &crate::settings::Settings) -> String {
    let sampling = match s.adaptive {
        Some(a) => format!(
            "{} to {} samples (adaptive, threshold {})",
            s.samples, a.max_samples, a.threshold
        ),
        None => noun(f64::from(s.samples), "sample"),
    };
    let alpha = if s.alpha { ", alpha" } else { "" };
    format!(
        "{sampling}, {}, exposure {}{alpha}",
        s.encoding.name(),
        s.exposure
    )
}

/// `3 spheres`, `1 plane`, `1.5 turns`.
fn noun(n: f64, what: &str) -> String {
    format!(
        "{} {what}{}",
        sequence::num(n),
        if n == 1.0 { "" } else { "s" }
    )
}

/// The `film:` line when frames are more than a pinhole's instant: a shutter, an open lens.
fn film(seq: &Sequence) -> String {
    let widest = match &seq.timeline.path {
        TimelinePath::Orbit(o) => o.aperture,
        TimelinePath::Keys(k) => k.keys.iter().map(|k| k.aperture).fold(0.0, f64::max),
    };
    let mut parts = Vec::new();
    if let Some(s) = seq.settings.shutter {
        parts.push(format!(
            "{}° shutter (open {:.4} s a frame, offset {})",
            sequence::num(s.angle),
            s.angle / 360.0 / seq.timeline.fps,
            sequence::num(s.offset)
        ));
    }
    if widest > 0.0 {
        parts.push(format!("lens aperture up to {}", sequence::num(widest)));
    }
    if parts.is_empty() {
        return String::new();
    }
    format!("  film:       {}\n", parts.join(", "))
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
    let mut seq = sequence::load(&args.file)?;
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    if !(first..=last).contains(&args.frame) {
        return Err(Error::Usage(format!(
            "--frame: frame {} is outside the timeline, which has frames {first}-{last}",
            args.frame
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
                    .max(1.0) as u32,
            )
        }
    };
    (seq.settings.width, seq.settings.height) = (w, h);
    if let Some(e) = args.encoding {
        seq.settings.encoding = e;
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| beside_frames(&seq, "measure"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::Failed(format!("{}: cannot create directory: {e}", dir.display())))?;
    eprintln!(
        "measuring frame {} of {} at {w}x{h}",
        args.frame,
        shown(&args.file)
    );
    let report =
        crate::tools::measure::measure(&seq, args.frame, args.runs as usize, &mut |line| {
            eprintln!("  {line}")
        })?;
    out(&report.table())?;
    for (name, text) in [
        ("measure.csv", report.csv()),
        ("measure.json", report.json()),
        ("measure.svg", report.svg()),
    ] {
        let path = dir.join(name);
        output::atomic::write_atomic(&path, text.as_bytes())
            .map_err(|e| Error::Failed(format!("{}: cannot write: {e}", path.display())))?;
        eprintln!("wrote {}", shown(&path));
    }
    Ok(())
}

fn bench(args: BenchArgs) -> Result<(), Error> {
    let options = crate::tools::bench::Options {
        runs: args.runs as usize,
        only: args.only,
        quick: args.quick,
    };
    // A reader that has gone ends the output, not the benchmark's own error reporting.
    crate::tools::bench::run(&options, &mut |line| {
        let _ = console::print(&format!("{line}\n"));
    })
    .map_err(|e| Error::Failed(e.to_string()))
}

/// A folder `name` in the frames' directory (`frames/orbit/preview`).
fn beside_frames(seq: &Sequence, name: &str) -> std::path::PathBuf {
    crate::plan::directory(Path::new(&seq.output)).join(name)
}

/// A path as the terminal may show it (see `console::printable`).
pub(crate) fn shown(path: &Path) -> String {
    printable(&path.display().to_string()).into_owned()
}

/// Text on stdout; a closed stdout is a normal end (see `console::print`).
pub(crate) fn out(text: &str) -> Result<(), Error> {
    console::print(text).map_err(Error::Failed)
}
