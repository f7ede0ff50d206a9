//! `rayreel bench --only motion`: what posing things that move costs a frame. 1,000 placements
//! of one model, each keyed to turn and rise, are posed at a frame's time (their tracks
//! evaluated, the top level and the rest of the per-frame stage rebuilt: `World::posed`), against
//! rendering that frame at 1920×1080 with one sample (`--quick`: 100 placements, 320×180).
//! Two layouts: a grid and a scatter (whose boxes overlap more).

use super::{BenchError, Options, load, render_only, repeat};
use crate::scene::{MeshShading, Object, Placement, Shape, rotation};
use crate::timeline::Interpolation;
use crate::timeline::motion::{MeshFrame, Posed, Rig, RigKey, Thing};
use crate::timeline::{Ease, motion::Field};
use crate::tools::meshgen;
use crate::tracer::World;
use glam::{DMat3, DVec3};
use std::sync::Arc;

const SCENE: &str = "render: { samples: 1, max_depth: 2 }
materials:
  clay: { ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }
objects:
  - plane: { point: [0, 0, 0], normal: [0, 1, 0], material: clay }
lights:
  - point: { position: [30, 40, 50], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
camera: { position: [-8, 14, 12], look_at: [18, 0, -18], fov: 60 }
";

/// Where placement i of n stands: on a grid, or scattered by a hash over the same area.
fn spot(i: usize, n: usize, scatter: bool) -> DVec3 {
    let side = (n as f64).sqrt().ceil() as usize;
    if !scatter {
        return DVec3::new((i % side) as f64 * 1.2, 0.5, (i / side) as f64 * -1.2);
    }
    // splitmix64's finaliser: a fixed scatter, the same on every machine.
    let mut h = (i as u64).wrapping_add(0x9e3779b97f4a7c15);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d049bb133111eb);
    h ^= h >> 31;
    let unit = |bits: u64| (bits >> 11) as f64 / (1u64 << 53) as f64;
    let reach = side as f64 * 1.2;
    DVec3::new(unit(h) * reach, 0.5, -unit(h.rotate_left(32)) * reach)
}

/// Placement i turning once about y and rising 0.5 over a second.
fn rig(i: usize, at: DVec3, material: usize) -> Rig {
    let place = Placement {
        scale: DVec3::splat(0.5),
        rotation: rotation(DVec3::ZERO),
        translate: at,
    };
    let object = Object {
        shape: Shape::Mesh {
            mesh: 0,
            place,
            shading: MeshShading::Phong,
        },
        material,
    };
    let key = |time: f64, turn: f64, rise: f64| RigKey {
        time,
        ease: Ease::Pass,
        values: vec![
            (Field::Rotate, DVec3::new(0.0, turn, 0.0)),
            (Field::Translate, at + DVec3::new(0.0, rise, 0.0)),
        ],
    };
    let frame = MeshFrame {
        up: DMat3::IDENTITY,
        offset: None,
    };
    Rig::new(
        Thing::Object(i),
        Posed::Object(object),
        Some(frame),
        &[key(0.0, 0.0, 0.0), key(1.0, 360.0, 0.5)],
        Interpolation::Smooth,
    )
}

pub(super) fn motion(o: &Options, out: &mut dyn FnMut(&str), cmd: &str) -> Result<(), BenchError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (n, size) = match o.quick {
        true => (100, (320, 180)),
        false => (1000, (1920, 1080)),
    };
    for scatter in [false, true] {
        let mut seq = load(SCENE, size)?;
        seq.scene.meshes = vec![Arc::new(meshgen::blob(24, 12))];
        let rigs: Vec<Rig> = (0..n).map(|i| rig(i + 1, spot(i, n, scatter), 0)).collect();
        for r in &rigs {
            if let Posed::Object(o) = r.base {
                seq.scene.objects.push(o);
            }
        }
        seq.timeline.motion = rigs;
        let world = World::new(seq.scene.clone());
        let t = 0.5;
        let pose = repeat(o.runs, || {
            std::hint::black_box(world.posed(&seq.timeline.poses_at(t)));
            Ok(())
        })?;
        let posed = world.posed(&seq.timeline.poses_at(t));
        let mut still = seq.clone();
        still.timeline.motion = Vec::new();
        let (frame, _) = render_only(&posed, &still, cores, o.runs)?;
        out(&format!(
            "motion {n} moving placements ({}): posed in {:.2} ms a frame ({:.2}-{:.2}, 1 thread) vs a {}x{} 1 spp frame {:.1} ms ({cores} threads): {:.2}% (target at most 5%)   [{cmd}]",
            if scatter { "scattered" } else { "grid" },
            pose.median * 1e3,
            pose.min * 1e3,
            pose.max * 1e3,
            size.0,
            size.1,
            frame.median * 1e3,
            100.0 * pose.median / frame.median
        ));
    }
    Ok(())
}
