//! PLY (ASCII, binary little- and big-endian): the `vertex` element's x y z, optional nx ny nz
//! and u v (or s t, texture_u texture_v), and the `face` element's `vertex_indices` (or
//! `vertex_index`) list of any length, whichever element comes first. Other elements and
//! properties are read past.
//!
//! The header is read by its grammar, one line at a time: a line is a keyword and its words,
//! and only the line `end_header` (spaces around it allowed) ends it, however long the header
//! and whatever its comments or property names contain. A line that starts with no PLY keyword
//! (old Blender exporters wrote one without `comment`) is read as a comment, with a note. An
//! ASCII body has one element per line, so a row with too many or too few values is named
//! itself. What a header declares is checked against what the file can hold before anything is
//! allocated for it.

use super::input::Input;
use super::{Fail, Soup, fan};
use crate::budget;
use glam::{DVec2, DVec3};
use std::io::BufRead;

#[derive(Clone, Copy, PartialEq, Debug)]
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

    fn size(self) -> u64 {
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
    /// The header line that declares it.
    line: usize,
}

impl Element {
    /// The fewest bytes a row can take: binary, every scalar and every list's count; ASCII,
    /// one character and one separator (or the line's end) a value.
    fn min_row_bytes(&self, format: Format) -> u64 {
        self.props
            .iter()
            .map(|p| match format {
                Format::Ascii => 2,
                _ => p.list.unwrap_or(p.ty).size(),
            })
            .sum()
    }
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    notes: Vec<String>,
}

pub(super) fn read<R: BufRead>(input: &mut Input<R>) -> Result<Soup, Fail> {
    let header = header(input)?;
    let mut body = Body {
        input,
        format: header.format,
        values: Vec::new(),
        next: 0,
    };
    let mut soup = Soup {
        notes: header.notes,
        ..Soup::default()
    };
    let mut faces = Faces::default();
    for e in &header.elements {
        fits(e, header.format, body.input.left())?;
        match e.name.as_str() {
            "vertex" => vertices(e, &mut body, &mut soup)?,
            "face" => faces.read(e, &mut body, &mut soup)?,
            _ => skip(e, &mut body)?,
        }
    }
    faces.finish(&header.elements, &mut soup)?;
    Ok(soup)
}

/// A binary element's rows take at least `min_row_bytes` each: a header that declares more than
/// the file holds is refused before anything is read or allocated for it, naming the first row
/// that cannot be there (exact when the rows have no lists). ASCII rows are lines, read until
/// the file ends, and their arrays are sized by what the file can hold (`capacity`).
fn fits(e: &Element, format: Format, left: u64) -> Result<(), Fail> {
    let row = e.min_row_bytes(format);
    if format == Format::Ascii || row.saturating_mul(e.count) <= left {
        return Ok(());
    }
    let exact = e.props.iter().all(|p| p.list.is_none());
    let where_ = match exact {
        true => format!("{} {}", e.name, left / row),
        false => format!("header line {}", e.line),
    };
    Err(Fail::at(
        where_,
        format!(
            "the file ends early: the header declares {} `{}` rows of at least {row} bytes, and {left} bytes are left",
            e.count, e.name
        ),
    ))
}

/// How many rows of `e` an array may be sized for up front: what the header declares, at most
/// what the bytes left can hold.
fn capacity(e: &Element, format: Format, left: u64) -> usize {
    let most = left / e.min_row_bytes(format).max(1) + 1;
    usize::try_from(e.count.min(most)).unwrap_or(usize::MAX)
}

/// A header line's refusal.
fn at_line(line: usize, message: impl Into<String>) -> Fail {
    Fail::at(format!("header line {line}"), message)
}

fn header<R: BufRead>(input: &mut Input<R>) -> Result<Header, Fail> {
    let start = input.peek(4)?;
    let magic =
        start.get(..3) == Some(b"ply") && start.get(3).is_none_or(|b| b.is_ascii_whitespace());
    if !magic {
        return Err(Fail::at("header", "the file does not start with `ply`"));
    }
    input.line()?;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut notes = Vec::new();
    loop {
        let n = input.line_number + 1;
        let Some(bytes) = input.line()? else {
            return Err(Fail::at(
                "header",
                "no `end_header` line: not a PLY file, or a truncated one",
            ));
        };
        let first = bytes
            .split(|b| b.is_ascii_whitespace())
            .find(|w| !w.is_empty());
        match first {
            None | Some(b"comment") | Some(b"obj_info") => continue,
            Some(b"end_header") | Some(b"format") | Some(b"element") | Some(b"property") => {}
            Some(_) => {
                if notes.is_empty() {
                    notes.push(format!(
                        "header line {n} starts with no PLY keyword and was read as a comment: `{}`",
                        String::from_utf8_lossy(bytes).trim()
                    ));
                }
                continue;
            }
        }
        let Ok(text) = std::str::from_utf8(bytes) else {
            return Err(at_line(n, "is not text"));
        };
        let w: Vec<&str> = text.split_ascii_whitespace().collect();
        match w.as_slice() {
            ["end_header"] => break,
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(at_line(n, format!("unknown format `{f}`"))),
                })
            }
            ["element", name, count] => {
                let Ok(count) = count.parse() else {
                    return Err(at_line(
                        n,
                        format!("element `{name}` has no count (got `{count}`)"),
                    ));
                };
                let twice = elements.iter().find(|e| e.name == *name);
                if let (Some(e), "vertex" | "face") = (twice, *name) {
                    return Err(at_line(
                        n,
                        format!(
                            "a second `{name}` element (the first is on header line {}); a PLY file has one",
                            e.line
                        ),
                    ));
                }
                budget::grow(&mut elements, 1, || "the PLY header".into())?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                    line: n,
                });
            }
            ["property", rest @ ..] => property(rest, n, elements.last_mut())?,
            _ => return Err(at_line(n, format!("cannot read `{}`", text.trim()))),
        }
    }
    let Some(format) = format else {
        return Err(Fail::at("header", "no `format` line"));
    };
    Ok(Header {
        format,
        elements,
        notes,
    })
}

/// `TYPE NAME` or `list COUNT_TYPE TYPE NAME`, added to the element declared last.
fn property(words: &[&str], n: usize, element: Option<&mut Element>) -> Result<(), Fail> {
    let (list, ty, name) = match words {
        ["list", c, t, name] => {
            let (Some(c), Some(t)) = (Scalar::parse(c), Scalar::parse(t)) else {
                return Err(at_line(n, format!("property `{name}` has an unknown type")));
            };
            (Some(c), t, name)
        }
        [t, name] => {
            let Some(t) = Scalar::parse(t) else {
                return Err(at_line(
                    n,
                    format!("property `{name}` has unknown type `{t}`"),
                ));
            };
            (None, t, name)
        }
        _ => {
            return Err(at_line(
                n,
                "a property is `TYPE NAME` or `list COUNT_TYPE TYPE NAME`",
            ));
        }
    };
    let Some(e) = element else {
        return Err(at_line(n, "a property before any element"));
    };
    budget::grow(&mut e.props, 1, || "the PLY header".into())?;
    e.props.push(Property {
        name: name.to_string(),
        list,
        ty,
    });
    Ok(())
}

/// Reads values one at a time from the body, in the file's format; an ASCII row is a line.
struct Body<'a, R> {
    input: &'a mut Input<R>,
    format: Format,
    /// The ASCII row being read, and the next of its values.
    values: Vec<f64>,
    next: usize,
}

impl<R: BufRead> Body<'_, R> {
    /// Starts row `i` of element `what` (ASCII: reads its line).
    fn row(&mut self, what: &str, i: u64) -> Result<(), Fail> {
        if self.format != Format::Ascii {
            return Ok(());
        }
        self.values.clear();
        self.next = 0;
        loop {
            let Some(line) = self.input.line()? else {
                return Err(early(what, i));
            };
            let Ok(text) = std::str::from_utf8(line) else {
                return Err(Fail::at(format!("{what} {i}"), "the row is not text"));
            };
            let mut words = text.split_ascii_whitespace().peekable();
            if words.peek().is_none() {
                continue;
            }
            for w in words {
                let v = w.parse::<f64>().map_err(|_| {
                    Fail::at(format!("{what} {i}"), format!("`{w}` is not a number"))
                })?;
                budget::grow(&mut self.values, 1, || format!("{what} {i}"))?;
                self.values.push(v);
            }
            return Ok(());
        }
    }

    /// Ends row `i`: an ASCII row must hold exactly the values its properties declare.
    fn end_row(&self, what: &str, i: u64) -> Result<(), Fail> {
        match self.values.len() - self.next {
            0 => Ok(()),
            extra => Err(Fail::at(
                format!("{what} {i}"),
                format!(
                    "the row has {} values, {extra} more than the header's properties take",
                    self.values.len()
                ),
            )),
        }
    }

    fn value(&mut self, ty: Scalar, what: &str, i: u64) -> Result<f64, Fail> {
        let value = match self.format {
            Format::Ascii => {
                let v = self.values.get(self.next).copied();
                self.next += 1;
                v
            }
            _ => self.binary(ty)?,
        };
        value.ok_or_else(|| early(what, i))
    }

    /// A list's length: a whole number, at least 0.
    fn count(&mut self, ty: Scalar, what: &str, i: u64) -> Result<u64, Fail> {
        let v = self.value(ty, what, i)?;
        if !(v >= 0.0 && v.fract() == 0.0 && v < 1e18) {
            return Err(Fail::at(
                format!("{what} {i}"),
                format!("a list's length must be a whole number, 0 or more (got {v})"),
            ));
        }
        Ok(v as u64)
    }

    fn binary(&mut self, ty: Scalar) -> Result<Option<f64>, Fail> {
        let big = self.format == Format::Big;
        macro_rules! take {
            ($t:ty, $n:literal) => {
                match self.input.bytes::<$n>()? {
                    None => None,
                    Some(b) => Some(f64::from(match big {
                        true => <$t>::from_be_bytes(b),
                        false => <$t>::from_le_bytes(b),
                    })),
                }
            };
        }
        Ok(match ty {
            Scalar::I8 => take!(i8, 1),
            Scalar::U8 => take!(u8, 1),
            Scalar::I16 => take!(i16, 2),
            Scalar::U16 => take!(u16, 2),
            Scalar::I32 => take!(i32, 4),
            Scalar::U32 => take!(u32, 4),
            Scalar::F32 => take!(f32, 4),
            Scalar::F64 => take!(f64, 8),
        })
    }
}

fn early(what: &str, i: u64) -> Fail {
    Fail::at(
        format!("{what} {i}"),
        "the file ends early (or the row has fewer values than the header's properties take)",
    )
}

fn vertices<R: BufRead>(e: &Element, body: &mut Body<R>, soup: &mut Soup) -> Result<(), Fail> {
    let at = |names: &[&str]| {
        e.props
            .iter()
            .position(|p| p.list.is_none() && names.contains(&p.name.as_str()))
    };
    let (Some(x), Some(y), Some(z)) = (at(&["x"]), at(&["y"]), at(&["z"])) else {
        return Err(at_line(e.line, "`vertex` needs x, y and z"));
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
    let n = capacity(e, body.format, body.input.left());
    let what = || "the file's vertices".to_string();
    budget::grow(&mut soup.positions, n, what)?;
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    if normal.is_some() {
        budget::grow(&mut normals, n, what)?;
    }
    if uv.is_some() {
        budget::grow(&mut uvs, n, what)?;
    }
    let mut values = vec![0.0; e.props.len()];
    for i in 0..e.count {
        body.row("vertex", i)?;
        for (k, p) in e.props.iter().enumerate() {
            values[k] = match p.list {
                None => body.value(p.ty, "vertex", i)?,
                Some(c) => {
                    for _ in 0..body.count(c, "vertex", i)? {
                        body.value(p.ty, "vertex", i)?;
                    }
                    0.0
                }
            };
        }
        body.end_row("vertex", i)?;
        soup.positions
            .push(DVec3::new(values[x], values[y], values[z]));
        if let Some([a, b, c]) = normal {
            normals.push(DVec3::new(values[a], values[b], values[c]));
        }
        if let Some([a, b]) = uv {
            uvs.push(DVec2::new(values[a], values[b]));
        }
    }
    soup.normals = normal.map(|_| normals);
    soup.uvs = uv.map(|_| uvs);
    Ok(())
}

/// The `face` element, which may come before or after `vertex`: indices are checked at once
/// when the vertices are known, else the largest is kept and checked at the end.
#[derive(Default)]
struct Faces {
    seen: bool,
    /// The largest index of faces read before the vertices, and its face.
    largest: Option<(f64, u64)>,
    /// Faces skipped for having fewer than 3 corners, and the first.
    short: (u64, u64),
}

impl Faces {
    fn read<R: BufRead>(
        &mut self,
        e: &Element,
        body: &mut Body<R>,
        soup: &mut Soup,
    ) -> Result<(), Fail> {
        let Some(list) = e.props.iter().position(|p| {
            p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
        }) else {
            return Err(at_line(e.line, "`face` needs a `vertex_indices` list"));
        };
        self.seen = true;
        // Vertices read already (an element before this one), or none yet.
        let known = (soup.positions.len() as f64, !soup.positions.is_empty());
        let mut polygon = Vec::new();
        for i in 0..e.count {
            body.row("face", i)?;
            for (k, p) in e.props.iter().enumerate() {
                let Some(c) = p.list else {
                    body.value(p.ty, "face", i)?;
                    continue;
                };
                let len = body.count(c, "face", i)?;
                polygon.clear();
                for _ in 0..len {
                    let v = body.value(p.ty, "face", i)?;
                    if k != list {
                        continue;
                    }
                    self.index(v, i, known)?;
                    budget::grow(&mut polygon, 1, || format!("face {i}"))?;
                    polygon.push(v as u32);
                }
                if k != list {
                    continue;
                }
                if polygon.len() < 3 {
                    if self.short.0 == 0 {
                        self.short.1 = i;
                    }
                    self.short.0 += 1;
                    continue;
                }
                budget::grow(&mut soup.triangles, polygon.len() - 2, || {
                    "the mesh's triangles".into()
                })?;
                fan(&polygon, &mut soup.triangles);
            }
            body.end_row("face", i)?;
        }
        Ok(())
    }

    /// A vertex index of face `i`: a whole number ≥ 0, below the vertex count when known.
    fn index(&mut self, v: f64, i: u64, (count, known): (f64, bool)) -> Result<(), Fail> {
        let whole = v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX);
        if !whole || (known && v >= count) {
            let range = match known {
                true => format!("{count} vertices"),
                false => "a vertex index is a whole number, 0 or more".into(),
            };
            return Err(Fail::at(
                format!("face {i}"),
                format!("vertex index {v} is out of range ({range})"),
            ));
        }
        if !known && self.largest.is_none_or(|(l, _)| v > l) {
            self.largest = Some((v, i));
        }
        Ok(())
    }

    /// After every element: a face element was there, and the indices read before the
    /// vertices fit them.
    fn finish(&self, elements: &[Element], soup: &mut Soup) -> Result<(), Fail> {
        if !self.seen {
            return Err(Fail::whole("the file has no `face` element"));
        }
        if !elements.iter().any(|e| e.name == "vertex") {
            return Err(Fail::whole("the file has no `vertex` element"));
        }
        let count = soup.positions.len();
        if let Some((v, i)) = self.largest.filter(|(v, _)| *v >= count as f64) {
            return Err(Fail::at(
                format!("face {i}"),
                format!("vertex index {v} is out of range ({count} vertices)"),
            ));
        }
        if self.short.0 > 0 {
            soup.notes.push(format!(
                "{} face{} with fewer than 3 corners skipped (the first is face {})",
                self.short.0,
                if self.short.0 == 1 { "" } else { "s" },
                self.short.1
            ));
        }
        Ok(())
    }
}

fn skip<R: BufRead>(e: &Element, body: &mut Body<R>) -> Result<(), Fail> {
    for i in 0..e.count {
        body.row(&e.name, i)?;
        for p in &e.props {
            let len = match p.list {
                Some(c) => body.count(c, &e.name, i)?,
                None => 1,
            };
            for _ in 0..len {
                body.value(p.ty, &e.name, i)?;
            }
        }
        body.end_row(&e.name, i)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_bytes(b: &[u8]) -> Result<Soup, Fail> {
        read(&mut Input::new(b, b.len() as u64))
    }

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
            let s = read_bytes(&binary(big)).unwrap();
            assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);
            assert_eq!(s.positions[2], DVec3::new(1.0, 1.0, 0.0));
            assert_eq!(s.uvs.as_ref().unwrap()[3], DVec2::new(0.0, 1.0));
        }
    }

    const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty double nx\nproperty double ny\nproperty double nz\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";

    #[test]
    fn reads_ascii_and_names_bad_rows() {
        let ok = format!("{HEAD}0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
        let s = read_bytes(ok.as_bytes()).unwrap();
        assert_eq!(s.normals.unwrap()[1], DVec3::Z);
        let place = |text: String| read_bytes(text.as_bytes()).err().unwrap().where_.unwrap();
        assert_eq!(
            place(format!(
                "{HEAD}0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 7\n"
            )),
            "face 0"
        );
        assert_eq!(place(format!("{HEAD}0 0 0 0 0 1\n1 0 0\n")), "vertex 1");
        // A row with a value too many is that row's fault, not the next one's.
        assert_eq!(
            place(format!(
                "{HEAD}0 0 0 0 0 1 9\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n"
            )),
            "vertex 0"
        );
        // A list length of 3.5 is not read as 3.
        let e = read_bytes(
            format!("{HEAD}0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3.5 0 1 2\n").as_bytes(),
        )
        .err()
        .unwrap();
        assert!(e.message.contains("whole number"), "{}", e.message);
        let mut b = binary(false);
        b.truncate(b.len() - 3);
        assert_eq!(
            read_bytes(&b).err().unwrap().where_.as_deref(),
            Some("face 0")
        );
    }

    #[test]
    fn the_header_is_read_by_its_grammar() {
        let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let head = |extra: &str, end: &str| {
            format!(
                "ply\nformat ascii 1.0\n{extra}element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n{end}\n{body}"
            )
        };
        for text in [
            head("comment see end_header below\n", "end_header"),
            head("", "end_header   "),
            head("Created by Blender3D 247 - www.blender.org\n", "end_header"),
            head(&"comment a long header\n".repeat(5000), "end_header"),
        ] {
            let s = read_bytes(text.as_bytes()).unwrap_or_else(|e| panic!("{}", e.message));
            assert_eq!(s.triangles, vec![[0, 1, 2]]);
        }
        let text = head("element edge 0\nproperty int end_header\n", "end_header");
        assert_eq!(
            read_bytes(text.as_bytes()).unwrap().triangles,
            vec![[0, 1, 2]]
        );
        // Faces before vertices, as the format allows.
        let text = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n";
        assert_eq!(
            read_bytes(text.as_bytes()).unwrap().triangles,
            vec![[0, 1, 2]]
        );
        let text = text.replace("3 0 1 2", "3 0 1 3");
        assert_eq!(
            read_bytes(text.as_bytes()).err().unwrap().where_.as_deref(),
            Some("face 0")
        );
    }

    #[test]
    fn two_vertex_elements_are_refused() {
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 0 0 0 0 1\n";
        let e = read_bytes(text.as_bytes()).err().unwrap();
        assert_eq!(e.where_.as_deref(), Some("header line 7"), "{}", e.message);
    }

    #[test]
    fn a_header_that_declares_more_than_the_file_holds_is_refused_before_reading() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        let e = read_bytes(text.as_bytes()).err().unwrap();
        assert_eq!(e.where_.as_deref(), Some("vertex 0"), "{}", e.message);
        assert!(
            e.message.starts_with("the file ends early"),
            "{}",
            e.message
        );
    }
}
