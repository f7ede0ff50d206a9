//! Numerical robustness: the tracer at extreme scales, distances, depths, sizes and parameters.
//!
//! Every criterion is measured against an independent answer: ray/sphere roots and miss
//! distances are recomputed here in double-double arithmetic (about 32 significant digits)
//! from the very f64 inputs the tracer gets, so "the true root" means the exact root for those
//! inputs, not another f64 approximation. Every frame rendered here must have
//! `non_finite == 0` and only finite values.
//!
//! `cargo test --release --test numerics -- --ignored --nocapture` prints the measured limits
//! (how far from the origin and over which scale ratio the images stay the same) that the
//! docs/numerics.md quotes.

use glam::DVec3;
use rayreel::camera::{Camera, screen_point};
use rayreel::cli::parse_size;
use rayreel::frame::Frame;
use rayreel::scene::{Light, Object, Shape};
use rayreel::schedule::render_frame;
use rayreel::sequence::{self, Sequence};
use rayreel::timeline::{Keyed, Path as TimelinePath};
use rayreel::tracer::intersect::{Ray, intersect, nearest};
use rayreel::tracer::path::trace;
use std::path::{Path, PathBuf};
use std::time::Instant;

// ---------------------------------------------------------------------------------------------
// Double-double arithmetic: the reference every geometric criterion is measured against.

#[derive(Debug, Clone, Copy)]
struct Dd {
    hi: f64,
    lo: f64,
}

fn two_sum(a: f64, b: f64) -> Dd {
    let s = a + b;
    let bb = s - a;
    Dd {
        hi: s,
        lo: (a - (s - bb)) + (b - bb),
    }
}

fn quick_two_sum(a: f64, b: f64) -> Dd {
    let s = a + b;
    Dd {
        hi: s,
        lo: b - (s - a),
    }
}

impl Dd {
    fn of(a: f64) -> Dd {
        Dd { hi: a, lo: 0.0 }
    }
    fn add(self, o: Dd) -> Dd {
        let s = two_sum(self.hi, o.hi);
        let t = two_sum(self.lo, o.lo);
        let s = quick_two_sum(s.hi, s.lo + t.hi);
        quick_two_sum(s.hi, s.lo + t.lo)
    }
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
    fn sub(self, o: Dd) -> Dd {
        self.add(o.neg())
    }
    fn mul(self, o: Dd) -> Dd {
        let p = self.hi * o.hi;
        let e = self.hi.mul_add(o.hi, -p);
        quick_two_sum(p, e + (self.hi * o.lo + self.lo * o.hi))
    }
    fn div(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self.sub(o.mul(Dd::of(q1)));
        let q2 = r.hi / o.hi;
        let r = r.sub(o.mul(Dd::of(q2)));
        let q3 = r.hi / o.hi;
        quick_two_sum(q1, q2).add(Dd::of(q3))
    }
    fn sqrt(self) -> Dd {
        if self.hi <= 0.0 {
            return Dd::of(0.0);
        }
        let x = self.hi.sqrt();
        let s = Dd::of(x);
        let r = self.sub(s.mul(s));
        s.add(Dd::of(r.hi / (2.0 * x)))
    }
    fn f(self) -> f64 {
        self.hi + self.lo
    }
}

type Dv = [Dd; 3];

/// a − b, exactly.
fn diff(a: DVec3, b: DVec3) -> Dv {
    [two_sum(a.x, -b.x), two_sum(a.y, -b.y), two_sum(a.z, -b.z)]
}

fn dv(a: DVec3) -> Dv {
    [Dd::of(a.x), Dd::of(a.y), Dd::of(a.z)]
}

fn dot(a: &Dv, b: &Dv) -> Dd {
    a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]))
}

/// The exact geometry of the line o + t·d against a sphere, for these f64 inputs.
#[derive(Debug, Clone, Copy)]
struct Truth {
    /// Distance from the centre to the line.
    miss_distance: f64,
    /// Nearest root with t > 0.
    t: Option<f64>,
}

fn sphere_truth(center: DVec3, radius: f64, o: DVec3, d: DVec3) -> Truth {
    let f = diff(o, center);
    let d = dv(d);
    let a = dot(&d, &d);
    let b = dot(&f, &d);
    let ff = dot(&f, &f);
    let rr = Dd::of(radius).mul(Dd::of(radius));
    let perp2 = ff.sub(b.mul(b).div(a));
    let miss_distance = perp2.f().max(0.0).sqrt();
    let c = ff.sub(rr);
    let disc = b.mul(b).sub(a.mul(c));
    if disc.hi < 0.0 {
        return Truth {
            miss_distance,
            t: None,
        };
    }
    let s = disc.sqrt();
    // q = −(b + sign(b)·√disc); the roots are q/a and c/q, with no cancellation.
    let q = if b.hi <= 0.0 {
        b.neg().add(s)
    } else {
        b.add(s).neg()
    };
    let (r0, r1) = if q.hi == 0.0 {
        (0.0, 0.0)
    } else {
        (q.div(a).f(), c.div(q).f())
    };
    let (t0, t1) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
    let t = if t0 > 0.0 {
        Some(t0)
    } else if t1 > 0.0 {
        Some(t1)
    } else {
        None
    };
    Truth { miss_distance, t }
}

#[test]
fn double_double_reference_is_exact_where_f64_is_not() {
    // (1 + 2^-60)² − 1 = 2^-59 + 2^-120: f64 loses it entirely.
    let x = Dd::of(1.0).add(Dd::of(2f64.powi(-60)));
    let y = x.mul(x).sub(Dd::of(1.0));
    assert_eq!(y.hi, 2f64.powi(-59));
    assert!((Dd::of(2.0).sqrt().mul(Dd::of(2.0).sqrt()).f() - 2.0).abs() == 0.0);
    let t = sphere_truth(DVec3::ZERO, 1.0, DVec3::new(0.6, 0.0, 5.0), DVec3::NEG_Z);
    assert!((t.t.unwrap() - 4.2).abs() < 1e-15);
    assert!((t.miss_distance - 0.6).abs() < 1e-15);
}

// ---------------------------------------------------------------------------------------------
// Helpers.

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// What these tests change after loading, as `--size` and `--depth` do.
#[derive(Debug, Clone, Copy, Default)]
struct Overrides {
    size: Option<(u32, u32)>,
    depth: bool,
}

/// One eye ray through each pixel centre unless the file chooses a sampling (it has the
/// default's): the checks follow single rays.
fn apply(mut seq: Sequence, o: &Overrides) -> Sequence {
    let default = seq.quality.is_none()
        && seq.settings.samples == sequence::DEFAULT_SAMPLES
        && seq
            .settings
            .adaptive
            .is_some_and(|a| a.max_samples == sequence::DEFAULT_SAMPLING_MAX);
    if default {
        (seq.settings.samples, seq.settings.adaptive) = (1, None);
    }
    if let Some((w, h)) = o.size {
        (seq.settings.width, seq.settings.height) = (w, h);
    }
    seq.settings.depth |= o.depth;
    seq
}

fn parse_with(yaml: &str, overrides: &Overrides) -> Sequence {
    let seq =
        sequence::parse(Path::new("numerics.yaml"), yaml).unwrap_or_else(|e| panic!("{e}\n{yaml}"));
    apply(seq, overrides)
}

fn parse(yaml: &str) -> Sequence {
    parse_with(yaml, &Overrides::default())
}

fn load(path: &Path, overrides: &Overrides) -> Sequence {
    apply(
        sequence::load(path).unwrap_or_else(|e| panic!("{e}")),
        overrides,
    )
}

/// Frame `n`, asserting the tracer never had to replace a NaN or an infinity.
fn render(seq: &Sequence, n: u64, what: &str) -> Frame {
    let frame = render_frame(seq, n).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_finite(&frame, what);
    frame
}

fn assert_finite(frame: &Frame, what: &str) {
    assert_eq!(frame.non_finite, 0, "{what}: non-finite colour values");
    assert!(
        frame.rgb.iter().all(|v| v.is_finite()),
        "{what}: a stored value is not finite"
    );
    assert_eq!(
        frame.rgb.len(),
        3 * frame.width as usize * frame.height as usize
    );
}

/// A YAML flow sequence that parses back to exactly these f64 values.
fn v3(v: DVec3) -> String {
    format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z)
}

fn camera_of(seq: &Sequence, n: u64) -> Camera {
    Camera::new(&seq.timeline.pose_of(n)).unwrap()
}

/// The eye ray the tracer casts through the centre of pixel (row, col).
fn eye_ray(cam: &Camera, row: u32, col: u32, w: u32, h: u32) -> Ray {
    let (x, y) = screen_point(row, col, 0.5, 0.5, w, h);
    Ray {
        origin: cam.origin,
        dir: cam.direction(x, y),
        leaving: None,
    }
}

/// Peak signal-to-noise ratio of two 8-bit images, in dB (infinite when identical).
fn psnr(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    let se: f64 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum();
    let mse = se / a.len() as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    }
}

/// Moves and scales everything in a sequence: p ↦ s·p + offset for points, lengths × s.
fn transform(seq: &mut Sequence, s: f64, offset: DVec3) {
    let map = |p: DVec3| s * p + offset;
    for o in &mut seq.scene.objects {
        o.shape = match o.shape {
            Shape::Sphere { center, radius } => Shape::Sphere {
                center: map(center),
                radius: s * radius,
            },
            Shape::Plane {
                point,
                normal,
                u_axis,
            } => Shape::Plane {
                point: map(point),
                normal,
                u_axis,
            },
            Shape::Mesh {
                mesh,
                place,
                shading,
            } => Shape::Mesh {
                mesh,
                place: rayreel::scene::Placement {
                    scale: s * place.scale,
                    translate: map(place.translate),
                    ..place
                },
                shading,
            },
        };
    }
    for l in &mut seq.scene.lights {
        match l {
            Light::Point { position, .. } | Light::Spot { position, .. } => {
                *position = map(*position)
            }
            Light::Sphere { center, radius, .. } => {
                *center = map(*center);
                *radius *= s;
            }
            Light::Rect {
                corner,
                edge_u,
                edge_v,
                ..
            } => {
                *corner = map(*corner);
                *edge_u *= s;
                *edge_v *= s;
            }
            Light::Directional { .. } | Light::Ambient { .. } => {}
        }
    }
    match &mut seq.timeline.path {
        TimelinePath::Keys(keyed) => {
            // The tracks are built from the keys, so moved keys make a new move.
            let mut keys = keyed.keys.clone();
            for k in &mut keys {
                k.pose.position = map(k.pose.position);
                k.pose.look_at = map(k.pose.look_at);
            }
            **keyed = Keyed::new(keys, keyed.interpolation, keyed.speed);
        }
        TimelinePath::Orbit(o) => {
            o.center = map(o.center);
            o.look_at = map(o.look_at);
            o.radius *= s;
            o.height *= s;
        }
    }
}

fn talk((w, h): (u64, u64)) -> Sequence {
    load(
        &repo().join("sequences/talk.yaml"),
        &Overrides {
            size: Some((w as u32, h as u32)),
            ..Overrides::default()
        },
    )
}

fn talk_psnr(s: f64, offset: DVec3, size: (u64, u64)) -> f64 {
    let base = talk(size);
    let mut moved = base.clone();
    transform(&mut moved, s, offset);
    let a = render(&base, 0, "talk").to_rgb8();
    let b = render(&moved, 0, &format!("talk ×{s:e} + {offset}")).to_rgb8();
    psnr(&a, &b)
}

/// Evenly spread unit vectors (a Fibonacci sphere).
fn directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - y * y).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), y, r * a.sin())
        })
        .collect()
}

/// Two unit vectors completing `n` to an orthonormal basis.
fn basis(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = n.cross(helper).normalize();
    (u, n.cross(u))
}

// ---------------------------------------------------------------------------------------------
// 1. Roots: a giant sphere from just above it, a unit sphere from far away.

/// The talk's floor.
const FLOOR_CENTER: DVec3 = DVec3::new(0.0, -9000.0, 0.0);
const FLOOR_RADIUS: f64 = 8999.3;

#[test]
fn giant_floor_from_just_above_gives_the_true_root() {
    let floor = Shape::Sphere {
        center: FLOOR_CENTER,
        radius: FLOOR_RADIUS,
    };
    let (mut hits, mut worst, mut worst_rel) = (0, 0.0f64, 0.0f64);
    let mut worst_case = String::new();
    // Where on the floor: the top, a little way off (the talk's scene), far around.
    let tilts: [f64; 5] = [0.0, 1e-4, 1e-3, 0.03, 0.5];
    for (i, tilt) in tilts.into_iter().enumerate() {
        let azimuth = 0.7 + i as f64;
        let n = DVec3::new(
            tilt.sin() * azimuth.cos(),
            tilt.cos(),
            tilt.sin() * azimuth.sin(),
        );
        let (u, v) = basis(n);
        for h in [1e-4, 1e-5, 1e-6] {
            let origin = FLOOR_CENTER + (FLOOR_RADIUS + h) * n;
            // Depression below the local horizon: straight down to far beyond the tangent angle
            // √(2h/R) at which the ray only just grazes the floor; negative angles point up.
            let grazing = (2.0 * h / FLOOR_RADIUS).sqrt();
            let angles = [
                std::f64::consts::FRAC_PI_2,
                1.2,
                std::f64::consts::FRAC_PI_4,
                0.1,
                1e-2,
                1e-3,
                10.0 * grazing,
                2.0 * grazing,
                1.1 * grazing,
                0.0,
                -1e-3,
                -0.5,
            ];
            for theta in angles {
                for k in 0..8 {
                    let phi = k as f64 * std::f64::consts::TAU / 8.0;
                    let d = if theta == std::f64::consts::FRAC_PI_2 {
                        -n
                    } else {
                        (-theta.sin() * n + theta.cos() * (phi.cos() * u + phi.sin() * v))
                            .normalize()
                    };
                    let ray = Ray {
                        origin,
                        dir: d,
                        leaving: None,
                    };
                    let truth = sphere_truth(FLOOR_CENTER, FLOOR_RADIUS, origin, d);
                    let got = intersect(&floor, &ray, false);
                    let case = format!("tilt {tilt} h {h:e} depression {theta:e} phi {phi:.2}");
                    match (truth.t, got) {
                        (Some(want), Some(t)) => {
                            hits += 1;
                            let err = (t - want).abs();
                            assert!(err <= 1e-6, "{case}: t {t:e}, true root {want:e}");
                            if err > worst {
                                worst = err;
                                worst_case = case;
                            }
                            worst_rel = worst_rel.max(err / want);
                        }
                        (None, None) => {}
                        (want, got) => {
                            panic!("{case}: got {got:?}, true {want:?} ({truth:?})")
                        }
                    }
                }
            }
        }
    }
    // Straight down from the top is exact: the root is the height above the surface.
    let o = DVec3::new(0.0, -0.7 + 1e-6, 0.0);
    let ray = Ray {
        origin: o,
        dir: DVec3::NEG_Y,
        leaving: None,
    };
    let exact = two_sum(o.y, 9000.0).sub(Dd::of(FLOOR_RADIUS)).f();
    let t = intersect(&floor, &ray, false).unwrap();
    // The limit of f64 here: o − centre alone rounds by half an ulp of 9000 (9e-13).
    assert!(
        (t - exact).abs() <= 4.0 * f64::EPSILON * FLOOR_RADIUS,
        "{t:e} {exact:e}"
    );
    assert!(hits > 1000, "{hits} hits only");
    eprintln!(
        "giant floor: {hits} hits, worst |t − t*| {worst:.2e} ({worst_case}), worst relative {worst_rel:.2e}"
    );
}

#[test]
fn unit_sphere_from_far_away_has_no_wrong_hits_or_misses() {
    const N: usize = 256;
    const BAND: f64 = 1e-3;
    let r = 1.0;
    for center in [DVec3::ZERO, DVec3::new(0.37, -1.25, 2.5)] {
        let sphere = Shape::Sphere { center, radius: r };
        for distance in [1e2, 1e3, 1e4] {
            let axis = DVec3::new(0.3, 0.55, -0.78).normalize();
            let eye = center + distance * axis;
            let (u, v) = basis(axis);
            // The silhouette's radius on the plane through the centre facing the eye, +10%.
            let half = 1.1 * r * distance / (distance * distance - r * r).sqrt();
            let (mut hits, mut checked, mut wrong, mut worst) = (0, 0, 0, 0.0f64);
            for i in 0..N {
                for j in 0..N {
                    let x = -half + 2.0 * half * (j as f64 + 0.5) / N as f64;
                    let y = -half + 2.0 * half * (i as f64 + 0.5) / N as f64;
                    let target = center + x * u + y * v;
                    let dir = (target - eye).normalize();
                    let truth = sphere_truth(center, r, eye, dir);
                    if (truth.miss_distance - r).abs() <= BAND * r {
                        continue;
                    }
                    checked += 1;
                    let got = intersect(
                        &sphere,
                        &Ray {
                            origin: eye,
                            dir,
                            leaving: None,
                        },
                        false,
                    );
                    match (truth.miss_distance < r, got) {
                        (true, Some(t)) => {
                            hits += 1;
                            let err = (t - truth.t.unwrap()).abs();
                            worst = worst.max(err);
                            if err > BAND * r {
                                wrong += 1;
                            }
                        }
                        (false, None) => {}
                        _ => wrong += 1,
                    }
                }
            }
            assert_eq!(
                wrong, 0,
                "centre {center}, distance {distance:e}: {wrong} wrong of {checked}"
            );
            assert!(hits > N * N / 2, "{hits}");
            eprintln!(
                "unit sphere at {distance:e}: {checked} rays checked, {hits} hits, worst |t − t*| {worst:.1e}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Shadow acne and light leaking.

#[test]
fn no_shadow_acne_on_giant_ground_spheres() {
    let (w, h) = (160u32, 120u32);
    let lights = [
        "- point: { position: [10, 50, -10], diffuse: [1, 1, 1], specular: [0, 0, 0] }",
        // Low sun, 5° above the horizon: grazing shadow rays everywhere, and on the small
        // ground sphere a terminator inside the view.
        "- directional: { direction: [-0.99619, -0.08716, 0], diffuse: [1, 1, 1], specular: [0, 0, 0] }",
    ];
    for radius in [1e2, 1e4, 1e6] {
        for light in lights {
            let center = DVec3::new(0.0, -radius, 0.0);
            let yaml = format!(
                "render: {{ width: {w}, height: {h}, max_depth: 1 }}
camera: {{ position: [0, 5, 0], look_at: [0, 0, -20], fov: 90 }}
objects:
  - sphere: {{ center: {}, radius: {radius:e}, material: {{ ambient: [0.1, 0.1, 0.1], diffuse: [0.8, 0.8, 0.8] }} }}
lights:
  {light}
  - ambient: {{ color: [1, 1, 1] }}
",
                v3(center)
            );
            let seq = parse(&yaml);
            let to_light = |p: DVec3| match seq.scene.lights[0] {
                Light::Point { position, .. } => (position - p).normalize(),
                Light::Directional { to_light, .. } => to_light,
                _ => unreachable!(),
            };
            let frame = render(&seq, 0, &format!("ground radius {radius:e}"));
            let cam = camera_of(&seq, 0);
            let (mut lit, mut acne, mut worst) = (0, 0, 0.0f64);
            for row in 0..h {
                for col in 0..w {
                    let ray = eye_ray(&cam, row, col, w, h);
                    let Some(t) = sphere_truth(center, radius, ray.origin, ray.dir).t else {
                        continue;
                    };
                    let p = ray.origin + t * ray.dir;
                    let n_dot_l = (p - center).normalize().dot(to_light(p));
                    let got = f64::from(frame.pixel(row, col)[0]);
                    if n_dot_l > 1e-6 {
                        lit += 1;
                        if (got - 0.1).abs() < 1e-7 {
                            acne += 1;
                        }
                        worst = worst.max((got - (0.1 + 0.8 * n_dot_l)).abs());
                    }
                }
            }
            assert!(lit > (w * h / 4) as usize, "{lit}");
            assert!(
                acne as f64 <= 1e-3 * lit as f64,
                "radius {radius:e}, {light}: {acne} of {lit} lit pixels shadowed"
            );
            eprintln!(
                "ground radius {radius:e}: {acne} of {lit} lit pixels shadowed, worst shading error {worst:.1e}"
            );
        }
    }
}

#[test]
fn shadows_do_not_leak_at_any_scale() {
    let (w, h) = (128u32, 96u32);
    // A ball resting on the plane (the contact point is where offset-based tracers leak) and
    // one floating above it.
    let balls = [
        (DVec3::new(0.0, 0.3, 0.0), 0.3),
        (DVec3::new(-0.9, 0.55, -0.6), 0.25),
    ];
    let light = DVec3::new(2.0, 2.2, 1.8);
    for s in [1e-4, 1e-2, 1.0, 1e2, 1e4] {
        let yaml = format!(
            "render: {{ width: {w}, height: {h}, max_depth: 1 }}
camera: {{ position: {}, look_at: {}, fov: 70 }}
objects:
  - plane: {{ point: [0, 0, 0], normal: [0, 1, 0], material: {{ ambient: [0.1, 0.1, 0.1], diffuse: [0.8, 0.8, 0.8] }} }}
  - sphere: {{ center: {}, radius: {:e}, material: {{ diffuse: [0.5, 0.5, 0.5] }} }}
  - sphere: {{ center: {}, radius: {:e}, material: {{ diffuse: [0.5, 0.5, 0.5] }} }}
lights:
  - point: {{ position: {}, diffuse: [1, 1, 1], specular: [0, 0, 0] }}
  - ambient: {{ color: [1, 1, 1] }}
",
            v3(s * DVec3::new(0.2, 1.3, 1.5)),
            v3(s * DVec3::new(-0.8, 0.0, -0.6)),
            v3(s * balls[0].0),
            s * balls[0].1,
            v3(s * balls[1].0),
            s * balls[1].1,
            v3(s * light),
        );
        let seq = parse(&yaml);
        let balls: Vec<(DVec3, f64)> = seq.scene.objects[1..]
            .iter()
            .map(|o| match o.shape {
                Shape::Sphere { center, radius } => (center, radius),
                _ => unreachable!(),
            })
            .collect();
        let light = match seq.scene.lights[0] {
            Light::Point { position, .. } => position,
            _ => unreachable!(),
        };
        let frame = render(&seq, 0, &format!("shadow scene ×{s:e}"));
        let cam = camera_of(&seq, 0);
        let (mut shadow, mut dark, mut open, mut bright) = (0, 0, 0, 0);
        'pixels: for row in 0..h {
            for col in 0..w {
                let ray = eye_ray(&cam, row, col, w, h);
                for &(c, r) in &balls {
                    if sphere_truth(c, r, ray.origin, ray.dir).miss_distance < r * (1.0 + 1e-3) {
                        continue 'pixels;
                    }
                }
                if ray.dir.y >= 0.0 {
                    continue;
                }
                let p = ray.origin + (-ray.origin.y / ray.dir.y) * ray.dir;
                // Distance from each ball's centre to the segment from p to the light.
                let seg = light - p;
                let len = seg.length();
                let mut closest = f64::INFINITY;
                for &(c, r) in &balls {
                    let k = ((c - p).dot(seg) / len).clamp(0.0, len);
                    closest = closest.min((p + seg * (k / len) - c).length() / r);
                }
                let got = f64::from(frame.pixel(row, col)[0]);
                let is_dark = (got - 0.1).abs() < 1e-7;
                if closest < 1.0 - 1e-3 {
                    shadow += 1;
                    dark += usize::from(is_dark);
                } else if closest > 1.0 + 1e-3 {
                    open += 1;
                    bright += usize::from(!is_dark);
                }
            }
        }
        assert!(shadow > 300, "scale {s:e}: only {shadow} shadow pixels");
        assert!(
            dark as f64 >= 0.99 * shadow as f64,
            "scale {s:e}: light leaks into {} of {shadow} shadow pixels",
            shadow - dark
        );
        assert!(
            bright as f64 >= 0.999 * open as f64,
            "scale {s:e}: {} of {open} lit plane pixels shadowed",
            open - bright
        );
        eprintln!(
            "shadow scale {s:e}: {dark}/{shadow} shadow pixels dark, {bright}/{open} open pixels lit"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Reflection rays and their own sphere; nested spheres 4e-5 apart.

#[test]
fn mirror_sphere_never_reflects_itself() {
    let (w, h) = (96u32, 96u32);
    for s in [1e-3, 1.0, 1e3] {
        let yaml = |depth: u32| {
            format!(
                "render: {{ width: {w}, height: {h}, max_depth: {depth}, background: [0.25, 0.5, 0.75] }}
camera: {{ position: [0, 0, 0], look_at: {}, fov: 60 }}
objects:
  - sphere: {{ center: {}, radius: {s:e}, material: {{ ambient: [0.1, 0.1, 0.1], diffuse: [0.5, 0.3, 0.2], specular: [0.3, 0.3, 0.3], shininess: 40, reflection: 1 }} }}
lights:
  - point: {{ position: {}, ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
",
                v3(s * DVec3::new(0.3, -0.1, -2.0)),
                v3(s * DVec3::new(0.3, -0.1, -2.0)),
                v3(s * DVec3::new(5.0, 5.0, 5.0))
            )
        };
        let overrides = Overrides {
            depth: true,
            ..Overrides::default()
        };
        let deep = render(&parse_with(&yaml(50), &overrides), 0, "mirror sphere");
        let local = render(
            &parse_with(&yaml(1), &overrides),
            0,
            "mirror sphere, depth 1",
        );
        let depth = deep.depth.as_ref().unwrap();
        let bg = [0.25f32, 0.5, 0.75];
        let mut on_sphere = 0;
        for row in 0..h {
            for col in 0..w {
                let (a, b) = (deep.pixel(row, col), local.pixel(row, col));
                let hit = depth[(row * w + col) as usize] < 1e10;
                on_sphere += usize::from(hit);
                for c in 0..3 {
                    // On the sphere: local shading + the background it reflects. Elsewhere:
                    // the background alone (the depth-1 image shows it too).
                    let want = if hit { b[c] + bg[c] } else { bg[c] };
                    assert!(
                        (a[c] - want).abs() <= 1e-6,
                        "scale {s:e}, pixel ({row}, {col}): {a:?}, local {b:?}"
                    );
                }
            }
        }
        assert!(on_sphere > 500, "{on_sphere}");
    }
}

#[test]
fn nested_spheres_four_hundred_thousandths_apart_are_both_hit() {
    let gap = 4e-5;
    for center in [
        DVec3::ZERO,
        DVec3::new(0.3, -0.2, 0.7),
        DVec3::new(1e3, 2e3, -1e3),
    ] {
        let objects = [
            Object {
                shape: Shape::Sphere {
                    center,
                    radius: 1.0 + gap,
                },
                material: 0,
            },
            Object {
                shape: Shape::Sphere {
                    center,
                    radius: 1.0,
                },
                material: 0,
            },
        ];
        for d in directions(2000) {
            // Outwards from the centre: the inner at 1, then, leaving it, the outer at 4e-5.
            let first = nearest(
                &objects,
                &Ray {
                    origin: center,
                    dir: d,
                    leaving: None,
                },
            )
            .unwrap();
            assert_eq!(first.object, 1, "{center} {d}");
            assert!((first.t - 1.0).abs() < 1e-12, "{}", first.t);
            let p = center + first.t * d;
            let want = sphere_truth(center, 1.0 + gap, p, d).t.unwrap();
            let second = nearest(
                &objects,
                &Ray {
                    origin: p,
                    dir: d,
                    leaving: Some(1),
                },
            )
            .unwrap();
            assert_eq!(second.object, 0, "{center} {d}");
            assert!(
                (second.t - want).abs() < 1e-9 && (second.t - gap).abs() < 1e-9,
                "{} vs {want}",
                second.t
            );
            // Inwards from outside: the outer, then the inner 4e-5 further on.
            let o = center + 3.0 * d;
            let first = nearest(
                &objects,
                &Ray {
                    origin: o,
                    dir: -d,
                    leaving: None,
                },
            )
            .unwrap();
            assert_eq!(first.object, 0);
            let p = o - first.t * d;
            let second = nearest(
                &objects,
                &Ray {
                    origin: p,
                    dir: -d,
                    leaving: Some(0),
                },
            )
            .unwrap();
            assert_eq!(second.object, 1, "{center} {d}");
            assert!((second.t - gap).abs() < 1e-9, "{}", second.t);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 4. A camera inside a sphere.

#[test]
fn camera_inside_a_sphere_sees_its_wall_at_the_radius() {
    let (w, h) = (64u32, 64u32);
    for center in [
        DVec3::ZERO,
        DVec3::new(3.0, -2.0, 5.0),
        DVec3::new(1e5, -2e4, 3e5),
    ] {
        for fov in [30.0, 90.0, 170.0] {
            let yaml = format!(
                "render: {{ width: {w}, height: {h}, max_depth: 4 }}
camera: {{ position: {}, look_at: {}, fov: {fov} }}
objects:
  - sphere: {{ center: {}, radius: 10, material: {{ ambient: [0.1, 0.1, 0.1], diffuse: [0.6, 0.6, 0.6], specular: [1, 1, 1], reflection: 0.5 }} }}
lights:
  - point: {{ position: {}, ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
",
                v3(center),
                v3(center + DVec3::new(0.3, 0.2, -1.0)),
                v3(center),
                v3(center + DVec3::new(1.0, 2.0, 0.5)),
            );
            let seq = parse_with(
                &yaml,
                &Overrides {
                    depth: true,
                    ..Overrides::default()
                },
            );
            let frame = render(&seq, 0, "inside a sphere");
            let cam = camera_of(&seq, 0);
            for (i, &z) in frame.depth.as_ref().unwrap().iter().enumerate() {
                // Z is planar depth: the distance along the ray times its cosine to the view.
                let ray = eye_ray(&cam, i as u32 / w, i as u32 % w, w, h);
                let t = f64::from(z) / ray.dir.dot(cam.forward);
                assert!(
                    (t - 10.0).abs() <= 1e-5 * 10.0 / ray.dir.dot(cam.forward),
                    "centre {center}, fov {fov}, pixel {i}: t = {t}"
                );
            }
            // And in f64, before the depth buffer's f32 rounding: from the centre exactly 10,
            // from anywhere else inside the true root to a few ulps of the coordinates.
            let sphere = &seq.scene.objects[0].shape;
            let ulp = f64::EPSILON * (center.abs().max_element() + 10.0);
            let mut worst = 0.0f64;
            for offset in [
                DVec3::ZERO,
                DVec3::new(3.0, -4.0, 2.0),
                DVec3::new(0.0, 9.999, 0.0),
            ] {
                let origin = center + offset;
                for row in 0..h {
                    for col in 0..w {
                        let ray = Ray {
                            origin,
                            ..eye_ray(&cam, row, col, w, h)
                        };
                        let t = intersect(sphere, &ray, false).unwrap();
                        let want = sphere_truth(center, 10.0, origin, ray.dir).t.unwrap();
                        if offset == DVec3::ZERO {
                            assert_eq!(t, 10.0, "centre {center}");
                        }
                        worst = worst.max((t - want).abs() / ulp);
                        assert!(
                            (t - want).abs() <= 64.0 * ulp,
                            "centre {center} + {offset}: {t} vs {want}"
                        );
                    }
                }
            }
            eprintln!("inside a sphere at {center}, fov {fov}: worst error {worst:.1} ulps");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 5. Far from the origin.

#[test]
fn talk_translated_by_1e5_matches_the_original() {
    let offset = DVec3::new(1e5, 0.0, 1e5);
    let db = talk_psnr(1.0, offset, (160, 90));
    assert!(db >= 40.0, "translated by {offset}: PSNR {db:.1} dB");
    eprintln!("talk translated by {offset}: {db:.1} dB");
}

#[test]
fn talk_far_out_and_at_any_scale_matches_the_original() {
    // The limits docs/numerics.md quotes: features of size 0.1 up to 1e11 from the origin, and any
    // uniform scale whose squared lengths stay inside f64 (1e-150 … 1e150).
    for d in [1e7, 1e9, 1e11] {
        let db = talk_psnr(1.0, DVec3::new(d, 0.0, d), (160, 90));
        assert!(
            db >= 40.0,
            "translated by ({d:e}, 0, {d:e}): PSNR {db:.1} dB"
        );
    }
    for s in [1e-150, 1e-100, 1e-8, 1e8, 1e100, 1e150] {
        let db = talk_psnr(s, DVec3::ZERO, (160, 90));
        assert!(db >= 40.0, "scaled by {s:e}: PSNR {db:.1} dB");
    }
}

#[test]
fn extreme_talk_variants_match_the_talk() {
    // The showcase files are the talk's scene moved or scaled: same image.
    let size = Some((160, 90));
    let base = render(&talk((160, 90)), 0, "talk").to_rgb8();
    for name in ["translated_1e5", "scaled_1e-4", "scaled_1e4"] {
        let path = repo().join(format!("sequences/extremes/{name}.yaml"));
        let seq = load(
            &path,
            &Overrides {
                size,
                ..Overrides::default()
            },
        );
        let db = psnr(&base, &render(&seq, 0, name).to_rgb8());
        assert!(db >= 40.0, "{name}: PSNR {db:.1} dB against the talk");
    }
}

// ---------------------------------------------------------------------------------------------
// 6. Parallel mirrors: deep paths.

fn mirrors_yaml(depth: u32, size: u32, lit: bool) -> String {
    let (material, lights) = if lit {
        (
            "{ ambient: [0.001, 0.001, 0.001], diffuse: [0.002, 0.001, 0], specular: [0.001, 0.001, 0.001], reflection: 1 }",
            "  - point: { position: [0.3, 0.2, 0], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }\n  - ambient: { color: [1, 1, 1] }\n",
        )
    } else {
        // Ambient only: every surface a path visits adds exactly 1/1024.
        (
            "{ ambient: [0.0009765625, 0, 0], diffuse: [0, 0, 0], reflection: 1 }",
            "  - ambient: { color: [1, 1, 1] }\n",
        )
    };
    format!(
        "render: {{ width: {size}, height: {size}, max_depth: {depth} }}
camera: {{ position: [0, 0, 0], look_at: [1, 0.05, 0.02], fov: 60 }}
objects:
  - plane: {{ point: [0, 0, -1], normal: [0, 0, 1], material: {material} }}
  - plane: {{ point: [0, 0, 1], normal: [0, 0, -1], material: {material} }}
lights:
{lights}"
    )
}

#[test]
fn parallel_mirrors_at_depth_1000_are_finite_and_linear() {
    let size = 48u32;
    let mut seconds = Vec::new();
    for depth in [100u32, 1000, 10_000] {
        let seq = parse(&mirrors_yaml(depth, size, false));
        let cam = camera_of(&seq, 0);
        let mut best = f64::INFINITY;
        let mut frame = None;
        // Best of three for the timed depths; the deepest is only checked for its values.
        for _ in 0..if depth > 1000 { 1 } else { 3 } {
            let start = Instant::now();
            frame = Some(render(&seq, 0, &format!("mirrors depth {depth}")));
            best = best.min(start.elapsed().as_secs_f64());
        }
        seconds.push(best);
        let frame = frame.unwrap();
        // Every ray that is not parallel to the mirrors visits exactly `depth` surfaces, each
        // adding 1/1024: the count of work done, read back from the image.
        let mut bouncing = 0u64;
        for row in 0..size {
            for col in 0..size {
                let got = frame.pixel(row, col)[0];
                if eye_ray(&cam, row, col, size, size).dir.z.abs() > 1e-9 {
                    bouncing += 1;
                    assert_eq!(
                        f64::from(got),
                        f64::from(depth) / 1024.0,
                        "depth {depth}, pixel ({row}, {col})"
                    );
                }
            }
        }
        assert!(bouncing > u64::from(size * size / 2));
        // Work is linear in depth: one ray per surface visited, counted rather than timed
        // (the machine is shared); rays parallel to the mirrors are one ray each.
        let missing = (size * size) as u64 - bouncing;
        assert_eq!(
            frame.rays,
            bouncing * u64::from(depth) + missing,
            "depth {depth}"
        );
    }
    // Lit, with shadow rays at every surface, at the deepest depth accepted.
    let seq = parse(&mirrors_yaml(10_000, 32, true));
    let frame = render(&seq, 0, "lit mirrors at depth 10000");
    assert!(frame.rgb.iter().any(|&v| v > 1.0));
    eprintln!(
        "parallel mirrors {size}×{size}: depth 100 {:.4} s, 1000 {:.4} s, 10000 {:.4} s",
        seconds[0], seconds[1], seconds[2]
    );
}

// ---------------------------------------------------------------------------------------------
// 7. Extreme material and light parameters.

#[test]
fn extreme_shininess_is_finite_and_too_large_is_rejected() {
    for shininess in ["0", "1e-300", "1", "1e6"] {
        let yaml = format!(
            "render: {{ width: 64, height: 64, max_depth: 3 }}
camera: {{ position: [0, 0, 2], look_at: [0, 0, 0] }}
objects:
  - sphere: {{ center: [0, 0, 0], radius: 1, material: {{ diffuse: [0.5, 0.5, 0.5], specular: [1e6, 1e6, 1e6], shininess: {shininess}, reflection: 1 }} }}
  - plane: {{ point: [0, -1, 0], normal: [0, 1, 0], material: {{ diffuse: [1e6, 1e6, 1e6], specular: [1, 1, 1], shininess: {shininess}, reflection: 1 }} }}
lights:
  - point: {{ position: [0, 0, 2], diffuse: [1e6, 1e6, 1e6], specular: [1e6, 1e6, 1e6] }}
  - directional: {{ direction: [0, -1, -1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
"
        );
        let frame = render(&parse(&yaml), 0, &format!("shininess {shininess}"));
        // Colours of 1e6 times intensities of 1e6, reflected: large, and still finite.
        assert!(frame.rgb.iter().any(|&v| v > 1e6), "shininess {shininess}");
    }
    let yaml = "camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
objects:
  - sphere: { center: [0, 0, -1], radius: 0.5, material: { diffuse: [1, 1, 1], shininess: 1e7 } }
";
    let err = sequence::parse(Path::new("s.yaml"), yaml)
        .expect_err("shininess 1e7 must be rejected")
        .to_string();
    assert!(err.contains("shininess"), "{err}");
    assert!(err.contains("10000000"), "{err}");
}

#[test]
fn light_exactly_on_the_surface_is_finite() {
    // An odd-sized image: the centre pixel looks exactly along −y, at the sphere's top (0, 1, 0)
    // and, through the plane-only scene, at the plane point (0, 0, 0) — where the lights are.
    let on_sphere = "render: { width: 33, height: 33, max_depth: 3 }
camera: { position: [0, 5, 0], look_at: [0, 0, 0], up: [0, 0, -1], fov: 40 }
objects:
  - sphere: { center: [0, 0, 0], radius: 1, material: { ambient: [0.1, 0.1, 0.1], diffuse: [0.5, 0.5, 0.5], specular: [1, 1, 1], shininess: 0, reflection: 0.5 } }
  - plane: { point: [0, -1, 0], normal: [0, 1, 0], material: { diffuse: [0.5, 0.5, 0.5], reflection: 0.5 } }
lights:
  - point: { position: [0, 1, 0], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
  - spot: { position: [0, 1, 0], direction: [0, -1, 0], inner_angle: 30, outer_angle: 30, ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
";
    let seq = parse(on_sphere);
    let frame = render(&seq, 0, "light on the sphere");
    let cam = camera_of(&seq, 0);
    let centre = eye_ray(&cam, 16, 16, 33, 33);
    assert_eq!(centre.dir, DVec3::NEG_Y);
    let t = intersect(&seq.scene.objects[0].shape, &centre, false).unwrap();
    assert_eq!(
        centre.origin + t * centre.dir,
        DVec3::Y,
        "hit point is the light"
    );
    let world = rayreel::tracer::World::new(seq.scene.clone());
    let color = trace(&world, centre, 3);
    assert!(color.is_finite(), "{color}");
    assert!(frame.pixel(16, 16).iter().all(|v| v.is_finite()));

    let on_plane = "render: { width: 33, height: 33, max_depth: 2 }
camera: { position: [0, 5, 0], look_at: [0, 0, 0], up: [0, 0, -1], fov: 40 }
objects:
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: { ambient: [0.1, 0.1, 0.1], diffuse: [0.5, 0.5, 0.5], specular: [1, 1, 1], shininess: 0, reflection: 1 } }
lights:
  - point: { position: [0, 0, 0], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
  - spot: { position: [0, 0, 0], direction: [0, 1, 0], inner_angle: 0, outer_angle: 0, diffuse: [1, 1, 1], specular: [1, 1, 1] }
";
    let seq = parse(on_plane);
    render(&seq, 0, "light on the plane");
    let cam = camera_of(&seq, 0);
    let centre = eye_ray(&cam, 16, 16, 33, 33);
    assert!(trace(&rayreel::tracer::World::new(seq.scene.clone()), centre, 2).is_finite());
}

#[test]
fn spot_lights_with_hard_edges_are_finite() {
    for (inner, outer) in [(0, 0), (20, 20), (90, 90), (180, 180), (0, 180)] {
        let yaml = format!(
            "render: {{ width: 64, height: 48, max_depth: 2 }}
camera: {{ position: [0, 2, 3], look_at: [0, 0, 0] }}
objects:
  - plane: {{ point: [0, 0, 0], normal: [0, 1, 0], material: {{ ambient: [0.1, 0.1, 0.1], diffuse: [0.7, 0.7, 0.7], specular: [1, 1, 1], reflection: 0.3 }} }}
  - sphere: {{ center: [0, 0.5, 0], radius: 0.5, material: {{ diffuse: [0.7, 0.2, 0.2], specular: [1, 1, 1], shininess: 1e6 }} }}
lights:
  - spot: {{ position: [0, 3, 0], direction: [0, -1, 0], inner_angle: {inner}, outer_angle: {outer}, ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
"
        );
        let frame = render(&parse(&yaml), 0, &format!("spot {inner}/{outer}"));
        if inner == 20 {
            // A hard edge: lit inside the cone, black outside (the falloff scales the ambient
            // term too).
            let values: std::collections::BTreeSet<u8> = frame.to_rgb8().into_iter().collect();
            assert!(values.contains(&0) && values.len() > 2);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 8. Time far into a sequence.

#[test]
fn frame_ten_million_at_60_fps_has_its_exact_time() {
    let yaml = "camera: { position: [0, 0, 1], look_at: [0, 0, 0] }
timeline:
  fps: 60
  duration: 166666.66666666666
  keyframes:
    - { time: 0, position: [0, 0, 1] }
    - { time: 166666.66666666666, position: [0, 0, 2] }
";
    let seq = parse(yaml);
    assert_eq!(seq.timeline.frame_count, 10_000_000);
    assert_eq!(seq.timeline.time_of(10_000_000), 1e7 / 60.0);
    assert_eq!(seq.timeline.time_of(9_999_999), 9_999_999.0 / 60.0);
    assert_eq!(seq.timeline.time_of(600), 10.0);
    for n in [1u64, 7, 59, 61, 999_999, 3_333_333, 9_999_999] {
        assert_eq!(seq.timeline.time_of(n), n as f64 / 60.0);
    }
    render(&seq, 9_999_999, "frame 9999999");
}

#[test]
fn keyframes_a_million_seconds_in_still_interpolate() {
    for interpolation in ["linear", "smooth"] {
        let yaml = format!(
            "render: {{ width: 32, height: 18 }}
camera: {{ position: [0, 0, 1], look_at: [0, 0, 0] }}
timeline:
  fps: 4
  interpolation: {interpolation}
  keyframes:
    - {{ time: 1000000, position: [0, 0, 1] }}
    - {{ time: 1000002, position: [2, 0, 1] }}
    - {{ time: 1000004, position: [4, 0, 1], fov: 60 }}
"
        );
        let seq = parse(&yaml);
        // Frames 0 to 4 000 016: the film ends on the last key.
        assert_eq!(seq.timeline.frame_count, 4_000_017);
        let at = |t: f64| seq.timeline.camera_at(t);
        assert_eq!(at(1e6).position.x, 0.0);
        assert_eq!(at(1e6 + 2.0).position.x, 2.0);
        assert_eq!(at(1e6 + 4.0).position.x, 4.0);
        // Frame 4 000 004 is t = 1 000 001 s, halfway between the first two keys.
        assert_eq!(seq.timeline.time_of(4_000_004), 1e6 + 1.0);
        let mid = seq.timeline.pose_of(4_000_004);
        assert!(
            (mid.position.x - 1.0).abs() < 1e-9,
            "{interpolation}: {}",
            mid.position
        );
        assert!((mid.fov - 90.0).abs() < 1e-9 || interpolation == "smooth");
        // Quarter steps: monotone and evenly spaced to 1e-6 on the linear path.
        let mut last = -1.0;
        for n in 4_000_000..=4_000_016u64 {
            let x = seq.timeline.pose_of(n).position.x;
            assert!(x > last, "{interpolation}: frame {n} at {x} after {last}");
            if interpolation == "linear" {
                assert!((x - (n - 4_000_000) as f64 * 0.25).abs() < 1e-6, "{n}: {x}");
            }
            last = x;
        }
        let frame = render(&seq, 4_000_004, "a million seconds in");
        assert_eq!((frame.width, frame.height), (32, 18));
    }
}

// ---------------------------------------------------------------------------------------------
// 9. Image sizes.

#[test]
fn one_pixel_wide_and_one_pixel_tall_images_render() {
    for (w, h) in [(1u32, 4096u32), (4096, 1), (1, 1)] {
        let yaml = format!(
            "render: {{ width: {w}, height: {h} }}
camera: {{ position: [0, 0, 1], look_at: [0, 0, 0] }}
materials:
  m: {{ ambient: [0.1, 0, 0], diffuse: [0.7, 0, 0], specular: [1, 1, 1], reflection: 0.5 }}
objects:
  - sphere: {{ center: [0, 0, -1], radius: 0.7, material: m }}
  - sphere: {{ center: [0, -9000, 0], radius: 8999.3, material: m }}
lights:
  - point: {{ position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
"
        );
        let frame = render(&parse(&yaml), 0, &format!("{w}×{h}"));
        assert_eq!((frame.width, frame.height), (w, h));
        assert_eq!(frame.to_rgb8().len(), 3 * (w * h) as usize);
        assert!(frame.rgb.iter().any(|&v| v > 0.0), "{w}×{h} is black");
    }
}

#[test]
fn sizes_beyond_the_limit_are_rejected_before_allocating() {
    let base = "camera: { position: [0, 0, 1], look_at: [0, 0, 0] }\n";
    // `--size` is checked as the command line is parsed.
    for size in ["70000x70000", "100000x1", "1x100000", "16385x16384", "0x10"] {
        let err = parse_size(size)
            .expect_err("oversized --size accepted")
            .to_string();
        assert!(err.contains("pixels"), "{err}");
    }
    // 70000 × 70000 = 4.9e9 pixels: more than u32 holds.
    assert!(70_000u64 * 70_000 > u64::from(u32::MAX));
    for key in ["width: 100000", "height: 100000", "width: 4294967296"] {
        let yaml = format!("render: {{ {key} }}\n{base}");
        let err = sequence::parse(Path::new("s.yaml"), &yaml)
            .expect_err("oversized render size accepted")
            .to_string();
        let field = key.split(':').next().unwrap();
        assert!(err.contains(&format!("render.{field}")), "{err}");
    }
    // The largest accepted sizes load (nothing is allocated before rendering): 16384 on a
    // side, and width × height up to 2^26 pixels.
    assert_eq!(parse_size("16384x4096"), Ok((16_384, 4096)));
    let err = parse_size("16384x16384").unwrap_err().to_string();
    assert!(err.contains("268435456 pixels"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// 10. The showcase files.

fn extremes() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("sequences/extremes"))
        .expect("sequences/extremes/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_extreme_sequence_checks_and_renders_finite() {
    let files = extremes();
    for name in [
        "giant_floor_grazing",
        "translated_1e5",
        "scaled_1e-4",
        "scaled_1e4",
        "parallel_mirrors",
    ] {
        assert!(
            files.iter().any(|f| f.file_stem().unwrap() == name),
            "sequences/extremes/{name}.yaml is missing"
        );
    }
    for file in &files {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_rayreel"))
            .arg("check")
            .arg(file)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "rayreel check {}: {}",
            file.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        let seq = load(
            file,
            &Overrides {
                size: Some((96, 54)),
                ..Overrides::default()
            },
        );
        let last = seq.timeline.frame_count - 1;
        for n in [0, last / 2, last] {
            let frame = render(&seq, n, &format!("{} frame {n}", file.display()));
            assert!(
                frame.to_rgb8().iter().any(|&v| v > 0),
                "{} frame {n} is black",
                file.display()
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Measurements behind the limits in docs/numerics.md (run with --ignored --nocapture).

#[test]
#[ignore = "measurement, not a check: prints the limits docs/numerics.md quotes"]
fn measure_limits() {
    for size in [(160, 90), (640, 360)] {
        for d in [1e5, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14] {
            let db = talk_psnr(1.0, DVec3::new(d, 0.0, d), size);
            eprintln!("{size:?} talk translated by ({d:e}, 0, {d:e}): PSNR {db:.1} dB");
        }
        for s in [
            1e-300, 1e-160, 1e-150, 1e-100, 1e-8, 1e-4, 1e4, 1e8, 1e100, 1e150, 1e152, 1e160,
        ] {
            let mut moved = talk(size);
            transform(&mut moved, s, DVec3::ZERO);
            match render_frame(&moved, 0) {
                Ok(f) => {
                    let base = render(&talk(size), 0, "talk").to_rgb8();
                    let db = psnr(&base, &f.to_rgb8());
                    let bad = f.non_finite;
                    eprintln!("{size:?} talk scaled by {s:e}: PSNR {db:.1} dB, non-finite {bad}");
                }
                Err(e) => eprintln!("{size:?} talk scaled by {s:e}: {e}"),
            }
        }
    }
    // Unit sphere from ever farther: the largest distance with no wrong hit outside the band.
    for distance in [1e4, 1e5, 1e6, 1e7, 1e8] {
        let eye = distance * DVec3::new(0.3, 0.55, -0.78).normalize();
        let sphere = Shape::Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        };
        let (mut wrong, mut checked, mut worst) = (0, 0, 0.0f64);
        for d in directions(20000) {
            let target = 1.1 * d;
            let dir = (target - eye).normalize();
            let truth = sphere_truth(DVec3::ZERO, 1.0, eye, dir);
            if (truth.miss_distance - 1.0).abs() <= 1e-3 {
                continue;
            }
            checked += 1;
            let ray = Ray {
                origin: eye,
                dir,
                leaving: None,
            };
            match (truth.t, intersect(&sphere, &ray, false)) {
                (Some(a), Some(b)) => worst = worst.max((a - b).abs()),
                (None, None) => {}
                _ => wrong += 1,
            }
        }
        eprintln!(
            "unit sphere from {distance:e}: {wrong} wrong of {checked}, worst |t − t*| {worst:.1e}"
        );
    }
}
