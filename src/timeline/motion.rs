//! Objects and lights that move: each keyed field of one object or light is a `Track` like the
//! camera's, and the thing at time t is the one the loader would build from those fields'
//! values at t (docs/spec/motion.md).
//!
//! ```yaml
//! objects:
//!   - sphere: { center: [0, 1, 0], radius: 0.5, material: red }
//!     interpolation: linear          # default: timeline.interpolation, else smooth
//!     keys:
//!       - { time: 0, center: [-2, 1, 0] }
//!       - { time: 2, center: [2, 1, 0], ease: stop }
//! ```

use super::track::{Timing, Track};
use super::{Ease, Interpolation};
use crate::scene::{Light, Object, Placement, Shape, area_normal, plane_axis, rotation, turned};
use glam::{DMat3, DVec3};

/// A field a key can set. Its value is a 3-vector (a number in x; a spot's two angles in x
/// and y).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Field {
    Scale,
    Rotate,
    Translate,
    Center,
    Radius,
    Point,
    Normal,
    Position,
    Direction,
    /// A spot's inner and outer angles (x, y), in degrees: one track, so both move together.
    Angles,
    Ambient,
    Diffuse,
    Specular,
    Color,
    Corner,
    /// A rect light's edges: its normal follows them.
    EdgeU,
    EdgeV,
    /// Not keyed: a plane's `u_axis` where its normal is keyed, turned with the normal (what
    /// `rayreel camera --object` prints so a still scene can write it).
    UAxis,
}

impl Field {
    /// The key field's name (both spot angles as `angles`).
    pub fn name(self) -> &'static str {
        match self {
            Field::Scale => "scale",
            Field::Rotate => "rotate",
            Field::Translate => "translate",
            Field::Center => "center",
            Field::Radius => "radius",
            Field::Point => "point",
            Field::Normal => "normal",
            Field::Position => "position",
            Field::Direction => "direction",
            Field::Angles => "angles",
            Field::Ambient => "ambient",
            Field::Diffuse => "diffuse",
            Field::Specular => "specular",
            Field::Color => "color",
            Field::Corner => "corner",
            Field::EdgeU => "edge_u",
            Field::EdgeV => "edge_v",
            Field::UAxis => "u_axis",
        }
    }

    /// Whether the track follows a curve under smooth interpolation: places and turns do;
    /// sizes, directions, angles and colours go straight, so they never overshoot their keys.
    pub(crate) fn curved(self) -> bool {
        matches!(
            self,
            Field::Rotate
                | Field::Translate
                | Field::Center
                | Field::Point
                | Field::Position
                | Field::Corner
        )
    }
}

/// Which thing of the scene a rig moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Thing {
    /// Index into `Scene::objects`.
    Object(usize),
    /// Index into `Scene::lights`.
    Light(usize),
}

/// The thing as the file's paths name it: `objects[i]` or `lights[i]`.
impl std::fmt::Display for Thing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Thing::Object(i) => write!(f, "objects[{i}]"),
            Thing::Light(i) => write!(f, "lights[{i}]"),
        }
    }
}

/// What a mesh placement needs beyond its keyed fields: how the loader folds `up` and
/// `origin` in (`fit` is refused together with keys on scale or rotate).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshFrame {
    /// The rotation that turns the file's up axis to +y, applied before `rotate`.
    pub up: DMat3,
    /// What `origin: center|bottom` subtracts from `translate`; None for `origin: file`.
    pub offset: Option<DVec3>,
}

/// One key of a rig: its time, how it is met, and the fields it gives (carried over from
/// the key before, or from the thing as written, where it gives none).
#[derive(Debug, Clone, PartialEq)]
pub struct RigKey {
    pub time: f64,
    pub ease: Ease,
    pub values: Vec<(Field, DVec3)>,
}

/// One object or light that moves: the thing as written, and a track per keyed field.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    pub thing: Thing,
    /// The object or light as the loader built it from its own fields.
    pub base: Posed,
    pub mesh: Option<MeshFrame>,
    /// Key times, strictly increasing.
    pub times: Vec<f64>,
    pub interpolation: Interpolation,
    tracks: Vec<(Field, Track)>,
}

/// An object or light at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Posed {
    Object(Object),
    Light(Light),
}

impl Rig {
    /// `keys` hold a value for every keyed field (the loader carries them over), in the same
    /// field order.
    pub fn new(
        thing: Thing,
        base: Posed,
        mesh: Option<MeshFrame>,
        keys: &[RigKey],
        interpolation: Interpolation,
    ) -> Rig {
        let times: Vec<f64> = keys.iter().map(|k| k.time).collect();
        let stops: Vec<bool> = keys.iter().map(|k| k.ease == Ease::Stop).collect();
        let timing = match interpolation {
            Interpolation::Linear => Timing::Linear,
            Interpolation::Smooth => Timing::Smooth,
        };
        let fields: Vec<Field> = keys[0].values.iter().map(|(f, _)| *f).collect();
        let tracks = fields
            .iter()
            .enumerate()
            .map(|(i, &f)| {
                let values = keys.iter().map(|k| k.values[i].1).collect();
                let curved = f.curved() && interpolation == Interpolation::Smooth;
                (f, Track::new(times.clone(), values, &stops, curved, timing))
            })
            .collect();
        Rig {
            thing,
            base,
            mesh,
            times,
            interpolation,
            tracks,
        }
    }

    /// The keyed fields' values at time t, in the rig's field order, then a plane's turned
    /// `u_axis` where its normal is keyed.
    pub fn values_at(&self, t: f64) -> Vec<(Field, DVec3)> {
        let mut values: Vec<(Field, DVec3)> =
            self.tracks.iter().map(|(f, k)| (*f, k.at(t).0)).collect();
        if let Some(a) = self.track(Field::Normal, t).and_then(|n| self.axis(n)) {
            values.push((Field::UAxis, a));
        }
        values
    }

    /// The fields this rig keys.
    pub fn fields(&self) -> impl Iterator<Item = Field> + '_ {
        self.tracks.iter().map(|(f, _)| *f)
    }

    /// The value of `field`'s track at t, if the rig keys it.
    fn track(&self, field: Field, t: f64) -> Option<DVec3> {
        let (_, track) = self.tracks.iter().find(|(f, _)| *f == field)?;
        Some(track.at(t).0)
    }

    /// A textured plane's `u_axis` when its normal's track is at `v`: the still plane's axis
    /// turned by the shortest turn from the still normal to v.normalize() (None for other
    /// things, and for a plane without `u_axis`).
    fn axis(&self, v: DVec3) -> Option<DVec3> {
        match self.base {
            Posed::Object(Object {
                shape:
                    Shape::Plane {
                        normal,
                        u_axis: Some(u),
                        ..
                    },
                ..
            }) => Some(turned(u, normal, v.normalize())),
            _ => None,
        }
    }

    /// The object or light at time t: the thing as written with each keyed field replaced
    /// by its value at t, converted as the loader converts that field.
    pub fn at(&self, t: f64) -> Posed {
        let mut posed = self.base;
        for (field, track) in &self.tracks {
            set(&mut posed, *field, track.at(t).0);
        }
        if let (Posed::Object(o), Some(m)) = (&mut posed, &self.mesh)
            && let Shape::Mesh { place, .. } = &mut o.shape
        {
            *place = placement(self, m, place, t);
        }
        self.derived(&mut posed, t);
        posed
    }

    /// What the loader works out from keyed fields: a textured plane's axis from its turned
    /// `u_axis` (as `rayreel camera` prints it), a rect's normal from its edges.
    fn derived(&self, posed: &mut Posed, t: f64) {
        match posed {
            Posed::Object(Object {
                shape:
                    Shape::Plane {
                        normal,
                        u_axis: Some(u),
                        ..
                    },
                ..
            }) => {
                if let Some(a) = self.track(Field::Normal, t).and_then(|v| self.axis(v)) {
                    *u = plane_axis(a.normalize(), *normal).0.normalize();
                }
            }
            Posed::Light(Light::Rect {
                edge_u,
                edge_v,
                normal,
                ..
            }) => {
                let (cross, length) = area_normal(*edge_u, *edge_v);
                // The keys keep an area between them (checked at load); rounding at a
                // near-degenerate pose keeps the last good normal rather than a NaN.
                if length > 0.0 && length.is_finite() {
                    *normal = cross * (1.0 / length);
                }
            }
            _ => {}
        }
    }
}

/// A mesh placement from the keyed scale, rotate and translate at t (or the written ones):
/// translate − offset + (Rz·Ry·Rx of rotate · up)·(scale ∘ p), as the loader builds it.
fn placement(rig: &Rig, m: &MeshFrame, place: &Placement, t: f64) -> Placement {
    let get = |f: Field| rig.track(f, t);
    let rotation = match get(Field::Rotate) {
        Some(degrees) => rotation(degrees) * m.up,
        None => place.rotation,
    };
    let translate = match (get(Field::Translate), m.offset) {
        (Some(v), Some(o)) => v - o,
        (Some(v), None) => v,
        (None, _) => place.translate,
    };
    Placement {
        scale: get(Field::Scale).unwrap_or(place.scale),
        rotation,
        translate,
    }
}

/// Replaces `field` of an object or light by `v`, converted as the loader converts it
/// (directions normalised, angles to cosines). Mesh fields are placed by `placement`.
fn set(posed: &mut Posed, field: Field, v: DVec3) {
    match posed {
        Posed::Object(o) => set_shape(&mut o.shape, field, v),
        Posed::Light(l) => set_light(l, field, v),
    }
}

fn set_shape(shape: &mut Shape, field: Field, v: DVec3) {
    match (shape, field) {
        (Shape::Sphere { center, .. }, Field::Center) => *center = v,
        (Shape::Sphere { radius, .. }, Field::Radius) => *radius = v.x,
        (Shape::Plane { point, .. }, Field::Point) => *point = v,
        (Shape::Plane { normal, .. }, Field::Normal) => *normal = v.normalize(),
        _ => {}
    }
}

fn set_light(light: &mut Light, field: Field, v: DVec3) {
    use Light::*;
    match (light, field) {
        (Point { position, .. } | Spot { position, .. }, Field::Position) => *position = v,
        (Sphere { center, .. }, Field::Center) => *center = v,
        (Sphere { radius, .. }, Field::Radius) => *radius = v.x,
        (Rect { corner, .. }, Field::Corner) => *corner = v,
        (Rect { edge_u, .. }, Field::EdgeU) => *edge_u = v,
        (Rect { edge_v, .. }, Field::EdgeV) => *edge_v = v,
        (Directional { to_light, .. }, Field::Direction) => *to_light = -v.normalize(),
        (Spot { axis, .. }, Field::Direction) => *axis = v.normalize(),
        (
            Spot {
                cos_inner,
                cos_outer,
                ..
            },
            Field::Angles,
        ) => {
            // Both angles lie on one straight track between keys whose inner ≤ outer, so
            // this min changes nothing but a rounding.
            *cos_inner = libm::cos(v.x.min(v.y).to_radians());
            *cos_outer = libm::cos(v.y.to_radians());
        }
        (Ambient { color }, Field::Color) => *color = v,
        (l, Field::Ambient | Field::Diffuse | Field::Specular) => {
            if let Some(i) = intensity(l) {
                match field {
                    Field::Ambient => i.ambient = v,
                    Field::Diffuse => i.diffuse = v,
                    _ => i.specular = v,
                }
            }
        }
        _ => {}
    }
}

fn intensity(l: &mut Light) -> Option<&mut crate::scene::Intensity> {
    use Light::*;
    match l {
        Point { intensity, .. }
        | Directional { intensity, .. }
        | Spot { intensity, .. }
        | Sphere { intensity, .. }
        | Rect { intensity, .. } => Some(intensity),
        Ambient { .. } => None,
    }
}

/// Every object and light that moves, each at one time (in the rigs' order): what a frame,
/// or one instant of its open shutter, sees in place of the scene's own.
pub type Poses = Vec<(Thing, Posed)>;

/// The poses of every rig at time t.
pub fn poses_at(rigs: &[Rig], t: f64) -> Poses {
    rigs.iter().map(|r| (r.thing, r.at(t))).collect()
}
