//! `rayreel check`: a sequence's one-screen summary and what a job of it may cost.

use super::screen::{Screen, grouped, runs};
use super::{Error, estimate, out, shown};
use crate::cli::CheckArgs;
use crate::console::printable;
use crate::frameset::FrameSet;
use crate::output::{Compression, ExrPrecision, FileFormat};
use crate::scene::{Image, Light, Scene, Shape, Sky, Texture};
use crate::sequence::{self, Sequence};
use crate::settings::Settings;
use crate::timeline::{Ease, Path as TimelinePath, Speed, Timeline};

pub(super) fn check(args: CheckArgs) -> Result<(), Error> {
    let seq = sequence::load_with(&args.file, &super::assets(&args.assets)?)?;
    let screen = Screen { full: args.full };
    let warnings: Vec<String> = crate::warnings::for_sequence(&seq)
        .into_iter()
        .map(|w| format!("warning: {w}"))
        .collect();
    // Line by line through the crate's `eprintln!`, which survives a failing stderr.
    for line in screen
        .lines(&warnings, warnings.len(), "", "warnings")
        .lines()
    {
        eprintln!("{line}");
    }
    let t = &seq.timeline;
    let frames = crate::frameset::FrameSet::range(t.first_frame(), t.last_frame(), 1);
    let format = crate::sequence::output_pattern(&seq.output, t.last_frame())
        .ok()
        .and_then(|p| {
            FileFormat::for_extension(&p.extension(), false, Compression::Fast, ExrPrecision::Half)
                .ok()
        });
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cost = cost(
        &seq,
        &frames,
        cores,
        format.as_ref(),
        &format!("\n{INDENT}"),
    )?;
    for w in cost
        .warning
        .iter()
        .cloned()
        .chain(super::grain::warning(&seq))
    {
        for line in super::screen::wrap(&w, "  ").lines() {
            eprintln!("{line}");
        }
    }
    let built = cost.hierarchies.as_deref();
    let summary = summary(&shown(&args.file), &seq, screen, built).map_err(Error::Failed)?;
    let text = format!("{summary}  cost:       {}\n", cost.line);
    out(&super::screen::wrap(&text, INDENT))
}

/// What `cost` found: the line, a warning for a long job, and the meshes' hierarchies as
/// its probe built them (`None` when it did not probe).
pub(crate) struct Cost {
    pub(crate) line: String,
    pub(crate) warning: Option<String>,
    pub(crate) hierarchies: Option<Vec<super::meshes::Built>>,
}

/// Where a summary's continuation lines start (under the values after `  objects:    `).
const INDENT: &str = "              ";

/// Jobs measured to take longer than this are worth a warning before they start.
const LONG_JOB_SECONDS: f64 = 24.0 * 3600.0;

/// An upper bound on the rays one frame traces: pixels × samples (adaptive: its maximum) ×
/// (1 + shadow rays per surface) × surfaces per sample, since each surface a path visits
/// sends at most one shadow ray per point, spot or directional light and `samples` per area
/// light. A sample visits at most max_depth surfaces on one path; where a material branches
/// (glass reflects and transmits, Fresnel weighs by angle) its paths become a tree of up to
/// 2^max_depth − 1 rays, cut at `glass::tree_budget`.
pub(crate) fn rays_per_frame(seq: &Sequence) -> f64 {
    let s = &seq.settings;
    let samples = s.adaptive.map_or(s.samples, |a| a.max_samples);
    let shadows: u64 = seq
        .scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Ambient { .. } => 0,
            _ => l.area_samples().map_or(1, u64::from),
        })
        .sum();
    f64::from(s.width)
        * f64::from(s.height)
        * f64::from(samples)
        * (1 + shadows) as f64
        * surfaces_per_sample(seq)
}

/// The most surfaces one eye sample visits: max_depth, or for a scene whose paths branch the
/// whole tree of that depth as far as the tracer's budget lets it grow.
fn surfaces_per_sample(seq: &Sequence) -> f64 {
    let depth = seq.settings.max_depth;
    if !seq.scene.materials.iter().any(|m| m.branches()) {
        return f64::from(depth);
    }
    let tree = 2f64.powi(depth.min(64) as i32) - 1.0;
    tree.min(f64::from(crate::tracer::glass::tree_budget(depth)))
}

/// `about 9.2 min for 240 frames (measured: …); at most 3.98e11 rays (…)`, or `nothing to
/// render`, and a warning for a job of more than a day: what `frames` of `seq` take on
/// `threads` threads written as `format`, from a short probe (`estimate`), beside the ray
/// count's upper bound, after `join` (`check` starts it on a line of its own).
pub(crate) fn cost(
    seq: &Sequence,
    frames: &FrameSet,
    threads: usize,
    format: Option<&FileFormat>,
    join: &str,
) -> Result<Cost, Error> {
    let n = frames.len();
    if n == 0 {
        return Ok(Cost {
            line: "nothing to render".into(),
            warning: None,
            hierarchies: None,
        });
    }
    // The probe builds the meshes' hierarchies and triangle copies, as a run would: refused
    // here with the figures when they cannot fit, where the allocation once aborted (exit 134).
    crate::schedule::memory::admit_hierarchies(seq, threads).map_err(Error::Failed)?;
    let rays = rays_per_frame(seq) * n as f64;
    let bound = format!(
        "at most {rays:.2e} rays (an upper bound: pixels × samples × (1 + {}) × {})",
        match seq.scene.lights.iter().any(|l| l.area_samples().is_some()) {
            true => "shadow rays: 1 a light, `samples` an area light",
            false => "lights",
        },
        match seq.scene.materials.iter().any(|m| m.branches()) {
            true => "the surfaces of a glass or Fresnel tree: up to 2^max_depth − 1",
            false => "max_depth",
        }
    );
    let frames_text = super::render::plural(n, "frame");
    let probed = estimate::estimate(seq, frames, threads, format)
        .map_err(|e| Error::Failed(e.to_string()))?;
    let Some(e) = probed else {
        return Ok(Cost {
            line: format!("{frames_text}: {bound}"),
            warning: None,
            hierarchies: None,
        });
    };
    let about = match e.lower_bound {
        true => format!("at least {}", estimate::duration(e.seconds)),
        false => format!("about {}", estimate::duration(e.seconds)),
    };
    let line = format!("{about} for {frames_text} ({});{join}{bound}", e.basis);
    let warning = (e.seconds > LONG_JOB_SECONDS).then(|| {
        format!(
            "warning: this job may take {about} on this machine ({}); check the size, render.samples and render.max_depth (Ctrl-C or SIGTERM stops a render within about a second)",
            e.basis
        )
    });
    Ok(Cost {
        line,
        warning,
        hierarchies: Some(e.hierarchies),
    })
}

/// The one-screen description `rayreel check` prints (everything with `--full`), with the
/// meshes' hierarchies as `built` (measured by the cost probe); an error when a hierarchy
/// built here to be measured does not fit in memory.
pub(crate) fn summary(
    file: &str,
    seq: &Sequence,
    screen: Screen,
    built: Option<&[super::meshes::Built]>,
) -> Result<String, String> {
    let (scene, s) = (&seq.scene, &seq.settings);
    Ok(format!(
        "{file}: ok\n  objects:    {}\n{}  materials:  {}\n{}{}  lights:     {}\n{}  resolution: {}x{}, max_depth {}\n  picture:    {}\n  frames:     {}\n{}{}{}  output:     {}\n",
        objects(scene),
        super::meshes::summary(scene, screen, built)?,
        scene.materials.len(),
        textures(scene, screen),
        sky(scene),
        lights(scene),
        penumbra_notes(scene, s),
        s.width,
        s.height,
        s.max_depth,
        picture(s),
        frames(&seq.timeline),
        moving(&seq.timeline),
        timing(&seq.timeline),
        film(seq),
        printable(&seq.output)
    ))
}

/// The `objects:` line: `4 (3 spheres, 1 plane)`, with `, 2 meshes` when there are any.
fn objects(scene: &Scene) -> String {
    let spheres = scene
        .objects
        .iter()
        .filter(|o| matches!(o.shape, Shape::Sphere { .. }))
        .count();
    let placed = scene
        .objects
        .iter()
        .filter(|o| matches!(o.shape, Shape::Mesh { .. }))
        .count();
    let planes = scene.objects.len() - spheres - placed;
    format!(
        "{} ({}, {}{})",
        scene.objects.len(),
        noun(spheres as f64, "sphere"),
        noun(planes as f64, "plane"),
        match placed {
            0 => String::new(),
            1 => ", 1 mesh".to_string(),
            n => format!(", {n} meshes"),
        }
    )
}

/// The `textures:` lines, nothing without textures: each image once (its size, levels,
/// memory and load time; the first few), and the number of checker maps.
fn textures(scene: &Scene, screen: Screen) -> String {
    let maps = scene
        .materials
        .iter()
        .flat_map(|m| [&m.diffuse_map, &m.ambient_map])
        .flatten();
    let (mut images, mut checkers) = (Vec::new(), 0);
    for t in maps {
        match t {
            Texture::Checker { .. } => checkers += 1,
            Texture::Image { image, .. } => {
                if !images
                    .iter()
                    .any(|i: &&std::sync::Arc<Image>| std::sync::Arc::ptr_eq(i, image))
                {
                    images.push(image);
                }
            }
        }
    }
    // Past the first few, the largest first, and the others summed up.
    let held = |i: &Image| i.levels.iter().map(|l| l.texels.len()).sum::<usize>() * 12;
    if !screen.full && images.len() > super::screen::SHOWN {
        images.sort_by_key(|i| std::cmp::Reverse(held(i)));
    }
    let lines: Vec<String> = images
        .iter()
        .take(screen.keep(images.len()))
        .map(|i| format!("  texture:    {}", image_line(i, "")))
        .collect();
    let counted = format!(
        "texture images, {} in all: {:.1} MiB, read in {:.3} s",
        images.len(),
        images.iter().map(|i| held(i)).sum::<usize>() as f64 / (1u64 << 20) as f64,
        images.iter().map(|i| i.load_seconds).sum::<f64>()
    );
    let mut out = screen.lines(&lines, images.len(), "              ", &counted);
    if checkers > 0 {
        out += &format!(
            "  texture:    {} (box-filtered over each ray's footprint)\n",
            noun(checkers as f64, "checker map")
        );
    }
    out
}

/// The `sky:` line, nothing with a flat background: the image (size, levels, memory, load
/// time, turn, intensity) or the gradient's colours.
fn sky(scene: &Scene) -> String {
    let line = match &scene.sky {
        None => return String::new(),
        Some(Sky::Gradient {
            zenith,
            horizon,
            ground,
        }) => format!(
            "gradient, zenith {}, horizon {}, ground {}",
            colour(*zenith),
            colour(*horizon),
            colour(*ground)
        ),
        Some(Sky::Image {
            image,
            rotate,
            intensity,
        }) => format!(
            "{}; rotate {}°, intensity {}",
            image_line(image, " (equirectangular)"),
            sequence::num(*rotate),
            sequence::num(*intensity)
        ),
    };
    format!("  sky:        {line}\n")
}

/// `textures/sky.png 1024x512{what}, 11 mip levels, 5.3 MiB, read in 0.012 s`.
fn image_line(i: &Image, what: &str) -> String {
    let l0 = &i.levels[0];
    let texels: usize = i.levels.iter().map(|l| l.texels.len()).sum();
    format!(
        "{} {}x{}{what}, {} mip levels, {:.1} MiB, read in {:.3} s",
        super::screen::short_name(&i.file.to_string_lossy()),
        l0.width,
        l0.height,
        i.levels.len(),
        (texels * 12) as f64 / (1u64 << 20) as f64,
        i.load_seconds
    )
}

/// A colour as the file writes it: `[0.2, 0.35, 0.7]`.
fn colour(v: glam::DVec3) -> String {
    format!(
        "[{}, {}, {}]",
        sequence::num(v.x),
        sequence::num(v.y),
        sequence::num(v.z)
    )
}

/// The `lights:` line: `2 (1 point, 1 ambient)`, or `0 (none)`; area lights with their
/// points per eye sample, grouped: `1 sphere (16 samples)`, `1000 rect (16 samples)`,
/// `3 rect (2 with 16, 1 with 64 samples)`.
fn lights(scene: &Scene) -> String {
    let mut kinds = [0usize; 6];
    let mut samples: [Vec<u32>; 6] = Default::default();
    for l in &scene.lights {
        let kind = kind_index(l);
        kinds[kind] += 1;
        if let Some(n) = l.area_samples() {
            samples[kind].push(n);
        }
    }
    let light_list: Vec<String> = ["point", "directional", "spot", "ambient", "sphere", "rect"]
        .iter()
        .zip(kinds)
        .zip(samples)
        .filter(|((_, n), _)| *n > 0)
        .map(|((k, n), s)| match grouped(s).as_slice() {
            [] => format!("{n} {k}"),
            [(m, _)] => format!("{n} {k} ({m} samples)"),
            groups => {
                let each: Vec<String> = groups
                    .iter()
                    .take(super::screen::SHOWN)
                    .map(|(m, c)| format!("{c} with {m}"))
                    .collect();
                let more = match groups.len() > super::screen::SHOWN {
                    true => format!(
                        " and {} other counts of",
                        groups.len() - super::screen::SHOWN
                    ),
                    false => String::new(),
                };
                format!("{n} {k} ({}{more} samples)", list(&each))
            }
        })
        .collect();
    let list = match light_list.is_empty() {
        true => "none".to_string(),
        false => light_list.join(", "),
    };
    format!("{} ({list})", scene.lights.len())
}

/// The place of a light's kind in the `lights:` line.
fn kind_index(l: &Light) -> usize {
    match l {
        Light::Point { .. } => 0,
        Light::Directional { .. } => 1,
        Light::Spot { .. } => 2,
        Light::Ambient { .. } => 3,
        Light::Sphere { .. } => 4,
        Light::Rect { .. } => 5,
    }
}

/// `16`, `16 and 64`, `4, 16 and 64`.
fn list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// Light points per pixel below which an area light's penumbra shows noise: 64 points give
/// a visible fraction to about 1/64 in the worst case, a couple of 8-bit levels in sRGB.
pub(crate) const QUIET_PENUMBRA: u64 = 64;

/// A note under `lights:` for each kind of area light (sphere, rect) whose points per pixel,
/// `samples` × the pixel samples every pixel gets (`render.samples`; adaptive passes add more
/// only where they see noise), are below `QUIET_PENUMBRA`: one note for all the lights of
/// that kind (`lights[0-999] (sphere)`), with their count of samples when they share one,
/// else the range of their points.
fn penumbra_notes(scene: &Scene, s: &Settings) -> String {
    let mut out = String::new();
    for (kind, name) in [(4, "sphere"), (5, "rect")] {
        let (mut noisy, mut samples) = (Vec::new(), Vec::new());
        for (i, l) in scene.lights.iter().enumerate() {
            let Some(m) = l.area_samples().filter(|_| kind_index(l) == kind) else {
                continue;
            };
            if u64::from(m) * u64::from(s.samples) < QUIET_PENUMBRA {
                noisy.push(i);
                samples.push(m);
            }
        }
        if let (Some(&least), Some(&most)) = (samples.iter().min(), samples.iter().max()) {
            out += &penumbra_note(&noisy, name, (least, most), s.samples);
        }
    }
    out
}

/// The note on the `lights` of kind `name` whose samples run from `least` to `most`, at
/// `pixel` samples a pixel.
fn penumbra_note(lights: &[usize], name: &str, (least, most): (u32, u32), pixel: u32) -> String {
    let per_pixel = |m: u32| u64::from(m) * u64::from(pixel);
    let pixel_samples = noun(f64::from(pixel), "pixel sample");
    let (its, raise) = match lights.len() {
        1 => ("its", "its samples"),
        _ => ("their", "their samples"),
    };
    let points = match least == most {
        true => format!(
            "{least} samples × {pixel_samples} = {} points on the light per pixel",
            per_pixel(least)
        ),
        false => format!(
            "{} to {} points on the light per pixel ({raise} × {pixel_samples})",
            per_pixel(least),
            per_pixel(most)
        ),
    };
    format!(
        "              note: lights[{}] ({name}): {points}, under {QUIET_PENUMBRA}: {its} soft shadows will be noisy; raise {raise} or render.samples\n",
        runs(lights),
    )
}

/// The `frames:` line: `144 at 24 fps (6 s), orbit of radius 3 (1 turn)`.
fn frames(t: &Timeline) -> String {
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
    format!(
        "{} at {} fps ({} s{}), {camera}",
        t.frame_count,
        t.fps_text(),
        t.running_time_text(),
        match t.first_frame() {
            0 => String::new(),
            first => format!(", frames {first}-{}", t.last_frame()),
        },
    )
}

/// The `moving:` line when objects or lights have keys: each (up to four) with the fields its
/// keys set and the frames between its first key and its last, e.g. `objects[1] (rotate)
/// frames 0-96`.
fn moving(t: &Timeline) -> String {
    const SHOWN: usize = 4;
    if t.motion.is_empty() {
        return String::new();
    }
    let frame_at = |time: f64, up: bool| {
        let at = time * t.fps;
        let i = if up {
            (at - 1e-6).ceil()
        } else {
            (at + 1e-6).floor()
        };
        t.first_frame() + (i.max(0.0) as u64).min(t.frame_count - 1)
    };
    let things: Vec<String> = t
        .motion
        .iter()
        .take(SHOWN)
        .map(|rig| {
            let name = rig.thing;
            let fields: Vec<&str> = rig.fields().map(|f| f.name()).collect();
            let (first, last) = (rig.times[0], rig.times[rig.times.len() - 1]);
            format!(
                "{name} ({}) frames {}-{}",
                fields.join(", "),
                frame_at(first, true),
                frame_at(last, false)
            )
        })
        .collect();
    let more = match t.motion.len().saturating_sub(SHOWN) {
        0 => String::new(),
        n => format!(", and {n} more"),
    };
    format!("  moving:     {}{more}\n", things.join("; "))
}

/// The `picture:` line: sampling, encoding, exposure, alpha and compositing passes, what
/// decides how frames look.
pub(super) fn picture(s: &Settings) -> String {
    let sampling = match s.adaptive {
        Some(a) => format!(
            "{} to {} samples (adaptive, threshold {})",
            s.samples, a.max_samples, a.threshold
        ),
        None => noun(f64::from(s.samples), "sample"),
    };
    let alpha = if s.alpha { ", alpha" } else { "" };
    let passes: Vec<&str> = s.aov.iter().map(|a| a.name()).collect();
    let passes = match passes.is_empty() {
        true => String::new(),
        false => format!(", passes {}", passes.join(",")),
    };
    format!(
        "{sampling}, {}, exposure {}{alpha}{passes}",
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
    let widest = seq.timeline.widest_aperture();
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
                .take(super::screen::SHOWN)
                .map(|i| format!("{i} at {:.3} s", k.passes[i]))
                .chain(
                    (inner.len() > super::screen::SHOWN)
                        .then(|| format!("and {} more", inner.len() - super::screen::SHOWN)),
                )
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
            let stops: Vec<usize> = (0..k.keys.len())
                .filter(|&i| k.keys[i].ease == Ease::Stop)
                .collect();
            match stops.is_empty() {
                true => "each keyframe at its time".to_string(),
                false => format!(
                    "each keyframe at its time, stopping at keyframe{} {}",
                    if stops.len() == 1 { "" } else { "s" },
                    runs(&stops)
                ),
            }
        }
    };
    format!("  timing:     {line}\n")
}
