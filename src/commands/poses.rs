//! `rayreel camera FILE --object SEL | --light N`: the poses of one moving object or light,
//! one line per frame, as `camera` prints the camera's. CSV and JSON give the keyed fields'
//! values at each frame's time, in the units keys are written in, so pasting a line's values
//! into the thing's own fields (its keys removed) gives the still scene of that frame; `chan`
//! gives a placement (translation and ZXY rotation) for compositing tools.

use super::Error;
use super::camera::{unwrap, zxy_degrees};
use crate::cli::CameraFormat;
use crate::frameset::FrameSet;
use crate::scene::{Light, Shape};
use crate::sequence::Sequence;
use crate::timeline::motion::{Field, Posed, Rig, Thing};
use glam::DVec3;

/// The rig of the thing `--object` or `--light` names; an error naming what exists when it
/// names nothing, or names a thing without keys.
pub(super) fn find<'a>(
    seq: &'a Sequence,
    object: Option<&str>,
    light: Option<usize>,
) -> Result<Option<&'a Rig>, Error> {
    let thing = match (object, light) {
        (Some(sel), _) => Thing::Object(object_index(seq, sel)?),
        (None, Some(i)) if i < seq.scene.lights.len() => Thing::Light(i),
        (None, Some(i)) => {
            return Err(Error::Usage(format!(
                "--light {i}: the sequence has {} lights (lights[0] to lights[{}])",
                seq.scene.lights.len(),
                seq.scene.lights.len().saturating_sub(1)
            )));
        }
        (None, None) => return Ok(None),
    };
    let rig = seq.timeline.motion.iter().find(|r| r.thing == thing);
    match rig {
        Some(rig) => Ok(Some(rig)),
        None => Err(Error::Usage(format!(
            "{} has no keys: it holds still at the values written in the file",
            thing
        ))),
    }
}

/// `--object`'s selector: an index into `objects:` (from 0, as `check` lists them) or a name.
fn object_index(seq: &Sequence, sel: &str) -> Result<usize, Error> {
    let count = seq.scene.objects.len();
    if let Ok(i) = sel.parse::<usize>() {
        return match i < count {
            true => Ok(i),
            false => Err(Error::Usage(format!(
                "--object {i}: the sequence has {count} objects (objects[0] to objects[{}])",
                count.saturating_sub(1)
            ))),
        };
    }
    let named = seq
        .object_names
        .iter()
        .position(|n| n.as_deref() == Some(sel));
    named.ok_or_else(|| {
        let names: Vec<&str> = seq
            .object_names
            .iter()
            .flatten()
            .map(String::as_str)
            .collect();
        let known = match names.is_empty() {
            true => "no object has a `name:`".to_string(),
            false => format!("names: {}", names.join(", ")),
        };
        Error::Usage(format!(
            "--object {sel}: no object is named `{sel}` ({known}); give a name or an index from 0"
        ))
    })
}

/// The lines `camera` prints for `rig` over `frames` (a CSV header first).
pub(super) fn lines(
    seq: &Sequence,
    rig: &Rig,
    frames: &FrameSet,
    format: CameraFormat,
) -> Result<Vec<String>, Error> {
    // The keyed fields and what follows from them (a turned plane's u_axis).
    let fields: Vec<Field> = rig.values_at(0.0).iter().map(|(f, _)| *f).collect();
    let mut out = Vec::new();
    if format == CameraFormat::Csv {
        let columns: Vec<String> = fields.iter().flat_map(|&f| columns(f)).collect();
        out.push(format!("frame,time,{}", columns.join(",")));
    }
    // chan's angles continue from the line before, as the camera's do.
    let mut before = None;
    for n in frames.iter() {
        let t = seq.timeline.time_of(n);
        out.push(match format {
            CameraFormat::Csv => csv_line(n, t, &rig.values_at(t)),
            CameraFormat::Json => json_line(n, t, &rig.values_at(t)),
            CameraFormat::Chan => chan_line(n, rig, t, &mut before)?,
        });
    }
    Ok(out)
}

/// Column names of a field: a vector's three (`_x`, `_y`, `_z`, colours `_r`, `_g`, `_b`), a
/// number's one, a spot's two angles.
fn columns(f: Field) -> Vec<String> {
    match f {
        Field::Radius => vec!["radius".into()],
        Field::Angles => vec!["inner_angle".into(), "outer_angle".into()],
        f if colour(f) => ["r", "g", "b"].map(|c| format!("{}_{c}", f.name())).into(),
        f => ["x", "y", "z"].map(|c| format!("{}_{c}", f.name())).into(),
    }
}

fn colour(f: Field) -> bool {
    matches!(
        f,
        Field::Ambient | Field::Diffuse | Field::Specular | Field::Color
    )
}

fn csv_line(n: u64, t: f64, values: &[(Field, DVec3)]) -> String {
    let mut line = format!("{n},{t:?}");
    for &(f, v) in values {
        let numbers = match f {
            Field::Radius => vec![v.x],
            Field::Angles => vec![v.x, v.y],
            _ => vec![v.x, v.y, v.z],
        };
        numbers.iter().for_each(|x| line += &format!(",{x:?}"));
    }
    line
}

/// One JSON object: the fields under the names keys give them (a spot's angles as
/// `inner_angle` and `outer_angle`), vectors as 3-element arrays.
fn json_line(n: u64, t: f64, values: &[(Field, DVec3)]) -> String {
    let mut line = format!("{{\"frame\": {n}, \"time\": {t:?}");
    for &(f, v) in values {
        line += &match f {
            Field::Radius => format!(", \"radius\": {:?}", v.x),
            Field::Angles => format!(", \"inner_angle\": {:?}, \"outer_angle\": {:?}", v.x, v.y),
            f => format!(", \"{}\": [{:?}, {:?}, {:?}]", f.name(), v.x, v.y, v.z),
        };
    }
    line + "}"
}

/// `frame tx ty tz rx ry rz`: where the thing is and how it is turned, as Nuke's Axis takes
/// it (rotation order ZXY, angles unwrapped across lines as the camera's are). A mesh gives
/// its placement's translation and rotation (its scale is in csv and json); a sphere, a
/// sphere light and a point light their centre or position, unturned; a spot and a
/// directional light a frame looking along their direction (−z), up as near +y as it can be;
/// a rect light its corner and a frame looking the way it shines (−z along its normal), up
/// as near its edge_v as it can be.
fn chan_line(n: u64, rig: &Rig, t: f64, before: &mut Option<[f64; 3]>) -> Result<String, Error> {
    let along = |d: DVec3| zxy_degrees(d, DVec3::Y);
    let (at, turn) = match rig.at(t) {
        Posed::Object(o) => match o.shape {
            Shape::Mesh { place, .. } => {
                let r = place.rotation;
                (place.translate, zxy_degrees(-r.z_axis, r.y_axis))
            }
            Shape::Sphere { center, .. } => (center, [0.0; 3]),
            Shape::Plane { .. } => return Err(no_chan(rig.thing, "a plane")),
        },
        Posed::Light(l) => match l {
            Light::Point { position, .. } => (position, [0.0; 3]),
            Light::Sphere { center, .. } => (center, [0.0; 3]),
            Light::Spot { position, axis, .. } => (position, along(axis)),
            Light::Directional { to_light, .. } => (DVec3::ZERO, along(-to_light)),
            Light::Rect {
                corner,
                normal,
                edge_v,
                ..
            } => (corner, zxy_degrees(normal, edge_v)),
            Light::Ambient { .. } => return Err(no_chan(rig.thing, "an ambient light")),
        },
    };
    let [rx, ry, rz] = unwrap(turn, *before);
    *before = Some([rx, ry, rz]);
    // `+ 0.0` turns −0 into 0, as in the camera's lines.
    let [x, y, z, rx, ry, rz] = [at.x, at.y, at.z, rx, ry, rz].map(|v| v + 0.0);
    Ok(format!("{n} {x:?} {y:?} {z:?} {rx:?} {ry:?} {rz:?}"))
}

fn no_chan(thing: Thing, what: &str) -> Error {
    Error::Usage(format!(
        "{} is {what}: a chan file has no place for it; use --format json or csv",
        thing
    ))
}
