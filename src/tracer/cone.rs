//! Which lanes see the whole of an area light: when the cone from a lane's surface point P to
//! a ball around the light (the union of the segments from P to its points) meets no opaque
//! object, every one of the light's m shadow rays is open and none needs tracing. The test is
//! conservative, with margins wider than the rounding of the shadow rays it stands for (in
//! the lanes' precision) and of its own f64 arithmetic, so it only ever says "open" where
//! every traced ray would have been open: frames keep every byte, the work of tracing falls
//! away. Transparent objects are not occluders (shadow rays pass them; their filters are
//! still applied to the open rays, as before).
//!
//! It applies to scenes of spheres and planes with at most `MAX_OCCLUDERS` opaque objects (it
//! tests each one, per lane); with meshes or more objects every shadow ray is traced as before.

use crate::lanes::{Lanes, Mask, V3, single};
use crate::scene::{Light, Scene, Shape};
use glam::DVec3;
use std::sync::OnceLock;

/// Above this many opaque objects testing each one per lane costs about what it saves.
const MAX_OCCLUDERS: usize = 16;

/// An opaque object a shadow ray may meet, in the world's coordinates (shifted for f32).
#[derive(Debug, Clone, Copy)]
pub(super) enum Occluder {
    Sphere {
        center: DVec3,
        radius: f64,
        /// Its index in the scene's objects, as the lanes carry it.
        object: f64,
    },
    Plane {
        point: DVec3,
        normal: DVec3,
        object: f64,
    },
}

/// The opaque objects of `scene` when the test applies: it has area lights, no meshes, at most
/// `MAX_OCCLUDERS` opaque objects, and `RAYREEL_SHADOW_CONES` is not `off` (the switch that
/// lets tests render the same frames with every shadow ray traced).
pub(super) fn occluders(scene: &Scene) -> Option<Vec<Occluder>> {
    if !enabled() || !scene.lights.iter().any(|l| l.area_samples().is_some()) {
        return None;
    }
    let mut out = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        // Any mesh, glass too: shadow rays leaving a mesh start lifted off it, not at P.
        if matches!(o.shape, Shape::Mesh { .. }) {
            return None;
        }
        if scene.materials[o.material].transparent() {
            continue;
        }
        let object = i as f64;
        out.push(match o.shape {
            Shape::Sphere { center, radius } => Occluder::Sphere {
                center,
                radius,
                object,
            },
            Shape::Plane { point, normal, .. } => Occluder::Plane {
                point,
                normal,
                object,
            },
            Shape::Mesh { .. } => unreachable!("meshes returned above"),
        });
    }
    (out.len() <= MAX_OCCLUDERS).then_some(out)
}

/// Whether `RAYREEL_SHADOW_CONES` leaves the test on (anything but `off`); read once.
fn enabled() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| std::env::var("RAYREEL_SHADOW_CONES").as_deref() != Ok("off"))
}

/// A ball (centre, radius) holding every point of an area light: a sphere light's own, a
/// rect's around its centre reaching its farthest corner.
pub(super) fn ball(light: &Light) -> (DVec3, f64) {
    match *light {
        Light::Sphere { center, radius, .. } => (center, radius),
        Light::Rect {
            corner,
            edge_u,
            edge_v,
            ..
        } => {
            let half = 0.5 * (edge_u + edge_v).length().max((edge_u - edge_v).length());
            (corner + 0.5 * (edge_u + edge_v), half * (1.0 + 1e-9))
        }
        _ => unreachable!("only area lights have a ball"),
    }
}

/// The lanes of `lanes` whose every shadow ray from `point` (leaving the object `object`)
/// to a point of the ball `light` is open: no occluder can block it. Computed in f64 lanes of
/// the same CPU feature, `V::F64::N` lanes at a time.
#[inline(always)]
pub(super) fn open<V: Lanes>(
    occluders: &[Occluder],
    light: (DVec3, f64),
    point: V3<V>,
    object: V,
    lanes: V::M,
) -> V::M {
    // The unit roundoff of the shadow rays' arithmetic, times a safety factor of 16 over the
    // error bounds argued below.
    let eps = 16.0
        * if single::<V>() {
            0.5 * f64::from(f32::EPSILON)
        } else {
            0.5 * f64::EPSILON
        };
    let p = [point.x.array(), point.y.array(), point.z.array()];
    let ids = object.array();
    let mut bits = 0;
    for c in (0..V::N).step_by(V::F64::N) {
        let on = lanes.bits() >> c;
        if on & ((1u32 << V::F64::N) - 1) == 0 {
            continue;
        }
        let at = V3::load(&p, c);
        bits |= open_group::<V::F64>(occluders, light, at, &ids[c..], on, eps) << c;
    }
    V::M::from_bits(bits)
}

/// `open` for one group of f64 lanes (`on`: bit k for lane k); returns the open lanes' bits.
#[inline(always)]
fn open_group<W: Lanes>(
    occluders: &[Occluder],
    light: (DVec3, f64),
    p: V3<W>,
    ids: &[f64],
    on: u32,
    eps: f64,
) -> u32 {
    let cone = Cone::new(light, p, eps);
    let object = W::load(ids);
    let mut open = W::M::from_bits(on).and(cone.gap.gt(W::splat(0.0)));
    for o in occluders {
        if !open.any() {
            return 0;
        }
        let safe = match *o {
            Occluder::Sphere {
                center,
                radius,
                object: id,
            } => cone.misses_sphere(center, radius, object.eq(W::splat(id))),
            Occluder::Plane {
                point,
                normal,
                object: id,
            } => object.eq(W::splat(id)).or(cone.misses_plane(point, normal)),
        };
        open = open.and(safe);
    }
    open.bits()
}

/// The cone from each lane's point P to the light's ball (centre C, radius R), and the sizes
/// its margins scale with.
struct Cone<W> {
    p: V3<W>,
    light: (DVec3, f64),
    /// v = C − P, d = |v|, the unit axis v/d.
    v: V3<W>,
    d: W,
    axis: V3<W>,
    /// D − R (the lane gets no claim unless > 0), and its reciprocal.
    gap: W,
    inv_gap: W,
    /// sin α = R/d and cos α of the half-angle α, and t = √(d² − R²), the distance from P to
    /// where its tangents touch the ball.
    sin: W,
    cos: W,
    t: W,
    /// |P|₁ and |C|₁ + R: bounds on the lengths the shadow rays' rounding scales with.
    size_p: W,
    size_l: W,
    eps: W,
}

impl<W: Lanes> Cone<W> {
    #[inline(always)]
    fn new((center, radius): (DVec3, f64), p: V3<W>, eps: f64) -> Cone<W> {
        let v = V3::splat(center) - p;
        let d = v.length();
        let r = W::splat(radius);
        let t = ((d - r) * (d + r)).sqrt();
        let one = W::splat(1.0);
        let inv_d = one / d;
        Cone {
            p,
            light: (center, radius),
            v,
            d,
            axis: v * inv_d,
            gap: d - r,
            inv_gap: one / (d - r),
            sin: r * inv_d,
            cos: t * inv_d,
            t,
            size_p: l1(p),
            size_l: W::splat(l1_of(center) + radius),
            eps: W::splat(eps),
        }
    }

    /// A length margin for a quantity of size `s` computed from rays whose direction is
    /// known to about (|P| + |C| + R)/(D − R) roundoffs: ε·s·(4 + 4·s/(D − R)).
    #[inline(always)]
    fn margin(&self, s: W) -> W {
        self.eps * s * (W::splat(4.0) + W::splat(4.0) * s * self.inv_gap)
    }

    /// Lanes on which no shadow ray from P towards the ball can meet the sphere (c, r);
    /// `own` lanes start on it.
    ///
    /// Two ways to be sure. (a) Every direction in the cone heads away from c: with n = (P −
    /// c)/|P − c|, h = v·n, h − R > 0 bounds d·n from below by (h − R)/(D + R) for every unit
    /// direction d towards the ball; `sphere_hit` then finds b = f·d > 0, which on its own
    /// sphere alone is no hit, and elsewhere with |f|² − r² ≥ 0 (P outside). The margins
    /// cover b's rounding (ε|f| for the dot product and the direction's error, about (|P| +
    /// |q|)/(D − R) roundoffs for a point q rounded into the lane, and f's own) and
    /// |f|² − r²'s (ε(|f|² + r²) plus f's error). (b) Or the cone stays farther than r from
    /// c: the distance from c to the cone (the convex hull of P and the ball) exceeds r by
    /// `margin`, which covers the rays' distance from the exact segments and the sphere
    /// test's discriminant and root errors.
    #[inline(always)]
    fn misses_sphere(&self, c: DVec3, r: f64, own: W::M) -> W::M {
        let (eps, rw, two) = (self.eps, W::splat(r), W::splat(2.0));
        let size_c = W::splat(l1_of(c));
        let f = self.p - V3::splat(c);
        let ff = f.dot(f);
        let lf = ff.sqrt();
        // (a), multiplied through by |f| > 0: v·f − R·|f| > κ·(D + R)·|f|, with
        // κ·|f| = ε·(4|f| + 8(|P| + |C| + R)|f|/(D − R) + 2(|P| + |c|)).
        let r_l = W::splat(self.light.1);
        let kappa_f = eps
            * (W::splat(4.0) * lf
                + W::splat(8.0) * (self.size_p + self.size_l) * self.inv_gap * lf
                + two * (self.size_p + size_c));
        let away = (self.v.dot(f) - r_l * lf).gt(kappa_f * (self.d + r_l));
        // |f|² − r² = (|f| − r)(|f| + r) > 2·err, err = ε(3(|f|² + r²) + 4|f|(|P| + |c|)).
        let err_c =
            eps * (W::splat(3.0) * (ff + rw * rw) + W::splat(4.0) * lf * (self.size_p + size_c));
        let outside = ((lf - rw) * (lf + rw)).gt(two * err_c);
        // (b)
        let hull = self.hull_distance(c, -f, lf);
        let size = self.size_p + self.size_l + size_c + rw;
        let apart = (hull - rw).gt(self.margin(size));
        own.and(away).or(away.and(outside).or(apart).andnot(own))
    }

    /// The distance from c (at w = c − P, |w| = lw) to the cone, the convex hull of P and the
    /// ball; ≤ 0 inside. In the plane of the axis and c: x along the axis, y ≥ 0 across it.
    /// The hull is bounded by the tangent from P (angle α) up to where it touches the ball,
    /// then by the ball. Behind P's normal to the tangent (u < 0) the nearest point is P,
    /// beyond the tangent point's (u ≥ t) it is on the ball, between them on the tangent.
    #[inline(always)]
    fn hull_distance(&self, c: DVec3, w: V3<W>, lw: W) -> W {
        let a = self.axis;
        let x = w.dot(a);
        let cross = V3 {
            x: w.y * a.z - w.z * a.y,
            y: w.z * a.x - w.x * a.z,
            z: w.x * a.y - w.y * a.x,
        };
        let y = cross.length();
        let u = x * self.cos + y * self.sin;
        let across = y * self.cos - x * self.sin;
        let to_ball = W::splat((c - self.light.0).length() - self.light.1);
        let near = W::select(u.lt(self.t), across, to_ball);
        W::select(u.lt(W::splat(0.0)), lw, near)
    }

    /// Lanes on which the cone stays on one side of the plane (point, normal), clear of it by
    /// `margin`: the ray's t is then negative or beyond the light, whatever its rounding.
    #[inline(always)]
    fn misses_plane(&self, point: DVec3, normal: DVec3) -> W::M {
        let (center, radius) = self.light;
        let side_p = (self.p - V3::splat(point)).dot(V3::splat(normal));
        let side_c = (center - point).dot(normal);
        let pad = self.margin(self.size_p + self.size_l + W::splat(l1_of(point)));
        let (near, far) = (W::splat(side_c - radius), W::splat(side_c + radius));
        let above = side_p.gt(pad).and(near.gt(pad));
        let below = (-side_p).gt(pad).and((-far).gt(pad));
        above.or(below)
    }
}

/// |x| + |y| + |z| per lane: a bound on the length, for margins.
#[inline(always)]
fn l1<W: Lanes>(p: V3<W>) -> W {
    let abs = |x: W| x.max(-x);
    abs(p.x) + abs(p.y) + abs(p.z)
}

fn l1_of(p: DVec3) -> f64 {
    p.abs().element_sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lanes::{F32x1, F64x1};
    use crate::scene::Object;
    use crate::tracer::accel::{Geometry, Rays};
    use crate::tracer::shade::towards;

    struct Rng(u64);

    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.unit()
        }
        fn direction(&mut self) -> DVec3 {
            loop {
                let v = DVec3::new(
                    self.range(-1., 1.),
                    self.range(-1., 1.),
                    self.range(-1., 1.),
                );
                if (0.01..=1.0).contains(&v.length_squared()) {
                    return v.normalize();
                }
            }
        }
    }

    fn sphere(center: DVec3, radius: f64) -> Object {
        Object {
            shape: Shape::Sphere { center, radius },
            material: 0,
        }
    }

    fn as_occluders(objects: &[Object]) -> Vec<Occluder> {
        let occluder = |(i, o): (usize, &Object)| match o.shape {
            Shape::Sphere { center, radius } => Occluder::Sphere {
                center,
                radius,
                object: i as f64,
            },
            Shape::Plane { point, normal, .. } => Occluder::Plane {
                point,
                normal,
                object: i as f64,
            },
            Shape::Mesh { .. } => unreachable!(),
        };
        objects.iter().enumerate().map(occluder).collect()
    }

    /// The cone's claim for P leaving `own`, in the lanes `V`.
    fn claims<V: Lanes>(o: &[Occluder], light: (DVec3, f64), p: DVec3, own: usize) -> bool {
        open(
            o,
            light,
            V3::<V>::splat(p),
            V::splat(own as f64),
            V::M::first(1),
        )
        .any()
    }

    /// Whether the shadow ray from P (leaving `own`) to q is blocked, traced as `shade::shine`
    /// traces it in the lanes `V`.
    fn blocked<V: Lanes>(g: &Geometry, p: DVec3, own: usize, q: DVec3) -> bool {
        let (from, to) = (V3::<V>::splat(p), V3::<V>::splat(q));
        let (l, d) = towards(from, to);
        let rays = Rays {
            origin: from,
            dir: l.normalize(),
            leaving: V::splat(own as f64),
        };
        g.occluded(&rays, d, V::M::first(1)).any()
    }

    /// Points of the ball: inside it, on it, and on its rim as seen from P towards each
    /// occluder (where a near miss is nearest).
    fn targets(rng: &mut Rng, (c, r): (DVec3, f64), p: DVec3, objects: &[Object]) -> Vec<DVec3> {
        let mut q = Vec::new();
        for _ in 0..24 {
            q.push(c + r * rng.unit().cbrt() * rng.direction());
            q.push(c + r * rng.direction());
        }
        let axis = (c - p).normalize();
        for o in objects {
            let towards = match o.shape {
                Shape::Sphere { center, .. } => center - c,
                Shape::Plane { normal, .. } => -normal,
                Shape::Mesh { .. } => unreachable!(),
            };
            let side = towards - axis * towards.dot(axis);
            if side.length() > 0.0 {
                let side = side.normalize();
                for k in 0..6 {
                    let s = 1.0 - f64::from(k) * 1e-3;
                    q.push(c + r * s * side);
                    q.push(c + r * (side + 1e-6 * rng.direction()).normalize());
                }
            }
        }
        q
    }

    /// Scenes built to sit on the test's edge: spheres resting on a floor (a plane, or a huge
    /// sphere as in the talk), and a sphere grown until it almost touches the cone from P (its
    /// gap 10^-k of the distance, k up to 15). Wherever the cone says "open", no shadow ray
    /// from P to a point of the light's ball is blocked, in f64 and in f32 lanes; and the
    /// cone does say it, often in f64, less in f32 whose margins are wider than most of the
    /// edge cases' gaps (about 30% and 7% of these scenes).
    #[test]
    fn an_open_cone_has_no_blocked_ray() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut claims64, mut claims32, mut scenes) = (0, 0, 0);
        for scene in 0..3000 {
            let floor_r = [0.0, 10.0, 9000.0 - 0.7][scene % 3];
            let mut objects = vec![match floor_r {
                0.0 => Object {
                    shape: Shape::Plane {
                        point: DVec3::ZERO,
                        normal: DVec3::Y,
                        u_axis: None,
                    },
                    material: 0,
                },
                r => sphere(DVec3::new(0.0, -r, 0.0), r),
            }];
            for _ in 0..3 {
                let r = rng.range(0.05, 0.7);
                let (x, z) = (rng.range(-2., 2.), rng.range(-2., 2.));
                let y = if rng.unit() < 0.5 {
                    r
                } else {
                    rng.range(r, 2.5)
                };
                objects.push(sphere(DVec3::new(x, y, z), r));
            }
            let light = (
                DVec3::new(rng.range(-4., 4.), rng.range(3., 6.), rng.range(-4., 4.)),
                rng.range(0.01, 1.5),
            );
            // P on an object, as a hit would be (rounded by its own arithmetic).
            let own = (rng.unit() * objects.len() as f64) as usize;
            let p = match objects[own].shape {
                Shape::Sphere { center, radius } => center + radius * rng.direction(),
                _ => DVec3::new(rng.range(-3., 3.), 0.0, rng.range(-3., 3.)),
            };
            // A sphere grown to just miss the cone from P.
            let c = DVec3::new(rng.range(-3., 3.), rng.range(0.2, 4.), rng.range(-3., 3.));
            if (light.0 - p).length() > light.1 {
                let cone = Cone::<F64x1>::new(light, V3::splat(p), 0.0);
                let w = c - p;
                let h = cone.hull_distance(c, V3::splat(w), F64x1(w.length())).0;
                let k = rng.range(1.0, 15.0);
                if h > 0.0 {
                    objects.push(sphere(c, h * (1.0 - 10f64.powf(-k))));
                }
            }
            let o = as_occluders(&objects);
            let g = Geometry::new(&objects);
            let open64 = claims::<F64x1>(&o, light, p, own);
            let open32 = claims::<F32x1>(&o, light, p, own);
            scenes += 1;
            claims64 += usize::from(open64);
            claims32 += usize::from(open32);
            for q in targets(&mut rng, light, p, &objects) {
                assert!(
                    !(open64 && blocked::<F64x1>(&g, p, own, q)),
                    "f64 scene {scene}: {p} to {q}"
                );
                assert!(
                    !(open32 && blocked::<F32x1>(&g, p, own, q)),
                    "f32 scene {scene}: {p} to {q}"
                );
            }
        }
        assert!(
            claims64 * 4 > scenes && claims32 * 20 > scenes,
            "{claims64} {claims32} of {scenes}"
        );
    }

    /// The talk with a sphere light of radius 0.5 at (5, 5, 5): the floor in the open and the
    /// tops of the spheres see all of it, the floor under the big red sphere does not.
    #[test]
    fn the_talks_lit_points_see_the_whole_light() {
        let objects = [
            sphere(DVec3::new(-0.2, 0.0, -1.0), 0.7),
            sphere(DVec3::new(0.1, -0.3, 0.0), 0.1),
            sphere(DVec3::new(-0.3, 0.0, 0.0), 0.15),
            sphere(DVec3::new(0.0, -9000.0, 0.0), 8999.3),
        ];
        let o = as_occluders(&objects);
        let light = (DVec3::splat(5.0), 0.5);
        let floor = |x: f64, z: f64| DVec3::new(x, -0.7, z);
        for (p, own, open) in [
            (floor(0.5, 0.5), 3, true),
            (floor(-1.0, 1.0), 3, true),
            (DVec3::new(-0.2, 0.7, -1.0), 0, true),
            (DVec3::new(-0.3, 0.15, 0.0), 2, true),
            (floor(-0.6, -1.4), 3, false),
        ] {
            assert_eq!(claims::<F64x1>(&o, light, p, own), open, "f64 {p}");
            assert_eq!(claims::<F32x1>(&o, light, p, own), open, "f32 {p}");
        }
    }
}
