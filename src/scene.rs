//! The validated scene: plain data, no I/O. Everything here has passed `sequence::load`, so
//! radii are positive, normals and directions are unit length, colours are finite and ≥ 0.
//!
//! ```yaml
//! materials: { red: { ambient: [0.1, 0, 0], diffuse: [0.7, 0, 0], specular: [1, 1, 1], shininess: 100, reflection: 0.5 } }
//! objects:   [ { sphere: { center: [-0.2, 0, -1], radius: 0.7, material: red } } ]
//! lights:    [ { point: { position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] } } ]
//! ```

use glam::DVec3;

#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub ambient: DVec3,
    pub diffuse: DVec3,
    pub specular: DVec3,
    /// The Blinn-Phong exponent: the YAML `shininess` divided by 4 (the talk's convention).
    pub exponent: f64,
    /// N·H at or below which the specular power is under 1e-30 and counts as 0.
    pub specular_floor: f64,
    pub reflection: f64,
    /// The colour filter light passing through the surface is multiplied by; zero for an
    /// opaque material.
    pub transmission: DVec3,
    /// Index of refraction of the medium behind the surface (inside a sphere, behind a plane),
    /// at least 1; every other medium has index 1.
    pub ior: f64,
    /// Schlick's Fresnel term replaces `reflection` and scales `transmission`.
    pub fresnel: bool,
}

impl Material {
    /// Whether light passes through the surface.
    pub fn transparent(&self) -> bool {
        self.transmission != DVec3::ZERO
    }

    /// Whether a hit can spawn more than one ray (or a reflection that depends on the angle),
    /// so paths become trees.
    pub fn branches(&self) -> bool {
        self.transparent() || self.fresnel
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// `normal` is unit length; the plane is every x with (x − point)·normal = 0.
    Plane {
        point: DVec3,
        normal: DVec3,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Object {
    pub shape: Shape,
    /// Index into `Scene::materials`.
    pub material: usize,
}

/// The three Blinn-Phong intensities a light carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intensity {
    pub ambient: DVec3,
    pub diffuse: DVec3,
    pub specular: DVec3,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    Point {
        position: DVec3,
        intensity: Intensity,
    },
    /// `to_light` is the unit vector towards the light (the YAML `direction` reversed).
    Directional {
        to_light: DVec3,
        intensity: Intensity,
    },
    /// `axis` is the unit direction the spot shines in; the cosines bound the smooth falloff.
    Spot {
        position: DVec3,
        axis: DVec3,
        cos_inner: f64,
        cos_outer: f64,
        intensity: Intensity,
    },
    Ambient {
        color: DVec3,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub background: DVec3,
}

impl Scene {
    /// The scene in coordinates whose origin is `by` (f32 traces relative to the camera):
    /// positions move by −`by` in f64, and a plane is anchored at its point nearest the new
    /// origin. Directions, colours and radii stay as they are.
    pub fn shifted(&self, by: DVec3) -> Scene {
        let objects = self
            .objects
            .iter()
            .map(|o| Object {
                shape: o.shape.shifted(by),
                ..*o
            })
            .collect();
        let lights = self.lights.iter().map(|l| l.shifted(by)).collect();
        Scene {
            objects,
            lights,
            ..self.clone()
        }
    }
}

impl Shape {
    pub fn shifted(self, by: DVec3) -> Shape {
        match self {
            Shape::Sphere { center, radius } => Shape::Sphere {
                center: center - by,
                radius,
            },
            Shape::Plane { point, normal } => Shape::Plane {
                point: closest_to_origin(point - by, normal),
                normal,
            },
        }
    }
}

impl Light {
    /// Where a point or spot light is; None for directional and ambient light.
    pub fn position(&self) -> Option<DVec3> {
        match *self {
            Light::Point { position, .. } | Light::Spot { position, .. } => Some(position),
            Light::Directional { .. } | Light::Ambient { .. } => None,
        }
    }

    fn shifted(mut self, by: DVec3) -> Light {
        if let Light::Point { position, .. } | Light::Spot { position, .. } = &mut self {
            *position -= by;
        }
        self
    }
}

/// The point of the plane through `point` with unit `normal` nearest the origin, n·(p·n): the
/// one whose coordinates are smallest, so rounding them costs the least.
pub fn closest_to_origin(point: DVec3, normal: DVec3) -> DVec3 {
    normal * point.dot(normal)
}
