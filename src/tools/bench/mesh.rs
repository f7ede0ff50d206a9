//! `rayreel bench --only mesh`: hierarchy build time and eye + shadow rays per second on
//! generated meshes (a 2-million-triangle terrain and a 1-million-triangle blob; `--quick`
//! makes them small), in f64 and f32, a 1M-triangle frame at 1280×720 with default sampling
//! against the talk's scene at the same settings, and 10,000 placements of a 100k-triangle
//! model against one placement of it covering as much of the frame.

use super::{BenchError, Options, load, render_only, repeat};
use crate::scene::{Mesh, MeshShading, Object, Placement, Shape};
use crate::schedule::RunError;
use crate::sequence::Sequence;
use crate::tools::meshgen;
use crate::tracer::bvh::Bvh;
use crate::tracer::{Precision, World};
use glam::{DMat3, DVec3};
use std::sync::Arc;

/// One model in a scene of its own: a clay material, one point light, no floor (so frames
/// cast exactly eye rays and one shadow ray per hit, as the Embree harness does).
fn scene(
    mesh: Arc<Mesh>,
    camera: &str,
    size: (u32, u32),
    extra: &str,
) -> Result<Sequence, BenchError> {
    let identity = Placement {
        scale: DVec3::ONE,
        rotation: DMat3::IDENTITY,
        translate: DVec3::ZERO,
    };
    placed(mesh, &[identity], camera, size, extra)
}

/// `scene` with the model placed at each of `places`.
fn placed(
    mesh: Arc<Mesh>,
    places: &[Placement],
    camera: &str,
    (w, h): (u32, u32),
    extra: &str,
) -> Result<Sequence, BenchError> {
    let text = format!(
        "render: {{ {extra} }}
materials:
  clay: {{ ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }}
objects:
  - sphere: {{ center: [0, 0, 0], radius: 1, material: clay }}
lights:
  - point: {{ position: [3, 5, 4], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }}
camera: {camera}
"
    );
    let mut seq = load(&text, (w, h))?;
    seq.scene.meshes = vec![mesh];
    seq.scene.objects = (places.iter())
        .map(|&place| Object {
            shape: Shape::Mesh {
                mesh: 0,
                place,
                shading: MeshShading::Phong,
            },
            material: 0,
        })
        .collect();
    Ok(seq)
}

pub(super) fn meshes(o: &Options, out: &mut dyn FnMut(&str), cmd: &str) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let size = if o.quick { (320, 180) } else { (1920, 1080) };
    let models = if o.quick {
        [
            ("terrain", meshgen::terrain(101)),
            ("blob", meshgen::blob(100, 50)),
        ]
    } else {
        [
            ("terrain", meshgen::terrain(1001)),
            ("blob", meshgen::blob(1000, 500)),
        ]
    };
    let cameras = [
        "{ position: [0.2, 1.1, 2.1], look_at: [0, -0.1, 0], fov: 60 }",
        "{ position: [0.4, 0.6, 3.1], look_at: [0, 0, 0], fov: 45 }",
    ];
    for ((name, mesh), camera) in models.into_iter().zip(cameras) {
        let triangles = mesh.triangles.len();
        let mesh = Arc::new(mesh);
        let build = repeat(o.runs, || {
            let built = Bvh::build(&mesh).map_err(RunError::Allocation)?;
            std::hint::black_box(built);
            Ok(())
        })?;
        let mut line = format!(
            "mesh {name} {triangles} triangles: hierarchy built in {:.3} s ({:.3}-{:.3})",
            build.median, build.min, build.max
        );
        let one = "samples: 1, max_depth: 1";
        let seq = scene(mesh, camera, size, one)?;
        let world = World::new(seq.scene.clone());
        for precision in [Precision::F64, Precision::F32] {
            let mut s = seq.clone();
            s.settings.precision = precision;
            let (t, frame) = render_only(&world, &s, cores, o.runs)?;
            line += &format!(
                "; {}x{} 1 spp eye+shadow {}: {:.2} frames/s, {:.1} M rays/s",
                size.0,
                size.1,
                precision.name(),
                1.0 / t.median,
                frame.rays as f64 / t.median / 1e6
            );
        }
        out(&format!("{line}   [{cmd}]"));
    }
    against_talk(o, out, cmd, cores)?;
    instances(o, out, cmd, cores)
}

/// 10,000 placements of one 100k-triangle model on a 100×100 grid seen from above, against
/// one placement of the same model scaled to cover as much of the frame (target: at most 3×
/// the time), 1920×1080, 1 sample, eye + shadow rays, in f64 and f32.
fn instances(
    o: &Options,
    out: &mut dyn FnMut(&str),
    cmd: &str,
    cores: usize,
) -> Result<(), BenchError> {
    let (side, model, size) = match o.quick {
        true => (20, meshgen::blob(60, 30), (320, 180)),
        false => (100, meshgen::blob(317, 159), (1920, 1080)),
    };
    let (n, triangles, model) = (side * side, model.triangles.len(), Arc::new(model));
    let half = side as f64 / 2.0;
    let camera = format!(
        "{{ position: [{half}, {}, {}], look_at: [{half}, 0, {half}], fov: 50 }}",
        0.9 * side as f64,
        1.3 * side as f64
    );
    let grid: Vec<Placement> = (0..n)
        .map(|i| Placement {
            scale: DVec3::splat(0.35),
            rotation: DMat3::from_rotation_y((i * 37 % 360) as f64 * std::f64::consts::PI / 180.0),
            translate: DVec3::new((i % side) as f64 + 0.5, 0.0, (i / side) as f64 + 0.5),
        })
        .collect();
    let one = "samples: 1, max_depth: 1";
    let forest = placed(model.clone(), &grid, &camera, size, one)?;
    let forest_world = World::new(forest.scene.clone());
    let covered = |world: &World, seq: &Sequence| -> Result<f64, BenchError> {
        let (_, frame) = render_only(world, seq, cores, 1)?;
        let lit = frame.rgb.chunks(3).filter(|p| p.iter().any(|&c| c > 0.0));
        Ok(lit.count() as f64 / (frame.width * frame.height) as f64)
    };
    let share = covered(&forest_world, &forest)?;
    // One placement at the grid's centre, scaled (twice, by the square root of the shares)
    // until it covers the forest's share of the frame.
    let mut scale = 0.35 * side as f64 / 3.0;
    let single = |scale: f64| {
        let place = Placement {
            scale: DVec3::splat(scale),
            rotation: DMat3::IDENTITY,
            translate: DVec3::new(half, 0.0, half),
        };
        let seq = placed(model.clone(), &[place], &camera, size, one)?;
        let world = World::new(seq.scene.clone());
        let got = covered(&world, &seq)?;
        Ok::<_, BenchError>((seq, world, got))
    };
    let (mut seq, mut world, mut got) = single(scale)?;
    for _ in 0..2 {
        scale *= (share / got).sqrt();
        (seq, world, got) = single(scale)?;
    }
    let mut line = format!(
        "mesh {n} placements of one {triangles}-triangle model ({:.1}% of the frame) vs one placement ({:.1}%), {}x{} 1 spp eye+shadow:",
        100.0 * share,
        100.0 * got,
        size.0,
        size.1
    );
    for precision in [Precision::F64, Precision::F32] {
        let (mut a, mut b) = (forest.clone(), seq.clone());
        (a.settings.precision, b.settings.precision) = (precision, precision);
        let (tf, _) = render_only(&forest_world, &a, cores, o.runs)?;
        let (t1, _) = render_only(&world, &b, cores, o.runs)?;
        line += &format!(
            " {} {:.1} ms vs {:.1} ms, {:.2}x the time;",
            precision.name(),
            1e3 * tf.median,
            1e3 * t1.median,
            tf.median / t1.median
        );
    }
    out(&format!("{line} (target at most 3x)   [{cmd}]"));
    Ok(())
}

/// The 1M-triangle blob at 1280×720 with default sampling, against the talk's scene.
fn against_talk(
    o: &Options,
    out: &mut dyn FnMut(&str),
    cmd: &str,
    cores: usize,
) -> Result<(), BenchError> {
    let size = if o.quick { (320, 180) } else { (1280, 720) };
    let blob = if o.quick {
        meshgen::blob(100, 50)
    } else {
        meshgen::blob(1000, 500)
    };
    let triangles = blob.triangles.len();
    let seq = scene(
        Arc::new(blob),
        "{ position: [0.4, 0.6, 3.1], look_at: [0, 0, 0], fov: 45 }",
        size,
        "",
    )?;
    let (tm, _) = render_only(&World::new(seq.scene.clone()), &seq, cores, o.runs)?;
    let mut plain = load(super::TALK, size)?;
    plain.settings.samples = seq.settings.samples;
    plain.settings.adaptive = seq.settings.adaptive;
    let (tt, _) = render_only(&World::new(plain.scene.clone()), &plain, cores, o.runs)?;
    out(&format!(
        "mesh blob {triangles} triangles {}x{} default sampling: {:.3} s a frame vs the talk's scene at the same settings {:.3} s: {:.2}x the time (target at most 3x)   [{cmd}]",
        size.0,
        size.1,
        tm.median,
        tt.median,
        tm.median / tt.median
    ));
    Ok(())
}
