//! Whitted shading of a packet of rays: Blinn-Phong per light with hard shadows, and mirror
//! reflection, for any lane type.
//!
//! At a hit with normal N facing the incoming ray d, for each light: ka∘ia always; if the light
//! is not blocked, kd∘id·max(0, N·L) and, when N·L > 0, ks∘is·max(0, N·H)^(shininess/4) with
//! H = normalize(L − d); `path` sums what the surfaces of a path send back. Each lane performs
//! exactly the operations, in exactly the order, of one scalar ray.

use super::World;
use super::accel::{Nearest, Rays};
use super::path::LightSeeds;
use super::polygon::MeshLanes;
use super::texture::{self, At, PixelRays};
use crate::lanes::{F64x1, Lanes, MAX_LANES, Mask, V3};
use crate::scene::Texture;
use crate::scene::{Intensity, Light, Material, Shape};
use glam::DVec3;

/// Below this weight a reflection cannot change any output value (f32 colours, half-float
/// EXRs and 16-bit PNGs alike), so the path ends rather than crawl through subnormals.
pub(super) const NEGLIGIBLE_WEIGHT: f64 = 1e-30;

/// Exponents up to this are whole-number powers by repeated squaring; larger or fractional
/// ones go through `libm::pow`.
const MAX_WHOLE_EXPONENT: f64 = 4096.0;

/// How far, and along which normal, rays leaving a mesh start off its surface (see
/// `polygon::lift_distance`): `normal` faces the incoming ray, `delta` is 0 on other lanes.
pub(super) struct Lift<V: Lanes> {
    pub normal: V3<V>,
    pub delta: V,
}

impl<V: Lanes> Lift<V> {
    /// `point` moved δ along the normal to the side `dir` leaves to: +δ when normal·dir ≥ 0.
    #[inline(always)]
    pub(super) fn origin(&self, point: V3<V>, dir: V3<V>) -> V3<V> {
        point + self.normal * self.delta.copysign(self.normal.dot(dir))
    }
}

/// A packet's hits, shaded: what the rays see there, and what the path needs to go on.
pub(super) struct Shaded<'a, V: Lanes> {
    pub surface: Surface<'a, V>,
    pub point: V3<V>,
    /// Set when a lane hit a mesh: rays leaving the hits start from `leave`.
    pub lift: Option<Lift<V>>,
    /// The unit normal, turned to face the incoming ray.
    pub normal: V3<V>,
    /// Lanes whose ray meets the surface from outside (its outward normal faces the ray).
    pub entering: V::M,
    /// The light the surface sends back: the local Blinn-Phong terms of every light.
    pub local: V3<V>,
    /// Lanes at the hit (station 0) that some light did not reach whole: facing away,
    /// blocked, or an area light's lane or point left out (docs/spec/tracer.md, *Smooth
    /// pixels*). Only `path`'s smooth-pixel walk reads it; elsewhere it compiles away.
    pub dark: V::M,
}

/// Shades the lanes `hit.hit` (at least one) of a packet; `footprint` is the rays' cone
/// width at the hits when the scene has textures, with the eye rays' pixels at their first
/// hits when it has a checker.
#[inline(always)]
pub(super) fn shade_hit<'a, V: Lanes>(
    world: &'a World,
    ray: &Rays<V>,
    hit: &Nearest<V>,
    seeds: Option<LightSeeds>,
    rays: &mut u64,
    footprint: Option<(V, Option<&PixelRays<V>>)>,
) -> Shaded<'a, V> {
    let mut surface = Surface::gather(world, hit);
    let point = ray.origin + ray.dir * hit.t;
    let (mut normal, mut entering) = surface.normal(point, ray.dir);
    let mesh = match world.has_meshes() {
        true => MeshLanes::of(world, hit, point),
        false => None,
    };
    let mut lift = None;
    let mut here = hit.hit;
    if let Some(m) = &mesh {
        let at = m.facing(ray.dir, normal, entering);
        (normal, entering, lift, here) = (at.0, at.1, Some(at.2), here.andnot(m.elsewhere()));
    }
    if let Some(f) = footprint {
        surface.paint(world, hit, ray, (point, normal), f);
    }
    // Station 0 lights the hit; on `gouraud` and `constant` lanes stations 1–3 light the
    // vertices and 4 the centroid (`polygon`). One call of `local` keeps the kernels small.
    let stations = match &mesh {
        Some(m) if m.elsewhere().any() => 5,
        _ => 1,
    };
    // The hit's light, and the other stations' only where a mesh needs them: zeroing five
    // vectors of lanes for every hit cost the mesh-free scenes a memset.
    let mut lit0 = V3::zero();
    let mut dark = V::M::none_set();
    let mut others: Option<[V3<V>; 4]> = None;
    for station in 0..stations {
        let (lanes, p, n, view, at) = match (station, &mesh, &lift) {
            (1.., Some(m), Some(l)) => {
                let s = m.station(station - 1, ray, l);
                (s.lanes, s.point, s.normal, s.view, Some(s.lift))
            }
            _ => (here, point, normal, ray.dir, None),
        };
        if !lanes.any() {
            continue;
        }
        let here = Here {
            point: p,
            normal: n,
            dir: view,
            object: hit.object,
            lift: at.as_ref().or(lift.as_ref()),
        };
        let (c, unlit) = local(world, &surface, &here, lanes, seeds, rays);
        match station {
            0 => (lit0, dark) = (c, unlit),
            s => others.get_or_insert([V3::zero(); 4])[s - 1] = c,
        }
    }
    let local = match (&mesh, others) {
        (Some(m), others) if stations > 1 => {
            let o = others.unwrap_or([V3::zero(); 4]);
            m.mixed(&[lit0, o[0], o[1], o[2], o[3]])
        }
        _ => lit0,
    };
    Shaded {
        surface,
        point,
        lift,
        normal,
        entering,
        local,
        dark,
    }
}

/// One ray's first surface as the compositing passes see it (`aov`): the shading normal
/// turned to face the ray (a mesh's interpolated one) and the diffuse colour (a texture's,
/// filtered over the cone width `width`, where the material has one). No light is computed.
pub(super) fn first_surface(
    world: &World,
    ray: &Rays<F64x1>,
    hit: &Nearest<F64x1>,
    width: Option<(F64x1, Option<&PixelRays<F64x1>>)>,
) -> (DVec3, DVec3) {
    let mut surface = Surface::gather(world, hit);
    let point = ray.origin + ray.dir * hit.t;
    let (mut normal, entering) = surface.normal(point, ray.dir);
    if let Some(m) = MeshLanes::of(world, hit, point) {
        normal = m.facing(ray.dir, normal, entering).0;
    }
    if let Some(f) = width {
        surface.paint(world, hit, ray, (point, normal), f);
    }
    (normal.lane(0), surface.diffuse.lane(0))
}

/// Lanes `first .. first + 4` of `v`, axis by axis (0 past the packet's lanes).
#[inline(always)]
fn quad<V: Lanes>(v: &V3<V>, first: usize) -> texture::Quad {
    quarter(&axes(v), first)
}

/// Lanes `first .. first + 4` of `a`.
#[inline(always)]
fn quarter(a: &texture::Axes, first: usize) -> texture::Quad {
    a.map(|x| std::array::from_fn(|j| x[first + j]))
}

/// The lanes of `v`, axis by axis. A function, not a closure: a closure is compiled outside
/// the kernel's `#[target_feature]` function, its stores then calls.
#[inline(always)]
fn axes<V: Lanes>(v: &V3<V>) -> texture::Axes {
    [v.x.array(), v.y.array(), v.z.array()]
}

impl<V: Lanes> Shaded<'_, V> {
    /// The mirror rays: from the hit point along d − 2(d·N)N, leaving the hit object.
    #[inline(always)]
    pub(super) fn reflected(&self, ray: &Rays<V>, hit: &Nearest<V>) -> Rays<V> {
        let n = self.normal;
        let bounce = ray.dir - n * (V::splat(2.0) * ray.dir.dot(n));
        let dir = bounce.normalize();
        Rays {
            origin: self.leave(dir),
            dir,
            leaving: hit.object,
        }
    }

    /// Where rays leaving the hits along `dir` start: the hit point, lifted off meshes.
    #[inline(always)]
    pub(super) fn leave(&self, dir: V3<V>) -> V3<V> {
        match &self.lift {
            None => self.point,
            Some(l) => l.origin(self.point, dir),
        }
    }
}

/// What shading needs to know about the objects the lanes hit.
pub(super) struct Surface<'a, V: Lanes> {
    /// Sphere lanes: the centre.
    center: V3<V>,
    /// Plane lanes: the unit normal.
    plane_normal: V3<V>,
    is_plane: V::M,
    ambient: V3<V>,
    diffuse: V3<V>,
    specular: V3<V>,
    pub reflection: V,
    /// Each lane's material: one reference when every lane hit the same object (the common
    /// case, shaded with splatted constants), else one per lane.
    pub materials: [&'a Material; MAX_LANES],
    pub shared: bool,
    /// Every lane's material has the same specular exponent (and so the same floor): the
    /// lanes' powers are taken together, as for one shared material.
    one_exponent: bool,
    /// Bit k: lane k's every texture is a checker that took its pixel's mean (`paint`).
    pub meaned: u32,
}

impl<'a, V: Lanes> Surface<'a, V> {
    #[inline(always)]
    fn gather(world: &'a World, hit: &Nearest<V>) -> Surface<'a, V> {
        let scene = &world.scene;
        let lead = hit.hit.bits().trailing_zeros() as usize;
        let first = hit.object.lane(lead);
        let shared = hit.hit.andnot(hit.object.eq(V::splat(first))).bits() == 0;
        if shared {
            let object = &scene.objects[first as usize];
            let m = &scene.materials[object.material];
            let (center, normal, is_plane) = anchor(object.shape);
            return Surface {
                center: V3::splat(center),
                plane_normal: V3::splat(normal),
                is_plane: if is_plane {
                    V::M::first(V::N)
                } else {
                    V::M::none_set()
                },
                ambient: V3::splat(m.ambient),
                diffuse: V3::splat(m.diffuse),
                specular: V3::splat(m.specular),
                reflection: V::splat(m.reflection),
                materials: [m; MAX_LANES],
                shared,
                one_exponent: true,
                meaned: 0,
            };
        }
        let mut objects = [first as usize; MAX_LANES];
        {
            let ids = hit.object.array();
            for (k, o) in objects.iter_mut().enumerate().take(V::N) {
                if hit.hit.lane(k) {
                    *o = ids[k] as usize;
                }
            }
        }
        // Closures below see plain f64 only: a closure is compiled on its own, outside the
        // kernel's `#[target_feature]` function, so lane operations must stay out of it.
        // Only the packet's lanes: the rest keep the first lane's material and anchor.
        let material = |k: usize| &scene.materials[scene.objects[objects[k]].material];
        let mut materials: [&Material; MAX_LANES] = [material(lead); MAX_LANES];
        let mut anchors = [anchor(scene.objects[first as usize].shape); MAX_LANES];
        for k in 0..V::N {
            materials[k] = material(k);
            anchors[k] = anchor(scene.objects[objects[k]].shape);
        }
        let plane_bits = (0..V::N)
            .filter(|&k| anchors[k].2)
            .fold(0, |b, k| b | 1 << k);
        Surface {
            center: V3::from_fn(|k| anchors[k].0),
            plane_normal: V3::from_fn(|k| anchors[k].1),
            is_plane: V::M::from_bits(plane_bits),
            ambient: V3::from_fn(|k| materials[k].ambient),
            diffuse: V3::from_fn(|k| materials[k].diffuse),
            specular: V3::from_fn(|k| materials[k].specular),
            reflection: V::from_fn(|k| materials[k].reflection),
            one_exponent: (materials[1..V::N].iter())
                .all(|m| m.exponent.to_bits() == materials[0].exponent.to_bits()),
            materials,
            shared,
            meaned: 0,
        }
    }

    /// The unit normal at `point`, turned to face the incoming ray, and the lanes whose ray
    /// comes from outside (a sphere's outside, a plane's front).
    #[inline(always)]
    pub(super) fn normal(&self, point: V3<V>, dir: V3<V>) -> (V3<V>, V::M) {
        let sphere = (point - self.center).normalize();
        let n = V3::select(self.is_plane, self.plane_normal, sphere);
        let inside = n.dot(dir).gt(V::splat(0.0));
        (V3::select(inside, -n, n), V::M::first(V::N).andnot(inside))
    }

    /// Replaces the diffuse and ambient colours of the lanes whose material has a texture by
    /// the texture's, filtered over the footprint of cone width `width` (a checker over the
    /// eye ray's `pixel` where there is one and the rule allows).
    #[inline(always)]
    fn paint(
        &mut self,
        world: &World,
        hit: &Nearest<V>,
        ray: &Rays<V>,
        (p, n): (V3<V>, V3<V>),
        (width, pixel): (V, Option<&PixelRays<V>>),
    ) {
        let hits = hit.hit.bits();
        let textured = (0..V::N)
            .filter(|&k| hits >> k & 1 == 1 && self.materials[k].textured())
            .fold(0u32, |m, k| m | 1 << k);
        if textured == 0 {
            return;
        }
        let (diffuse, ambient, meaned) =
            self.lookups(world, hit, ray, (p, n), (width, pixel), textured);
        (self.diffuse, self.ambient) = (diffuse, ambient);
        self.meaned |= meaned;
    }

    /// `paint`'s lookups for the lanes in `textured`: the new diffuse and ambient lanes, and
    /// the lanes whose every map took the pixel's mean.
    #[inline(always)]
    fn lookups(
        &self,
        world: &World,
        hit: &Nearest<V>,
        ray: &Rays<V>,
        (p, n): (V3<V>, V3<V>),
        (width, pixel): (V, Option<&PixelRays<V>>),
        textured: u32,
    ) -> (V3<V>, V3<V>, u32) {
        let (o, d) = (ray.origin, ray.dir);
        let (p, n, d) = (axes(&p), axes(&n), axes(&d));

        let (width, object, u, v) = (
            width.array(),
            hit.object.array(),
            hit.u.array(),
            hit.v.array(),
        );
        // Each textured lane's lookups, written into per-lane colours (only the packet's
        // lanes: building a footprint record for all MAX_LANES cost more than the lookups'
        // bookkeeping). Footprints are made four lanes at a time.
        let mut colors = [[DVec3::ZERO; MAX_LANES]; 2];
        let mut painted = [0u32; 2];
        let mut meaned = 0u32;
        for first in (0..V::N).step_by(4) {
            let lanes = textured >> first & 0xf;
            if lanes == 0 {
                continue;
            }
            // Each lane's hit as lookups see it, and first a checker's mean over the eye ray's
            // pixel: a lane whose every map that answers needs no footprint.
            let checkered = (0..4).fold(0u32, |m, j| {
                let k = first + j;
                m | u32::from(lanes >> j & 1 == 1 && self.materials[k.min(V::N - 1)].checkered())
                    << j
            });
            let patches = match pixel {
                Some(q) if checkered != 0 => {
                    let rays = (
                        quad(&q.centre, first),
                        quad(&q.right, first),
                        quad(&q.down, first),
                    );
                    let (p, n) = (quarter(&p, first), quarter(&n, first));
                    texture::patches(
                        (&quad(&o, first), &p, &n),
                        (&rays.0, &rays.1, &rays.2),
                        checkered,
                    )
                }
                _ => [None; 4],
            };
            let ats: [Option<At>; 4] = std::array::from_fn(|j| {
                let k = first + j;
                (lanes >> j & 1 == 1).then(|| At {
                    p: DVec3::new(p[0][k], p[1][k], p[2][k]) + world.origin,
                    r: 0.5 * width[k],
                    object: object[k] as usize,
                    prim: hit.prim[k],
                    bary: (u[k], v[k]),
                    patch: patches[j],
                })
            });
            let mut left = 0u32;
            for c in 0..2 {
                let maps: [Option<&Texture>; 4] = std::array::from_fn(|j| {
                    let m = self.materials[(first + j).min(V::N - 1)];
                    let map = [&m.diffuse_map, &m.ambient_map][c];
                    map.as_ref().filter(|_| lanes >> j & 1 == 1)
                });
                let has = maps.map(|m| m.is_some());
                let found = match has.contains(&true) && patches.iter().any(Option::is_some) {
                    true => texture::pixel_colors(world, maps, &ats),
                    false => [None; 4],
                };
                for j in 0..4 {
                    let k = first + j;
                    match (has[j], found[j]) {
                        (true, Some(colour)) => {
                            colors[c][k] = colour;
                            painted[c] |= 1 << k;
                        }
                        (true, None) => left |= 1 << j,
                        _ => {}
                    }
                }
            }
            meaned |= (lanes & !left) << first;
            if left == 0 {
                continue;
            }
            let fs = texture::footprints((&n, &d, &width), first, left);
            for (j, (f, at)) in fs.iter().zip(&ats).enumerate() {
                let (Some(f), Some(at)) = (f, at) else {
                    continue;
                };
                let k = first + j;
                let m = self.materials[k];
                for (c, map) in [&m.diffuse_map, &m.ambient_map].into_iter().enumerate() {
                    if let Some(t) = map
                        && painted[c] >> k & 1 == 0
                    {
                        colors[c][k] = texture::color(world, t, at, f);
                        painted[c] |= 1 << k;
                    }
                }
            }
        }
        let [diffuse, ambient] = colors;
        (
            texture::lanes(painted[0], &diffuse, self.diffuse),
            texture::lanes(painted[1], &ambient, self.ambient),
            meaned,
        )
    }

    /// max(0, N·H)^exponent per lane (see `specular_power`). The floor below which a power is
    /// 0 is a function of the exponent alone (`sequence::scene::material`), so lanes of one
    /// exponent take the first lane's material's.
    #[inline(always)]
    fn specular_power(&self, x: V) -> V {
        if self.one_exponent {
            return specular_power(x, self.materials[0]);
        }
        let x = x.array();
        V::from_fn(|k| specular_power(V::One::splat(x[k]), self.materials[k]).lane(0))
    }
}

/// A sphere's centre or a plane's normal, and whether it is a plane.
#[inline(always)]
fn anchor(shape: Shape) -> (DVec3, DVec3, bool) {
    match shape {
        Shape::Sphere { center, .. } => (center, DVec3::ZERO, false),
        Shape::Plane { normal, .. } => (DVec3::ZERO, normal, true),
        // Replaced by the triangle's normals (`polygon`); a plane's form avoids a division.
        Shape::Mesh { .. } => (DVec3::ZERO, DVec3::Y, true),
    }
}

/// A surface point per lane, as lights see it: `dir` is the incoming ray's direction, and
/// shadow rays start at `point`, or lifted off a mesh by `lift`, leaving `object`.
pub(super) struct Here<'l, V: Lanes> {
    pub point: V3<V>,
    pub normal: V3<V>,
    pub dir: V3<V>,
    pub object: V,
    pub lift: Option<&'l Lift<V>>,
}

/// Sum over the lights of the Blinn-Phong terms at one surface point per lane, and the lanes
/// of `active` some light did not reach whole (see `shine`).
#[inline(always)]
pub(super) fn local<V: Lanes>(
    world: &World,
    s: &Surface<V>,
    at: &Here<V>,
    active: V::M,
    seeds: Option<LightSeeds>,
    rays: &mut u64,
) -> (V3<V>, V::M) {
    let point = at.point;
    let mut sum = V3::zero();
    let mut dark = V::M::none_set();
    for (index, light) in world.scene.lights.iter().enumerate() {
        let (to_light, distance, scale, i) = match *light {
            Light::Ambient { color } => {
                sum = sum + s.ambient * V3::splat(color);
                continue;
            }
            Light::Point {
                position,
                intensity,
            } => {
                let (l, d) = towards(point, V3::splat(position));
                (l, d, None, intensity)
            }
            Light::Directional {
                to_light,
                intensity,
            } => (
                V3::splat(to_light),
                V::splat(f64::INFINITY),
                None,
                intensity,
            ),
            Light::Spot {
                position,
                axis,
                cos_inner,
                cos_outer,
                intensity,
            } => {
                let (l, d) = towards(point, V3::splat(position));
                let falloff = smoothstep(cos_outer, cos_inner, -l.dot(V3::splat(axis)));
                (l, d, Some(falloff), intensity)
            }
            Light::Sphere { intensity, .. } | Light::Rect { intensity, .. } => {
                // The ambient term once, then the light's points.
                let ambient = s.ambient * V3::splat(intensity.ambient);
                sum = V3::select(active, sum + ambient, sum);
                // Out of line: inlined, the area light's lane code crowded the registers of
                // every light's loop and cost mesh- and area-free frames 1–2% in instructions.
                let area = (light, index);
                let unlit = V::outlined(
                    #[inline(always)]
                    || super::area::light(world, s, at, area, active, seeds, &mut sum, rays),
                );
                dark = dark.or(unlit);
                continue;
            }
        };
        let lit_at_all = match scale {
            Some(f) => active.andnot(f.eq(V::splat(0.0))),
            None => active,
        };
        let ambient = scaled(scale, s.ambient) * V3::splat(i.ambient);
        sum = V3::select(lit_at_all, sum + ambient, sum);
        let unlit = shine(
            world,
            s,
            at,
            (lit_at_all, None),
            (to_light, distance),
            &Tints::new(s, &i),
            scale,
            &mut sum,
            rays,
        );
        dark = dark.or(unlit);
    }
    (sum, dark)
}

/// Adds to `sum`, on the lanes of `lit` that face it (N·L > 0, or NaN) and see it past every
/// opaque object, the diffuse and specular light coming from `to_light` (a unit vector, or 0)
/// from `distance` away, filtered by glass on the way and scaled by `scale`. Lanes of `seen`,
/// when given, are known to see it (`cone`): their shadow rays are not traced. Returns the
/// lanes of `lit` it did not reach (facing away or blocked): callers that ignore them pay
/// nothing, the mask being dead code once inlined.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn shine<V: Lanes>(
    world: &World,
    s: &Surface<V>,
    at: &Here<V>,
    (lit, seen): (V::M, Option<V::M>),
    (to_light, distance): (V3<V>, V),
    tints: &Tints<V>,
    scale: Option<V>,
    sum: &mut V3<V>,
    rays: &mut u64,
) -> V::M {
    let n_dot_l = at.normal.dot(to_light);
    // Diffuse and specular vanish when N·L ≤ 0: a shadow ray is only worth tracing
    // otherwise (NaN, which never compares ≤, is traced like the scalar code did).
    let facing = lit.andnot(n_dot_l.le(V::splat(0.0)));
    if !facing.any() {
        return lit;
    }
    *rays += facing.count();
    // The lanes `seen` would find nothing: each lane's answer is its own, so leaving them out
    // of the packet changes no other lane's.
    let test = match seen {
        None => facing,
        Some(seen) => facing.andnot(seen),
    };
    // The shadow ray (a normalisation) is made only where some lane traces it or glass
    // filters the light along it: not when every facing lane's cone is open.
    let shadow = if test.any() || !world.clear.is_empty() {
        Some(shadow_rays(at, to_light))
    } else {
        None
    };
    let blocked = match &shadow {
        Some(shadow) if test.any() => world.blockers().occluded(shadow, distance, test),
        _ => V::M::none_set(),
    };
    let open = facing.andnot(blocked);
    if open.any() {
        let mut term = direct(s, tints, at.normal, to_light, n_dot_l, at.dir);
        if let Some(shadow) = &shadow
            && !world.clear.is_empty()
        {
            term = term * super::glass::transmittance(world, shadow, distance, open);
        }
        let term = scaled(scale, term);
        *sum = V3::select(open, *sum + term, *sum);
    }
    lit.andnot(open)
}

/// Shadow rays from the lanes' surface points (lifted off a mesh where it needs) along the
/// unit vectors `to_light`, normalised once more.
#[inline(always)]
fn shadow_rays<V: Lanes>(at: &Here<V>, to_light: V3<V>) -> Rays<V> {
    let towards = to_light.normalize();
    Rays {
        origin: match at.lift {
            None => at.point,
            Some(l) => l.origin(at.point, towards),
        },
        dir: towards,
        leaving: at.object,
    }
}

/// A spot's falloff scales every term; point and directional lights have scale 1, and
/// 1·x = x exactly, so they skip the multiplications.
#[inline(always)]
fn scaled<V: Lanes>(scale: Option<V>, v: V3<V>) -> V3<V> {
    match scale {
        Some(f) => v * f,
        None => v,
    }
}

/// A light's diffuse and specular intensities times the surface's colours, kd∘id and ks∘is:
/// the same for every point of an area light, so its points' loop takes them made.
pub(super) struct Tints<V: Lanes> {
    diffuse: V3<V>,
    specular: V3<V>,
}

impl<V: Lanes> Tints<V> {
    #[inline(always)]
    pub(super) fn new(s: &Surface<V>, i: &Intensity) -> Tints<V> {
        Tints {
            diffuse: s.diffuse * V3::splat(i.diffuse),
            specular: s.specular * V3::splat(i.specular),
        }
    }
}

/// Diffuse plus specular for an unblocked light with N·L > 0: (kd∘id)·n_l + (ks∘is)·spec.
#[inline(always)]
fn direct<V: Lanes>(
    s: &Surface<V>,
    tints: &Tints<V>,
    n: V3<V>,
    l: V3<V>,
    n_dot_l: V,
    dir: V3<V>,
) -> V3<V> {
    let h = (l + -dir).normalize();
    // N·H can exceed 1 by an ulp; clamping keeps huge exponents from amplifying it.
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let x = n.dot(h);
    let x = V::select(x.lt(zero), zero, x);
    let x = V::select(x.gt(one), one, x);
    let diffuse = tints.diffuse * n_dot_l;
    let specular = tints.specular * s.specular_power(x);
    diffuse + specular
}

/// max(0, N·H)^exponent, with 0^0 = 1. Whole exponents (the talk's 100/4 = 25) multiply;
/// others go through the portable `libm` pow, so every machine computes the same bits.
/// Values whose power falls below 1e-30 give 0 before any subnormal arithmetic happens.
#[inline(always)]
pub fn specular_power<V: Lanes>(x: V, m: &Material) -> V {
    let e = m.exponent;
    if e == 0.0 {
        return V::splat(1.0);
    }
    let power = if e.fract() == 0.0 && e <= MAX_WHOLE_EXPONENT {
        powi(x, e as u32)
    } else {
        let x = x.array();
        V::from_fn(|k| libm::pow(x[k], e))
    };
    V::select(x.le(V::splat(m.specular_floor)), V::splat(0.0), power)
}

/// x^e by binary exponentiation, multiplying in a fixed order (the order of compiler-builtins'
/// `__powidf2`, which `f64::powi` used before): Rust does not pin down `powi`'s result across
/// versions or platforms, this sequence of IEEE products is the same everywhere.
#[inline(always)]
pub fn powi<V: Lanes>(x: V, e: u32) -> V {
    let (mut result, mut base, mut e) = (V::splat(1.0), x, e);
    loop {
        if e & 1 != 0 {
            result = result * base;
        }
        e >>= 1;
        if e == 0 {
            return result;
        }
        base = base * base;
    }
}

/// Unit vector from `from` to `to`, and the distance (zero vector and 0 when they coincide).
#[inline(always)]
pub(super) fn towards<V: Lanes>(from: V3<V>, to: V3<V>) -> (V3<V>, V) {
    let v = to - from;
    let d = v.length();
    let apart = d.gt(V::splat(0.0));
    (
        V3::select(apart, v / d, V3::zero()),
        V::select(apart, d, V::splat(0.0)),
    )
}

/// 0 at or below `edge0`, 1 at or above `edge1`, a cubic in between; a step when they meet.
#[inline(always)]
fn smoothstep<V: Lanes>(edge0: f64, edge1: f64, x: V) -> V {
    let (e0, e1) = (V::splat(edge0), V::splat(edge1));
    let t = (x - e0) / (e1 - e0);
    let cubic = t * t * (V::splat(3.0) - V::splat(2.0) * t);
    let low = V::select(x.le(e0), V::splat(0.0), cubic);
    V::select(e1.le(x), V::splat(1.0), low)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::F64x1;

    #[test]
    fn powi_multiplies_in_binary_order() {
        for (x, e) in [(0.9f64, 25u32), (1.0000001, 4096), (0.5, 1), (0.3, 7)] {
            let mut want = 1.0;
            let (mut b, mut n) = (x, e);
            while n > 0 {
                if n & 1 == 1 {
                    want *= b;
                }
                n >>= 1;
                if n > 0 {
                    b *= b;
                }
            }
            assert_eq!(powi(F64x1(x), e).0.to_bits(), want.to_bits());
        }
        assert_eq!(powi(F64x1(0.7), 0).0, 1.0);
    }

    #[test]
    fn smoothstep_is_a_step_when_the_edges_meet() {
        let s = |x| smoothstep(0.5, 0.5, F64x1(x)).0;
        assert_eq!((s(0.4), s(0.5), s(0.6)), (0.0, 1.0, 1.0));
        assert_eq!(smoothstep(0.0, 1.0, F64x1(0.5)).0, 0.5);
    }
}
