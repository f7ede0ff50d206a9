//! `rayreel bench --only kernels`: the lane widths against each other on the talk.

use super::{Options, TALK, Timing, first_exposure, load, pool, timing};
use crate::tracer::{self, Kernel, World};
use std::time::Instant;

/// Every lane width this CPU has on the same frames, interleaved round by round so a busy
/// machine slows them alike; each ratio is the median of the rounds' ratios to the scalar
/// kernel. Also checks that every width wrote the same frame.
pub(super) fn kernels(o: &Options, out: &mut dyn FnMut(&str), cmd: &str) -> Result<(), String> {
    let kernels: Vec<Kernel> = Kernel::ALL.into_iter().filter(|k| k.supported()).collect();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let big = if o.quick { (320, 180) } else { (1920, 1080) };
    let small = if o.quick { (160, 90) } else { (640, 360) };
    let cases = [
        ("1 spp", big, "samples: 1"),
        ("16 spp", small, "samples: 16"),
        ("final (adaptive 4-64)", small, "quality: final"),
    ];
    out(&format!(
        "talk, render only, {cores} threads, kernels {} interleaved   [{cmd}]",
        kernels
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let pool = pool(cores)?;
    if !TALK.contains("  samples: 1\n") {
        return Err(
            "bench: talk.yaml no longer says `samples: 1`; update the kernels bench".into(),
        );
    }
    for (name, size, setting) in cases {
        let text = TALK.replace("  samples: 1\n", &format!("  {setting}\n"));
        let seq = load(&text, size)?;
        let world = World::new(seq.scene.clone());
        let exposure = first_exposure(&seq)?;
        let mut seconds = vec![Vec::new(); kernels.len()];
        let mut frames = vec![None; kernels.len()];
        for _ in 0..o.runs {
            for (i, &k) in kernels.iter().enumerate() {
                let start = Instant::now();
                let frame =
                    pool.install(|| tracer::render_with(k, &world, &exposure, &seq.settings, 0));
                seconds[i].push(start.elapsed().as_secs_f64());
                frames[i] = Some(frame.rgb.clone());
                frame.recycle();
            }
        }
        let same = frames.iter().all(|f| *f == frames[0]);
        let ratios: Vec<Timing> = (0..kernels.len())
            .map(|i| timing((0..o.runs).map(|r| seconds[0][r] / seconds[i][r]).collect()))
            .collect();
        let figures: Vec<String> = kernels
            .iter()
            .zip(&seconds)
            .zip(&ratios)
            .map(|((k, s), r)| {
                let t = timing(s.clone());
                format!(
                    "{} {:.1} frames/s ({:.2}x)",
                    k.name(),
                    1.0 / t.median,
                    r.median
                )
            })
            .collect();
        out(&format!(
            "  {name} {}x{}: {}; same frame from every kernel: {}",
            size.0,
            size.1,
            figures.join(", "),
            if same { "yes" } else { "NO" }
        ));
    }
    Ok(())
}
