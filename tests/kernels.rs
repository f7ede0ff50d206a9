//! Every lane width against the scalar kernel, bit for bit: random rays (from outside, starting
//! on surfaces, inside spheres, grazing spheres, parallel to planes) through random scenes with
//! every light kind, and whole frames from the binary with the widest kernel and with
//! `RAYREEL_KERNEL=scalar`, in f64 and in f32.

mod common;

use common::{run_in, scratch, stderr};
use glam::DVec3;
use rayreel::scene::Shape;
use rayreel::sequence;
use rayreel::tracer::intersect::Ray;
use rayreel::tracer::{Kernel, Precision, World};
use std::path::Path;

/// A small deterministic generator (xorshift64*), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn pick<'a, T>(&mut self, from: &'a [T]) -> &'a T {
        &from[(self.next() * from.len() as f64) as usize % from.len()]
    }
    fn vec(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            if v.length() > 0.1 {
                return v.normalize();
            }
        }
    }
}

fn triple(v: DVec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// A scene of `spheres` spheres (a hierarchy from 12 on) and `planes` planes, with materials
/// mixing whole, fractional, zero and huge exponents and mirrors, and every light kind; with
/// `glass`, most objects also transmit (fixed weights or Fresnel, ior 1 to 2.4, coloured).
fn scene(rng: &mut Rng, spheres: usize, planes: usize, glass: bool) -> String {
    let mut s = String::from("objects:\n");
    let material = |rng: &mut Rng| {
        let reflection = *rng.pick(&[0.0, 0.3, 0.5, 1.0]);
        let mut m = format!(
            "{{ ambient: {}, diffuse: {}, specular: {}, shininess: {}",
            triple(rng.vec(0.0, 0.2)),
            triple(rng.vec(0.0, 1.0)),
            triple(rng.vec(0.0, 1.0)),
            rng.pick(&[0.0, 1.0, 10.0, 37.5, 100.0, 101.0, 400.0, 1e5]),
        );
        let ior = *rng.pick(&[1.0, 1.0, 1.33, 1.5, 2.4]);
        match (glass, *rng.pick(&[0, 1, 2, 3])) {
            (true, 1) => {
                m += &format!(
                    ", fresnel: true, transmission: {}, ior: {ior}",
                    triple(rng.vec(0.3, 1.0))
                )
            }
            (true, 2 | 3) => {
                let t = rng.range(0.0, 1.0 - reflection);
                m += &format!(", reflection: {reflection}, transmission: {t}, ior: {ior}");
            }
            _ => m += &format!(", reflection: {reflection}"),
        }
        m + " }"
    };
    for _ in 0..spheres {
        let (c, r) = (rng.vec(-3.0, 3.0), rng.range(0.05, 1.2));
        s += &format!(
            "  - sphere: {{ center: {}, radius: {r}, material: {} }}\n",
            triple(c),
            material(rng)
        );
    }
    for _ in 0..planes {
        let (p, n) = (rng.vec(-3.0, 3.0), rng.unit());
        s += &format!(
            "  - plane: {{ point: {}, normal: {}, material: {} }}\n",
            triple(p),
            triple(n),
            material(rng)
        );
    }
    let i = |rng: &mut Rng| {
        format!(
            "ambient: {}, diffuse: {}, specular: {}",
            triple(rng.vec(0.0, 1.0)),
            triple(rng.vec(0.0, 1.0)),
            triple(rng.vec(0.0, 1.0))
        )
    };
    s += &format!(
        "lights:\n  - point: {{ position: {}, {} }}\n  - directional: {{ direction: {}, {} }}\n",
        triple(rng.vec(-6.0, 6.0)),
        i(rng),
        triple(rng.unit()),
        i(rng)
    );
    let inner = rng.range(0.0, 40.0);
    for outer in [inner, inner + 20.0] {
        s += &format!(
            "  - spot: {{ position: {}, direction: {}, inner_angle: {inner}, outer_angle: {outer}, {} }}\n",
            triple(rng.vec(-6.0, 6.0)),
            triple(rng.unit()),
            i(rng)
        );
    }
    s += &format!("  - ambient: {{ color: {} }}\n", triple(rng.vec(0.0, 0.3)));
    s + "camera: { position: [0, 0, 10], look_at: [0, 0, 0] }\n"
}

/// Rays of every awkward kind for the scene's objects.
fn rays(rng: &mut Rng, world: &World, n: usize) -> Vec<Ray> {
    let objects = &world.scene.objects;
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let i = (rng.next() * objects.len() as f64) as usize % objects.len();
        let kind = (rng.next() * 6.0) as usize;
        let ray = match (objects[i].shape, kind) {
            // From anywhere, in any direction.
            (_, 0) => Ray {
                origin: rng.vec(-8.0, 8.0),
                dir: rng.unit(),
                leaving: None,
            },
            // Starting on a sphere, heading in or out.
            (Shape::Sphere { center, radius }, 1) => {
                let n = rng.unit();
                let d = rng.unit();
                Ray {
                    origin: center + radius * n,
                    dir: d,
                    leaving: Some(i),
                }
            }
            // Inside a sphere.
            (Shape::Sphere { center, radius }, 2) => Ray {
                origin: center + rng.range(0.0, 0.99) * radius * rng.unit(),
                dir: rng.unit(),
                leaving: None,
            },
            // Grazing a sphere: along a tangent through a surface point.
            (Shape::Sphere { center, radius }, 3) => {
                let n = rng.unit();
                let t = n.cross(rng.unit()).normalize();
                let p = center + radius * n;
                Ray {
                    origin: p - rng.range(0.5, 5.0) * t,
                    dir: t,
                    leaving: None,
                }
            }
            // Parallel to a plane, above it or in it.
            (Shape::Plane { point, normal, .. }, 4) => {
                let d = normal.cross(rng.unit()).normalize();
                let lift = *rng.pick(&[0.0, 1e-9, 0.3]);
                Ray {
                    origin: point + lift * normal + rng.vec(-2.0, 2.0).reject_from(normal),
                    dir: d,
                    leaving: (lift == 0.0).then_some(i),
                }
            }
            // Starting on a plane.
            (Shape::Plane { point, normal, .. }, 5) => Ray {
                origin: point + rng.vec(-2.0, 2.0).reject_from(normal),
                dir: rng.unit(),
                leaving: Some(i),
            },
            _ => continue,
        };
        out.push(ray);
    }
    out
}

fn same(a: DVec3, b: DVec3) -> bool {
    let bits = |v: DVec3| {
        v.to_array()
            .map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() })
    };
    bits(a) == bits(b)
}

/// The kernels wider than the scalar one this CPU has; None (and a notice) when it has none.
fn wide_kernels() -> Option<Vec<Kernel>> {
    let wide: Vec<Kernel> = Kernel::ALL
        .into_iter()
        .filter(|k| *k != Kernel::Scalar && k.supported())
        .collect();
    if wide.is_empty() {
        eprintln!("SKIPPED: this CPU has only the scalar kernel");
        return None;
    }
    Some(wide)
}

#[test]
fn every_width_traces_every_ray_as_the_scalar_kernel_does() {
    let Some(wide) = wide_kernels() else {
        return;
    };
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let cases = [(3, 1), (6, 2), (1, 0), (0, 2), (40, 1), (200, 2)];
    let glass = [(4, 1), (2, 2), (1, 0), (30, 1)];
    let cases = cases
        .map(|c| (c, false))
        .into_iter()
        .chain(glass.map(|c| (c, true)));
    for (case, ((spheres, planes), glass)) in cases.enumerate() {
        let text = scene(&mut rng, spheres, planes, glass);
        let seq = sequence::parse(Path::new("random.yaml"), &text)
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        let world = World::new(seq.scene.clone());
        // Not a multiple of any width, so the last packet has idle lanes.
        let rays = rays(&mut rng, &world, 1003);
        for (depth, p) in [1, 3, 6]
            .into_iter()
            .flat_map(|d| PRECISIONS.map(|p| (d, p)))
        {
            let (want, cast) = Kernel::Scalar.trace(p, &world, &rays, depth);
            for &k in &wide {
                let (got, got_cast) = k.trace(p, &world, &rays, depth);
                let name = format!("case {case} depth {depth} {} {}", k.name(), p.name());
                for (i, (a, b)) in want.iter().zip(&got).enumerate() {
                    assert!(same(*a, *b), "{name}: ray {i} {:?}: {a} vs {b}", rays[i]);
                }
                assert_eq!(cast, got_cast, "{name}");
            }
        }
    }
}

/// Random meshes (a triangle soup and two closed spheres, placed with rotations and uneven
/// scales) among spheres and planes: rays from anywhere, and rays aimed exactly at vertices
/// and at points of shared edges, traced by every width as by the scalar kernel.
#[test]
fn every_width_traces_rays_through_meshes_as_the_scalar_kernel_does() {
    let Some(wide) = wide_kernels() else {
        return;
    };
    let tmp = scratch("kernels-random-mesh");
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let mut soup = String::new();
    for _ in 0..60 {
        soup += &format!(
            "v {} {} {}\n",
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0)
        );
    }
    for _ in 0..80 {
        let i = |rng: &mut Rng| 1 + (rng.next() * 60.0) as usize % 60;
        soup += &format!("f {} {} {}\n", i(&mut rng), i(&mut rng), i(&mut rng));
    }
    std::fs::write(tmp.join("soup.obj"), soup).unwrap();
    std::fs::write(tmp.join("ball.obj"), common::uv_sphere(11, 6, true, false)).unwrap();
    let mut text = scene(&mut rng, 5, 1, true);
    let meshes = "objects:
  - mesh: { file: soup.obj, scale: [1.5, 0.8, 1.1], rotate: [12, 40, -7], translate: [0.5, 0.2, 0], material: { diffuse: [0.6, 0.5, 0.4], specular: [1, 1, 1], reflection: 0.4 } }
  - mesh: { file: ball.obj, shading: gouraud, translate: [-1.5, 0.5, 1], material: { diffuse: [0.3, 0.6, 0.4], specular: [1, 1, 1] } }
  - mesh: { file: ball.obj, shading: constant, scale: 0.7, translate: [1.8, -0.5, 1.5], material: { diffuse: [0, 0, 0], transmission: 0.8, ior: 1.4 } }
";
    text = text.replacen("objects:\n", meshes, 1);
    let file = tmp.join("random.yaml");
    let seq = sequence::parse(&file, &text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let world = World::new(seq.scene.clone());
    let mut rays = Vec::new();
    let corners: Vec<DVec3> = (0..40).map(|_| rng.vec(-2.0, 2.0)).collect();
    while rays.len() < 1003 {
        let origin = rng.vec(-6.0, 6.0);
        let target = match rays.len() % 3 {
            0 => rng.vec(-2.0, 2.0),
            // Along the line between two random points, as shared edges of the soup lie.
            1 => {
                let (a, b) = (*rng.pick(&corners), *rng.pick(&corners));
                a + (b - a) * rng.next()
            }
            _ => *rng.pick(&corners),
        };
        let d = (target - origin).normalize();
        if d.is_finite() {
            rays.push(Ray {
                origin,
                dir: d,
                leaving: None,
            });
        }
    }
    for (depth, p) in [1, 4].into_iter().flat_map(|d| PRECISIONS.map(|p| (d, p))) {
        let (want, cast) = Kernel::Scalar.trace(p, &world, &rays, depth);
        for &k in &wide {
            let (got, got_cast) = k.trace(p, &world, &rays, depth);
            let name = format!("depth {depth} {} {}", k.name(), p.name());
            for (i, (a, b)) in want.iter().zip(&got).enumerate() {
                assert!(same(*a, *b), "{name}: ray {i} {:?}: {a} vs {b}", rays[i]);
            }
            assert_eq!(cast, got_cast, "{name}");
        }
    }
}

const PRECISIONS: [Precision; 2] = [Precision::F64, Precision::F32];

/// Renders `args` with every kernel this CPU has, in f64 and in f32; every output must equal
/// the scalar one of its precision.
fn every_kernel_equals_scalar(dir: &Path, name: &str, args: &[&str]) {
    for p in PRECISIONS {
        let name = format!("{name}-{}", p.name());
        let args = [args, &["--precision", p.name()]].concat();
        kernels_agree(dir, &name, &args);
    }
}

fn kernels_agree(dir: &Path, name: &str, args: &[&str]) {
    let mut outputs = Vec::new();
    for kernel in Kernel::ALL
        .iter()
        .filter(|k| k.supported())
        .map(|k| k.name())
    {
        let out_dir = format!("{name}-{kernel}");
        let pattern = format!("{out_dir}/f_####.exr");
        let mut all = vec!["render", "seq.yaml", "-q", "--exr-precision", "float", "-o"];
        all.push(&pattern);
        all.extend(args);
        let out = common::bin()
            .args(&all)
            .current_dir(dir)
            .env("RAYREEL_KERNEL", kernel)
            .output()
            .unwrap();
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        outputs.push(dir.join(out_dir));
    }
    // Every channel of every frame, bit for bit (the headers hold nothing of the kernel).
    let frames = common::files(&outputs[0]);
    for (f, other) in outputs[1..]
        .iter()
        .flat_map(|o| frames.iter().map(move |f| (f, o)))
    {
        let read = |dir: &Path| {
            let img = exr::prelude::read_all_flat_layers_from_file(dir.join(f)).unwrap();
            let layer = &img.layer_data[0];
            let channels: Vec<(String, Vec<u32>)> = layer
                .channel_data
                .list
                .iter()
                .map(|c| {
                    let bits = match &c.sample_data {
                        exr::image::FlatSamples::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
                        other => panic!("{f}: {} is not f32: {other:?}", c.name),
                    };
                    (c.name.to_string(), bits)
                })
                .collect();
            channels
        };
        assert!(
            read(&outputs[0]) == read(other),
            "{name}: {f} differs in {}",
            other.display()
        );
    }
}

#[test]
fn frames_from_every_kernel_equal_the_scalar_kernels() {
    let tmp = scratch("kernels");
    let talk = std::fs::read_to_string(common::repo().join("sequences/talk.yaml")).unwrap();
    std::fs::write(tmp.join("seq.yaml"), talk).unwrap();
    every_kernel_equals_scalar(&tmp, "talk", &["--size", "333x187", "--depth"]);
    every_kernel_equals_scalar(&tmp, "final", &["--size", "161x90", "--quality", "final"]);
    every_kernel_equals_scalar(&tmp, "grid", &["--size", "97x55", "--samples", "9"]);
    let alpha = [
        "--size",
        "161x90",
        "--quality",
        "final",
        "--alpha",
        "--depth",
    ];
    every_kernel_equals_scalar(&tmp, "alpha", &alpha);
    let mut rng = Rng(7);
    let field = scene(&mut rng, 60, 1, false).replace(
        "camera: { position: [0, 0, 10]",
        "render: { max_depth: 4 }\ncamera: { position: [0, 0, 10]",
    );
    std::fs::write(tmp.join("seq.yaml"), field).unwrap();
    every_kernel_equals_scalar(&tmp, "field", &["--size", "130x70", "--samples", "5"]);
    let alpha = ["--size", "130x70", "--alpha", "--exposure", "0.7"];
    every_kernel_equals_scalar(&tmp, "field-alpha", &alpha);
    let glass = scene(&mut rng, 20, 2, true).replace(
        "camera: { position: [0, 0, 10]",
        "render: { max_depth: 6 }\ncamera: { position: [0, 0, 10]",
    );
    std::fs::write(tmp.join("seq.yaml"), glass).unwrap();
    every_kernel_equals_scalar(&tmp, "glass", &["--size", "120x66", "--samples", "5"]);
    let glass_seq = std::fs::read_to_string(common::repo().join("sequences/glass.yaml")).unwrap();
    std::fs::write(tmp.join("seq.yaml"), glass_seq).unwrap();
    every_kernel_equals_scalar(&tmp, "glass.yaml", &["--size", "96x54", "--frames", "0,30"]);
    let glass_alpha = ["--size", "96x54", "--frames", "30", "--alpha"];
    every_kernel_equals_scalar(&tmp, "glass-alpha", &glass_alpha);
    let out = run_in(&tmp, &["check", "seq.yaml"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// Checker and image maps on planes, spheres and a mesh, seen directly, in a curved mirror and
/// through glass (cones through reflection and refraction), with motion blur.
#[test]
fn textured_frames_from_every_kernel_equal_the_scalar_kernels() {
    let tmp = scratch("kernels-texture");
    let textures = common::repo().join("sequences/textures");
    std::fs::create_dir(tmp.join("textures")).unwrap();
    for f in ["globe.png", "wood.png"] {
        std::fs::copy(textures.join(f), tmp.join("textures").join(f)).unwrap();
    }
    std::fs::write(
        tmp.join("tile.obj"),
        "v -1 0 -1\nv 1 0 -1\nv 1 0.4 1\nv -1 0 1\nvt 0 0\nvt 3 0\nvt 3 3\nvt 0 3\nf 1/1 4/4 3/3 2/2\n",
    )
    .unwrap();
    let seq = "render: { max_depth: 5 }
materials:
  tiles: { diffuse: { checker: { size: 0.4, colors: [[0.9, 0.9, 0.9], [0.1, 0.2, 0.1]] } }, ambient: [0.05, 0.05, 0.05], reflection: 0.2 }
  globe: { diffuse: { image: textures/globe.png }, ambient: { image: textures/globe.png, scale: [1, 1] }, specular: [1, 1, 1], shininess: 80 }
  wood:  { diffuse: { image: textures/wood.png, scale: [2, 1] }, specular: [0.2, 0.2, 0.2] }
objects:
  - plane:  { point: [0, -1, 0], normal: [0, 1, 0], material: tiles }
  - plane:  { point: [0, 0, -6], normal: [0, 0, 1], u_axis: [1, 1, 0], material: wood }
  - sphere: { center: [-0.9, 0, -1], radius: 0.8, material: globe }
  - sphere: { center: [1.1, -0.3, -0.5], radius: 0.6, material: { diffuse: [0.05, 0.05, 0.05], specular: [1, 1, 1], reflection: 0.8 } }
  - sphere: { center: [0.2, -0.5, 0.8], radius: 0.35, material: { diffuse: [0, 0, 0], transmission: 0.9, ior: 1.5 } }
  - mesh:   { file: tile.obj, translate: [0.3, -0.9, -2.5], material: wood }
lights:
  - point: { position: [4, 5, 6], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
timeline:
  fps: 12
  keyframes:
    - { time: 0, position: [0.3, 0.6, 4], look_at: [0, -0.4, -1], fov: 60 }
    - { time: 1, position: [-0.5, 0.2, 3], look_at: [0, -0.4, -1], fov: 50 }
";
    std::fs::write(tmp.join("seq.yaml"), seq).unwrap();
    every_kernel_equals_scalar(
        &tmp,
        "texture",
        &["--size", "97x55", "--samples", "2", "--frames", "3"],
    );
    let blurred = seq.replace(
        "render: { max_depth: 5 }",
        "render: { max_depth: 5, shutter: 180 }",
    );
    std::fs::write(tmp.join("seq.yaml"), &blurred).unwrap();
    let blur = ["--size", "81x45", "--samples", "3", "--frames", "5"];
    every_kernel_equals_scalar(&tmp, "texture-blur", &blur);
    // A lens too: each lane's pixel seen from its own lens point at its own instant.
    let lens = blurred.replacen(
        "fov: 60 }",
        "fov: 60, aperture: 0.08, focus_distance: 4 }",
        1,
    );
    assert!(lens.contains("aperture"));
    std::fs::write(tmp.join("seq.yaml"), lens).unwrap();
    every_kernel_equals_scalar(&tmp, "texture-lens", &blur);
    // Under an image sky (the globe, turned), seen directly, in the mirror and through glass.
    let sky = seq.replace(
        "render: { max_depth: 5 }",
        "render: { max_depth: 5, background: { image: textures/globe.png, rotate: 20 } }",
    );
    std::fs::write(tmp.join("seq.yaml"), sky).unwrap();
    let args = ["--size", "65x37", "--samples", "2", "--frames", "3"];
    every_kernel_equals_scalar(&tmp, "texture-sky", &args);
}

/// Motion blur and depth of field give each lane its own camera, instant and lens point.
/// Meshes in every shading model, with a mirror and glass, traced by every kernel.
#[test]
fn mesh_frames_from_every_kernel_equal_the_scalar_kernels() {
    let tmp = scratch("kernels-mesh");
    std::fs::write(tmp.join("ball.obj"), common::uv_sphere(14, 7, true, false)).unwrap();
    std::fs::write(tmp.join("bare.obj"), common::uv_sphere(9, 5, false, true)).unwrap();
    let clay = "{ ambient: [0.1, 0.05, 0.05], diffuse: [0.7, 0.4, 0.3], specular: [1, 1, 1], shininess: 40, reflection: 0.2 }";
    let seq = format!(
        "objects:
  - mesh: {{ file: ball.obj, shading: phong, translate: [-1.1, 0, 0], material: {clay} }}
  - mesh: {{ file: ball.obj, shading: flat, translate: [1.1, 0, 0], rotate: [10, 20, 30], material: {clay} }}
  - mesh: {{ file: bare.obj, shading: gouraud, translate: [0, 0, -1.6], scale: [1, 0.7, 1], material: {clay} }}
  - mesh: {{ file: ball.obj, shading: constant, translate: [0, -0.3, 1.2], scale: 0.5, material: {clay} }}
  - mesh: {{ file: bare.obj, translate: [0.4, 0.9, 0.9], scale: 0.4, material: {{ diffuse: [0, 0, 0], transmission: 0.9, ior: 1.5 }} }}
  - sphere: {{ center: [-0.6, 0.9, -0.4], radius: 0.3, material: {clay} }}
  - plane: {{ point: [0, -1, 0], normal: [0, 1, 0], material: {{ diffuse: [0.6, 0.6, 0.6], reflection: 0.3 }} }}
lights:
  - point: {{ position: [4, 5, 6], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
  - directional: {{ direction: [-1, -2, -0.5], diffuse: [0.3, 0.3, 0.3], specular: [0.2, 0.2, 0.2] }}
camera: {{ position: [0.3, 1.2, 4], look_at: [0, 0, -0.3], fov: 60 }}
"
    );
    std::fs::write(tmp.join("seq.yaml"), seq).unwrap();
    every_kernel_equals_scalar(
        &tmp,
        "mesh",
        &["--size", "97x55", "--samples", "2", "--depth"],
    );
}

/// Sphere and rect lights (their points are placed per lane, in f64, from each lane's own
/// surface point and pixel) over spheres, a plane, glass, a mirror and meshes in every
/// shading model, at one sample, a grid, R2 and adaptive sampling, with a lens.
#[test]
fn area_light_frames_from_every_kernel_equal_the_scalar_kernels() {
    let tmp = scratch("kernels-area");
    std::fs::write(tmp.join("ball.obj"), common::uv_sphere(14, 7, true, false)).unwrap();
    let soft = std::fs::read_to_string(common::repo().join("sequences/soft-shadows.yaml")).unwrap();
    std::fs::write(tmp.join("seq.yaml"), &soft).unwrap();
    every_kernel_equals_scalar(&tmp, "soft", &["--size", "97x55", "--samples", "1"]);
    every_kernel_equals_scalar(
        &tmp,
        "soft-final",
        &["--size", "65x37", "--quality", "final"],
    );
    let extra = "objects:
  - mesh: { file: ball.obj, shading: gouraud, scale: 0.3, translate: [0.2, 0.3, 1.5], material: { diffuse: [0.3, 0.3, 0.7], specular: [1, 1, 1] } }
  - mesh: { file: ball.obj, shading: phong, scale: 0.25, translate: [-1.6, 0.25, 1.2], material: { diffuse: [0.7, 0.6, 0.2], specular: [1, 1, 1], shininess: 30 } }
  - sphere: { center: [0.6, 0.3, 2.0], radius: 0.3, material: { diffuse: [0, 0, 0], transmission: 0.9, ior: 1.5, fresnel: true } }
  - sphere: { center: [-0.2, 3.3, 0.6], radius: 0.2, material: { diffuse: [0.5, 0.5, 0.5] } }
";
    let scene = soft.replacen("objects:\n", extra, 1).replacen(
        "  fov: 60\n",
        "  fov: 60\n  aperture: 0.05\n",
        1,
    );
    std::fs::write(tmp.join("seq.yaml"), scene).unwrap();
    every_kernel_equals_scalar(&tmp, "mixed-grid", &["--size", "81x46", "--samples", "4"]);
    every_kernel_equals_scalar(&tmp, "mixed-r2", &["--size", "65x37", "--samples", "3"]);
}

#[test]
fn blurred_and_defocused_frames_from_every_kernel_equal_the_scalar_kernels() {
    let tmp = scratch("kernels-film");
    let read = |name: &str| std::fs::read_to_string(common::repo().join(name)).unwrap();
    let talk = read("sequences/talk.yaml");
    let lens = "camera:\n  aperture: 0.08\n  focus_distance: 0.9\n";
    std::fs::write(tmp.join("seq.yaml"), talk.replacen("camera:\n", lens, 1)).unwrap();
    every_kernel_equals_scalar(&tmp, "lens", &["--size", "97x55", "--samples", "5"]);
    let flyby = read("sequences/flyby.yaml");
    std::fs::write(tmp.join("seq.yaml"), &flyby).unwrap();
    let frames = ["--frames", "20,100"];
    let film = |args: &[&'static str]| [&frames[..], args].concat();
    every_kernel_equals_scalar(
        &tmp,
        "film-grid",
        &film(&["--size", "97x55", "--samples", "4"]),
    );
    every_kernel_equals_scalar(
        &tmp,
        "film-r2",
        &film(&["--size", "81x46", "--samples", "3"]),
    );
    every_kernel_equals_scalar(
        &tmp,
        "film-final",
        &film(&["--size", "65x37", "--quality", "final"]),
    );
    every_kernel_equals_scalar(
        &tmp,
        "film-alpha",
        &film(&["--size", "65x37", "--alpha", "--exposure", "-0.5"]),
    );
    // A lens opening from a pinhole at frame 0: lanes of one packet with and without a lens.
    let opening = flyby
        .replacen("aperture: 0.04 }", "aperture: 0 }", 1)
        .replacen("fov: 65 }", "fov: 65, aperture: 0.08 }", 1);
    assert_ne!(opening, flyby);
    std::fs::write(tmp.join("seq.yaml"), opening).unwrap();
    every_kernel_equals_scalar(
        &tmp,
        "opening",
        &["--size", "97x55", "--frames", "0-1", "--samples", "4"],
    );
    let orbit = read("sequences/orbit.yaml");
    std::fs::write(tmp.join("seq.yaml"), orbit).unwrap();
    every_kernel_equals_scalar(
        &tmp,
        "orbit",
        &["--size", "97x55", "--frames", "5", "--depth"],
    );
    let glass = read("sequences/glass.yaml")
        .replacen("  samples: 4\n", "  samples: 4\n  shutter: 180\n", 1)
        .replacen("  fov: 70\n", "  fov: 70\n  aperture: 0.05\n", 1);
    assert!(glass.contains("shutter: 180") && glass.contains("aperture: 0.05"));
    std::fs::write(tmp.join("seq.yaml"), glass).unwrap();
    every_kernel_equals_scalar(&tmp, "glass", &["--size", "96x54", "--frames", "0,30"]);
}

/// The wide kernels are generic code inlined into `#[target_feature]` functions; anything on
/// that path the compiler cannot inline (a closure doing lane arithmetic, for instance) turns
/// each SIMD instruction into a call and the kernel several times slower while every test
/// still passes. The binary must call no SIMD intrinsic out of line except CPU detection's.
#[test]
fn no_simd_intrinsic_is_left_out_of_line() {
    if !common::have_tool("objdump") {
        return;
    }
    let out = std::process::Command::new("objdump")
        .args([
            "-d",
            "--no-show-raw-insn",
            "-C",
            env!("CARGO_BIN_EXE_rayreel"),
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let mut function = "";
    let calls: Vec<String> = text
        .lines()
        .filter_map(|l| {
            if l.ends_with(">:") {
                function = l;
            }
            (l.contains("call") && l.contains("core_arch") && !l.contains("xgetbv"))
                .then(|| format!("{function} {l}"))
        })
        .collect();
    assert!(
        calls.is_empty(),
        "out-of-line SIMD calls:\n{}",
        calls.join("\n")
    );
}
