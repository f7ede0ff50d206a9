//! The subcommands: each turns validated arguments into calls down the pipeline.

use crate::Error;
use crate::cli::{CheckArgs, Cli, Command, RenderArgs};
use crate::output::pattern::Pattern;
use crate::progress::Progress;
use crate::scene::{Light, Shape};
use crate::schedule::{self, Job};
use crate::sequence::{self, Overrides, Sequence};
use crate::timeline::Path as TimelinePath;
use std::sync::Arc;

pub fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Render(args) => render(args),
        Command::Check(args) => check(args),
    }
}

fn render(args: RenderArgs) -> Result<(), Error> {
    let overrides = Overrides {
        size: args.size,
        max_depth: args.max_depth,
        output: args.output.clone(),
        depth: false,
    };
    let seq = sequence::load(&args.file, &overrides)?;
    let count = seq.timeline.frame_count;
    let frames = match &args.frames {
        Some(spec) => spec
            .frames(count)
            .map_err(|e| Error::Usage(format!("--frames: {e}")))?,
        None => (0..count).collect(),
    };
    let pattern = Pattern::new(&seq.output, count).map_err(Error::Usage)?;
    match pattern.extension().as_str() {
        "png" => {}
        other => {
            return Err(Error::Usage(format!(
                "output `{}`: unsupported file type `.{other}` (use .png)",
                seq.output
            )));
        }
    }
    if let Some(dir) = pattern
        .frame_path(0)
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
    {
        std::fs::create_dir_all(dir).map_err(|e| {
            Error::Failed(format!("{}: cannot create directory: {e}", dir.display()))
        })?;
    }
    let threads = match args.threads {
        Some(t) => usize::from(t),
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let mut progress = Progress::new(frames.len() as u64, count, args.quiet);
    let job = Job {
        sequence: Arc::new(seq),
        frames,
        pattern,
        threads,
    };
    let result = schedule::run(job, &mut progress);
    progress.finish();
    result.map_err(Error::Failed)
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
