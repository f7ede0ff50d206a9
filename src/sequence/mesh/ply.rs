//! PLY (ASCII, binary little- and big-endian): the `vertex` element's x y z, optional nx ny nz
//! and u v (or s t, texture_u texture_v), and the `face` element's `vertex_indices` (or
//! `vertex_index`) list of any length. Other elements and properties are read past.

use super::{Soup, fan};
use glam::{DVec2, DVec3};

type Fail = (Option<String>, String);

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

struct Property {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Scalar>,
    ty: Scalar,
}

struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

/// Reads values one at a time from the body, in the file's format.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    format: Format,
}

impl Body<'_> {
    fn value(&mut self, ty: Scalar) -> Option<f64> {
        if self.format == Format::Ascii {
            let rest = &self.bytes[self.at..];
            let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
            let len = rest[start..]
                .iter()
                .position(|b| b.is_ascii_whitespace())
                .unwrap_or(rest.len() - start);
            self.at += start + len;
            let word = std::str::from_utf8(&rest[start..start + len]).ok()?;
            return word.parse::<f64>().ok();
        }
        let n = ty.size();
        let b = self.bytes.get(self.at..self.at + n)?;
        self.at += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.format == Format::Big {
            a[..n].reverse();
        }
        Some(match ty {
            Scalar::I8 => f64::from(a[0] as i8),
            Scalar::U8 => f64::from(a[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

pub(super) fn read(bytes: &[u8]) -> Result<Soup, Fail> {
    let (format, elements, body) = header(bytes)?;
    let mut body = Body {
        bytes,
        at: body,
        format,
    };
    let mut soup = Soup::default();
    let mut faces_seen = false;
    for e in &elements {
        match e.name.as_str() {
            "vertex" => vertices(e, &mut body, &mut soup)?,
            "face" => {
                faces_seen = true;
                faces(e, &mut body, &mut soup)?;
            }
            _ => skip(e, &mut body)?,
        }
    }
    if !faces_seen {
        return Err((None, "the file has no `face` element".into()));
    }
    Ok(soup)
}

fn header(bytes: &[u8]) -> Result<(Format, Vec<Element>, usize), Fail> {
    let fail = |m: &str| Err((Some("header".to_string()), m.to_string()));
    let end = find(bytes, b"end_header").ok_or((
        Some("header".to_string()),
        "no `end_header` line: not a PLY file, or a truncated one".to_string(),
    ))?;
    let mut body = end + b"end_header".len();
    // The header ends with the line: `\n` (or `\r\n`).
    if bytes.get(body) == Some(&b'\r') {
        body += 1;
    }
    if bytes.get(body) == Some(&b'\n') {
        body += 1;
    }
    let Ok(text) = std::str::from_utf8(&bytes[..end]) else {
        return fail("the header is not ASCII text");
    };
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return fail("the file does not start with `ply`");
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return fail(&format!("unknown format `{f}`")),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let Ok(count) = count.parse() else {
                    return fail(&format!("element `{name}` has no count (got `{count}`)"));
                };
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", c, t, name] => {
                let (Some(c), Some(t)) = (Scalar::parse(c), Scalar::parse(t)) else {
                    return fail(&format!("property `{name}` has an unknown type"));
                };
                let Some(e) = elements.last_mut() else {
                    return fail("a property before any element");
                };
                e.props.push(Property {
                    name: name.to_string(),
                    list: Some(c),
                    ty: t,
                });
            }
            ["property", t, name] => {
                let Some(t) = Scalar::parse(t) else {
                    return fail(&format!("property `{name}` has unknown type `{t}`"));
                };
                let Some(e) = elements.last_mut() else {
                    return fail("a property before any element");
                };
                e.props.push(Property {
                    name: name.to_string(),
                    list: None,
                    ty: t,
                });
            }
            _ => return fail(&format!("cannot read the header line `{}`", line.trim())),
        }
    }
    let Some(format) = format else {
        return fail("no `format` line");
    };
    Ok((format, elements, body))
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    // The header is short; stop looking after 64 KiB of it.
    let hay = &hay[..hay.len().min(1 << 16)];
    hay.windows(needle.len()).position(|w| w == needle)
}

fn truncated(what: &str, i: u64) -> Fail {
    (
        Some(format!("{what} {i}")),
        "the file ends early, or a value is not a number".into(),
    )
}

fn vertices(e: &Element, body: &mut Body, soup: &mut Soup) -> Result<(), Fail> {
    let at = |names: &[&str]| {
        e.props
            .iter()
            .position(|p| names.contains(&p.name.as_str()))
    };
    let (Some(x), Some(y), Some(z)) = (at(&["x"]), at(&["y"]), at(&["z"])) else {
        return Err((Some("header".into()), "`vertex` needs x, y and z".into()));
    };
    let normal = match (at(&["nx"]), at(&["ny"]), at(&["nz"])) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let uv = match (
        at(&["u", "s", "texture_u", "texture_s"]),
        at(&["v", "t", "texture_v", "texture_t"]),
    ) {
        (Some(a), Some(b)) => Some([a, b]),
        _ => None,
    };
    let n = usize::try_from(e.count).unwrap_or(usize::MAX);
    let cap = n.min(body.bytes.len() / 3 + 1);
    soup.positions.reserve(cap);
    let mut normals = normal.map(|_| Vec::with_capacity(cap));
    let mut uvs = uv.map(|_| Vec::with_capacity(cap));
    let mut values = vec![0.0; e.props.len()];
    for i in 0..e.count {
        for (k, p) in e.props.iter().enumerate() {
            values[k] = match p.list {
                None => body.value(p.ty).ok_or_else(|| truncated("vertex", i))?,
                Some(c) => {
                    let len = body.value(c).ok_or_else(|| truncated("vertex", i))?;
                    for _ in 0..len as u64 {
                        body.value(p.ty).ok_or_else(|| truncated("vertex", i))?;
                    }
                    0.0
                }
            };
        }
        soup.positions
            .push(DVec3::new(values[x], values[y], values[z]));
        if let (Some(out), Some([a, b, c])) = (normals.as_mut(), normal) {
            out.push(DVec3::new(values[a], values[b], values[c]));
        }
        if let (Some(out), Some([a, b])) = (uvs.as_mut(), uv) {
            out.push(DVec2::new(values[a], values[b]));
        }
    }
    soup.normals = normals;
    soup.uvs = uvs;
    Ok(())
}

fn faces(e: &Element, body: &mut Body, soup: &mut Soup) -> Result<(), Fail> {
    let Some(list) = e
        .props
        .iter()
        .position(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"))
    else {
        return Err((
            Some("header".into()),
            "`face` needs a `vertex_indices` list".into(),
        ));
    };
    let nv = soup.positions.len() as f64;
    let mut polygon = Vec::new();
    for i in 0..e.count {
        for (k, p) in e.props.iter().enumerate() {
            let Some(c) = p.list else {
                body.value(p.ty).ok_or_else(|| truncated("face", i))?;
                continue;
            };
            let len = body.value(c).ok_or_else(|| truncated("face", i))?;
            if k == list && (len.is_nan() || len < 3.0) {
                return Err((
                    Some(format!("face {i}")),
                    format!("a face needs at least 3 vertices (got {len})"),
                ));
            }
            polygon.clear();
            for _ in 0..len as u64 {
                let v = body.value(p.ty).ok_or_else(|| truncated("face", i))?;
                if k == list {
                    if !(v >= 0.0 && v < nv && v.fract() == 0.0) {
                        return Err((
                            Some(format!("face {i}")),
                            format!("vertex index {v} is out of range ({nv} vertices)"),
                        ));
                    }
                    polygon.push(v as u32);
                }
            }
            if k == list {
                fan(&polygon, &mut soup.triangles);
            }
        }
    }
    Ok(())
}

fn skip(e: &Element, body: &mut Body) -> Result<(), Fail> {
    for i in 0..e.count {
        for p in &e.props {
            let len = match p.list {
                Some(c) => body.value(c).ok_or_else(|| truncated(&e.name, i))? as u64,
                None => 1,
            };
            for _ in 0..len {
                body.value(p.ty).ok_or_else(|| truncated(&e.name, i))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary(big: bool) -> Vec<u8> {
        let head = format!(
            "ply\nformat {} 1.0\ncomment made by hand\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
            if big {
                "binary_big_endian"
            } else {
                "binary_little_endian"
            }
        );
        let mut b = head.into_bytes();
        let f = |b: &mut Vec<u8>, x: f32| {
            b.extend(if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            })
        };
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            for v in [x, y, 0.0, x, y] {
                f(&mut b, v);
            }
        }
        b.push(4);
        for i in 0..4i32 {
            b.extend(if big {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
        b
    }

    #[test]
    fn reads_both_endians_alike() {
        for big in [false, true] {
            let s = read(&binary(big)).unwrap();
            assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);
            assert_eq!(s.positions[2], DVec3::new(1.0, 1.0, 0.0));
            assert_eq!(s.uvs.as_ref().unwrap()[3], DVec2::new(0.0, 1.0));
        }
    }

    #[test]
    fn reads_ascii_and_names_bad_faces() {
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty double nx\nproperty double ny\nproperty double nz\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
        let ok = format!("{head}0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
        let s = read(ok.as_bytes()).unwrap();
        assert_eq!(s.normals.unwrap()[1], DVec3::Z);
        let bad = format!("{head}0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 7\n");
        let e = read(bad.as_bytes()).err().unwrap();
        assert_eq!(e.0.as_deref(), Some("face 0"));
        let short = format!("{head}0 0 0 0 0 1\n1 0 0\n");
        assert_eq!(
            read(short.as_bytes()).err().unwrap().0.as_deref(),
            Some("vertex 1")
        );
        let mut b = binary(false);
        b.truncate(b.len() - 3);
        assert_eq!(read(&b).err().unwrap().0.as_deref(), Some("face 0"));
    }
}
