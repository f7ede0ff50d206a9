//! Micro-benchmarks of the tracer's kernels: ray/sphere and ray/plane intersection, a
//! nearest-hit query, and the shading of one eye ray through the talk's scene.
//! Run with `cargo bench`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rayreel::scene::Shape;
use rayreel::sequence;
use rayreel::tracer::World;
use rayreel::tracer::intersect::{Ray, intersect};
use rayreel::tracer::path::trace;
use std::hint::black_box;
use std::path::Path;

fn talk() -> World {
    let text = include_str!("../sequences/talk.yaml");
    let seq = sequence::parse(Path::new("talk.yaml"), text).unwrap();
    World::new(seq.scene)
}

fn rays(n: usize) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let (x, y) = ((i % 64) as f64 / 32.0 - 1.0, (i / 64) as f64 / 32.0 - 0.5);
            Ray {
                origin: DVec3::new(0.0, 0.0, 1.0),
                dir: DVec3::new(x, y, -1.0).normalize(),
                leaving: None,
            }
        })
        .collect()
}

fn kernels(c: &mut Criterion) {
    let rays = rays(4096);
    let sphere = Shape::Sphere {
        center: DVec3::new(-0.2, 0.0, -1.0),
        radius: 0.7,
    };
    let floor = Shape::Sphere {
        center: DVec3::new(0.0, -9000.0, 0.0),
        radius: 8999.3,
    };
    let plane = Shape::Plane {
        point: DVec3::new(0.0, -0.7, 0.0),
        normal: DVec3::Y,
        u_axis: None,
    };
    for (name, shape) in [
        ("sphere", sphere),
        ("giant sphere", floor),
        ("plane", plane),
    ] {
        c.bench_function(&format!("intersect {name} x4096"), |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|r| intersect(black_box(&shape), r, false).is_some())
                    .count()
            })
        });
    }
    let world = talk();
    c.bench_function("nearest hit, talk scene x4096", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| world.geometry.nearest_one(black_box(r)).is_some())
                .count()
        })
    });
    c.bench_function("trace depth 3, talk scene x4096", |b| {
        b.iter(|| {
            rays.iter()
                .map(|r| trace(&world, *black_box(r), 3).x)
                .sum::<f64>()
        })
    });
}

criterion_group!(benches, kernels);
criterion_main!(benches);
