//! Serde structs that mirror the YAML exactly. Nothing here is checked beyond its type;
//! `sequence::load` validates and turns these into a `Scene`, a `Timeline` and `Settings`.

use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use std::fmt;

pub type V3 = [f64; 3];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sequence {
    #[serde(default)]
    pub render: Render,
    pub output: Option<String>,
    pub camera: Option<Camera>,
    #[serde(default)]
    pub materials: NamedMaterials,
    #[serde(default)]
    pub objects: Vec<Object>,
    #[serde(default)]
    pub lights: Vec<Light>,
    pub timeline: Option<Timeline>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Render {
    // Whole numbers whose least value is 1 are read signed, so that `-1` is refused by their
    // own check, with their range, rather than by serde as "0 or more".
    pub width: Option<i64>,
    pub height: Option<i64>,
    pub max_depth: Option<i64>,
    pub background: Option<Background>,
    pub depth: Option<bool>,
    pub samples: Option<i64>,
    pub adaptive: Option<Adaptive>,
    pub quality: Option<Quality>,
    pub sampler: Option<Sampler>,
    pub encoding: Option<crate::transfer::Encoding>,
    pub exposure: Option<f64>,
    pub alpha: Option<bool>,
    pub shutter: Option<f64>,
    pub shutter_offset: Option<f64>,
    pub precision: Option<crate::settings::Precision>,
    pub aov: Option<Vec<crate::settings::Aov>>,
    pub denoise: Option<bool>,
}

/// `render.background`: a colour triple, or a sky (`{ image: … }`, `{ gradient: … }`).
#[derive(Debug, Clone)]
pub enum Background {
    Color(V3),
    Sky(Box<Sky>),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sky {
    pub image: Option<String>,
    pub rotate: Option<f64>,
    pub encoding: Option<ImageEncoding>,
    pub intensity: Option<f64>,
    pub gradient: Option<Gradient>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gradient {
    pub zenith: V3,
    pub horizon: V3,
    pub ground: Option<V3>,
}

impl<'de> Deserialize<'de> for Background {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct B;
        impl<'de> Visitor<'de> for B {
            type Value = Background;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a colour triple [r, g, b] or a sky ({ image: … } or { gradient: … })")
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, seq: A) -> Result<Background, A::Error> {
                V3::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(Background::Color)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Background, A::Error> {
                Sky::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|s| Background::Sky(Box::new(s)))
            }
        }
        d.deserialize_any(B)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Adaptive {
    pub threshold: Option<f64>,
    pub max_samples: Option<i64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    /// 1 sample, max_depth 2, half resolution: for looking at a path.
    Draft,
    /// 4 jittered samples, max_depth 3.
    Preview,
    /// Adaptive 4 to 64 samples, max_depth 5.
    Final,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    Stratified,
    Random,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub position: V3,
    pub look_at: Target,
    pub up: Option<V3>,
    pub fov: Option<f64>,
    pub aperture: Option<f64>,
    pub focus_distance: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    #[serde(default)]
    pub ambient: Paint,
    pub diffuse: Paint,
    #[serde(default)]
    pub specular: V3,
    pub shininess: Option<f64>,
    pub reflection: Option<f64>,
    pub transmission: Option<Filter>,
    pub ior: Option<f64>,
    #[serde(default)]
    pub fresnel: bool,
}

/// `diffuse` or `ambient`: a colour triple, or a texture map (`{ checker: … }`, `{ image: … }`).
#[derive(Debug, Clone)]
pub enum Paint {
    Color(V3),
    Map(Box<TextureMap>),
}

impl Default for Paint {
    fn default() -> Paint {
        Paint::Color([0.0; 3])
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureMap {
    pub checker: Option<Checker>,
    pub image: Option<String>,
    pub scale: Option<[f64; 2]>,
    pub encoding: Option<ImageEncoding>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checker {
    pub size: Option<f64>,
    pub colors: [V3; 2],
}

/// How an image's 8- or 16-bit values map to linear light.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ImageEncoding {
    Srgb,
    Linear,
}

impl<'de> Deserialize<'de> for Paint {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct P;
        impl<'de> Visitor<'de> for P {
            type Value = Paint;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a colour triple [r, g, b] or a texture map ({ checker: … } or { image: … })",
                )
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Paint, A::Error> {
                V3::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(Paint::Color)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Paint, A::Error> {
                TextureMap::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(|m| Paint::Map(Box::new(m)))
            }
        }
        d.deserialize_any(P)
    }
}

/// A colour filter given as one number for every channel (`0.9`) or as a triple.
#[derive(Debug, Clone, Copy)]
pub struct Filter(pub V3);

impl<'de> Deserialize<'de> for Filter {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct F;
        impl<'de> Visitor<'de> for F {
            type Value = Filter;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number in [0, 1] or a colour triple [r, g, b]")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Filter, E> {
                Ok(Filter([v; 3]))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Filter, E> {
                self.visit_f64(v as f64)
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Filter, E> {
                self.visit_f64(v as f64)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Filter, A::Error> {
                V3::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(Filter)
            }
        }
        d.deserialize_any(F)
    }
}

/// `materials:` keeps the user's order and rejects a name given twice (a plain map would
/// silently keep the last one).
#[derive(Debug, Default)]
pub struct NamedMaterials(pub Vec<(String, Material)>);

impl<'de> Deserialize<'de> for NamedMaterials {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NamedMaterials;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map from material names to materials")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out: Vec<(String, Material)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if out.iter().any(|(n, _)| *n == name) {
                        return Err(de::Error::custom(format!(
                            "material `{name}` is defined twice"
                        )));
                    }
                    out.push((name, map.next_value()?));
                }
                Ok(NamedMaterials(out))
            }
        }
        d.deserialize_map(V)
    }
}

/// `material: red` names an entry of `materials:`; `material: { diffuse: ... }` is inline.
#[derive(Debug, Clone)]
pub enum MaterialRef {
    Named(String),
    Inline(Box<Material>),
}

impl<'de> Deserialize<'de> for MaterialRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = MaterialRef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a material name or an inline material map")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<Self::Value, E> {
                Ok(MaterialRef::Named(s.to_owned()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
                Material::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|m| MaterialRef::Inline(Box::new(m)))
            }
        }
        d.deserialize_any(V)
    }
}

/// One of `sphere:` or `plane:` (serde_yaml only reads enums as `!tags`, so the
/// single-key form is a struct of options, checked for exactly one in `load`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    pub sphere: Option<Sphere>,
    pub plane: Option<Plane>,
    pub mesh: Option<Mesh>,
    /// What camera keys call it (`look_at: { object: NAME }`) and messages name it by.
    pub name: Option<String>,
    /// Keys that move it (docs/sequence-file.md#things-that-move).
    pub keys: Option<Vec<ThingKey>>,
    /// How its keys are interpolated; default `timeline.interpolation`, else smooth.
    pub interpolation: Option<Interpolation>,
}

/// A key on an object or light: its time as a camera key's, and the fields it moves.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThingKey {
    #[serde(default, deserialize_with = "key_time")]
    pub time: Option<KeyTime>,
    pub frame: Option<u64>,
    pub ease: Option<String>,
    pub scale: Option<Scale>,
    pub rotate: Option<V3>,
    pub translate: Option<V3>,
    pub center: Option<V3>,
    pub radius: Option<f64>,
    pub point: Option<V3>,
    pub normal: Option<V3>,
    pub position: Option<V3>,
    pub direction: Option<V3>,
    pub inner_angle: Option<f64>,
    pub outer_angle: Option<f64>,
    pub ambient: Option<V3>,
    pub diffuse: Option<V3>,
    pub specular: Option<V3>,
    pub color: Option<V3>,
    pub corner: Option<V3>,
    pub edge_u: Option<V3>,
    pub edge_v: Option<V3>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mesh {
    pub file: String,
    pub material: MaterialRef,
    pub shading: Option<crate::scene::MeshShading>,
    pub scale: Option<Scale>,
    pub rotate: Option<V3>,
    pub translate: Option<V3>,
    /// The file's up axis (`y`, `z`, `x`, `-y`, …): turned to +y before `rotate`.
    pub up: Option<String>,
    /// The largest extent, after scale, up and rotate, in scene units.
    pub fit: Option<f64>,
    /// Which point of the model `translate` places: `file` (its own origin), `center` or
    /// `bottom` (of its bounds).
    pub origin: Option<Origin>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Origin {
    #[default]
    File,
    Center,
    Bottom,
}

/// A mesh's `scale`: one number for every axis (`2`) or a triple.
#[derive(Debug, Clone, Copy)]
pub struct Scale(pub V3);

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Filter::deserialize(d)
            .map(|Filter(v)| Scale(v))
            .map_err(|e| {
                de::Error::custom(e.to_string().replace(
                    "a number in [0, 1] or a colour triple [r, g, b]",
                    "a number or a triple [x, y, z]",
                ))
            })
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sphere {
    pub center: V3,
    pub radius: f64,
    pub material: MaterialRef,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    pub point: V3,
    pub normal: V3,
    pub u_axis: Option<V3>,
    pub material: MaterialRef,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    pub point: Option<PointLight>,
    pub directional: Option<DirectionalLight>,
    pub spot: Option<SpotLight>,
    pub ambient: Option<AmbientLight>,
    pub sphere: Option<SphereLight>,
    pub rect: Option<RectLight>,
    /// Keys that move it or change its colours.
    pub keys: Option<Vec<ThingKey>>,
    /// How its keys are interpolated; default `timeline.interpolation`, else smooth.
    pub interpolation: Option<Interpolation>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLight {
    pub position: V3,
    #[serde(default)]
    pub ambient: V3,
    pub diffuse: V3,
    pub specular: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionalLight {
    pub direction: V3,
    #[serde(default)]
    pub ambient: V3,
    pub diffuse: V3,
    pub specular: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpotLight {
    pub position: V3,
    pub direction: V3,
    pub inner_angle: f64,
    pub outer_angle: f64,
    #[serde(default)]
    pub ambient: V3,
    pub diffuse: V3,
    pub specular: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereLight {
    pub center: V3,
    pub radius: f64,
    pub samples: Option<i64>,
    #[serde(default)]
    pub ambient: V3,
    pub diffuse: V3,
    pub specular: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RectLight {
    pub corner: V3,
    pub edge_u: V3,
    pub edge_v: V3,
    pub samples: Option<i64>,
    #[serde(default)]
    pub ambient: V3,
    pub diffuse: V3,
    pub specular: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmbientLight {
    pub color: V3,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Timeline {
    #[serde(default, deserialize_with = "fps")]
    pub fps: Option<Fps>,
    pub first_frame: Option<u64>,
    pub duration: Option<f64>,
    pub interpolation: Option<Interpolation>,
    pub speed: Option<Speed>,
    pub keyframes: Option<Vec<Keyframe>>,
    pub orbit: Option<Orbit>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Interpolation {
    Linear,
    Smooth,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Speed {
    Keys,
    Constant,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Seconds: a number or an exact fraction (`71/24`). Exactly one of `time` and `frame`.
    #[serde(default, deserialize_with = "key_time")]
    pub time: Option<KeyTime>,
    /// A frame number, as Blender keys: the key is at that frame's own time.
    pub frame: Option<u64>,
    pub position: Option<V3>,
    pub look_at: Option<Target>,
    pub up: Option<V3>,
    pub fov: Option<f64>,
    pub aperture: Option<f64>,
    pub focus_distance: Option<f64>,
    /// A string rather than an enum, so that the eases of earlier versions get a message
    /// saying what replaces them.
    pub ease: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orbit {
    pub center: Target,
    pub radius: f64,
    #[serde(default)]
    pub height: f64,
    #[serde(default)]
    pub start_angle: f64,
    pub turns: Option<f64>,
    pub duration: f64,
    pub look_at: Option<Target>,
    pub up: Option<V3>,
    pub fov: Option<f64>,
}

/// A point the camera aims at (or an orbit circles): a triple, or `{ object: NAME }`, the
/// centre of the bounds of the object of that `name:`. The loader replaces every object by
/// its point before the timeline reads it.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    Point(V3),
    Object(String),
}

impl Target {
    /// The point; an object not yet replaced by its point gives NaN, which the checks of
    /// every point refuse.
    pub fn point(&self) -> V3 {
        match self {
            Target::Point(v) => *v,
            Target::Object(_) => [f64::NAN; 3],
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectTarget {
    object: String,
}

impl<'de> Deserialize<'de> for Target {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct T;
        impl<'de> Visitor<'de> for T {
            type Value = Target;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a point [x, y, z] or an object's name ({ object: NAME })")
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, seq: A) -> Result<Target, A::Error> {
                V3::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(Target::Point)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Target, A::Error> {
                ObjectTarget::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|t| Target::Object(t.object))
            }
        }
        d.deserialize_any(T)
    }
}

/// A number, or a fraction of whole numbers kept exact until the loader divides it once:
/// `fps: 24`, `fps: 29.97`, `fps: 24000/1001` (as ffmpeg's `-r` takes it), `time: 71/24`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Amount {
    Number(f64),
    Fraction(u64, u64),
}

/// `timeline.fps`: the fraction's numerator above 0 too.
pub type Fps = Amount;

/// `keyframes[].time`, in seconds.
pub type KeyTime = Amount;

fn fps<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Fps>, D::Error> {
    d.deserialize_any(AmountVisitor {
        what: "frames per second",
        example: "24000/1001",
        zero: false,
    })
}

fn key_time<'de, D: Deserializer<'de>>(d: D) -> Result<Option<KeyTime>, D::Error> {
    d.deserialize_any(AmountVisitor {
        what: "seconds",
        example: "71/24",
        zero: true,
    })
}

/// Reads an `Amount` (null: none); `zero` allows a fraction of 0.
struct AmountVisitor {
    what: &'static str,
    example: &'static str,
    zero: bool,
}

impl Visitor<'_> for AmountVisitor {
    type Value = Option<Amount>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "{} as a number or a fraction such as {}",
            self.what, self.example
        )
    }
    fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
        Ok(None)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
        Ok(Some(Amount::Number(v)))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
        Ok(Some(Amount::Number(v as f64)))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
        Ok(Some(Amount::Number(v as f64)))
    }
    fn visit_str<E: de::Error>(self, s: &str) -> Result<Self::Value, E> {
        match fraction(s).filter(|&(num, _)| self.zero || num > 0) {
            Some((num, den)) => Ok(Some(Amount::Fraction(num, den))),
            None => Err(E::custom(format!(
                "expected {} as a number or a fraction of whole numbers such as {} (got `{s}`)",
                self.what, self.example
            ))),
        }
    }
}

/// `NUM/DEN` in whole numbers, DEN above 0: how `fps` and key times are written as fractions.
fn fraction(s: &str) -> Option<(u64, u64)> {
    let whole = |t: &str| t.trim().parse::<u64>().ok();
    let (num, den) = s.split_once('/')?;
    Some((whole(num)?, whole(den).filter(|&d| d > 0)?))
}
