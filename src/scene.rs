//! The validated scene: plain data, no I/O. Everything here has passed `sequence::load`, so
//! radii are positive, normals and directions are unit length, colours are finite and ≥ 0.
//!
//! ```yaml
//! materials: { red: { ambient: [0.1, 0, 0], diffuse: [0.7, 0, 0], specular: [1, 1, 1], shininess: 100, reflection: 0.5 } }
//! objects:   [ { sphere: { center: [-0.2, 0, -1], radius: 0.7, material: red } } ]
//! lights:    [ { point: { position: [5, 5, 5], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] } } ]
//! ```

use glam::{DMat3, DVec2, DVec3};
use std::path::PathBuf;
use std::sync::Arc;

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
    /// A texture that replaces `diffuse` at every hit (docs/spec/texture.md).
    pub diffuse_map: Option<Texture>,
    /// A texture that replaces `ambient` at every hit.
    pub ambient_map: Option<Texture>,
}

/// A colour that varies over a surface: `{ checker: … }` or `{ image: … }`.
#[derive(Debug, Clone, PartialEq)]
pub enum Texture {
    /// A solid checker in world space: cell (i, j, k) = ⌊p/size⌋ takes `colors[(i+j+k) mod 2]`.
    Checker { size: f64, colors: [DVec3; 2] },
    /// An image at the hit's texture coordinates times `scale`, repeated.
    Image { image: Arc<Image>, scale: DVec2 },
}

/// A texture image: linear RGB texels, level 0 the file's pixels, each further level half
/// the size (rounded up) down to 1×1 (docs/spec/texture.md).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// The file, as the sequence names it after resolving against its folder.
    pub file: PathBuf,
    pub levels: Vec<Level>,
    /// FNV-1a 64 of the file's bytes and its decoding: the fingerprint covers the content.
    pub digest: u64,
    /// Bytes the file had, and seconds the read and the pyramid took, for `check`.
    pub bytes: u64,
    pub load_seconds: f64,
}

/// One mip level: `texels[row * width + col]`, row 0 at the top of the image (v = 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
}

impl Material {
    /// Whether a texture replaces a colour of this material.
    pub fn textured(&self) -> bool {
        self.diffuse_map.is_some() || self.ambient_map.is_some()
    }

    /// Whether a checker replaces a colour of this material (its eye hits then read their
    /// pixel's average, docs/spec/texture.md **The pixel**).
    pub fn checkered(&self) -> bool {
        let checker = |m: &Option<Texture>| matches!(m, Some(Texture::Checker { .. }));
        checker(&self.diffuse_map) || checker(&self.ambient_map)
    }
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
    /// `normal` is unit length; the plane is every x with (x − point)·normal = 0. `u_axis`
    /// is the YAML's, when given: the direction an image's u runs along (docs/spec/texture.md).
    Plane {
        point: DVec3,
        normal: DVec3,
        u_axis: Option<DVec3>,
    },
    /// One placement of `Scene::meshes[mesh]` (a file used twice is loaded once).
    Mesh {
        mesh: usize,
        place: Placement,
        shading: MeshShading,
    },
}

/// How a mesh's triangles are shaded (`shading:`); see docs/spec/mesh.md.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MeshShading {
    /// Vertex normals interpolated by the hit's barycentrics; lighting at the hit.
    #[default]
    Phong,
    /// The face's geometric normal; lighting at the hit.
    Flat,
    /// Lighting at the three vertices, colours interpolated by the barycentrics.
    Gouraud,
    /// Lighting once at the centroid with the face normal: one colour per triangle.
    Constant,
}

impl MeshShading {
    pub fn name(self) -> &'static str {
        match self {
            MeshShading::Phong => "phong",
            MeshShading::Flat => "flat",
            MeshShading::Gouraud => "gouraud",
            MeshShading::Constant => "constant",
        }
    }
}

/// Where a mesh sits: world = translate + rotation · (scale ∘ local).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    pub scale: DVec3,
    /// Rz · Ry · Rx of the YAML `rotate` (degrees about X, then Y, then Z).
    pub rotation: DMat3,
    pub translate: DVec3,
}

impl Placement {
    /// A local point in world space: translate + R·(s ∘ p), in that order.
    pub fn point(&self, p: DVec3) -> DVec3 {
        self.translate + self.rotation * (self.scale * p)
    }

    /// A local normal in world space (the inverse transpose: R · (n / s)), unit length.
    pub fn normal(&self, n: DVec3) -> DVec3 {
        (self.rotation * (n / self.scale)).normalize()
    }

    /// The world box of the local box [lo, hi]: its eight corners placed.
    pub fn placed_box(&self, lo: DVec3, hi: DVec3) -> (DVec3, DVec3) {
        (0..8).fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), k| {
            let c = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let p = self.point(c);
            (a.min(p), b.max(p))
        })
    }

    /// The world → local linear map without the translation: (1/s) ∘ Rᵀ.
    pub fn to_local(&self) -> DMat3 {
        let rt = self.rotation.transpose();
        DMat3::from_cols(
            rt.x_axis / self.scale,
            rt.y_axis / self.scale,
            rt.z_axis / self.scale,
        )
    }
}

/// A triangle mesh as read from its file, in the file's own coordinates: shared by every
/// object that places it.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// The file, as the sequence names it after resolving against its folder.
    pub file: PathBuf,
    pub positions: Vec<DVec3>,
    /// One unit normal per vertex: the file's where it gives them, else the area-weighted
    /// average of the normals of the faces around the vertex.
    pub normals: Vec<DVec3>,
    /// Texture coordinates per vertex, when the file has them.
    pub uvs: Option<Vec<DVec2>>,
    /// Vertex indices of each triangle, in the file's order after fanning polygons.
    pub triangles: Vec<[u32; 3]>,
    /// How many of `normals` came from the file (the rest are averaged from the faces).
    pub file_normals: usize,
    /// Triangles dropped as degenerate (zero area, a repeated index, a non-finite vertex).
    pub skipped: usize,
    /// Notes for `check` (e.g. materials the file names and rayreel ignores).
    pub notes: Vec<String>,
    /// FNV-1a 64 of the file's bytes: the fingerprint covers the model's content.
    pub digest: u64,
    /// Bytes and seconds the read took, for `check`.
    pub bytes: u64,
    pub load_seconds: f64,
    /// `box_of(positions, triangles)`, made once with them: every frame asks for it (the f32
    /// precision check), and a walk over millions of triangles a frame is not free.
    pub local_box: (DVec3, DVec3),
}

impl Mesh {
    /// The smallest and largest local coordinates of the vertices its triangles use.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.local_box
    }
}

/// The smallest and largest of the `positions` the `triangles` use (a vertex only a dropped
/// triangle used, finite or not, does not count).
pub fn box_of(positions: &[DVec3], triangles: &[[u32; 3]]) -> (DVec3, DVec3) {
    triangles
        .iter()
        .flatten()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &i| {
            let p = positions[i as usize];
            (lo.min(p), hi.max(p))
        })
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
    /// A sphere that emits: each shading point samples the disk through `center` facing it,
    /// `samples` points a sample, each a point light with 1/samples of `intensity`.
    Sphere {
        center: DVec3,
        radius: f64,
        samples: u32,
        intensity: Intensity,
    },
    /// A one-sided parallelogram, corner + x·edge_u + y·edge_v for x, y in [0, 1), emitting
    /// towards `normal`, the unit edge_u × edge_v; sampled like a sphere light.
    Rect {
        corner: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
        normal: DVec3,
        samples: u32,
        intensity: Intensity,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub objects: Vec<Object>,
    /// The meshes `Shape::Mesh` objects place, one per distinct file.
    pub meshes: Vec<Arc<Mesh>>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    /// What rays that miss see: this colour, or the sky when there is one (then this is the
    /// colour that stands for it where one must, its mean or horizon).
    pub background: DVec3,
    /// A sky in place of the flat background (docs/spec/texture.md#the-sky).
    pub sky: Option<Sky>,
}

/// `render.background` as a sky: what a ray that leaves the scene in direction d sees.
#[derive(Debug, Clone, PartialEq)]
pub enum Sky {
    /// An equirectangular image (u along the horizon from −z, v from the nadir to the
    /// zenith), turned `rotate` degrees about +y, times `intensity`; filtered by the ray's
    /// footprint over the image's mip pyramid.
    Image {
        image: Arc<Image>,
        rotate: f64,
        intensity: f64,
    },
    /// Blends from `horizon` to `zenith` (upwards) or `ground` (downwards) by |d.y|/|d|.
    Gradient {
        zenith: DVec3,
        horizon: DVec3,
        ground: DVec3,
    },
}

impl Scene {
    /// Whether any material lets light through (glass), so paths need depth to show it.
    pub fn has_glass(&self) -> bool {
        self.materials.iter().any(Material::transparent)
    }

    /// The world box of a placed mesh: its file's box with the eight corners placed.
    pub fn mesh_bounds(&self, mesh: usize, place: &Placement) -> (DVec3, DVec3) {
        let (lo, hi) = self.meshes[mesh].bounds();
        place.placed_box(lo, hi)
    }

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
            Shape::Plane {
                point,
                normal,
                u_axis,
            } => Shape::Plane {
                point: closest_to_origin(point - by, normal),
                normal,
                u_axis,
            },
            Shape::Mesh {
                mesh,
                place,
                shading,
            } => Shape::Mesh {
                mesh,
                place: Placement {
                    translate: place.translate - by,
                    ..place
                },
                shading,
            },
        }
    }
}

impl Light {
    /// Where a point or spot light is, or an area light's centre; None for directional and
    /// ambient light.
    pub fn position(&self) -> Option<DVec3> {
        match *self {
            Light::Point { position, .. } | Light::Spot { position, .. } => Some(position),
            Light::Sphere { center, .. } => Some(center),
            Light::Rect {
                corner,
                edge_u,
                edge_v,
                ..
            } => Some(corner + 0.5 * edge_u + 0.5 * edge_v),
            Light::Directional { .. } | Light::Ambient { .. } => None,
        }
    }

    /// The points an area light (sphere or rect) takes for each eye sample; None for the
    /// others.
    pub fn area_samples(&self) -> Option<u32> {
        match *self {
            Light::Sphere { samples, .. } | Light::Rect { samples, .. } => Some(samples),
            _ => None,
        }
    }

    fn shifted(mut self, by: DVec3) -> Light {
        if let Light::Point { position: p, .. }
        | Light::Spot { position: p, .. }
        | Light::Sphere { center: p, .. }
        | Light::Rect { corner: p, .. } = &mut self
        {
            *p -= by;
        }
        self
    }
}

/// The point of the plane through `point` with unit `normal` nearest the origin, n·(p·n): the
/// one whose coordinates are smallest, so rounding them costs the least.
pub fn closest_to_origin(point: DVec3, normal: DVec3) -> DVec3 {
    normal * point.dot(normal)
}

/// v turned by the shortest rotation that takes the unit vector n to the unit vector m
/// (Rodrigues' formula with c = n × m and d = n·m, which are the axis times sin and the cos of
/// the angle): v·d + c × v + c·((c·v)/(1 + d)); v itself when 1 + d ≤ 1e-9 (n and m opposite:
/// no shortest turn). Motion vectors carry plane points with it, and a plane whose normal
/// moves carries its `u_axis` with it.
pub fn turned(v: DVec3, n: DVec3, m: DVec3) -> DVec3 {
    let (c, d) = (n.cross(m), n.dot(m));
    // Not `1 + d > 1e-9` (NaN included): no turn.
    if (1.0 + d).partial_cmp(&1e-9) != Some(std::cmp::Ordering::Greater) {
        return v;
    }
    v * d + c.cross(v) + c * (c.dot(v) / (1.0 + d))
}

/// A plane's texture axis from a unit vector `a` and the plane's unit normal: `a` projected
/// into the plane, a − n·(a·n), and its length (the loader refuses lengths below 1e-6).
pub fn plane_axis(a: DVec3, normal: DVec3) -> (DVec3, f64) {
    let along = a - normal * a.dot(normal);
    (along, along.length())
}

/// edge_u × edge_v and its length; where that length overflows or underflows (edges near
/// 1e100 or 1e-100), the same direction from the edges each divided by its largest component,
/// so perpendicular edges of any length are never taken for parallel ones.
pub fn area_normal(u: DVec3, v: DVec3) -> (DVec3, f64) {
    let cross = u.cross(v);
    let length = cross.length();
    if length > 0.0 && length.is_finite() {
        return (cross, length);
    }
    let cross = (u / u.abs().max_element()).cross(v / v.abs().max_element());
    (cross, cross.length())
}

/// Rz · Ry · Rx for angles in degrees, right-handed (counter-clockwise seen from the positive
/// axis). Whole multiples of 90° use exact 0 and ±1, so axis-aligned models stay aligned.
pub fn rotation(degrees: DVec3) -> DMat3 {
    let (sx, cx) = sin_cos(degrees.x);
    let (sy, cy) = sin_cos(degrees.y);
    let (sz, cz) = sin_cos(degrees.z);
    let rx = DMat3::from_cols(
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, cx, sx),
        DVec3::new(0.0, -sx, cx),
    );
    let ry = DMat3::from_cols(
        DVec3::new(cy, 0.0, -sy),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(sy, 0.0, cy),
    );
    let rz = DMat3::from_cols(
        DVec3::new(cz, sz, 0.0),
        DVec3::new(-sz, cz, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    );
    rz * (ry * rx)
}

/// sin and cos of an angle in degrees: exact at whole multiples of 90°, else libm's of the
/// angle (reduced to (−360, 360) by `%`) times π/180.
fn sin_cos(degrees: f64) -> (f64, f64) {
    let d = degrees % 360.0;
    if d % 90.0 == 0.0 {
        let quarter = ((d / 90.0) as i64).rem_euclid(4);
        return [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][quarter as usize];
    }
    let r = d.to_radians();
    (libm::sin(r), libm::cos(r))
}
