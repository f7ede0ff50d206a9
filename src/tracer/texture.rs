//! Texture lookups at hits, filtered over each ray's footprint so that one sample per pixel
//! shows no moiré: the checker box-filtered analytically, images mip-mapped and trilinearly
//! interpolated. The footprint is a ray cone (Amanatides 1984; Akenine-Möller et al. 2019):
//! each ray carries its width at its origin and its spread, and its width at a hit is
//! |width + spread·t|. The rules, operation by operation, are in docs/spec/texture.md.
//!
//! Everything here is f64 per lane, from the lanes' values widened exactly, so a lane's colour
//! is the same for every packet width: scalar, except the footprints and a checker's taps,
//! four at a time in AVX2 registers with the scalar rule's operations in its order.

use super::World;
use crate::lanes::{Lanes, MAX_LANES, Mask, V3};
use crate::scene::{Image, Level, Scene, Shape, Texture};
use glam::{DVec2, DVec3};
use std::f64::consts::PI;

#[cfg(target_arch = "x86_64")]
mod footprint;
mod patch;
#[cfg(target_arch = "x86_64")]
mod pixels;
#[cfg(target_arch = "x86_64")]
mod taps;

/// Per axis, one f64 value per lane.
pub(super) type Axes = [[f64; MAX_LANES]; 3];

/// The footprint cones of a packet's rays: full width at the origin, and growth per unit
/// length (radians, small-angle).
#[derive(Clone, Copy)]
pub(super) struct Cone<V: Lanes> {
    pub width: V,
    pub spread: V,
}

impl<V: Lanes> Cone<V> {
    /// The eye rays' cone: width 0 at the eye, `spread` per unit length.
    #[inline(always)]
    pub(super) fn eye(spread: f64) -> Cone<V> {
        Cone {
            width: V::splat(0.0),
            spread: V::splat(spread),
        }
    }

    /// The full width at distance `t`: |width + spread·t|.
    #[inline(always)]
    pub(super) fn at(&self, t: V) -> V {
        let w = self.width + self.spread * t;
        w.copysign(V::splat(1.0))
    }

    /// The cone of the rays leaving the hits at distance `t`: the width there, and the spread
    /// changed by a mirror whose normal turns by `curvature` (1/radius, 0 on flat surfaces)
    /// per unit length: + 2·width·curvature off a convex side (`entering`), − off a concave
    /// one. Transmitted rays keep their spread (`curvature` 0).
    #[inline(always)]
    pub(super) fn leaving(&self, t: V, curvature: V, entering: V::M) -> Cone<V> {
        let width = self.at(t);
        let turn = V::splat(2.0) * width * curvature;
        Cone {
            width,
            spread: V::select(entering, self.spread + turn, self.spread - turn),
        }
    }

    #[inline(always)]
    pub(super) fn select(m: V::M, a: Cone<V>, b: Cone<V>) -> Cone<V> {
        Cone {
            width: V::select(m, a.width, b.width),
            spread: V::select(m, a.spread, b.spread),
        }
    }
}

/// Each object's curvature for the cone: 1/radius for a sphere, 0 otherwise.
pub(super) fn curvatures(world: &World) -> Vec<f64> {
    let objects = &world.scene.objects;
    objects
        .iter()
        .map(|o| match o.shape {
            Shape::Sphere { radius, .. } => 1.0 / radius,
            _ => 0.0,
        })
        .collect()
}

/// The curvature of each lane's object (`object` holds object indices).
#[inline(always)]
pub(super) fn curvature<V: Lanes>(world: &World, object: V) -> V {
    let ids = object.array();
    let table = &world.curvature;
    V::from_fn(|k| table.get(ids[k] as usize).copied().unwrap_or(0.0))
}

/// One lane's hit as a lookup sees it.
pub(super) struct At {
    /// The hit point in world coordinates (`p + origin`, see `point`).
    pub p: DVec3,
    /// Half the footprint's width at the hit.
    pub r: f64,
    pub object: usize,
    /// The triangle and its barycentrics (u, v) on a mesh.
    pub prim: u32,
    pub bary: (f64, f64),
    /// The eye ray's pixel on the hit's tangent plane, at an eye ray's first hit where the
    /// scene has a checker (else None).
    pub patch: Option<Patch>,
}

/// The texture's colour at `at`, filtered over its footprint: the mean of the lookups at the
/// footprint's taps.
#[inline(never)]
pub(super) fn color(world: &World, texture: &Texture, at: &At, f: &Footprint) -> DVec3 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("sse4.1") {
            // SAFETY: the CPU has SSE4.1.
            return unsafe { color_sse41(world, texture, at, f) };
        }
        color_with::<Portable>(world, texture, at, f)
    }
    #[cfg(not(target_arch = "x86_64"))]
    color_with::<Native>(world, texture, at, f)
}

/// Each lane's pixel as its eye ray's camera sees it (docs/spec/texture.md, **The pixel**):
/// the direction from the lane's ray origin through the pixel's centre, unnormalised, and
/// that direction's steps one pixel right and one pixel down.
#[derive(Clone, Copy)]
pub struct PixelRays<V: Lanes> {
    pub centre: V3<V>,
    pub right: V3<V>,
    pub down: V3<V>,
}

impl<V: Lanes> PixelRays<V> {
    #[inline(always)]
    pub(super) fn zero() -> PixelRays<V> {
        PixelRays {
            centre: V3::zero(),
            right: V3::zero(),
            down: V3::zero(),
        }
    }
}

/// An eye ray's pixel on the tangent plane of its hit: the offset of the centre ray's point
/// from the hit, and the parallelogram's half-edges (half a pixel's step each way).
#[derive(Clone, Copy)]
pub(super) struct Patch {
    offset: DVec3,
    a: DVec3,
    b: DVec3,
}

impl Patch {
    /// The pixel (`centre`, `right`, `down` of `PixelRays`, widened) of the eye ray from `o`
    /// whose hit is `p` with unit normal `n` facing it; None where the centre's ray does not
    /// meet the plane from the same side, ahead, at a finite point.
    /// Out of line, like `color`: scalar, once a textured lane, and kept out of shading's body.
    #[inline(never)]
    pub(super) fn new(
        o: DVec3,
        p: DVec3,
        n: DVec3,
        (c, right, down): (DVec3, DVec3, DVec3),
    ) -> Option<Patch> {
        let q = n.dot(c);
        if q.is_nan() || q >= 0.0 {
            return None;
        }
        let t = (p - o).dot(n) / q;
        if t.is_nan() || t <= 0.0 {
            return None;
        }
        let half = 0.5 * t;
        let edge = |s: DVec3| (s - c * (s.dot(n) / q)) * half;
        let patch = Patch {
            offset: (o + c * t) - p,
            a: edge(right),
            b: edge(down),
        };
        (patch.offset.is_finite() && patch.a.is_finite() && patch.b.is_finite()).then_some(patch)
    }
}

/// Four lanes' values per axis.
pub(super) type Quad = [[f64; 4]; 3];

/// The patches (`Patch::new`) of the lanes in `lanes` (bit j for lane j) of four eye rays from
/// `o` with hits `p`, unit normals `n` facing the rays and pixel rays `(centre, right, down)`:
/// four at a time where the CPU has AVX2, the same bits.
#[inline(never)]
pub(super) fn patches(
    (o, p, n): (&Quad, &Quad, &Quad),
    rays: (&Quad, &Quad, &Quad),
    lanes: u32,
) -> [Option<Patch>; 4] {
    #[cfg(target_arch = "x86_64")]
    if lanes.count_ones() > 1 && std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        let (four, valid) = unsafe { pixels::patches(o, p, n, rays) };
        return std::array::from_fn(|j| ((lanes & valid) >> j & 1 == 1).then_some(four[j]));
    }
    let v = |a: &Quad, j: usize| DVec3::new(a[0][j], a[1][j], a[2][j]);
    std::array::from_fn(|j| {
        let r = (v(rays.0, j), v(rays.1, j), v(rays.2, j));
        (lanes >> j & 1 == 1)
            .then(|| Patch::new(v(o, j), v(p, j), v(n, j), r))
            .flatten()
    })
}

/// `pixel_color` of four lanes (`maps[j]` looked up at `ats[j]`; None where a lane has no map
/// or no hit): where the CPU has AVX2, the axes' test of every lane at once, and the closed
/// forms only for the lanes whose pixel crosses a cell boundary. The same bits.
#[inline(never)]
pub(super) fn pixel_colors(
    world: &World,
    maps: [Option<&Texture>; 4],
    ats: &[Option<At>; 4],
) -> [Option<DVec3>; 4] {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (and so SSE4.1).
        return unsafe { pixel_colors_avx2(world, maps, ats) };
    }
    std::array::from_fn(|j| match (maps[j], &ats[j]) {
        (Some(t), Some(at)) => pixel_color(world, t, at),
        _ => None,
    })
}

/// `pixel_colors` with AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn pixel_colors_avx2(
    world: &World,
    maps: [Option<&Texture>; 4],
    ats: &[Option<At>; 4],
) -> [Option<DVec3>; 4] {
    let scene = world.unshifted.as_deref().unwrap_or(&world.scene);
    let (mut c, mut a, mut b) = ([[0.0; 4]; 3], [[0.0; 4]; 3], [[0.0; 4]; 3]);
    let mut sizes = [1.0; 4];
    let mut checkers: [Option<(f64, &[DVec3; 2])>; 4] = [None; 4];
    for j in 0..4 {
        let (Some(Texture::Checker { size, colors }), Some(at)) = (maps[j], &ats[j]) else {
            continue;
        };
        let Some(q) = &at.patch else { continue };
        let held = held(scene, at);
        let (cj, aj, bj) = parallelogram(point(scene, at, &held), q, &held);
        for i in 0..3 {
            (c[i][j], a[i][j], b[i][j]) = (cj[i], aj[i], bj[i]);
        }
        sizes[j] = *size;
        checkers[j] = Some((*size, colors));
    }
    // SAFETY: the CPU has AVX2.
    let (sigma, one) = unsafe { pixels::one_cell(&c, &a, &b, &sizes) };
    let mut out = [None; 4];
    for (j, slot) in out.iter_mut().enumerate() {
        let Some((size, colors)) = checkers[j] else {
            continue;
        };
        *slot = match one >> j & 1 {
            1 => Some(patch::mix(colors, sigma[j])),
            _ => {
                let v = |q: &Quad| DVec3::new(q[0][j], q[1][j], q[2][j]);
                patch::checker::<Native>(size, colors, (v(&c), v(&a), v(&b)))
            }
        };
    }
    out
}

/// The footprints (`Footprint::new`) of the lanes `first .. first + 4` that are in `lanes`
/// (bit j for lane first + j), for unit normals `n` facing the rays, unit directions `d` and
/// cones of full width `width`: four at a time where the CPU has AVX2, the same bits. Lanes
/// not in `lanes` hold no footprint. Out of line, like `color`: inlined into shading it
/// changed the compiler's layout of frames without textures (talk orbit f64 +2.4%).
#[inline(never)]
pub(super) fn footprints(
    (n, d, width): (&Axes, &Axes, &[f64; MAX_LANES]),
    first: usize,
    lanes: u32,
) -> [Option<Footprint>; 4] {
    let one = |j: usize| {
        let k = first + j;
        let v = |a: &Axes| DVec3::new(a[0][k], a[1][k], a[2][k]);
        Footprint::new(v(d), v(n), 0.5 * width[k])
    };
    #[cfg(target_arch = "x86_64")]
    if lanes.count_ones() > 1 && std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2; `first` is a multiple of 4 below MAX_LANES.
        let (four, redo) = unsafe { footprint::four(n, d, width, first) };
        let mut four = four.map(Some);
        for (j, f) in four.iter_mut().enumerate() {
            *f = match (lanes >> j & 1, redo >> j & 1) {
                (0, _) => None,
                (_, 1) => Some(one(j)),
                _ => f.take(),
            };
        }
        return four;
    }
    std::array::from_fn(|j| (lanes >> j & 1 == 1).then(|| one(j)))
}

/// `color` compiled with SSE4.1, whose rounding instruction is the library's floor and ceil
/// (a lookup takes dozens of floors: the portable one cost the checker a quarter of its
/// frame).
///
/// # Safety
/// The CPU must have SSE4.1.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse4.1")]
unsafe fn color_sse41(world: &World, texture: &Texture, at: &At, f: &Footprint) -> DVec3 {
    color_with::<Native>(world, texture, at, f)
}

/// The checker `texture`'s mean over the eye ray's pixel (`at.patch`), or None where the rule
/// leaves the lookup to `color` and the footprint: an image map, no pixel, or a parallelogram
/// the closed forms do not hold. Tried first, so a lane it answers needs no footprint.
#[inline(never)]
pub(super) fn pixel_color(world: &World, texture: &Texture, at: &At) -> Option<DVec3> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("sse4.1") {
            // SAFETY: the CPU has SSE4.1.
            return unsafe { pixel_sse41(world, texture, at) };
        }
        pixel_color_with::<Portable>(world, texture, at)
    }
    #[cfg(not(target_arch = "x86_64"))]
    pixel_color_with::<Native>(world, texture, at)
}

/// `pixel_color` compiled with SSE4.1, as `color_sse41`.
///
/// # Safety
/// The CPU must have SSE4.1.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse4.1")]
unsafe fn pixel_sse41(world: &World, texture: &Texture, at: &At) -> Option<DVec3> {
    pixel_color_with::<Native>(world, texture, at)
}

#[inline(always)]
fn pixel_color_with<R: Round>(world: &World, texture: &Texture, at: &At) -> Option<DVec3> {
    let (Texture::Checker { size, colors }, Some(q)) = (texture, &at.patch) else {
        return None;
    };
    let scene = world.unshifted.as_deref().unwrap_or(&world.scene);
    let held = held(scene, at);
    let p = point(scene, at, &held);
    pixel::<R>(*size, colors, p, q, &held)
}

/// How a lookup takes ⌊x⌋: the same bits either way (`floor` is the library's, bit for bit).
trait Round {
    fn floor(x: f64) -> f64;
}

/// The library's floor: one instruction where the caller is built with SSE4.1 (and on other
/// architectures), a call where it is not.
struct Native;

impl Round for Native {
    #[inline(always)]
    fn floor(x: f64) -> f64 {
        x.floor()
    }
}

/// `floor`, for code built for the baseline x86-64.
struct Portable;

impl Round for Portable {
    #[inline(always)]
    fn floor(x: f64) -> f64 {
        floor(x)
    }
}

/// `color`'s work, every function under it inlined so that it is built with the caller's CPU
/// features.
#[inline(always)]
fn color_with<R: Round>(world: &World, texture: &Texture, at: &At, f: &Footprint) -> DVec3 {
    let scene = world.unshifted.as_deref().unwrap_or(&world.scene);
    let held = held(scene, at);
    let p = point(scene, at, &held);
    let mut f = *f;
    if let Texture::Checker { size, colors } = texture {
        if let Some(c) = one_cell::<R>(*size, colors, p, &f) {
            return c;
        }
        f.taps = checker_taps(f.taps, at.r, *size);
    }
    let line = Line {
        p,
        major: f.major,
        taps: f.taps,
        held,
    };
    // The semi-axis of each tap's ellipse along the footprint's long axis.
    let major = f.major / f64::from(f.taps);
    let sum = match texture {
        Texture::Checker { size, colors } => {
            // Taps differ only in their centres: their boxes' half-widths are the same.
            let tap = Tap {
                p,
                offset: DVec3::ZERO,
                minor: f.minor,
                major,
            };
            let half = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| tap.extent(a) / *size);
            checker_line::<R>(*size, colors, &line, &half)
        }
        Texture::Image { image, scale } => {
            let mut sum = DVec3::ZERO;
            for k in 0..f.taps {
                let c = line.centre(k);
                let tap = Tap {
                    p: c,
                    offset: c - p,
                    minor: f.minor,
                    major,
                };
                sum += image_color::<R>(scene, image, *scale, at, &tap);
            }
            sum
        }
    };
    sum / f64::from(f.taps)
}

/// The checker's colour when the whole footprint lies in one cell: the box of half-extent
/// |majorᵢ| + |minorᵢ| around `p` holds every tap's box, so every tap would see that cell
/// alone and the average is its colour. Most lookups near the camera end here, without taps.
#[inline(always)]
fn one_cell<R: Round>(size: f64, colors: &[DVec3; 2], p: DVec3, f: &Footprint) -> Option<DVec3> {
    let (p, major, minor) = (p.to_array(), f.major.to_array(), f.minor.to_array());
    let mut a = 1.0;
    for i in 0..3 {
        let x = p[i] / size;
        let h = (major[i].abs() + minor[i].abs()) / size;
        let k = if h < TINY_BOX {
            R::floor(x)
        } else {
            let k = R::floor(x - h);
            if k != R::floor(x + h) {
                return None;
            }
            k
        };
        a *= sign(k);
    }
    Some(if a > 0.0 { colors[0] } else { colors[1] })
}

/// The checker over the eye ray's pixel `q` around the lookup point `p`.
#[inline(always)]
fn pixel<R: Round>(
    size: f64,
    colors: &[DVec3; 2],
    p: DVec3,
    q: &Patch,
    held: &[Option<f64>; 3],
) -> Option<DVec3> {
    patch::checker::<R>(size, colors, parallelogram(p, q, held))
}

/// The eye ray's pixel `q` around the lookup point `p` as the checker's closed forms take it:
/// its centre snapped like every lookup point, the coordinates the surface holds constant held
/// along its edges.
#[inline(always)]
fn parallelogram(p: DVec3, q: &Patch, held: &[Option<f64>; 3]) -> (DVec3, DVec3, DVec3) {
    let mask = DVec3::from_array(held.map(|h| if h.is_some() { 0.0 } else { 1.0 }));
    (snapped(held, p + q.offset), q.a * mask, q.b * mask)
}

/// Footprints at least this many cells across (the disc's radius over the cell size) take
/// the checker in one tap.
pub const WIDE_FOOTPRINT: f64 = 0.5;

/// The checker's taps: one where the footprint's radius `r` spans `WIDE_FOOTPRINT` cells of
/// size `size` or more. Taps keep a long footprint from blurring across itself; once the
/// footprint is that wide each tap averages out to nearly the checker's mean, and so does the
/// one box around the whole ellipse, at a sixteenth of the work near the horizon.
#[inline(always)]
fn checker_taps(taps: u32, r: f64, size: f64) -> u32 {
    if r >= WIDE_FOOTPRINT * size { 1 } else { taps }
}

/// The point a lookup uses, from the scene in world coordinates: on a mesh the barycentric
/// blend of the placed corners, elsewhere the hit; then `snapped` with the surface's `held`.
#[inline(always)]
fn point(scene: &Scene, at: &At, held: &[Option<f64>; 3]) -> DVec3 {
    let p = match scene.objects[at.object].shape {
        Shape::Mesh { mesh, place, .. } => {
            let m = &scene.meshes[mesh];
            let q = m.triangles[at.prim as usize].map(|i| place.point(m.positions[i as usize]));
            let (b1, b2) = at.bary;
            q[0] * (1.0 - b1 - b2) + q[1] * b1 + q[2] * b2
        }
        _ => at.p,
    };
    snapped(held, p)
}

/// The coordinates the surface holds constant, `Some(value)` for each (`snapped` sets them):
/// a plane whose normal has one non-zero component i has coordinate i of its point
/// everywhere; a placed triangle whose three corners share coordinate i, that coordinate. So a
/// floor at y = 0 is looked up at y = 0 exactly, whatever the rounding of the hit or of a
/// tap's offset.
#[inline(always)]
fn held(scene: &Scene, at: &At) -> [Option<f64>; 3] {
    let mut held = [None; 3];
    match scene.objects[at.object].shape {
        Shape::Plane { point, normal, .. } => {
            let n = normal.to_array();
            let axes = n.iter().filter(|c| **c != 0.0).count();
            if let (1, Some(i)) = (axes, n.iter().position(|c| *c != 0.0)) {
                held[i] = Some(point.to_array()[i]);
            }
        }
        Shape::Mesh { mesh, place, .. } => {
            let m = &scene.meshes[mesh];
            let q = m.triangles[at.prim as usize]
                .map(|i| place.point(m.positions[i as usize]).to_array());
            for (i, h) in held.iter_mut().enumerate() {
                if q[0][i] == q[1][i] && q[1][i] == q[2][i] {
                    *h = Some(q[0][i]);
                }
            }
        }
        Shape::Sphere { .. } => {}
    }
    held
}

/// `p` with the coordinates in `held` set.
#[inline(always)]
fn snapped(held: &[Option<f64>; 3], p: DVec3) -> DVec3 {
    let mut p = p.to_array();
    for (c, h) in p.iter_mut().zip(held) {
        if let Some(v) = h {
            *c = *v;
        }
    }
    DVec3::from_array(p)
}

/// Most taps a footprint is split into along its long axis.
pub const MAX_TAPS: u32 = 16;

/// The footprint: the disc of radius r across the ray projected along it onto the tangent
/// plane, an ellipse with semi-axis vectors `minor` (across the plane of incidence, length r)
/// and `major` (length r/|cos θ|), covered by `taps` ellipses side by side along `major`.
#[derive(Clone, Copy)]
pub(super) struct Footprint {
    minor: DVec3,
    major: DVec3,
    taps: u32,
}

impl Footprint {
    /// The footprint at a hit of unit normal `n` (facing the ray) seen along the unit
    /// direction `d`, for a cone of half-width `r` there.
    #[inline(always)]
    fn new(d: DVec3, n: DVec3, r: f64) -> Footprint {
        let mut m = d.cross(n);
        if m == DVec3::ZERO {
            m = n.cross(DVec3::X);
        }
        if m == DVec3::ZERO {
            m = n.cross(DVec3::Y);
        }
        let across = m.normalize();
        let e2 = across.cross(d);
        let minor = across * r;
        let major = (e2 - d * (e2.dot(n) / d.dot(n))) * r;
        let ratio = (major.length() / minor.length()).ceil();
        Footprint {
            minor,
            major,
            taps: taps_of(ratio),
        }
    }
}

/// Taps for the ratio ⌈|major| / |minor|⌉: at least 1, at most `MAX_TAPS`.
#[inline(always)]
fn taps_of(ratio: f64) -> u32 {
    if ratio >= 1.0 {
        ratio.min(f64::from(MAX_TAPS)) as u32
    } else {
        1
    }
}

/// One tap: its centre, its offset from the hit, and its ellipse's semi-axis vectors.
struct Tap {
    p: DVec3,
    offset: DVec3,
    minor: DVec3,
    major: DVec3,
}

impl Tap {
    /// The half-extent of the tap's ellipse along the unit vector `a`: √((minor·a)² + (major·a)²);
    /// infinite when it is not finite.
    #[inline(always)]
    fn extent(&self, a: DVec3) -> f64 {
        let (x, y) = (self.minor.dot(a), self.major.dot(a));
        let e = (x * x + y * y).sqrt();
        if e.is_finite() { e } else { f64::INFINITY }
    }
}

/// The line a lookup's taps lie on: tap k of `taps` is centred at
/// `p + major · (((2k + 1) − taps) / taps)`, with the coordinates in `held` set.
struct Line {
    p: DVec3,
    major: DVec3,
    taps: u32,
    held: [Option<f64>; 3],
}

impl Line {
    /// Tap k's centre.
    #[inline(always)]
    fn centre(&self, k: u32) -> DVec3 {
        let taps = f64::from(self.taps);
        let step = (f64::from(2 * k + 1) - taps) / taps;
        snapped(&self.held, self.p + self.major * step)
    }
}

/// Σ over the line's taps of `checker`, summed from tap 0 up, starting at 0: four taps at a time
/// where the CPU has AVX2 (`taps`, the same bits), else one at a time.
#[inline(always)]
fn checker_line<R: Round>(size: f64, colors: &[DVec3; 2], line: &Line, half: &[f64; 3]) -> DVec3 {
    #[cfg(target_arch = "x86_64")]
    if line.taps > 1 && std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2.
        return unsafe { taps::checker_sum(size, colors, line, half) };
    }
    checker_taps_one_by_one::<R>(size, colors, line, half)
}

/// `checker_line` one tap at a time: the rule as docs/spec/texture.md writes it.
#[inline(always)]
fn checker_taps_one_by_one<R: Round>(
    size: f64,
    colors: &[DVec3; 2],
    line: &Line,
    half: &[f64; 3],
) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for k in 0..line.taps {
        sum += checker::<R>(size, colors, line.centre(k), half);
    }
    sum
}

/// The checker averaged over a tap's bounding box, centred on `p` with half-widths `half` in
/// cells: the product of three square waves, averaged axis by axis (their product's average
/// over a box is the product of their averages); colour weights (1 ± A)/2.
#[inline(always)]
fn checker<R: Round>(size: f64, colors: &[DVec3; 2], p: DVec3, half: &[f64; 3]) -> DVec3 {
    let p = p.to_array();
    let mut a = 1.0;
    for i in 0..3 {
        a *= square_average_with::<R>(p[i] / size, half[i]);
    }
    colors[0] * (0.5 + 0.5 * a) + colors[1] * (0.5 - 0.5 * a)
}

/// ⌊x⌋, bit for bit what `f64::floor` gives (−0 included), without its call: the kernels'
/// scalar code is built for the baseline x86-64, which has no rounding instruction, and the
/// library's floor cost the checker a third of its frame (each tap takes up to a dozen).
#[inline(always)]
pub fn floor(x: f64) -> f64 {
    // Beyond 2⁵² every f64 is an integer (and NaN and ±∞ are their own floor).
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        return x;
    }
    let t = x as i64 as f64;
    let t = if t > x { t - 1.0 } else { t };
    t.copysign(x)
}

/// Half-widths below this many cells count as 0.
pub const TINY_BOX: f64 = 1e-12;

/// S on cell k (a whole number, or ±∞ or NaN): +1 where k is even, −1 where it is odd; this
/// is the spec's k − 2⌊k/2⌋ == 0 without its floor. Below 2⁵³ the test is the integer's
/// parity, every finite f64 beyond is even, and ±∞ and NaN count as odd (the spec's
/// difference is NaN there).
#[inline(always)]
fn sign(k: f64) -> f64 {
    let even = if k.abs() < 9_007_199_254_740_992.0 {
        // SAFETY: below 2⁵³ in magnitude, k truncates to a value an i64 holds, so the cast
        // needs none of `as`'s saturating checks.
        (unsafe { k.to_int_unchecked::<i64>() } & 1) == 0
    } else {
        k.is_finite()
    };
    if even { 1.0 } else { -1.0 }
}

/// The average over [x − h, x + h] of S(u) = +1 where ⌊u⌋ is even, −1 where it is odd.
pub fn square_average(x: f64, h: f64) -> f64 {
    square_average_with::<Portable>(x, h)
}

#[inline(always)]
fn square_average_with<R: Round>(x: f64, h: f64) -> f64 {
    if h.is_nan() || h == f64::INFINITY {
        return 0.0;
    }
    // A box this narrow is rounding noise (a floor's extent along its own normal): a point
    // sample, so a surface lying on a cell boundary takes the cell above it.
    if h < TINY_BOX {
        return sign(R::floor(x));
    }
    let (a, b) = (x - h, x + h);
    let (ka, kb) = (R::floor(a), R::floor(b));
    if ka == kb {
        sign(ka)
    } else if kb == ka + 1.0 {
        (sign(ka) * (kb - a) + sign(kb) * (b - kb)) / (b - a)
    } else {
        (triangle::<R>(b) - triangle::<R>(a)) / (b - a)
    }
}

/// ∫₀ᵘ S: the triangle wave f for f = u − 2⌊u/2⌋ < 1, else 2 − f.
#[inline(always)]
fn triangle<R: Round>(u: f64) -> f64 {
    let f = u - 2.0 * R::floor(u / 2.0);
    if f < 1.0 { f } else { 2.0 - f }
}

/// The default direction of a plane's u: for a plane facing mostly along x (|n.x| > 0.5),
/// (0, 0, −sign n.x), else +x; projected into the plane and made unit length.
pub fn plane_u_axis(normal: DVec3, given: Option<DVec3>) -> DVec3 {
    given.unwrap_or_else(|| {
        let a = if normal.x.abs() > 0.5 {
            DVec3::new(0.0, 0.0, -normal.x.signum())
        } else {
            DVec3::X
        };
        (a - normal * a.dot(normal)).normalize()
    })
}

/// Texture coordinates (u, v) of the tap and its width in level-0 texels.
#[inline(always)]
fn coordinates(scene: &Scene, image: &Image, scale: DVec2, at: &At, tap: &Tap) -> (f64, f64, f64) {
    let level0 = &image.levels[0];
    let (w, h) = (f64::from(level0.width), f64::from(level0.height));
    let (sx, sy) = (scale.x.abs(), scale.y.abs());
    match scene.objects[at.object].shape {
        Shape::Plane { normal, u_axis, .. } => {
            let ua = plane_u_axis(normal, u_axis);
            let va = normal.cross(ua);
            let texels = (2.0 * tap.extent(ua) * sx * w).max(2.0 * tap.extent(va) * sy * h);
            (tap.p.dot(ua), tap.p.dot(va), texels)
        }
        Shape::Sphere { center, radius } => {
            let q = (tap.p - center).normalize();
            let u = 0.5 - libm::atan2(q.z, q.x) / (2.0 * PI);
            let v = 1.0 - libm::acos(q.y.clamp(-1.0, 1.0)) / PI;
            let ring = (q.x * q.x + q.z * q.z).sqrt();
            let across = if ring > 0.0 {
                let t_u = DVec3::new(-q.z / ring, 0.0, q.x / ring);
                2.0 * tap.extent(t_u) * sx * w / (2.0 * PI * radius * ring)
            } else {
                f64::INFINITY
            };
            let t_v = q.cross(DVec3::new(-q.z, 0.0, q.x)).normalize_or_zero();
            let along = 2.0 * tap.extent(t_v) * sy * h / (PI * radius);
            (u, v, across.max(along))
        }
        Shape::Mesh { mesh, place, .. } => {
            let m = &scene.meshes[mesh];
            let tri = m.triangles[at.prim as usize];
            let uvs = m
                .uvs
                .as_ref()
                .expect("checked at load: image maps need UVs");
            let t = tri.map(|i| uvs[i as usize]);
            let (b1, b2) = at.bary;
            let q = tri.map(|i| place.point(m.positions[i as usize]));
            let (e1, e2) = (q[1] - q[0], q[2] - q[0]);
            // The tap's offset in the triangle's edge coordinates (least squares).
            let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let (r1, r2) = (tap.offset.dot(e1), tap.offset.dot(e2));
            let det = g11 * g22 - g12 * g12;
            let (alpha, beta) = ((g22 * r1 - g12 * r2) / det, (g11 * r2 - g12 * r1) / det);
            let uv = t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
            let uv = uv + (t[1] - t[0]) * alpha + (t[2] - t[0]) * beta;
            let world_area = e1.cross(e2).length();
            let uv_area = (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
            let density = (w * h * sx * sy * uv_area / world_area).sqrt();
            let reach = tap.minor.length().max(tap.major.length());
            (uv.x, uv.y, density * (2.0 * reach))
        }
    }
}

/// The image at the tap: trilinear between the two mip levels around log2 of its width in
/// texels.
#[inline(always)]
fn image_color<R: Round>(scene: &Scene, image: &Image, scale: DVec2, at: &At, tap: &Tap) -> DVec3 {
    let (u, v, texels) = coordinates(scene, image, scale, at, tap);
    let (u, v) = (u * scale.x, v * scale.y);
    let last = image.levels.len() - 1;
    let mean = |l: &Level| DVec3::from_array(l.texels[0].map(f64::from));
    if !(u.is_finite() && v.is_finite()) {
        return mean(&image.levels[last]);
    }
    trilinear_with::<R>(image, texels, |level| bilinear_with::<R>(level, u, v))
}

/// `sample` of the two mip levels around log2 of a footprint `texels` level-0 texels wide,
/// blended by the fraction: the level and blend rule of docs/spec/texture.md (image lookups
/// and the sky).
pub(super) fn trilinear(image: &Image, texels: f64, sample: impl Fn(&Level) -> DVec3) -> DVec3 {
    trilinear_with::<Portable>(image, texels, sample)
}

#[inline(always)]
fn trilinear_with<R: Round>(image: &Image, texels: f64, sample: impl Fn(&Level) -> DVec3) -> DVec3 {
    let last = image.levels.len() - 1;
    let lod = if texels > 1.0 {
        libm::log2(texels)
    } else {
        0.0
    };
    if lod.is_nan() || lod >= last as f64 {
        return sample(&image.levels[last]);
    }
    let l = R::floor(lod);
    let f = lod - l;
    let c = sample(&image.levels[l as usize]);
    if f == 0.0 {
        return c;
    }
    c * (1.0 - f) + sample(&image.levels[l as usize + 1]) * f
}

/// Bilinear interpolation at (u, v) repeated: texel (i, j)'s centre is at
/// u = (i + 0.5)/width, v = 1 − (j + 0.5)/height (row 0 at the top, v = 1).
pub fn bilinear(level: &Level, u: f64, v: f64) -> DVec3 {
    bilinear_with::<Portable>(level, u, v)
}

#[inline(always)]
fn bilinear_with<R: Round>(level: &Level, u: f64, v: f64) -> DVec3 {
    let (w, h) = (f64::from(level.width), f64::from(level.height));
    let x = (u - R::floor(u)) * w - 0.5;
    let y = (1.0 - (v - R::floor(v))) * h - 0.5;
    let (x0, y0) = (R::floor(x), R::floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let wrap = |i: f64, n: u32| (i as i64).rem_euclid(i64::from(n)) as u32;
    let (i0, j0) = (wrap(x0, level.width), wrap(y0, level.height));
    let (i1, j1) = ((i0 + 1) % level.width, (j0 + 1) % level.height);
    let t = |i: u32, j: u32| {
        DVec3::from_array(level.texels[(j * level.width + i) as usize].map(f64::from))
    };
    (t(i0, j0) * (1.0 - fx) + t(i1, j0) * fx) * (1.0 - fy)
        + (t(i0, j1) * (1.0 - fx) + t(i1, j1) * fx) * fy
}

/// `colors` on the lanes of `painted` (bit k for lane k), `fallback` on the others.
#[inline(always)]
pub(super) fn lanes<V: Lanes>(painted: u32, colors: &[DVec3; MAX_LANES], fallback: V3<V>) -> V3<V> {
    if painted == 0 {
        return fallback;
    }
    V3::select(
        V::M::from_bits(painted),
        V3::from_fn(|k| colors[k]),
        fallback,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The box average is exact where the box stays in one cell, converges to 0 (the mean)
    /// as the box grows, and matches a fine numerical average across boundaries.
    #[test]
    fn square_average_is_the_box_mean_of_the_square_wave() {
        assert_eq!(square_average(0.25, 0.0), 1.0);
        assert_eq!(square_average(1.25, 0.2), -1.0);
        assert_eq!(square_average(-0.5, 0.1), -1.0);
        assert_eq!(square_average(3.0, f64::INFINITY), 0.0);
        assert_eq!(square_average(0.0, 1e-17), 1.0);
        assert_eq!(square_average(-1e-300, 0.0), -1.0);
        for (x, h) in [
            (0.9, 0.3),
            (2.0, 1.7),
            (-3.3, 5.1),
            (10.5, 0.75),
            (0.0, 1e-9),
            (0.0, 2e-12),
        ] {
            let n = 200_000;
            let s = |u: f64| {
                if u.floor().rem_euclid(2.0) == 0.0 {
                    1.0
                } else {
                    -1.0
                }
            };
            let numeric = (0..n)
                .map(|i| s(x - h + 2.0 * h * (i as f64 + 0.5) / n as f64))
                .sum::<f64>()
                / n as f64;
            let got = square_average(x, h);
            assert!(
                (got - numeric).abs() < 1e-4,
                "({x}, {h}): {got} vs {numeric}"
            );
        }
        assert!(square_average(0.3, 1e6).abs() < 1e-6);
    }

    /// The inlined floor gives f64::floor's bits, signed zeros and the edges of f64 included.
    #[test]
    fn floor_is_the_library_floor_bit_for_bit() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1e-300,
            -1e-300,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            -4_503_599_627_370_497.0,
            9.3e18,
            -9.3e18,
            1e300,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            f64::EPSILON,
            1.0 - f64::EPSILON / 2.0,
            -(1.0 - f64::EPSILON / 2.0),
        ];
        let mut z = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..100_000 {
            z = z.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            xs.push(f64::from_bits(z));
            xs.push((z >> 11) as f64 * 2f64.powi(-40) - 4096.0);
        }
        for x in xs.into_iter().filter(|x| !x.is_nan()) {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x:e}");
        }
        assert!(floor(f64::NAN).is_nan());
    }

    /// Lookups built with SSE4.1 (the library's floor) and without (`floor`) give the same
    /// bits: box averages, bilinear taps and the mip level, on values across cell edges, far
    /// from the origin, signed zeros and non-finite ones.
    #[test]
    fn both_builds_of_a_lookup_agree() {
        let mut xs = vec![
            0.0, -0.0, 1.0, -1.0, 0.5, -2.5, 1e-300, 4.5e15, -9.1e15, 3e300,
        ];
        xs.extend([f64::INFINITY, f64::NEG_INFINITY, f64::NAN]);
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for _ in 0..4000 {
            state = crate::tracer::sample::mix(state);
            let scale = [1e-6, 0.01, 1.0, 37.0, 1e5, 1e12][(state % 6) as usize];
            xs.push(((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * scale);
        }
        let level = Level {
            width: 3,
            height: 2,
            texels: (0..6)
                .map(|i| [i as f32, 0.5 * i as f32, 1.0 - i as f32])
                .collect(),
        };
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        let both = |x: f64, h: f64| {
            let p = square_average_with::<Portable>(x, h);
            let n = square_average_with::<Native>(x, h);
            assert!(same(p, n), "square_average({x:e}, {h:e}): {p:e} vs {n:e}");
            if x.is_finite() && h.is_finite() {
                let (p, n) = (
                    bilinear_with::<Portable>(&level, x, h),
                    bilinear_with::<Native>(&level, x, h),
                );
                assert_eq!(
                    p.to_array().map(f64::to_bits),
                    n.to_array().map(f64::to_bits)
                );
            }
            assert!(same(Portable::floor(x), Native::floor(x)), "floor({x:e})");
        };
        for (i, &x) in xs.iter().enumerate() {
            for h in [0.0, 1e-13, 0.3, xs[(i * 7 + 3) % xs.len()].abs()] {
                both(x, h);
            }
        }
    }

    /// The parity test gives the spec's k − 2⌊k/2⌋ == 0 on every whole number, ±∞ and NaN.
    #[test]
    fn sign_is_the_spec_parity() {
        let spec = |k: f64| {
            if k - 2.0 * (k / 2.0).floor() == 0.0 {
                1.0
            } else {
                -1.0
            }
        };
        let mut ks = vec![0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
        for e in [0, 1, 2, 20, 52, 53, 54, 62, 63, 64, 100, 1023] {
            let b = 2f64.powi(e);
            ks.extend([
                b,
                -b,
                b - 1.0,
                1.0 - b,
                b + 1.0,
                -b - 1.0,
                b + 2.0,
                -b - 2.0,
            ]);
        }
        ks.extend((-1000..1000).map(f64::from));
        for k in ks {
            assert_eq!(sign(k), spec(k), "{k:e}");
        }
    }

    #[test]
    fn default_plane_axes_keep_images_upright() {
        assert_eq!(plane_u_axis(DVec3::Y, None), DVec3::X);
        assert_eq!(DVec3::Y.cross(plane_u_axis(DVec3::Y, None)), -DVec3::Z);
        let wall = DVec3::Z;
        assert_eq!(wall.cross(plane_u_axis(wall, None)), DVec3::Y);
        for n in [DVec3::X, -DVec3::X] {
            assert_eq!(n.cross(plane_u_axis(n, None)), DVec3::Y, "{n}");
        }
    }
}
