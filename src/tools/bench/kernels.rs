//! `rayreel bench --only kernels`: the lane widths against each other on the talk, every
//! kernel in f64 and the packet kernels in f32 too (`Settings.precision`), in the same rounds.

use super::{BenchError, Options, Sequence, TALK, first_exposure, load, pool, timing};
use crate::tracer::{self, Kernel, Precision, World};
use std::time::Instant;

/// The f32 target of issue 19: the widest packet kernel in f32 at least this many times as
/// fast as in f64.
const F32_TARGET: f64 = 1.7;

/// A kernel computing in one precision: every kernel in f64, the packet kernels in f32 too.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Variant {
    kernel: Kernel,
    precision: Precision,
}

impl Variant {
    fn name(self) -> String {
        match self.precision {
            Precision::F64 => self.kernel.name().to_string(),
            p => format!("{} {}", self.kernel.name(), p.name()),
        }
    }
}

/// The variants this CPU has, scalar f64 first (the base of every ratio).
fn variants() -> Vec<Variant> {
    let kernels: Vec<Kernel> = Kernel::ALL.into_iter().filter(|k| k.supported()).collect();
    let f64s = kernels.iter().map(|&kernel| Variant {
        kernel,
        precision: Precision::F64,
    });
    let f32s = kernels
        .iter()
        .filter(|&&k| k != Kernel::Scalar)
        .map(|&kernel| Variant {
            kernel,
            precision: Precision::F32,
        });
    f64s.chain(f32s).collect()
}

/// Every lane width this CPU has, in f64 and (packets) in f32, on the same frames, interleaved
/// round by round so a busy machine slows them alike; each ratio is the median of the rounds'
/// ratios to the scalar kernel. Also checks that every width wrote the same frame in each
/// precision, and gives the widest kernel's f32 speed over its f64 speed.
pub(super) fn kernels(o: &Options, out: &mut dyn FnMut(&str), cmd: &str) -> Result<(), BenchError> {
    let variants = variants();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let big = if o.quick { (320, 180) } else { (1920, 1080) };
    let small = if o.quick { (160, 90) } else { (640, 360) };
    let cases = [
        ("1 spp", big, "samples: 1"),
        ("16 spp", small, "samples: 16"),
        ("final (adaptive 4-64)", small, "quality: final"),
    ];
    let names: Vec<String> = variants.iter().map(|v| v.name()).collect();
    out(&format!(
        "talk, render only, {cores} threads, kernels {} interleaved   [{cmd}]",
        names.join(", ")
    ));
    let pool = pool(cores)?;
    if !TALK.contains("  samples: 1\n") {
        return Err(BenchError::Stale(
            "talk.yaml no longer says `samples: 1`; update the kernels bench",
        ));
    }
    for (name, size, setting) in cases {
        let text = TALK.replace("  samples: 1\n", &format!("  {setting}\n"));
        let seq = load(&text, size)?;
        let Rounds { seconds, frames } = kernel_rounds(&pool, &seq, &variants, o.runs)?;
        out(&format!(
            "  {name} {}x{}: {}; same frame from every kernel: {}",
            size.0,
            size.1,
            kernel_figures(&variants, &seconds).join(", "),
            same_frames(&variants, &frames)
        ));
        if let Some(line) = f32_over_f64(&variants, &seconds) {
            out(&format!("    {line}"));
        }
    }
    Ok(())
}

/// Each variant's seconds, round by round, and its frame.
struct Rounds {
    seconds: Vec<Vec<f64>>,
    frames: Vec<Vec<f32>>,
}

/// Renders frame 0 with every variant, `runs` rounds.
fn kernel_rounds(
    pool: &rayon::ThreadPool,
    seq: &Sequence,
    variants: &[Variant],
    runs: usize,
) -> Result<Rounds, BenchError> {
    let world = World::new(seq.scene.clone());
    let exposure = first_exposure(seq)?;
    let mut seconds = vec![Vec::new(); variants.len()];
    let mut frames = vec![Vec::new(); variants.len()];
    for _ in 0..runs {
        for (i, v) in variants.iter().enumerate() {
            let mut settings = seq.settings;
            settings.precision = v.precision;
            let start = Instant::now();
            let frame =
                pool.install(|| tracer::render_with(v.kernel, &world, &exposure, &settings, 0));
            seconds[i].push(start.elapsed().as_secs_f64());
            frames[i] = frame.rgb.clone();
            frame.recycle();
        }
    }
    Ok(Rounds { seconds, frames })
}

/// `avx2 15.1 frames/s (5.35x)`: the median rate, and the median ratio to scalar f64.
fn kernel_figures(variants: &[Variant], seconds: &[Vec<f64>]) -> Vec<String> {
    let runs = seconds[0].len();
    let figure = |(v, s): (&Variant, &Vec<f64>)| {
        let ratio = timing((0..runs).map(|r| seconds[0][r] / s[r]).collect());
        let t = timing(s.clone());
        format!(
            "{} {:.1} frames/s ({:.2}x)",
            v.name(),
            1.0 / t.median,
            ratio.median
        )
    };
    variants.iter().zip(seconds).map(figure).collect()
}

/// `f64 yes, f32 yes`: whether every kernel wrote the same frame, precision by precision.
fn same_frames(variants: &[Variant], frames: &[Vec<f32>]) -> String {
    let same = |p: Precision| {
        let mut of_p = variants
            .iter()
            .zip(frames)
            .filter(|(v, _)| v.precision == p);
        let first = of_p.next()?.1;
        Some(of_p.all(|(_, f)| f == first))
    };
    [Precision::F64, Precision::F32]
        .into_iter()
        .filter_map(|p| {
            Some(format!(
                "{} {}",
                p.name(),
                if same(p)? { "yes" } else { "NO" }
            ))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The widest kernel's f32 speed over its f64 speed, median (min-max) of the rounds' ratios,
/// with the target; None when the CPU has no packet kernel.
fn f32_over_f64(variants: &[Variant], seconds: &[Vec<f64>]) -> Option<String> {
    let index = |v: Variant| variants.iter().position(|&w| w == v);
    let kernel = variants
        .iter()
        .rev()
        .find(|v| v.precision == Precision::F32)?
        .kernel;
    let f64s = &seconds[index(Variant {
        kernel,
        precision: Precision::F64,
    })?];
    let f32s = &seconds[index(Variant {
        kernel,
        precision: Precision::F32,
    })?];
    let ratio = timing(f64s.iter().zip(f32s).map(|(a, b)| a / b).collect());
    let met = if ratio.median >= F32_TARGET {
        "met"
    } else {
        "not met"
    };
    Some(format!(
        "{k} f32 over {k} f64: {:.2}x ({:.2}-{:.2}); target f32 >= {F32_TARGET}x the f64 packet kernel: {met}",
        ratio.median,
        ratio.min,
        ratio.max,
        k = kernel.name()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(kernel: Kernel, precision: Precision) -> Variant {
        Variant { kernel, precision }
    }

    #[test]
    fn the_packet_kernels_also_run_in_f32_after_every_f64_kernel() {
        let all = variants();
        assert_eq!(all[0], v(Kernel::Scalar, Precision::F64));
        let packets = Kernel::ALL.iter().filter(|k| k.supported()).count() - 1;
        assert_eq!(all.len(), 1 + 2 * packets);
        assert!(
            all[1 + packets..]
                .iter()
                .all(|w| w.precision == Precision::F32)
        );
        assert!(!all.contains(&v(Kernel::Scalar, Precision::F32)));
        assert_eq!(v(Kernel::Avx512, Precision::F32).name(), "avx512 f32");
        assert_eq!(v(Kernel::Avx2, Precision::F64).name(), "avx2");
    }

    #[test]
    fn the_widest_kernel_f32_over_f64_with_its_target() {
        let all = [
            v(Kernel::Scalar, Precision::F64),
            v(Kernel::Avx2, Precision::F64),
            v(Kernel::Avx512, Precision::F64),
            v(Kernel::Avx2, Precision::F32),
            v(Kernel::Avx512, Precision::F32),
        ];
        let seconds = [
            [8.0, 8.0, 8.0],
            [2.0; 3],
            [1.0, 1.2, 0.9],
            [1.0; 3],
            [0.5, 0.8, 0.5],
        ];
        let seconds: Vec<Vec<f64>> = seconds.iter().map(|s| s.to_vec()).collect();
        assert_eq!(
            f32_over_f64(&all, &seconds).unwrap(),
            "avx512 f32 over avx512 f64: 1.80x (1.50-2.00); target f32 >= 1.7x the f64 packet kernel: met"
        );
        let slow = [seconds[2].clone(), seconds[2].clone()];
        let pair = [all[2], all[4]];
        assert!(
            f32_over_f64(&pair, &slow).unwrap().ends_with(
                ": 1.00x (1.00-1.00); target f32 >= 1.7x the f64 packet kernel: not met"
            )
        );
        assert_eq!(f32_over_f64(&all[..3], &seconds[..3]), None);
        let figures = kernel_figures(&all[..2], &seconds[..2]);
        assert_eq!(
            figures,
            ["scalar 0.1 frames/s (1.00x)", "avx2 0.5 frames/s (4.00x)"]
        );
    }

    #[test]
    fn same_frames_precision_by_precision() {
        let all = [
            v(Kernel::Scalar, Precision::F64),
            v(Kernel::Avx2, Precision::F64),
            v(Kernel::Avx2, Precision::F32),
            v(Kernel::Avx512, Precision::F32),
        ];
        let frames = [vec![1.0], vec![1.0], vec![0.5], vec![0.25]];
        assert_eq!(same_frames(&all, &frames), "f64 yes, f32 NO");
        assert_eq!(same_frames(&all[..2], &frames[..2]), "f64 yes");
    }
}
