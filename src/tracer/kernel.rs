//! Which lane width traces a frame. The kernels are one generic code path (`rows::band`),
//! instantiated per precision for 1 lane (the scalar oracle, any CPU), packets in pairs of
//! AVX2 registers (8 lanes of f64, 16 of f32) and packets of AVX-512 registers (16 lanes of
//! f64 in two, 32 of f32 in two), behind one generic `#[target_feature]` entry point per CPU
//! feature, so the released binary runs on any x86-64 and builds elsewhere. The widest the CPU
//! has is used unless `RAYREEL_KERNEL=scalar|avx2|avx512` asks for another (tests and
//! `rayreel bench` compare them); every width gives the same bytes in each precision.
use super::intersect::Ray;
use super::rows::{self, Old, Pass, RowOut, RowStats};
use super::{Precision, World};
use crate::lanes::Lanes;
use glam::DVec3;
use std::sync::OnceLock;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kernel {
    /// One lane: plain f64 arithmetic.
    Scalar,
    /// Packets of 8 lanes: two AVX registers of 4 f64.
    Avx2,
    /// Packets of 16 lanes: two AVX-512 registers of 8 f64.
    Avx512,
}

impl Kernel {
    pub const ALL: [Kernel; 3] = [Kernel::Scalar, Kernel::Avx2, Kernel::Avx512];

    pub fn name(self) -> &'static str {
        match self {
            Kernel::Scalar => "scalar",
            Kernel::Avx2 => "avx2",
            Kernel::Avx512 => "avx512",
        }
    }

    /// Whether this CPU can run the kernel.
    pub fn supported(self) -> bool {
        match self {
            Kernel::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The kernel frames use: `RAYREEL_KERNEL` if set to a supported name, else the widest
    /// supported one. Decided once per process.
    pub fn chosen() -> Kernel {
        static CHOSEN: OnceLock<Kernel> = OnceLock::new();
        *CHOSEN.get_or_init(|| {
            let asked = std::env::var("RAYREEL_KERNEL").ok();
            let named = Kernel::ALL
                .into_iter()
                .find(|k| asked.as_deref() == Some(k.name()) && k.supported());
            named.unwrap_or_else(Kernel::widest)
        })
    }

    pub fn widest() -> Kernel {
        Kernel::ALL
            .into_iter()
            .rev()
            .find(|k| k.supported())
            .unwrap_or(Kernel::Scalar)
    }

    /// Rays per packet in `precision`: f64 packets are two registers of 4 (AVX2) or 8
    /// (AVX-512) lanes; f32 packets two registers of 8 (AVX2) or one of 16 (AVX-512).
    pub fn lanes_in(self, precision: Precision) -> usize {
        match (self, precision) {
            (Kernel::Scalar, _) => 1,
            (Kernel::Avx2, Precision::F64) => 8,
            (Kernel::Avx512, Precision::F32) => 32,
            _ => 16,
        }
    }

    /// Traces arbitrary rays through at most `max_depth` surfaces each, in packets of this
    /// kernel's width and `precision`: their colours, and the rays cast (eye, reflection and
    /// shadow rays). Tests compare every width with the scalar kernel through this, lane by lane.
    pub fn trace(
        self,
        precision: Precision,
        world: &World,
        rays: &[Ray],
        max_depth: u32,
    ) -> (Vec<DVec3>, u64) {
        let mut out = vec![DVec3::ZERO; rays.len()];
        let cast = match self.run(precision, Job::Rays(world, rays, max_depth, &mut out)) {
            Done::Cast(n) => n,
            _ => unreachable!("a Rays job counts rays"),
        };
        (out, cast)
    }

    /// The lens's concentric map (`lens::disc`) of each point of `ab` in this kernel's lanes
    /// and `precision`, for tests that compare the widths lane by lane.
    #[cfg(test)]
    pub(super) fn disc(self, precision: Precision, ab: &[(f64, f64)]) -> Vec<(f64, f64)> {
        let mut out = vec![(0.0, 0.0); ab.len()];
        self.run(precision, Job::Disc(ab, &mut out));
        out
    }

    /// Rows a band of one pass holds: the height of this kernel's tiles.
    pub(super) fn band_rows(self, precision: Precision) -> usize {
        rows::tile_rows(self.lanes_in(precision))
    }

    /// Runs one pass over the band of rows starting at `top` with this kernel.
    pub(super) fn band(self, pass: &Pass, top: u32, out: RowOut) -> RowStats {
        self.stats(pass, Job::Band(pass, top, out))
    }

    /// Adds samples to the `pixels` of a frame whose means are `old`; new means into `out`.
    pub(super) fn marked(
        self,
        pass: &Pass,
        pixels: &[u32],
        old: Old,
        out: &mut [[f32; 5]],
    ) -> RowStats {
        self.stats(pass, Job::Marked(pass, pixels, old, out))
    }

    /// Distance to the first hit of each pixel centre's eye ray in one row.
    pub(super) fn depth_row(self, pass: &Pass, row: u32, out: &mut [f32]) {
        self.run(pass.settings.precision, Job::Depth(pass, row, out));
    }

    fn stats(self, pass: &Pass, job: Job) -> RowStats {
        match self.run(pass.settings.precision, job) {
            Done::Stats(s) => s,
            _ => unreachable!("a pass job returns its statistics"),
        }
    }

    /// Runs `job` with this kernel's lanes in `precision`. A kernel the CPU lacks (only
    /// possible through `trace` or `render_with`) runs as the scalar one, with the same result.
    fn run(self, precision: Precision, job: Job) -> Done {
        use crate::lanes::{F32x1, F64x1};
        #[cfg(target_arch = "x86_64")]
        if self.supported() {
            use crate::lanes::Pair;
            use crate::lanes::x86::{F32x8, F32x16, F64x4, F64x8};
            match (self, precision) {
                // SAFETY: `supported` said the CPU has AVX2, the feature `avx2` enables.
                (Kernel::Avx2, Precision::F64) => return unsafe { x86::avx2::<Pair<F64x4>>(job) },
                // SAFETY: as above, AVX2 is present.
                (Kernel::Avx2, Precision::F32) => return unsafe { x86::avx2::<Pair<F32x8>>(job) },
                (Kernel::Avx512, Precision::F64) => {
                    // SAFETY: `supported` said the CPU has AVX-512F, the feature `avx512` enables.
                    return unsafe { x86::avx512::<Pair<F64x8>>(job) };
                }
                (Kernel::Avx512, Precision::F32) => {
                    // SAFETY: as above, AVX-512F is present.
                    return unsafe { x86::avx512::<Pair<F32x16>>(job) };
                }
                (Kernel::Scalar, _) => {}
            }
        }
        match precision {
            Precision::F64 => job.run::<F64x1>(),
            Precision::F32 => job.run::<F32x1>(),
        }
    }
}

/// One call into the generic kernel code, so that each CPU feature needs one entry point.
enum Job<'a, 'b> {
    Band(&'a Pass<'b>, u32, RowOut<'a>),
    Marked(&'a Pass<'b>, &'a [u32], Old<'a>, &'a mut [[f32; 5]]),
    Depth(&'a Pass<'b>, u32, &'a mut [f32]),
    Rays(&'a World, &'a [Ray], u32, &'a mut [DVec3]),
    #[cfg(test)]
    Disc(&'a [(f64, f64)], &'a mut [(f64, f64)]),
}

enum Done {
    Stats(RowStats),
    Cast(u64),
    Nothing,
}

impl Job<'_, '_> {
    #[inline(always)]
    fn run<V: Lanes>(self) -> Done {
        match self {
            Job::Band(pass, top, out) => Done::Stats(rows::band::<V>(pass, top, out)),
            Job::Marked(pass, pixels, old, out) => {
                Done::Stats(rows::marked::<V>(pass, pixels, old, out))
            }
            Job::Depth(pass, row, out) => {
                rows::depth::<V>(pass, row, out);
                Done::Nothing
            }
            Job::Rays(world, rays, depth, out) => {
                Done::Cast(rows::rays::<V>(world, rays, depth, out))
            }
            #[cfg(test)]
            Job::Disc(ab, out) => {
                super::lens::disc_all::<V>(ab, out);
                Done::Nothing
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::{Done, Job};
    use crate::lanes::Lanes;

    /// # Safety
    /// The CPU must have AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn avx2<V: Lanes>(job: Job) -> Done {
        job.run::<V>()
    }

    /// # Safety
    /// The CPU must have AVX-512F.
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn avx512<V: Lanes>(job: Job) -> Done {
        job.run::<V>()
    }
}
