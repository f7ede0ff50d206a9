//! `rayreel bench --only mesh`: hierarchy build time and eye + shadow rays per second on
//! generated meshes (a 2-million-triangle terrain and a 1-million-triangle blob; `--quick`
//! makes them small), in f64 and f32, and a 1M-triangle frame at 1280×720 with default sampling
//! against the talk's scene at the same settings.

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
    seq.scene.objects = vec![Object {
        shape: Shape::Mesh {
            mesh: 0,
            place: Placement {
                scale: DVec3::ONE,
                rotation: DMat3::IDENTITY,
                translate: DVec3::ZERO,
            },
            shading: MeshShading::Phong,
        },
        material: 0,
    }];
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
    against_talk(o, out, cmd, cores)
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
