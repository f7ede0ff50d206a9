//! Objects by name: `name:` on an object, and camera points given as `{ object: NAME }`,
//! which become the centre of that object's bounds before the timeline reads them.
//!
//! ```yaml
//! objects:
//!   - name: statue
//!     mesh: { file: models/statue.ply, material: clay, up: z, fit: 2, origin: bottom }
//! timeline:
//!   orbit: { center: { object: statue }, radius: 4, height: 1, duration: 6 }
//!   # or keyframes: - { time: 0, position: [0, 1, 5], look_at: { object: statue } }
//! ```

use super::*;
use raw::Target;

/// Each object's `name:`, checked: not empty, and no two alike.
pub(super) fn names(objects: &[raw::Object]) -> Check<Vec<Option<String>>> {
    let mut names: Vec<Option<String>> = Vec::with_capacity(objects.len());
    for (i, o) in objects.iter().enumerate() {
        let path = format!("objects[{i}].name");
        if let Some(name) = &o.name {
            if name.trim().is_empty() {
                return invalid(path, "a name must not be empty");
            }
            if let Some(j) = names.iter().position(|n| n.as_ref() == Some(name)) {
                return invalid(
                    path,
                    format!(
                        "`{}` already names objects[{j}]; names must differ",
                        crate::console::printable(name)
                    ),
                );
            }
        }
        names.push(o.name.clone());
    }
    Ok(names)
}

/// Replaces every `{ object: NAME }` of the camera, the keyframes and the orbit by the centre
/// of that object's bounds (`centre`).
pub(super) fn resolve(
    raw: &mut raw::Sequence,
    scene: &Scene,
    names: &[Option<String>],
) -> Check<()> {
    let mut targets: Vec<(String, &mut Target)> = Vec::new();
    if let Some(c) = &mut raw.camera {
        targets.push(("camera.look_at".into(), &mut c.look_at));
    }
    if let Some(t) = &mut raw.timeline {
        for (i, k) in t.keyframes.iter_mut().flatten().enumerate() {
            if let Some(l) = &mut k.look_at {
                targets.push((format!("timeline.keyframes[{i}].look_at"), l));
            }
        }
        if let Some(o) = &mut t.orbit {
            targets.push(("timeline.orbit.center".into(), &mut o.center));
            if let Some(l) = &mut o.look_at {
                targets.push(("timeline.orbit.look_at".into(), l));
            }
        }
    }
    for (path, target) in targets {
        let Target::Object(name) = target else {
            continue;
        };
        let shown = crate::console::printable(name).into_owned();
        let Some(i) = names.iter().position(|n| n.as_ref() == Some(name)) else {
            let named: Vec<String> = names.iter().flatten().map(|n| format!("`{n}`")).collect();
            let named = match named.is_empty() {
                true => "no object has a `name:`".to_string(),
                false => format!("named: {}", named.join(", ")),
            };
            return invalid(
                format!("{path}.object"),
                format!("no object is named `{shown}` ({named})"),
            );
        };
        let Some(point) = centre(scene, i) else {
            return invalid(
                format!("{path}.object"),
                format!("objects[{i}] (`{shown}`) is a plane, which has no centre to aim at"),
            );
        };
        *target = Target::Point(point.to_array());
    }
    Ok(())
}

/// The centre of object `i`'s bounds: a sphere's centre; a mesh's (lo + hi) · 0.5 over its
/// placed vertices; none for a plane.
pub(crate) fn centre(scene: &Scene, i: usize) -> Option<DVec3> {
    match scene.objects[i].shape {
        Shape::Sphere { center, .. } => Some(center),
        Shape::Plane { .. } => None,
        Shape::Mesh { mesh, place, .. } => {
            let m = &scene.meshes[mesh];
            let (lo, hi) = meshes::placed_bounds(m, place.scale, place.rotation, place.translate);
            Some((lo + hi) * 0.5)
        }
    }
}
