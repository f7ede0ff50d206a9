//! Which lane width traces a frame. The kernels are one generic code path (`rows::band`),
//! instantiated for 1 lane (the scalar oracle, any CPU), packets of 8 lanes in pairs of AVX2
//! registers (4 f64 per instruction) and packets of 16 lanes in pairs of AVX-512 registers
//! (8 f64 per instruction), behind `#[target_feature]` entry points, so the released binary
//! runs on any x86-64 and builds elsewhere. The widest the CPU has is used unless `RAYREEL_KERNEL=scalar|avx2|avx512`
//! asks for another (tests and `rayreel bench` compare them); every width gives the same bytes.

use super::World;
use super::intersect::Ray;
use super::rows::{self, Old, Pass, RowOut};
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

    /// Rays per packet.
    pub fn lanes(self) -> usize {
        match self {
            Kernel::Scalar => 1,
            Kernel::Avx2 => 8,
            Kernel::Avx512 => 16,
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

    /// Traces arbitrary rays through at most `max_depth` surfaces each, in packets of this
    /// kernel's width: their colours, and the rays cast (eye, reflection and shadow rays).
    /// Tests compare every width with the scalar kernel through this, lane by lane.
    pub fn trace(self, world: &World, rays: &[Ray], max_depth: u32) -> (Vec<DVec3>, u64) {
        let mut out = vec![DVec3::ZERO; rays.len()];
        let cast = match self {
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 if self.supported() => unsafe {
                x86::rays_avx2(world, rays, max_depth, &mut out)
            },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 if self.supported() => unsafe {
                x86::rays_avx512(world, rays, max_depth, &mut out)
            },
            _ => rows::rays::<super::lanes::F64x1>(world, rays, max_depth, &mut out),
        };
        (out, cast)
    }

    /// Rows a band of one pass holds: the height of this kernel's tiles.
    pub(super) fn band_rows(self) -> usize {
        rows::tile_rows(self.lanes())
    }

    /// Runs one pass over the band of rows starting at `top` with this kernel.
    pub(super) fn band(self, pass: &Pass, top: u32, out: RowOut) -> rows::RowStats {
        match self {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: a kernel is only chosen when `supported` said the CPU has the feature.
            Kernel::Avx2 if self.supported() => unsafe { x86::band_avx2(pass, top, out) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 if self.supported() => unsafe { x86::band_avx512(pass, top, out) },
            _ => rows::band::<super::lanes::F64x1>(pass, top, out),
        }
    }

    /// Adds samples to the `pixels` of a frame whose means are `old`; new means into `out`.
    pub(super) fn marked(
        self,
        pass: &Pass,
        pixels: &[u32],
        old: Old,
        out: &mut [[f32; 4]],
    ) -> rows::RowStats {
        match self {
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 if self.supported() => unsafe { x86::marked_avx2(pass, pixels, old, out) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 if self.supported() => unsafe {
                x86::marked_avx512(pass, pixels, old, out)
            },
            _ => rows::marked::<super::lanes::F64x1>(pass, pixels, old, out),
        }
    }

    /// Distance to the first hit of each pixel centre's eye ray in one row.
    pub(super) fn depth_row(self, pass: &Pass, row: u32, out: &mut [f32]) {
        match self {
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 if self.supported() => unsafe { x86::depth_avx2(pass, row, out) },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 if self.supported() => unsafe { x86::depth_avx512(pass, row, out) },
            _ => rows::depth::<super::lanes::F64x1>(pass, row, out),
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::super::lanes::Pair;
    use super::super::lanes::x86::{F64x4, F64x8};
    use super::rows::{self, Old, Pass, RowOut, RowStats};
    use crate::tracer::World;
    use crate::tracer::intersect::Ray;
    use glam::DVec3;

    type Avx2Packet = Pair<F64x4>;
    type Avx512Packet = Pair<F64x8>;

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn band_avx2(pass: &Pass, top: u32, out: RowOut) -> RowStats {
        rows::band::<Avx2Packet>(pass, top, out)
    }

    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn band_avx512(pass: &Pass, top: u32, out: RowOut) -> RowStats {
        rows::band::<Avx512Packet>(pass, top, out)
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn marked_avx2(
        pass: &Pass,
        pixels: &[u32],
        old: Old,
        out: &mut [[f32; 4]],
    ) -> RowStats {
        rows::marked::<Avx2Packet>(pass, pixels, old, out)
    }

    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn marked_avx512(
        pass: &Pass,
        pixels: &[u32],
        old: Old,
        out: &mut [[f32; 4]],
    ) -> RowStats {
        rows::marked::<Avx512Packet>(pass, pixels, old, out)
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn rays_avx2(
        world: &World,
        rays: &[Ray],
        depth: u32,
        out: &mut [DVec3],
    ) -> u64 {
        rows::rays::<Avx2Packet>(world, rays, depth, out)
    }

    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn rays_avx512(
        world: &World,
        rays: &[Ray],
        depth: u32,
        out: &mut [DVec3],
    ) -> u64 {
        rows::rays::<Avx512Packet>(world, rays, depth, out)
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn depth_avx2(pass: &Pass, row: u32, out: &mut [f32]) {
        rows::depth::<Avx2Packet>(pass, row, out)
    }

    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn depth_avx512(pass: &Pass, row: u32, out: &mut [f32]) {
        rows::depth::<Avx512Packet>(pass, row, out)
    }
}
