//! Whitted shading: Blinn-Phong per light with hard shadows, and mirror reflection.
//!
//! At a hit with normal N facing the incoming ray d, for each light: ka∘ia always; if the light
//! is not blocked, kd∘id·max(0, N·L) and, when N·L > 0, ks∘is·max(0, N·H)^(shininess/4) with
//! H = normalize(L − d). A path sums i0 + r0·i1 + r0·r1·i2 + … over at most `max_depth` surfaces.

use super::World;
use super::intersect::{Hit, Ray, normal_at};
use crate::scene::{Intensity, Light, Material, Scene};
use glam::DVec3;

/// Below this weight a reflection cannot change any output value (f32 colours, half-float
/// EXRs and 16-bit PNGs alike), so the path ends rather than crawl through subnormals.
const NEGLIGIBLE_WEIGHT: f64 = 1e-30;

/// Follows one eye ray through at most `max_depth` surfaces; returns its colour.
pub fn trace(world: &World, eye: Ray, max_depth: u32) -> DVec3 {
    trace_counted(world, eye, max_depth, &mut 0)
}

/// `trace`, adding the rays it casts (eye, reflection and shadow rays) to `rays`.
pub fn trace_counted(world: &World, eye: Ray, max_depth: u32, rays: &mut u64) -> DVec3 {
    let scene = &world.scene;
    let mut ray = eye;
    let mut color = DVec3::ZERO;
    let mut weight = DVec3::ONE;
    for _ in 0..max_depth {
        *rays += 1;
        let Some(hit) = world.geometry.nearest(&ray) else {
            color += weight * scene.background;
            break;
        };
        let (point, normal) = surface(scene, &ray, &hit);
        let material = &scene.materials[scene.objects[hit.object].material];
        color += weight * local(world, material, point, normal, ray.dir, hit.object, rays);
        weight *= material.reflection;
        if weight.max_element() < NEGLIGIBLE_WEIGHT {
            break;
        }
        ray = spawn_ray(
            point,
            ray.dir - 2.0 * ray.dir.dot(normal) * normal,
            hit.object,
        );
    }
    color
}

/// The one way secondary rays leave a surface: from the hit point itself, remembering the
/// object, so the intersection code can tell the surface just left from a real hit.
#[inline]
pub fn spawn_ray(point: DVec3, dir: DVec3, object: usize) -> Ray {
    Ray {
        origin: point,
        dir: dir.normalize(),
        leaving: Some(object),
    }
}

/// Hit point and the unit normal turned to face the incoming ray.
#[inline]
fn surface(scene: &Scene, ray: &Ray, hit: &Hit) -> (DVec3, DVec3) {
    let point = ray.origin + hit.t * ray.dir;
    let n = normal_at(&scene.objects[hit.object].shape, point);
    (point, if n.dot(ray.dir) > 0.0 { -n } else { n })
}

/// Sum over the lights of the Blinn-Phong terms at one surface point.
fn local(
    world: &World,
    m: &Material,
    point: DVec3,
    normal: DVec3,
    dir: DVec3,
    object: usize,
    rays: &mut u64,
) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for light in &world.scene.lights {
        let (to_light, distance, scale, i) = match *light {
            Light::Ambient { color } => {
                sum += m.ambient * color;
                continue;
            }
            Light::Point {
                position,
                intensity,
            } => {
                let (l, dist) = towards(point, position);
                (l, dist, 1.0, intensity)
            }
            Light::Directional {
                to_light,
                intensity,
            } => (to_light, f64::INFINITY, 1.0, intensity),
            Light::Spot {
                position,
                axis,
                cos_inner,
                cos_outer,
                intensity,
            } => {
                let (l, dist) = towards(point, position);
                let falloff = smoothstep(cos_outer, cos_inner, -l.dot(axis));
                (l, dist, falloff, intensity)
            }
        };
        if scale == 0.0 {
            continue;
        }
        sum += scale * m.ambient * i.ambient;
        let n_dot_l = normal.dot(to_light);
        // Diffuse and specular vanish when N·L ≤ 0: a shadow ray is only worth tracing otherwise.
        if n_dot_l <= 0.0 {
            continue;
        }
        *rays += 1;
        let shadow = spawn_ray(point, to_light, object);
        if !world.geometry.occluded(&shadow, distance) {
            sum += scale * direct(m, &i, normal, to_light, n_dot_l, -dir);
        }
    }
    sum
}

/// Diffuse plus specular for an unblocked light with N·L > 0.
#[inline]
fn direct(m: &Material, i: &Intensity, n: DVec3, l: DVec3, n_dot_l: f64, v: DVec3) -> DVec3 {
    let h = (l + v).normalize();
    // N·H can exceed 1 by an ulp; clamping keeps huge exponents from amplifying it.
    let n_dot_h = n.dot(h).clamp(0.0, 1.0);
    m.diffuse * i.diffuse * n_dot_l + m.specular * i.specular * specular_power(n_dot_h, m)
}

/// max(0, N·H)^exponent, with 0^0 = 1. Whole exponents (the talk's 100/4 = 25) multiply;
/// others go through the portable `libm` pow, so every machine computes the same bits.
/// Values whose power falls below 1e-30 give 0 before any subnormal arithmetic happens.
#[inline]
fn specular_power(x: f64, m: &Material) -> f64 {
    let e = m.exponent;
    if e == 0.0 {
        return 1.0;
    }
    if x <= m.specular_floor {
        return 0.0;
    }
    if e.fract() == 0.0 && e <= 4096.0 {
        x.powi(e as i32)
    } else {
        libm::pow(x, e)
    }
}

/// Unit vector from `from` to `to`, and the distance.
#[inline]
fn towards(from: DVec3, to: DVec3) -> (DVec3, f64) {
    let v = to - from;
    let d = v.length();
    if d > 0.0 {
        (v / d, d)
    } else {
        (DVec3::ZERO, 0.0)
    }
}

/// 0 at or below `edge0`, 1 at or above `edge1`, a cubic in between; a step when they meet.
#[inline]
fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    if x >= edge1 {
        return 1.0;
    }
    if x <= edge0 {
        return 0.0;
    }
    let t = (x - edge0) / (edge1 - edge0);
    t * t * (3.0 - 2.0 * t)
}
