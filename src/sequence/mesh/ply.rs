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
use super::ply_rows::{Body, Faces, skip, vertices};
use super::{Fail, Soup};
use crate::budget;
use std::io::BufRead;

#[derive(Clone, Copy, PartialEq, Debug)]
pub(super) enum Format {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Copy, PartialEq, Debug)]
pub(super) enum Scalar {
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

    pub(super) fn size(self) -> u64 {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

pub(super) struct Property {
    pub(super) name: String,
    /// `Some(count type)` for a list.
    pub(super) list: Option<Scalar>,
    pub(super) ty: Scalar,
}

pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) props: Vec<Property>,
    /// The header line that declares it.
    pub(super) line: usize,
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
pub(super) fn capacity(e: &Element, format: Format, left: u64) -> usize {
    let most = left / e.min_row_bytes(format).max(1) + 1;
    usize::try_from(e.count.min(most)).unwrap_or(usize::MAX)
}

/// A header line's refusal.
pub(super) fn at_line(line: usize, message: impl Into<String>) -> Fail {
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
                        super::quoted(String::from_utf8_lossy(bytes).trim())
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
            ["format", f, _] => match format {
                None => format = Some((format_of(f, n)?, n)),
                Some((_, first)) => {
                    return Err(at_line(
                        n,
                        format!("a second `format` line (the first is header line {first})"),
                    ));
                }
            },
            ["element", name, count] => element(name, count, n, &mut elements)?,
            ["property", rest @ ..] => property(rest, n, elements.last_mut())?,
            _ => return Err(at_line(n, format!("cannot read `{}`", text.trim()))),
        }
    }
    let Some((format, _)) = format else {
        return Err(Fail::at("header", "no `format` line"));
    };
    Ok(Header {
        format,
        elements,
        notes,
    })
}

fn format_of(f: &str, n: usize) -> Result<Format, Fail> {
    Ok(match f {
        "ascii" => Format::Ascii,
        "binary_little_endian" => Format::Little,
        "binary_big_endian" => Format::Big,
        _ => return Err(at_line(n, format!("unknown format `{f}`"))),
    })
}

/// `element NAME COUNT`: a new element; a second `vertex` or `face` is refused.
fn element(name: &str, count: &str, n: usize, elements: &mut Vec<Element>) -> Result<(), Fail> {
    let Ok(count) = count.parse() else {
        return Err(at_line(
            n,
            format!("element `{name}` has no count (got `{count}`)"),
        ));
    };
    let twice = elements.iter().find(|e| e.name == name);
    if let (Some(e), "vertex" | "face") = (twice, name) {
        return Err(at_line(
            n,
            format!(
                "a second `{name}` element (the first is on header line {}); a PLY file has one",
                e.line
            ),
        ));
    }
    budget::grow(elements, 1, || "the PLY header".into())?;
    elements.push(Element {
        name: name.to_string(),
        count,
        props: Vec::new(),
        line: n,
    });
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec2, DVec3};

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

    /// Triangle rows taken straight (`ply_rows::triangle_rows`) give what the general reader
    /// gives, around a quad, a 2-corner face and either index type; an index to refuse is
    /// refused with the same face named.
    #[test]
    fn triangle_rows_read_as_the_general_reader_does() {
        let faces: Vec<Vec<i64>> = vec![
            vec![0, 1, 2],
            vec![2, 1, 0],
            vec![0, 1, 2, 3],
            vec![1, 2],
            vec![3, 2, 1],
            vec![1, 3, 2],
        ];
        let file = |format: &str, ty: &str, faces: &[Vec<i64>]| {
            let mut b = format!(
                "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar {ty} vertex_indices\nend_header\n",
                faces.len()
            )
            .into_bytes();
            for (x, y) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                for v in [x, y, 0.0] {
                    match format {
                        "ascii" => b.extend(format!("{v} ").as_bytes()),
                        _ => b.extend(v.to_le_bytes()),
                    }
                }
                if format == "ascii" {
                    b.push(b'\n');
                }
            }
            for f in faces {
                match format {
                    "ascii" => {
                        let words: Vec<String> = f.iter().map(|v| v.to_string()).collect();
                        b.extend(format!("{} {}\n", f.len(), words.join(" ")).as_bytes());
                    }
                    _ => {
                        b.push(f.len() as u8);
                        for &v in f {
                            b.extend((v as u32).to_le_bytes());
                        }
                    }
                }
            }
            b
        };
        let expected = read_bytes(&file("ascii", "int", &faces)).unwrap().triangles;
        assert_eq!(expected.len(), 6);
        for ty in ["int", "uint"] {
            let got = read_bytes(&file("binary_little_endian", ty, &faces)).unwrap();
            assert_eq!(got.triangles, expected, "{ty}");
        }
        for (bad, ty) in [(4, "uint"), (4, "int"), (-1, "int")] {
            let mut refused = faces.clone();
            refused[4][1] = bad;
            let e = read_bytes(&file("binary_little_endian", ty, &refused))
                .err()
                .unwrap();
            assert_eq!(e.where_.as_deref(), Some("face 4"), "{bad} {ty}");
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

    /// One mesh in PLY of every body format: vertices `double x, float y, short z, float nx
    /// ny nz, uchar u, float v`; faces of 2 to 5 corners, with a flag before the list or not.
    fn every_format(flagged: bool) -> [Vec<u8>; 3] {
        let n = 97u32;
        let vertex = |i: u32| {
            let f = f64::from(i);
            [
                f * 0.125 - 3.0,
                f * 0.5,
                f - 40.0,
                0.0,
                0.75,
                -0.5,
                f64::from(i % 7),
                0.25,
            ]
        };
        let corners =
            |k: u32| -> Vec<u32> { (0..2 + k % 4).map(|j| (k * 31 + j * 17) % n).collect() };
        let faces = 211u32;
        let mut out = Vec::new();
        for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
            let flag = if flagged { "property uchar flag\n" } else { "" };
            let mut b = format!(
                "ply\nformat {format} 1.0\nelement vertex {n}\nproperty double x\nproperty float y\nproperty short z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar u\nproperty float v\nelement face {faces}\n{flag}property list uchar uint vertex_indices\nend_header\n"
            )
            .into_bytes();
            let big = format == "binary_big_endian";
            let put = |b: &mut Vec<u8>, le: &[u8], be: &[u8]| b.extend(if big { be } else { le });
            for i in 0..n {
                let v = vertex(i);
                if format == "ascii" {
                    let words: Vec<String> = v.iter().map(|x| x.to_string()).collect();
                    b.extend(format!("{}\n", words.join(" ")).bytes());
                    continue;
                }
                put(&mut b, &v[0].to_le_bytes(), &v[0].to_be_bytes());
                put(
                    &mut b,
                    &(v[1] as f32).to_le_bytes(),
                    &(v[1] as f32).to_be_bytes(),
                );
                put(
                    &mut b,
                    &(v[2] as i16).to_le_bytes(),
                    &(v[2] as i16).to_be_bytes(),
                );
                for x in &v[3..6] {
                    put(
                        &mut b,
                        &(*x as f32).to_le_bytes(),
                        &(*x as f32).to_be_bytes(),
                    );
                }
                b.push(v[6] as u8);
                put(
                    &mut b,
                    &(v[7] as f32).to_le_bytes(),
                    &(v[7] as f32).to_be_bytes(),
                );
            }
            for k in 0..faces {
                let c = corners(k);
                if format == "ascii" {
                    let words: Vec<String> = c.iter().map(|x| x.to_string()).collect();
                    let flag = if flagged { "1 " } else { "" };
                    b.extend(format!("{flag}{} {}\n", c.len(), words.join(" ")).bytes());
                    continue;
                }
                if flagged {
                    b.push(1);
                }
                b.push(c.len() as u8);
                for i in c {
                    put(&mut b, &i.to_le_bytes(), &i.to_be_bytes());
                }
            }
            out.push(b);
        }
        out.try_into().unwrap()
    }

    /// Binary rows decoded where they lie in the read buffer, and rows across its end read
    /// value by value, give what the ASCII body gives; the digest covers every byte once.
    #[test]
    fn binary_rows_read_alike_wherever_the_buffer_ends() {
        for flagged in [false, true] {
            let [ascii, little, big] = every_format(flagged);
            let want = read_bytes(&ascii).unwrap();
            assert_eq!(want.triangles.len(), 52 * 6 + 3, "2 to 5 corners fanned");
            for bytes in [little, big] {
                for cap in [3, 7, 13, 64, 1000, 1 << 16] {
                    let stream = std::io::BufReader::with_capacity(cap, &bytes[..]);
                    let mut input = Input::new(stream, bytes.len() as u64);
                    let got = read(&mut input).unwrap_or_else(|e| panic!("{}", e.message));
                    assert_eq!(got.positions, want.positions, "buffer of {cap}");
                    assert_eq!(got.normals, want.normals);
                    assert_eq!(got.uvs, want.uvs);
                    assert_eq!(got.triangles, want.triangles, "buffer of {cap}");
                    assert_eq!(got.notes, want.notes);
                    let digest = super::super::fnv1a(&bytes);
                    assert_eq!(input.finish().unwrap(), (digest, bytes.len() as u64));
                }
            }
        }
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
