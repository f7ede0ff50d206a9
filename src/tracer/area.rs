//! Area lights (sphere and rect): each eye sample takes `samples` points on the light, each
//! lit like a point light carrying 1/samples of it. The points continue one (0,2)-sequence
//! through a pixel's samples (point j of sample k is point k·samples + j), XOR-shifted per
//! (frame, pixel, light); a sphere is sampled on the disk through its centre that faces the
//! shading point. Points are placed per lane in f64 from the lane's own surface point, so
//! they do not depend on the packet (see docs/spec/tracer.md, "Area lights").

use super::World;
use super::path::LightSeeds;
use super::shade::{Here, Surface, shine, towards};
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::scene::Light;
use glam::DVec3;

/// An area light (sphere or rect) of index `index` in the scene's lights, after its ambient
/// term: its m = `samples` points j = 0 … m − 1 in order, each lit as a point light whose
/// term is scaled by 1/m. Each lane's points are computed in f64 from the lane's own surface
/// point and pixel, so they do not depend on the packet.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn light<V: Lanes>(
    world: &World,
    s: &Surface<V>,
    at: &Here<V>,
    (light, index): (&Light, usize),
    active: V::M,
    seeds: Option<LightSeeds>,
    sum: &mut V3<V>,
    rays: &mut u64,
) {
    let (i, m) = match *light {
        Light::Sphere {
            intensity, samples, ..
        }
        | Light::Rect {
            intensity, samples, ..
        } => (intensity, samples),
        _ => unreachable!("only area lights come here"),
    };
    let lit = match *light {
        // One-sided: only points in front of the rectangle's plane see it.
        Light::Rect { corner, normal, .. } => {
            let side = (at.point - V3::splat(corner)).dot(V3::splat(normal));
            active.and(side.gt(V::splat(0.0)))
        }
        _ => active,
    };
    let fallback;
    let (seeds, k) = match seeds {
        Some(l) => (l.seeds, l.k),
        None => {
            fallback = [super::sample::light_seed(0, 0); MAX_LANES];
            (&fallback, 0)
        }
    };
    let points = AreaPoints::new::<V>(light, index, seeds, at.point, lit);
    let lit = lit.and(V::M::from_bits(points.lanes));
    if !lit.any() {
        return;
    }
    let share = Some(V::splat(1.0 / f64::from(m)));
    let mut block = [[[0.0; MAX_LANES]; 3]; BLOCK];
    let mut j = 0;
    while j < m {
        let n = (m - j).min(BLOCK as u32);
        points.block(k * m + j, n as usize, V::N, &mut block);
        for q in &block[..n as usize] {
            let q = V3 {
                x: V::load(&q[0]),
                y: V::load(&q[1]),
                z: V::load(&q[2]),
            };
            let (l, d) = towards(at.point, q);
            shine(world, s, at, lit, (l, d), &i, share, sum, rays);
        }
        j += n;
    }
}

/// Light points placed at a time: the scalar work (libm's sin and cos for a sphere) runs as
/// one loop between lane work, so the lanes' registers are saved around it once, not around
/// every call.
const BLOCK: usize = 16;

/// `BLOCK` points of every lane, as f64 coordinates: [point][axis][lane].
type Block = [[[f64; MAX_LANES]; 3]; BLOCK];

/// Where an area light's points fall for each lane of a packet: per lane its digital shift
/// and, for a sphere, the disk it sees (centre, radius and the basis of the disk's plane).
struct AreaPoints {
    /// Lanes to place points for (bit k for lane k): active, in front of a rect, outside a
    /// sphere.
    lanes: u32,
    shift: [(u32, u32); MAX_LANES],
    shape: AreaShape,
}

// Built once per light and shading call, on the stack: the sphere's per-lane basis is what it
// needs, and boxing the variant would cost an allocation each time.
#[allow(clippy::large_enum_variant)]
enum AreaShape {
    Rect {
        corner: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
    },
    Sphere {
        center: DVec3,
        radius: f64,
        /// Per lane, e1 and e2 of the disk facing the lane's point.
        basis: [(DVec3, DVec3); MAX_LANES],
    },
}

impl AreaPoints {
    /// The points of `light` (index `index`) for the lanes of `lit`, whose surface points are
    /// `point` and light states `seeds`. Lanes inside a sphere light get none.
    #[inline(always)]
    fn new<V: Lanes>(
        light: &Light,
        index: usize,
        seeds: &[u64; MAX_LANES],
        point: V3<V>,
        lit: V::M,
    ) -> AreaPoints {
        let mut lanes = lit.bits();
        let mut shift = [(0, 0); MAX_LANES];
        for (k, s) in shift.iter_mut().enumerate().take(V::N) {
            if lanes >> k & 1 == 1 {
                *s = super::sample::light_shift(seeds[k], index);
            }
        }
        let shape = match *light {
            Light::Rect {
                corner,
                edge_u,
                edge_v,
                ..
            } => AreaShape::Rect {
                corner,
                edge_u,
                edge_v,
            },
            Light::Sphere { center, radius, .. } => {
                let (px, py, pz) = (point.x.array(), point.y.array(), point.z.array());
                let mut basis = [(DVec3::ZERO, DVec3::ZERO); MAX_LANES];
                for (k, b) in basis.iter_mut().enumerate().take(V::N) {
                    if lanes >> k & 1 == 0 {
                        continue;
                    }
                    match disk_basis(center, radius, DVec3::new(px[k], py[k], pz[k])) {
                        Some(e) => *b = e,
                        None => lanes &= !(1 << k),
                    }
                }
                AreaShape::Sphere {
                    center,
                    radius,
                    basis,
                }
            }
            _ => unreachable!("only area lights have points"),
        };
        AreaPoints {
            lanes,
            shift,
            shape,
        }
    }

    /// Points g … g + n − 1 (n ≤ `BLOCK`) of each lane's sequence on the light into
    /// `out[..n]`, for lanes 0 … lanes − 1 (the light's centre or corner on lanes that take no
    /// points). Plain f64 code, kept out of line: the same function for every lane type.
    #[inline(never)]
    fn block(&self, g: u32, n: usize, lanes: usize, out: &mut Block) {
        use super::sample::{sobol02, unit32};
        for (j, q) in out.iter_mut().enumerate().take(n) {
            let (gx, gy) = sobol02(g + j as u32);
            for k in 0..lanes {
                let live = self.lanes >> k & 1 == 1;
                let (x, y) = (unit32(gx ^ self.shift[k].0), unit32(gy ^ self.shift[k].1));
                let p = match &self.shape {
                    AreaShape::Rect {
                        corner,
                        edge_u,
                        edge_v,
                    } => match live {
                        true => rect_point(*corner, *edge_u, *edge_v, x, y),
                        false => *corner,
                    },
                    AreaShape::Sphere {
                        center,
                        radius,
                        basis,
                    } => match live {
                        true => disk_point(*center, *radius, basis[k], x, y),
                        false => *center,
                    },
                };
                (q[0][k], q[1][k], q[2][k]) = (p.x, p.y, p.z);
            }
        }
    }
}

/// corner + x·edge_u + y·edge_v, per component ((corner + x·u) + y·v).
#[inline(always)]
fn rect_point(corner: DVec3, u: DVec3, v: DVec3, x: f64, y: f64) -> DVec3 {
    DVec3::new(
        (corner.x + x * u.x) + y * v.x,
        (corner.y + x * u.y) + y * v.y,
        (corner.z + x * u.z) + y * v.z,
    )
}

/// The basis (e1, e2) of the disk through `center` perpendicular to w = normalize(center − p),
/// by Duff et al. 2017; None when p is not outside the sphere (|center − p| ≤ radius, or NaN).
#[inline(always)]
fn disk_basis(center: DVec3, radius: f64, p: DVec3) -> Option<(DVec3, DVec3)> {
    let v = DVec3::new(center.x - p.x, center.y - p.y, center.z - p.z);
    let d = ((v.x * v.x + v.y * v.y) + v.z * v.z).sqrt();
    if d.is_nan() || d <= radius {
        return None;
    }
    let r = 1.0 / d;
    let w = DVec3::new(v.x * r, v.y * r, v.z * r);
    let sign = 1f64.copysign(w.z);
    let a = -1.0 / (sign + w.z);
    let b = w.x * w.y * a;
    let e1 = DVec3::new(1.0 + sign * w.x * w.x * a, sign * b, -sign * w.x);
    let e2 = DVec3::new(b, sign + w.y * w.y * a, -w.y);
    Some((e1, e2))
}

/// center + radius·(a·e1 + b·e2) with (a, b) the concentric map of (x, y), per component
/// c + radius·((a·e1) + (b·e2)).
#[inline(always)]
fn disk_point(center: DVec3, radius: f64, (e1, e2): (DVec3, DVec3), x: f64, y: f64) -> DVec3 {
    let (a, b) = super::lens::concentric(x, y);
    DVec3::new(
        center.x + radius * (a * e1.x + b * e2.x),
        center.y + radius * (a * e1.y + b * e2.y),
        center.z + radius * (a * e1.z + b * e2.z),
    )
}
