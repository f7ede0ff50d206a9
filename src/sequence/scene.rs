//! `materials:`, `objects:` and `lights:` → the validated `Scene`'s parts.

use super::*;
use crate::scene::Texture;

pub(super) fn material(
    path: &str,
    m: &raw::Material,
    textures: &mut super::textures::Textures,
) -> Check<Material> {
    let shininess = m.shininess.unwrap_or(100.0);
    let exponent = shininess / 4.0;
    let (ambient, ambient_map) = textures.paint(&format!("{path}.ambient"), &m.ambient)?;
    let (diffuse, diffuse_map) = textures.paint(&format!("{path}.diffuse"), &m.diffuse)?;
    Ok(Material {
        // x^e < 1e-30 ⇔ x < exp(−69.08 / e).
        specular_floor: if exponent > 0.0 {
            libm::exp(-69.08 / exponent)
        } else {
            0.0
        },
        ambient,
        diffuse,
        ambient_map,
        diffuse_map,
        specular: color(&format!("{path}.specular"), m.specular)?,
        exponent: in_range(
            &format!("{path}.shininess"),
            shininess,
            0.0,
            MAX_SHININESS,
            &format!("in [0, {MAX_SHININESS}]"),
        )? / 4.0,
        reflection: in_range(
            &format!("{path}.reflection"),
            m.reflection.unwrap_or(0.0),
            0.0,
            1.0,
            "in [0, 1]",
        )?,
        transmission: transmission(path, m)?,
        ior: in_range(
            &format!("{path}.ior"),
            m.ior.unwrap_or(1.5),
            1.0,
            MAX_IOR,
            &format!("in [1, {MAX_IOR}]"),
        )?,
        fresnel: m.fresnel,
    })
}

/// Glass refracts at most as much as diamond's 2.42 several times over; beyond this an index
/// means nothing physical.
const MAX_IOR: f64 = 100.0;

/// The transmission filter: each channel in [0, 1], and with the reflection at most 1, since
/// a surface cannot pass on more light than it receives (Fresnel shares it out itself).
fn transmission(path: &str, m: &raw::Material) -> Check<DVec3> {
    if m.fresnel && m.reflection.is_some() {
        return invalid(
            format!("{path}.reflection"),
            "with `fresnel: true` the Fresnel term decides how much is reflected; remove `reflection`",
        );
    }
    let field = format!("{path}.transmission");
    let Some(raw::Filter(v)) = m.transmission else {
        return Ok(DVec3::ZERO);
    };
    let t = vector(&field, v)?;
    if t.min_element() < 0.0 || t.max_element() > 1.0 {
        return invalid(&field, format!("must be in [0, 1] {}", got(fmt3(v))));
    }
    let r = m.reflection.unwrap_or(0.0);
    if !m.fresnel && r + t.max_element() > 1.0 {
        return invalid(
            &field,
            format!(
                "reflection + transmission must not exceed 1 in any channel: a surface cannot pass on more light than it receives {}",
                got(format!("{} + {}", num(r), fmt3(v)))
            ),
        );
    }
    Ok(t)
}

pub(super) fn material_ref(
    path: &str,
    r: &raw::MaterialRef,
    names: &[&str],
    materials: &mut Vec<Material>,
    textures: &mut super::textures::Textures,
) -> Check<usize> {
    match r {
        raw::MaterialRef::Named(n) => names.iter().position(|m| m == n).map_or_else(
            || {
                let known = if names.is_empty() {
                    "no materials are defined under `materials:`".to_string()
                } else {
                    format!("defined: {}", names.join(", "))
                };
                invalid(path, format!("unknown material `{n}` ({known})"))
            },
            Ok,
        ),
        raw::MaterialRef::Inline(m) => {
            materials.push(material(path, m, textures)?);
            Ok(materials.len() - 1)
        }
    }
}

pub(super) fn exactly_one<T>(path: &str, options: &[(&str, Option<T>)]) -> Check<T>
where
    T: Copy,
{
    let given: Vec<&(&str, Option<T>)> = options.iter().filter(|(_, v)| v.is_some()).collect();
    let names: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
    match given.as_slice() {
        [(_, Some(v))] => Ok(*v),
        [] => invalid(path, format!("needs one of: {}", names.join(", "))),
        many => invalid(
            path,
            format!(
                "give exactly one of {} per entry (got {})",
                names.join(", "),
                many.iter()
                    .map(|(n, _)| *n)
                    .collect::<Vec<_>>()
                    .join(" and ")
            ),
        ),
    }
}

pub(super) fn object(
    path: &str,
    o: &raw::Object,
    names: &[&str],
    materials: &mut Vec<Material>,
    (meshes, textures): (&mut super::meshes::Meshes, &mut super::textures::Textures),
) -> Check<Object> {
    let mut material = |p: &str, r: &raw::MaterialRef| {
        material_ref(&format!("{p}.material"), r, names, materials, textures)
    };
    let which = exactly_one(
        path,
        &[
            ("sphere", o.sphere.as_ref().map(|_| 0)),
            ("plane", o.plane.as_ref().map(|_| 1)),
            ("mesh", o.mesh.as_ref().map(|_| 2)),
        ],
    )?;
    if which == 2 {
        let m = o.mesh.as_ref().expect("checked");
        let p = format!("{path}.mesh");
        let shape = meshes.place(&p, m)?;
        let index = material(&p, &m.material)?;
        let image = |t: &Option<Texture>| matches!(t, Some(Texture::Image { .. }));
        let mat = &materials[index];
        if (image(&mat.diffuse_map) || image(&mat.ambient_map)) && !meshes.has_uvs(&shape) {
            return invalid(
                format!("{p}.material"),
                format!(
                    "an image texture needs texture coordinates, and {} has none (OBJ `vt`, PLY `u`/`v` or `s`/`t`); use a checker or add UVs",
                    m.file
                ),
            );
        }
        return Ok(Object {
            shape,
            material: index,
        });
    }
    if which == 0 {
        let s = o.sphere.as_ref().expect("checked");
        let p = format!("{path}.sphere");
        Ok(Object {
            shape: Shape::Sphere {
                center: vector(&format!("{p}.center"), s.center)?,
                radius: in_range(
                    &format!("{p}.radius"),
                    s.radius,
                    MIN_RADIUS,
                    MAX_MAGNITUDE,
                    "a positive length in [1e-100, 1e100]",
                )?,
            },
            material: material(&p, &s.material)?,
        })
    } else {
        let s = o.plane.as_ref().expect("checked");
        let p = format!("{path}.plane");
        Ok(Object {
            shape: plane(&p, s)?,
            material: material(&p, &s.material)?,
        })
    }
}

/// A plane; its `u_axis`, when given, projected into the plane and made unit length.
fn plane(path: &str, s: &raw::Plane) -> Check<Shape> {
    let normal = unit(&format!("{path}.normal"), s.normal)?;
    let u_axis = match s.u_axis {
        None => None,
        Some(a) => {
            let field = format!("{path}.u_axis");
            let a = unit(&field, a)?;
            let (along, length) = crate::scene::plane_axis(a, normal);
            if length < 1e-6 {
                return invalid(
                    &field,
                    format!(
                        "must not be parallel to the plane's normal {}",
                        got(num3(a))
                    ),
                );
            }
            Some(along.normalize())
        }
    };
    Ok(Shape::Plane {
        point: vector(&format!("{path}.point"), s.point)?,
        normal,
        u_axis,
    })
}

pub(super) fn intensity(
    path: &str,
    ambient: raw::V3,
    diffuse: raw::V3,
    specular: raw::V3,
) -> Check<Intensity> {
    Ok(Intensity {
        ambient: color(&format!("{path}.ambient"), ambient)?,
        diffuse: color(&format!("{path}.diffuse"), diffuse)?,
        specular: color(&format!("{path}.specular"), specular)?,
    })
}

pub(super) fn light(path: &str, l: &raw::Light) -> Check<Light> {
    let which = exactly_one(
        path,
        &[
            ("point", l.point.as_ref().map(|_| 0)),
            ("directional", l.directional.as_ref().map(|_| 1)),
            ("spot", l.spot.as_ref().map(|_| 2)),
            ("ambient", l.ambient.as_ref().map(|_| 3)),
            ("sphere", l.sphere.as_ref().map(|_| 4)),
            ("rect", l.rect.as_ref().map(|_| 5)),
        ],
    )?;
    Ok(match which {
        0 => {
            let p = l.point.as_ref().expect("checked");
            let path = format!("{path}.point");
            Light::Point {
                position: vector(&format!("{path}.position"), p.position)?,
                intensity: intensity(&path, p.ambient, p.diffuse, p.specular)?,
            }
        }
        1 => {
            let d = l.directional.as_ref().expect("checked");
            let path = format!("{path}.directional");
            Light::Directional {
                to_light: -unit(&format!("{path}.direction"), d.direction)?,
                intensity: intensity(&path, d.ambient, d.diffuse, d.specular)?,
            }
        }
        2 => spot(&format!("{path}.spot"), l.spot.as_ref().expect("checked"))?,
        4 => sphere_light(
            &format!("{path}.sphere"),
            l.sphere.as_ref().expect("checked"),
        )?,
        5 => rect_light(&format!("{path}.rect"), l.rect.as_ref().expect("checked"))?,
        _ => Light::Ambient {
            color: color(
                &format!("{path}.ambient.color"),
                l.ambient.as_ref().expect("checked").color,
            )?,
        },
    })
}

pub(super) fn spot(path: &str, s: &raw::SpotLight) -> Check<Light> {
    let angle = |name: &str, v: f64| {
        in_range(
            &format!("{path}.{name}"),
            v,
            0.0,
            180.0,
            "an angle in [0, 180] degrees",
        )
    };
    let inner = angle("inner_angle", s.inner_angle)?;
    let outer = angle("outer_angle", s.outer_angle)?;
    if inner > outer {
        return invalid(
            format!("{path}.inner_angle"),
            format!(
                "must not exceed outer_angle ({}) {}",
                num(outer),
                got_num(inner)
            ),
        );
    }
    Ok(Light::Spot {
        position: vector(&format!("{path}.position"), s.position)?,
        axis: unit(&format!("{path}.direction"), s.direction)?,
        cos_inner: libm::cos(inner.to_radians()),
        cos_outer: libm::cos(outer.to_radians()),
        intensity: intensity(path, s.ambient, s.diffuse, s.specular)?,
    })
}

/// Default points an area light takes for each eye sample.
pub(crate) const DEFAULT_LIGHT_SAMPLES: u32 = 16;
/// Most points an area light may take for each eye sample.
pub(crate) const MAX_LIGHT_SAMPLES: u64 = 4096;

/// An area light's `samples`: 1 to 4096, 16 when absent.
fn light_samples(path: &str, n: Option<i64>) -> Check<u32> {
    match n {
        None => Ok(DEFAULT_LIGHT_SAMPLES),
        Some(n) if (1..=MAX_LIGHT_SAMPLES as i64).contains(&n) => Ok(n as u32),
        Some(n) => invalid(
            format!("{path}.samples"),
            format!(
                "must be 1 to {MAX_LIGHT_SAMPLES} points on the light per eye sample {}",
                got(n)
            ),
        ),
    }
}

pub(super) fn sphere_light(path: &str, s: &raw::SphereLight) -> Check<Light> {
    Ok(Light::Sphere {
        center: vector(&format!("{path}.center"), s.center)?,
        radius: in_range(
            &format!("{path}.radius"),
            s.radius,
            MIN_RADIUS,
            MAX_MAGNITUDE,
            "a positive length in [1e-100, 1e100]",
        )?,
        samples: light_samples(path, s.samples)?,
        intensity: intensity(path, s.ambient, s.diffuse, s.specular)?,
    })
}

/// A rect light: its edges must span a parallelogram whose normal edge_u × edge_v has a
/// finite, non-zero length (so it can be normalised).
pub(super) fn rect_light(path: &str, r: &raw::RectLight) -> Check<Light> {
    let corner = vector(&format!("{path}.corner"), r.corner)?;
    let edge_u = direction(&format!("{path}.edge_u"), r.edge_u)?;
    let edge_v = direction(&format!("{path}.edge_v"), r.edge_v)?;
    let (cross, length) = crate::scene::area_normal(edge_u, edge_v);
    if !(length > 0.0 && length.is_finite()) {
        return invalid(
            format!("{path}.edge_v"),
            format!(
                "must not be parallel to edge_u: the rectangle needs an area, |edge_u × edge_v| finite and non-zero {}",
                got(format!("{} × {}", fmt3(r.edge_u), fmt3(r.edge_v)))
            ),
        );
    }
    Ok(Light::Rect {
        corner,
        edge_u,
        edge_v,
        normal: cross * (1.0 / length),
        samples: light_samples(path, r.samples)?,
        intensity: intensity(path, r.ambient, r.diffuse, r.specular)?,
    })
}
