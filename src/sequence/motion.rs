//! `keys:` on objects and lights → `timeline::motion::Rig`s. Every key is checked as the
//! field it sets is checked in a still scene, and the keys together so that every pose
//! between them is one too: a scale keeps its sign, a direction never turns through zero.

use super::timeline::{Frames, ease, increasing, key_time};
use super::*;
use crate::scene::area_normal;
use crate::timeline::Interpolation;
use crate::timeline::motion::{Field, MeshFrame, Posed, Rig, RigKey, Thing};

/// The rigs of every object and light with keys, objects first, each in file order.
pub(super) fn rigs(
    raw: &raw::Sequence,
    scene: &Scene,
    frames: Frames,
    interpolation: Interpolation,
) -> Check<Vec<Rig>> {
    let mut rigs = Vec::new();
    for (i, o) in raw.objects.iter().enumerate() {
        let Some(keys) = &o.keys else { continue };
        let path = format!("objects[{i}]");
        let object = scene.objects[i];
        let kind = object_kind(o, &object);
        let mesh = mesh_frame(&path, o, &object, scene, keys)?;
        let how = o.interpolation.map_or(interpolation, interpolation_of);
        let keys = rig_keys(&path, &kind, keys, frames)?;
        rigs.push(Rig::new(
            Thing::Object(i),
            Posed::Object(object),
            mesh,
            &keys,
            how,
        ));
    }
    for (i, l) in raw.lights.iter().enumerate() {
        let Some(keys) = &l.keys else { continue };
        let path = format!("lights[{i}]");
        let light = scene.lights[i];
        let kind = light_kind(l, &light);
        let how = l.interpolation.map_or(interpolation, interpolation_of);
        let keys = rig_keys(&path, &kind, keys, frames)?;
        if let Light::Rect { edge_u, edge_v, .. } = light {
            rect_keys(&path, (edge_u, edge_v), &keys)?;
        }
        rigs.push(Rig::new(
            Thing::Light(i),
            Posed::Light(light),
            None,
            &keys,
            how,
        ));
    }
    Ok(rigs)
}

pub(super) fn interpolation_of(i: raw::Interpolation) -> Interpolation {
    match i {
        raw::Interpolation::Linear => Interpolation::Linear,
        raw::Interpolation::Smooth => Interpolation::Smooth,
    }
}

/// What a thing is called in messages, and the fields its keys may set with their values as
/// the thing is written (what the first key carries over where it gives none).
struct Kind {
    what: &'static str,
    fields: Vec<(&'static str, Field, DVec3)>,
}

fn object_kind(o: &raw::Object, object: &Object) -> Kind {
    let x = |v: f64| DVec3::new(v, 0.0, 0.0);
    match object.shape {
        Shape::Sphere { center, radius } => Kind {
            what: "a sphere",
            fields: vec![
                ("center", Field::Center, center),
                ("radius", Field::Radius, x(radius)),
            ],
        },
        Shape::Plane { point, normal, .. } => Kind {
            what: "a plane",
            fields: vec![
                ("point", Field::Point, point),
                ("normal", Field::Normal, normal),
            ],
        },
        Shape::Mesh { place, .. } => {
            let m = o.mesh.as_ref();
            let written = |f: fn(&raw::Mesh) -> Option<raw::V3>| {
                m.and_then(f).map_or(DVec3::ZERO, DVec3::from)
            };
            Kind {
                what: "a mesh",
                fields: vec![
                    ("scale", Field::Scale, place.scale),
                    ("rotate", Field::Rotate, written(|m| m.rotate)),
                    ("translate", Field::Translate, written(|m| m.translate)),
                ],
            }
        }
    }
}

fn light_kind(l: &raw::Light, light: &Light) -> Kind {
    let colours = |i: &Intensity| {
        vec![
            ("ambient", Field::Ambient, i.ambient),
            ("diffuse", Field::Diffuse, i.diffuse),
            ("specular", Field::Specular, i.specular),
        ]
    };
    let with = |what, mut first: Vec<(&'static str, Field, DVec3)>, i: &Intensity| {
        first.extend(colours(i));
        Kind {
            what,
            fields: first,
        }
    };
    let x = |v: f64| DVec3::new(v, 0.0, 0.0);
    match light {
        Light::Point {
            position,
            intensity,
        } => with(
            "a point light",
            vec![("position", Field::Position, *position)],
            intensity,
        ),
        Light::Directional {
            to_light,
            intensity,
        } => with(
            "a directional light",
            vec![("direction", Field::Direction, -*to_light)],
            intensity,
        ),
        Light::Spot {
            position,
            axis,
            intensity,
            ..
        } => {
            let s = l.spot.as_ref();
            let angles = s.map_or(DVec3::ZERO, |s| {
                DVec3::new(s.inner_angle, s.outer_angle, 0.0)
            });
            with(
                "a spot light",
                vec![
                    ("position", Field::Position, *position),
                    ("direction", Field::Direction, *axis),
                    ("inner_angle", Field::Angles, angles),
                    ("outer_angle", Field::Angles, angles),
                ],
                intensity,
            )
        }
        Light::Ambient { color } => Kind {
            what: "an ambient light",
            fields: vec![("color", Field::Color, *color)],
        },
        Light::Sphere {
            center,
            radius,
            intensity,
            ..
        } => with(
            "a sphere light",
            vec![
                ("center", Field::Center, *center),
                ("radius", Field::Radius, x(*radius)),
            ],
            intensity,
        ),
        Light::Rect {
            corner,
            edge_u,
            edge_v,
            intensity,
            ..
        } => with(
            "a rect light",
            vec![
                ("corner", Field::Corner, *corner),
                ("edge_u", Field::EdgeU, *edge_u),
                ("edge_v", Field::EdgeV, *edge_v),
            ],
            intensity,
        ),
    }
}

/// A value a key gives, as written.
#[derive(Clone, Copy)]
enum Given {
    Vector(raw::V3),
    Number(f64),
}

/// The fields key `k` gives, by name, in the order of `raw::ThingKey`.
fn given(k: &raw::ThingKey) -> Vec<(&'static str, Given)> {
    let v = |name, x: Option<raw::V3>| x.map(|x| (name, Given::Vector(x)));
    let n = |name, x: Option<f64>| x.map(|x| (name, Given::Number(x)));
    [
        v("scale", k.scale.map(|raw::Scale(s)| s)),
        v("rotate", k.rotate),
        v("translate", k.translate),
        v("center", k.center),
        n("radius", k.radius),
        v("point", k.point),
        v("normal", k.normal),
        v("position", k.position),
        v("direction", k.direction),
        n("inner_angle", k.inner_angle),
        n("outer_angle", k.outer_angle),
        v("ambient", k.ambient),
        v("diffuse", k.diffuse),
        v("specular", k.specular),
        v("color", k.color),
        v("corner", k.corner),
        v("edge_u", k.edge_u),
        v("edge_v", k.edge_v),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The keys, each with a value for every field some key sets (carried over from the key
/// before, or from the thing as written), checked one by one and pair by pair.
fn rig_keys(path: &str, kind: &Kind, keys: &[raw::ThingKey], frames: Frames) -> Check<Vec<RigKey>> {
    if keys.is_empty() {
        return invalid(format!("{path}.keys"), "needs at least one key");
    }
    let keyed = keyed_fields(path, kind, keys)?;
    let mut out: Vec<RigKey> = Vec::with_capacity(keys.len());
    for (i, k) in keys.iter().enumerate() {
        let kp = format!("{path}.keys[{i}]");
        let (time, field) = key_time(&kp, (k.time, k.frame), frames)?;
        increasing(
            &format!("{kp}.{field}"),
            "key",
            i,
            out.last().map(|k| k.time),
            time,
        )?;
        let mut values = match out.last() {
            Some(prev) => prev.values.clone(),
            None => keyed.clone(),
        };
        for (name, g) in given(k) {
            set_value(&kp, name, g, &mut values)?;
        }
        angles_in_order(&kp, &values)?;
        let ease = ease(&kp, i, keys.len(), k.ease.as_deref())?;
        out.push(RigKey { time, ease, values });
    }
    for (i, pair) in out.windows(2).enumerate() {
        between(&format!("{path}.keys[{}]", i + 1), i, &pair[0], &pair[1])?;
    }
    Ok(out)
}

/// Every field some key sets, with its value as the thing is written, in the kind's order;
/// a field the kind cannot key is refused where it is given.
fn keyed_fields(path: &str, kind: &Kind, keys: &[raw::ThingKey]) -> Check<Vec<(Field, DVec3)>> {
    let mut keyed: Vec<(Field, DVec3)> = Vec::new();
    for (i, k) in keys.iter().enumerate() {
        for (name, _) in given(k) {
            let Some(&(_, field, _)) = kind.fields.iter().find(|(n, _, _)| *n == name) else {
                let names: Vec<&str> = kind.fields.iter().map(|(n, _, _)| *n).collect();
                return invalid(
                    format!("{path}.keys[{i}].{name}"),
                    format!(
                        "{} cannot key `{name}`; its keys can set {}",
                        kind.what,
                        names.join(", ")
                    ),
                );
            };
            if !keyed.iter().any(|(f, _)| *f == field) {
                keyed.push((field, DVec3::ZERO));
            }
        }
    }
    let order = |f: &Field| kind.fields.iter().position(|(_, g, _)| g == f);
    keyed.sort_by_key(|(f, _)| order(f));
    for (f, v) in &mut keyed {
        *v = kind
            .fields
            .iter()
            .find(|(_, g, _)| g == f)
            .expect("keyed")
            .2;
    }
    Ok(keyed)
}

/// Checks the value key `kp` gives field `name` as a still scene checks it and sets it.
fn set_value(kp: &str, name: &str, g: Given, values: &mut [(Field, DVec3)]) -> Check<()> {
    let p = format!("{kp}.{name}");
    let v = match (name, g) {
        ("scale", Given::Vector(v)) => scale(&p, v)?,
        ("normal" | "direction", Given::Vector(v)) => unit(&p, v)?,
        ("edge_u" | "edge_v", Given::Vector(v)) => direction(&p, v)?,
        ("ambient" | "diffuse" | "specular" | "color", Given::Vector(v)) => color(&p, v)?,
        (_, Given::Vector(v)) => vector(&p, v)?,
        ("radius", Given::Number(r)) => DVec3::new(
            in_range(
                &p,
                r,
                MIN_RADIUS,
                MAX_MAGNITUDE,
                "a positive length in [1e-100, 1e100]",
            )?,
            0.0,
            0.0,
        ),
        (_, Given::Number(a)) => {
            let a = in_range(&p, a, 0.0, 180.0, "an angle in [0, 180] degrees")?;
            let slot = values.iter_mut().find(|(f, _)| *f == Field::Angles);
            let angles = &mut slot.expect("keyed").1;
            match name {
                "inner_angle" => angles.x = a,
                _ => angles.y = a,
            }
            return Ok(());
        }
    };
    let field = field_of(name);
    values
        .iter_mut()
        .find(|(f, _)| *f == field)
        .expect("keyed")
        .1 = v;
    Ok(())
}

fn field_of(name: &str) -> Field {
    match name {
        "scale" => Field::Scale,
        "rotate" => Field::Rotate,
        "translate" => Field::Translate,
        "center" => Field::Center,
        "radius" => Field::Radius,
        "point" => Field::Point,
        "normal" => Field::Normal,
        "position" => Field::Position,
        "direction" => Field::Direction,
        "ambient" => Field::Ambient,
        "diffuse" => Field::Diffuse,
        "specular" => Field::Specular,
        "color" => Field::Color,
        "corner" => Field::Corner,
        "edge_u" => Field::EdgeU,
        "edge_v" => Field::EdgeV,
        _ => Field::Angles,
    }
}

/// A key's scale: every factor finite and at least 1e-100 in size, as a still mesh's.
fn scale(path: &str, v: raw::V3) -> Check<DVec3> {
    let s = vector(path, v)?;
    if s.abs().min_element() < 1e-100 {
        return invalid(
            path,
            format!(
                "each factor must be non-zero, at least 1e-100 in size {}",
                got(num3(s))
            ),
        );
    }
    Ok(s)
}

fn angles_in_order(kp: &str, values: &[(Field, DVec3)]) -> Check<()> {
    match values.iter().find(|(f, _)| *f == Field::Angles) {
        Some((_, a)) if a.x > a.y => invalid(
            format!("{kp}.inner_angle"),
            format!(
                "must not exceed outer_angle ({}) {}",
                num(a.y),
                got_num(a.x)
            ),
        ),
        _ => Ok(()),
    }
}

/// What must hold between key i and the next (at `kp`) for every pose between them to be
/// valid: a scale factor keeps its sign (a straight track would pass through 0), and a
/// direction does not turn straight back (it would pass through the zero vector).
fn between(kp: &str, i: usize, a: &RigKey, b: &RigKey) -> Check<()> {
    for ((field, x), (_, y)) in a.values.iter().zip(&b.values) {
        match field {
            Field::Scale => {
                let axis = (0..3).find(|&c| (x[c] > 0.0) != (y[c] > 0.0));
                if let Some(c) = axis {
                    return invalid(
                        format!("{kp}.scale"),
                        format!(
                            "the scale would cross zero between keys {i} and {} ({} axis from {} to {}): a model cannot turn inside out by moving; keep each factor's sign",
                            i + 1,
                            ["x", "y", "z"][c],
                            num(x[c]),
                            num(y[c])
                        ),
                    );
                }
            }
            Field::Normal | Field::Direction if (*x + *y).length() < 1e-9 => {
                let name = if *field == Field::Normal {
                    "normal"
                } else {
                    "direction"
                };
                return invalid(
                    format!("{kp}.{name}"),
                    format!(
                        "turns straight back from key {i} ({}); it would pass through zero length: add a key between",
                        num3(*x)
                    ),
                );
            }
            _ => {}
        }
    }
    Ok(())
}

/// How the loader placed a mesh that has keys, or None for a sphere or plane. `fit` and
/// `origin: center|bottom` are worked out for one pose, so they refuse keys on scale and
/// rotate.
fn mesh_frame(
    path: &str,
    o: &raw::Object,
    object: &Object,
    scene: &Scene,
    keys: &[raw::ThingKey],
) -> Check<Option<MeshFrame>> {
    let turned = |k: &raw::ThingKey| k.scale.is_some() || k.rotate.is_some();
    let (Some(m), Shape::Mesh { mesh, place, .. }) = (&o.mesh, object.shape) else {
        return Ok(None);
    };
    let origin = m.origin.unwrap_or_default();
    if (m.fit.is_some() || origin != raw::Origin::File)
        && let Some(i) = keys.iter().position(turned)
    {
        let field = if keys[i].scale.is_some() {
            "scale"
        } else {
            "rotate"
        };
        return invalid(
            format!("{path}.keys[{i}].{field}"),
            "a model placed with `fit` or `origin: center|bottom` cannot key scale or rotate (they are worked out for one pose); place it with scale and translate instead",
        );
    }
    let up = meshes::up_axis(&format!("{path}.mesh.up"), m.up.as_deref())?;
    let model = &scene.meshes[mesh];
    let offset = meshes::origin_offset(model, place.scale, place.rotation, origin);
    Ok(Some(MeshFrame { up, offset }))
}

/// A rect light's keyed edges span an area at every key and at every pose between two keys:
/// on a segment the edges are (1−s)·a + s·b and (1−s)·c + s·d for some s in [0, 1], whose
/// cross product is (1−s)²·A + s(1−s)·B + s²·C; its component along the first key's normal
/// must stay positive, so the rectangle never turns edge-on or flips between keys.
fn rect_keys(path: &str, still: (DVec3, DVec3), keys: &[RigKey]) -> Check<()> {
    let edges = |k: &RigKey| {
        let get = |f: Field, or: DVec3| k.values.iter().find(|(g, _)| *g == f).map_or(or, |v| v.1);
        (get(Field::EdgeU, still.0), get(Field::EdgeV, still.1))
    };
    for (i, k) in keys.iter().enumerate() {
        let (u, v) = edges(k);
        let (_, length) = area_normal(u, v);
        if !(length > 0.0 && length.is_finite()) {
            return invalid(
                format!("{path}.keys[{i}].edge_v"),
                format!(
                    "must not be parallel to edge_u: the rectangle needs an area, |edge_u × edge_v| finite and non-zero {}",
                    got(format!("{} × {}", num3(u), num3(v)))
                ),
            );
        }
    }
    for (i, pair) in keys.windows(2).enumerate() {
        if !keeps_area(edges(&pair[0]), edges(&pair[1])) {
            return invalid(
                format!("{path}.keys[{}]", i + 1),
                format!(
                    "the rect light's edges would turn edge-on or flip between keys {i} and {}: add a key between",
                    i + 1
                ),
            );
        }
    }
    Ok(())
}

/// Whether f(s) = (1−s)²·α + s(1−s)·β + s²·γ stays positive on [0, 1], with α, β, γ the
/// components of A = a × c, B = a × d + b × c and C = b × d along n, the unit normal of A,
/// each divided by the largest of the three in size (docs/spec/motion.md): γ > 0 and, where the parabola f = α + l·s + q·s² (l = β − 2α,
/// q = (α − β) + γ) has its lowest point inside (q > 0 and 0 < −l < 2q), l·l < 4·q·α.
fn keeps_area((a, c): (DVec3, DVec3), (b, d): (DVec3, DVec3)) -> bool {
    let (cross, length) = area_normal(a, c);
    let n = cross * (1.0 / length);
    let f = [a.cross(c), a.cross(d) + b.cross(c), b.cross(d)].map(|v| v.dot(n));
    // Scaled to at most 1 in size, so the products below neither overflow nor underflow.
    let big = f.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let [alpha, beta, gamma] = f.map(|x| x / big);
    let (l, q) = (beta - 2.0 * alpha, (alpha - beta) + gamma);
    let inside = q > 0.0 && 0.0 < -l && -l < 2.0 * q;
    gamma > 0.0 && (!inside || l * l < 4.0 * q * alpha)
}
