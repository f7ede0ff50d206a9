//! `rayreel bench`: speed on this machine. Every figure is the median of repeated runs with
//! min and max, and comes with the command that reproduces it (`rayreel bench --only NAME`).
//! The scenes are built in: the talk's scene (sequences/talk.yaml), its 24-frame orbit
//! (sequences/bench/talk_orbit.yaml, also timed against POV-Ray when `povray` is installed),
//! and fields of 4 to 100 000 spheres for the acceleration structure.

use crate::frame::Frame;
use crate::output::{Compression, FileFormat, Files, stream::StreamFormat};
use crate::pattern::{Pattern, PatternError};
use crate::progress::Progress;
use crate::schedule::{self, Batch, RunError, Task};
use crate::sequence::{self, LoadError, Sequence};
use crate::shutter::{Exposure, NoCamera};
use crate::tracer::{self, World};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

mod kernels;
mod mesh;
mod motion;
mod texture;

const TALK: &str = include_str!("../../../sequences/talk.yaml");
const TALK_ORBIT: &str = include_str!("../../../sequences/bench/talk_orbit.yaml");
const TALK_POV: &str = include_str!("../../../sequences/bench/talk_orbit.pov");

/// Why a benchmark could not run.
#[derive(Debug, thiserror::Error)]
pub(crate) enum BenchError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error(transparent)]
    Workers(#[from] rayon::ThreadPoolBuildError),
    #[error(transparent)]
    Camera(#[from] NoCamera),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Pattern(#[from] PatternError),
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// A built-in scene no longer has the text a benchmark edits in it.
    #[error("bench: {0}")]
    Stale(&'static str),
    /// A program the benchmark runs (`rayreel render`, `povray`) failed.
    #[error("{0} failed")]
    Failed(&'static str),
}

/// Median, min and max of some seconds.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Spread {
    pub(crate) median: f64,
    pub(crate) min: f64,
    pub(crate) max: f64,
}

fn timing(mut t: Vec<f64>) -> Spread {
    t.sort_by(f64::total_cmp);
    Spread {
        median: t[t.len() / 2],
        min: t[0],
        max: t[t.len() - 1],
    }
}

fn repeat(
    runs: usize,
    mut f: impl FnMut() -> Result<(), BenchError>,
) -> Result<Spread, BenchError> {
    let mut t = Vec::with_capacity(runs);
    for _ in 0..runs {
        let start = Instant::now();
        f()?;
        t.push(start.elapsed().as_secs_f64());
    }
    Ok(timing(t))
}

fn load(text: &str, (width, height): (u32, u32)) -> Result<Sequence, BenchError> {
    let mut seq = sequence::parse(Path::new("bench.yaml"), text)?;
    (seq.settings.width, seq.settings.height) = (width, height);
    Ok(seq)
}

/// A warning when other work already keeps at least half a core busy (the first field of
/// `/proc/loadavg`, the 1-minute load average): every figure is then lower than this machine
/// can do, and thread scaling flatter.
fn busy_warning(loadavg: &str, cores: usize) -> Option<String> {
    let load: f64 = loadavg.split_whitespace().next()?.parse().ok()?;
    (load >= 0.5).then(|| {
        format!(
            "warning: the machine is busy (load average {load:.1} on {cores} cores before starting): figures will be lower and thread scaling flatter than this machine can do; rerun when it is idle"
        )
    })
}

fn pool(threads: usize) -> Result<rayon::ThreadPool, BenchError> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?)
}

/// The cameras of frame 0.
fn first_exposure(seq: &Sequence) -> Result<Exposure, BenchError> {
    Ok(Exposure::of_frame(&seq.timeline, seq.settings.shutter, 0)?)
}

/// Renders frame 0 `runs` times on `threads` threads; returns the timing and one frame.
fn render_only(
    world: &World,
    seq: &Sequence,
    threads: usize,
    runs: usize,
) -> Result<(Spread, Frame), BenchError> {
    let exposure = first_exposure(seq)?;
    let pool = pool(threads)?;
    let mut frame = None;
    let t = pool.install(|| {
        repeat(runs, || {
            frame = Some(tracer::render(world, &exposure, &seq.settings, 0));
            Ok(())
        })
    })?;
    Ok((t, frame.expect("ran")))
}

/// Renders frames 0..frames one after the other on `threads` threads, keeping nothing.
fn render_frames(
    world: &World,
    seq: &Sequence,
    frames: u64,
    threads: usize,
) -> Result<f64, BenchError> {
    let pool = pool(threads)?;
    let start = Instant::now();
    for n in 0..frames {
        pool.install(|| schedule::render_with(world, seq, n, &seq.settings))?;
    }
    Ok(start.elapsed().as_secs_f64())
}

/// Runs the real scheduler over `frames` frames, to PNG files in `dir` or to a raw stream.
fn sequence_run(
    seq: &Sequence,
    frames: u64,
    threads: usize,
    png_in: Option<&Path>,
) -> Result<f64, BenchError> {
    let files = match png_in {
        Some(dir) => Some(Files {
            pattern: Pattern::new(&dir.join("f_####.png").to_string_lossy(), frames)?,
            format: FileFormat::Png {
                sixteen_bit: false,
                compression: Compression::Fast,
            },
        }),
        None => None,
    };
    let batch = Batch {
        sequence: Arc::new(seq.clone()),
        tasks: (0..frames)
            .map(|frame| Task {
                frame,
                write_file: png_in.is_some(),
            })
            .collect(),
        files,
        stream: png_in.is_none().then_some((StreamFormat::Raw, false)),
        stream_out: Some(Box::new(std::io::sink())),
        threads,
        claims: None,
    };
    let start = Instant::now();
    schedule::run(batch, &mut Progress::new(frames, frames, true))?;
    Ok(start.elapsed().as_secs_f64())
}

/// A field of `n` spheres on a plane, under one light, seen from above at an angle.
pub(crate) fn field(n: usize) -> String {
    let side = (n as f64).sqrt().ceil() as usize;
    let spacing = 20.0 / side as f64;
    let mut s = String::from(
        "render: { width: 640, height: 360, max_depth: 2, samples: 1 }\ncamera: { position: [0, 8, 14], look_at: [0, 0, 0], fov: 70 }\nmaterials:\n  ball: { ambient: [0.1, 0, 0], diffuse: [0.7, 0.2, 0.1], specular: [1, 1, 1], shininess: 100, reflection: 0.3 }\n  floor: { ambient: [0.1, 0.1, 0.1], diffuse: [0.6, 0.6, 0.6], reflection: 0.2 }\nlights:\n  - point: { position: [5, 10, 8], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }\nobjects:\n  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: floor }\n",
    );
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..n {
        let (gx, gz) = ((i % side) as f64, (i / side) as f64);
        let r = spacing * (0.15 + 0.25 * rnd());
        let x = -10.0 + spacing * (gx + 0.5) + (rnd() - 0.5) * 0.3 * spacing;
        let z = -10.0 + spacing * (gz + 0.5) + (rnd() - 0.5) * 0.3 * spacing;
        let _ = writeln!(
            s,
            "  - sphere: {{ center: [{x:.5}, {r:.5}, {z:.5}], radius: {r:.5}, material: ball }}"
        );
    }
    s
}

pub(crate) struct Options {
    pub(crate) runs: usize,
    pub(crate) only: Option<String>,
    /// Smaller sizes and fields, for tests of the command itself.
    pub(crate) quick: bool,
}

/// Runs the benchmarks, printing lines as they finish.
pub fn run(o: &Options, out: &mut dyn FnMut(&str)) -> Result<(), BenchError> {
    let want = |name: &str| o.only.as_deref().is_none_or(|w| w == name);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let size = if o.quick { (320, 180) } else { (1920, 1080) };
    header(o, cores, out);
    let talk = load(TALK, size)?;
    let world = World::new(talk.scene.clone());
    let cmd = |name: &str| {
        format!(
            "rayreel bench --only {name}{}",
            if o.quick { " --quick" } else { "" }
        )
    };
    if want("kernels") {
        kernels::kernels(o, out, &cmd("kernels"))?;
    }
    if want("mesh") {
        mesh::meshes(o, out, &cmd("mesh"))?;
    }
    if want("motion") {
        motion::motion(o, out, &cmd("motion"))?;
    }
    if want("texture") {
        texture::textures(o, out, &cmd("texture"))?;
    }
    if want("render") || want("threads") {
        let threads = want("threads").then(|| cmd("threads"));
        render_figures(o, (&talk, &world), out, &cmd("render"), threads.as_deref())?;
    }
    if want("reflections") {
        reflections(o, (&talk, &world), out, &cmd("reflections"))?;
    }
    if want("glass") {
        glass(o, size, &talk, &world, out, &cmd("glass"))?;
    }
    if want("sequence") {
        sequence_figures(o, size, out, &cmd("sequence"))?;
    }
    if want("scaling") {
        scaling(o, out, &cmd("scaling"))?;
    }
    if want("povray") {
        povray(o, out, &cmd("povray"))?;
    }
    Ok(())
}

/// The machine, the date, how figures are made, and a warning when the machine is busy.
fn header(o: &Options, cores: usize, out: &mut dyn FnMut(&str)) {
    out(&format!(
        "rayreel bench: {} ({cores} threads), {}",
        cpu_model(),
        today()
    ));
    out(&format!(
        "each figure: median (min-max) of {} runs; reproduce with the command after it",
        o.runs
    ));
    let loadavg = std::fs::read_to_string("/proc/loadavg").ok();
    if let Some(w) = loadavg.as_deref().and_then(|l| busy_warning(l, cores)) {
        out(&w);
    }
}

/// The talk's render speed on every core, and (`threads` given) on one.
fn render_figures(
    o: &Options,
    (talk, world): (&Sequence, &World),
    out: &mut dyn FnMut(&str),
    cmd: &str,
    threads: Option<&str>,
) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (w, h) = (talk.settings.width, talk.settings.height);
    let (t2, frame) = render_only(world, talk, cores, o.runs)?;
    let rays = frame.rays as f64;
    out(&format!(
        "talk {w}x{h} 1 spp depth 3, render only, {cores} threads: {:.1} frames/s ({:.1}-{:.1}), {:.1} M rays/s, {:.2} rays/pixel   [{cmd}]",
        1.0 / t2.median,
        1.0 / t2.max,
        1.0 / t2.min,
        rays / t2.median / 1e6,
        rays / (w * h) as f64,
    ));
    let Some(cmd) = threads.filter(|_| cores > 1) else {
        return Ok(());
    };
    let (t1, _) = render_only(world, talk, 1, o.runs)?;
    let speedup = t1.median / t2.median;
    let busy = match speedup < 1.0 {
        true => " (below 1x: other work had the cores; this says nothing of scaling)",
        false => "",
    };
    out(&format!(
        "  1 thread: {:.1} frames/s; {cores} threads over 1: {speedup:.2}x{busy}   [{cmd}]",
        1.0 / t1.median,
    ));
    Ok(())
}

/// What reflections cost: the talk with every reflection 0 against the talk.
fn reflections(
    o: &Options,
    (talk, world): (&Sequence, &World),
    out: &mut dyn FnMut(&str),
    cmd: &str,
) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let size = (talk.settings.width, talk.settings.height);
    let flat = load(&TALK.replace("reflection: 0.5", "reflection: 0"), size)?;
    let (tf, f) = render_only(&World::new(flat.scene.clone()), &flat, cores, o.runs)?;
    let (tr, r) = render_only(world, talk, cores, o.runs)?;
    out(&format!(
        "talk without reflections: {:.1} frames/s ({} rays) vs with: {:.1} frames/s ({} rays): {:.2}x cheaper   [{cmd}]",
        1.0 / tf.median,
        f.rays,
        1.0 / tr.median,
        r.rays,
        tr.median / tf.median,
    ));
    Ok(())
}

/// The orbit's frames rendered only, to a raw stream, and to PNG files.
fn sequence_figures(
    o: &Options,
    (w, h): (u32, u32),
    out: &mut dyn FnMut(&str),
    cmd: &str,
) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let frames = if o.quick { 4 } else { 12 };
    let orbit = load(TALK_ORBIT, (w, h))?;
    let dir = std::env::temp_dir().join(format!("rayreel-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let raw = timing(
        (0..o.runs)
            .map(|_| sequence_run(&orbit, frames, cores, None))
            .collect::<Result<_, _>>()?,
    );
    let png = timing(
        (0..o.runs)
            .map(|_| {
                let _ = std::fs::remove_dir_all(&dir);
                std::fs::create_dir_all(&dir)?;
                sequence_run(&orbit, frames, cores, Some(&dir))
            })
            .collect::<Result<_, _>>()?,
    );
    let _ = std::fs::remove_dir_all(&dir);
    let orbit_world = World::new(orbit.scene.clone());
    let render = timing(
        (0..o.runs)
            .map(|_| render_frames(&orbit_world, &orbit, frames, cores))
            .collect::<Result<_, _>>()?,
    );
    let f = frames as f64;
    out(&format!(
        "talk orbit {frames} frames {w}x{h}: render only {:.1} frames/s, raw stream {:.1} frames/s, PNG files (fast deflate, written and synced) {:.1} frames/s   [{cmd}]",
        f / render.median,
        f / raw.median,
        f / png.median,
    ));
    Ok(())
}

/// What glass costs: the talk with its red sphere turned to Fresnel glass, against the talk.
fn glass(
    o: &Options,
    (w, h): (u32, u32),
    talk: &Sequence,
    world: &World,
    out: &mut dyn FnMut(&str),
    cmd: &str,
) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (tt, t) = render_only(world, talk, cores, o.runs)?;
    for depth in [3, 8] {
        let text = TALK
            .replace(
                "red:    { ambient: [0.1, 0, 0],     diffuse: [0.7, 0, 0],     specular: [1, 1, 1], shininess: 100, reflection: 0.5 }",
                "red:    { diffuse: [0, 0, 0], specular: [1, 1, 1], shininess: 400, transmission: [0.95, 0.97, 1], fresnel: true }",
            )
            .replace("max_depth: 3", &format!("max_depth: {depth}"));
        if !text.contains("transmission") {
            return Err(BenchError::Stale(
                "talk.yaml's red material changed; update the glass bench",
            ));
        }
        let glass = load(&text, (w, h))?;
        let (tg, g) = render_only(&World::new(glass.scene.clone()), &glass, cores, o.runs)?;
        out(&format!(
            "talk with a glass red sphere, depth {depth}: {:.1} frames/s ({} rays) vs the talk: {:.1} frames/s ({} rays): {:.2}x the time   [{cmd}]",
            1.0 / tg.median,
            g.rays,
            1.0 / tt.median,
            t.rays,
            tg.median / tt.median,
        ));
    }
    Ok(())
}

/// Per-ray cost as the sphere count grows, with the hierarchy's build time. Every round times
/// every count, so a busy moment slows them alike; each ratio is the median over rounds of
/// that round's ratio to 4 spheres.
fn scaling(o: &Options, out: &mut dyn FnMut(&str), cmd: &str) -> Result<(), BenchError> {
    let counts: &[usize] = if o.quick {
        &[4, 100, 1000]
    } else {
        &[4, 100, 1000, 10_000, 100_000]
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    out(&format!(
        "spheres   bvh build   frame 640x360   ns/ray   vs 4 spheres   [{cmd}]"
    ));
    let mut scenes = Vec::new();
    for &n in counts {
        let seq = sequence::parse(Path::new("field.yaml"), &field(n))?;
        let start = Instant::now();
        let world = World::new(seq.scene.clone());
        scenes.push((seq, world, start.elapsed().as_secs_f64()));
    }
    let mut per_ray = vec![Vec::new(); counts.len()];
    let mut frames = Vec::new();
    for _ in 0..o.runs {
        for (i, (seq, world, _)) in scenes.iter().enumerate() {
            let (t, frame) = render_only(world, seq, cores, 1)?;
            per_ray[i].push(t.median * cores as f64 / frame.rays as f64 * 1e9);
            frames.push(frame);
        }
    }
    for (i, (&n, (_, world, build))) in counts.iter().zip(&scenes).enumerate() {
        let ratio = timing((0..o.runs).map(|r| per_ray[i][r] / per_ray[0][r]).collect());
        let ns = timing(per_ray[i].clone());
        out(&format!(
            "{n:>7}   {:>7.1} ms   {:>9.1} ms   {:>6.0}   {:>6.2}x{}",
            build * 1e3,
            ns.median * frames[i].rays as f64 / cores as f64 / 1e6,
            ns.median,
            ratio.median,
            if world.geometry.has_bvh() {
                ""
            } else {
                "   (no hierarchy: too few spheres)"
            }
        ));
    }
    Ok(())
}

/// The 24-frame 640x360 orbit end to end (the binary, to PNG files) against POV-Ray 3.7.
fn povray(o: &Options, out: &mut dyn FnMut(&str), cmd: &str) -> Result<(), BenchError> {
    let dir = std::env::temp_dir().join(format!("rayreel-pov-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    let (seq_file, pov_file) = (dir.join("talk_orbit.yaml"), dir.join("talk_orbit.pov"));
    std::fs::write(&seq_file, TALK_ORBIT)?;
    std::fs::write(&pov_file, TALK_POV)?;
    let exe = std::env::current_exe()?;
    let ours = repeat(o.runs, || {
        let _ = std::fs::remove_dir_all(dir.join("rr"));
        let status = std::process::Command::new(&exe)
            .args(["render", &seq_file.to_string_lossy(), "-q", "-o"])
            .arg(dir.join("rr/frame_##.png"))
            .status()?;
        status
            .success()
            .then_some(())
            .ok_or(BenchError::Failed("rayreel render"))
    })?;
    let mut line = format!(
        "talk orbit 24 frames 640x360 to PNG, end to end: rayreel {:.2} s ({:.2}-{:.2})",
        ours.median, ours.min, ours.max
    );
    let pov = std::process::Command::new("povray")
        .arg("--version")
        .output();
    if pov.is_ok() {
        let theirs = repeat(o.runs.min(3), || {
            std::fs::create_dir_all(dir.join("pov"))?;
            let status = std::process::Command::new("povray")
                .arg(format!("+I{}", pov_file.display()))
                .args(["+W640", "+H360", "+KFI0", "+KFF23", "-A", "-D", "-V", "-GA"])
                .arg(format!(
                    "+WT{}",
                    std::thread::available_parallelism().map_or(1, |n| n.get())
                ))
                .arg(format!("+O{}", dir.join("pov/frame.png").display()))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()?;
            status
                .success()
                .then_some(())
                .ok_or(BenchError::Failed("povray"))
        })?;
        let _ = write!(
            line,
            "; POV-Ray 3.7 {:.2} s ({:.2}-{:.2}): rayreel is {:.1}x faster",
            theirs.median,
            theirs.min,
            theirs.max,
            theirs.median / ours.median
        );
    } else {
        line.push_str("; povray not installed (apt-get install povray) so no comparison");
    }
    out(&format!("{line}   [{cmd}]"));
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

fn today() -> String {
    std::process::Command::new("date")
        .arg("+%Y-%m-%d")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_machine_is_named() {
        assert_eq!(busy_warning("0.12 0.30 0.40 1/200 999", 2), None);
        let w = busy_warning("1.93 1.20 0.40 3/200 999", 2).unwrap();
        assert!(w.contains("busy (load average 1.9 on 2 cores"), "{w}");
        assert_eq!(busy_warning("garbage", 2), None);
    }
}
