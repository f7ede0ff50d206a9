//! The rows of a PLY body: values in the file's format (an ASCII row is a line, and must hold
//! exactly the values its properties take), the `vertex` element's positions, normals and
//! texture coordinates, the `face` element's polygons (whichever element comes first), and
//! other elements read past.

use super::input::Input;
use super::ply::{Element, Format, Scalar, at_line, capacity};
use super::{Fail, Soup, fan};
use crate::budget;
use glam::{DVec2, DVec3};
use std::io::BufRead;

/// Reads values one at a time from the body, in the file's format; an ASCII row is a line.
pub(super) struct Body<'a, R> {
    pub(super) input: &'a mut Input<R>,
    pub(super) format: Format,
    /// The ASCII row being read, and the next of its values.
    pub(super) values: Vec<f64>,
    pub(super) next: usize,
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
        list_len(v, what, i)
    }

    fn binary(&mut self, ty: Scalar) -> Result<Option<f64>, Fail> {
        let big = self.format == Format::Big;
        macro_rules! take {
            ($n:literal) => {
                self.input.bytes::<$n>()?.map(|b| decode(ty, big, &b))
            };
        }
        Ok(match ty.size() {
            1 => take!(1),
            2 => take!(2),
            4 => take!(4),
            _ => take!(8),
        })
    }
}

/// The value of type `ty` at the start of `b` (which holds at least its size).
#[inline]
fn decode(ty: Scalar, big: bool, b: &[u8]) -> f64 {
    macro_rules! get {
        ($t:ty, $n:literal) => {{
            let a: [u8; $n] = b[..$n].try_into().expect("the caller holds the bytes");
            f64::from(match big {
                true => <$t>::from_be_bytes(a),
                false => <$t>::from_le_bytes(a),
            })
        }};
    }
    match ty {
        Scalar::I8 => get!(i8, 1),
        Scalar::U8 => get!(u8, 1),
        Scalar::I16 => get!(i16, 2),
        Scalar::U16 => get!(u16, 2),
        Scalar::I32 => get!(i32, 4),
        Scalar::U32 => get!(u32, 4),
        Scalar::F32 => get!(f32, 4),
        Scalar::F64 => get!(f64, 8),
    }
}

/// A list's length: a whole number, at least 0.
fn list_len(v: f64, what: &str, i: u64) -> Result<u64, Fail> {
    if !(v >= 0.0 && v.fract() == 0.0 && v < 1e18) {
        return Err(Fail::at(
            format!("{what} {i}"),
            format!("a list's length must be a whole number, 0 or more (got {v})"),
        ));
    }
    Ok(v as u64)
}

fn early(what: &str, i: u64) -> Fail {
    Fail::at(
        format!("{what} {i}"),
        "the file ends early (or the row has fewer values than the header's properties take)",
    )
}

pub(super) fn vertices<R: BufRead>(
    e: &Element,
    body: &mut Body<R>,
    soup: &mut Soup,
) -> Result<(), Fail> {
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
    let mut keep = |values: &[f64], i: u64| -> Result<(), Fail> {
        let used = normal.iter().flatten().chain(uv.iter().flatten());
        finite(e, values, used, i)?;
        soup.positions
            .push(DVec3::new(values[x], values[y], values[z]));
        if let Some([a, b, c]) = normal {
            normals.push(DVec3::new(values[a], values[b], values[c]));
        }
        if let Some([a, b]) = uv {
            uvs.push(DVec2::new(values[a], values[b]));
        }
        Ok(())
    };
    let layout = fixed_layout(e, body.format);
    let big = body.format == Format::Big;
    let mut values = vec![0.0; e.props.len()];
    let mut i = 0;
    while i < e.count {
        // Whole binary rows of one layout, decoded where they lie in the read buffer.
        if let Some((stride, fields)) = &layout {
            let buf = body.input.buffered()?;
            let whole = (buf.len() / stride).min((e.count - i).try_into().unwrap_or(usize::MAX));
            for row in buf.chunks_exact(*stride).take(whole) {
                for (v, &(at, ty)) in values.iter_mut().zip(fields) {
                    *v = decode(ty, big, &row[at..]);
                }
                keep(&values, i)?;
                i += 1;
            }
            if whole > 0 {
                body.input.consume(whole * stride)?;
                continue;
            }
        }
        // A row across the buffer's end, or any ASCII row or row with a list: value by value.
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
        keep(&values, i)?;
        i += 1;
    }
    soup.normals = normal.map(|_| normals);
    soup.uvs = uv.map(|_| uvs);
    Ok(())
}

/// A binary element's row size and each property's offset and type, when no property is a
/// list (every row then has the same layout).
fn fixed_layout(e: &Element, format: Format) -> Option<(usize, Vec<(usize, Scalar)>)> {
    if format == Format::Ascii || e.props.iter().any(|p| p.list.is_some()) {
        return None;
    }
    let mut at = 0;
    let fields = e.props.iter().map(|p| {
        let field = (at, p.ty);
        at += p.ty.size() as usize;
        field
    });
    let fields = fields.collect();
    Some((at, fields))
}

/// A vertex's normal and texture coordinates (the properties at `used`) must be finite: a NaN
/// there would reach the shading. A non-finite position only makes its triangles degenerate
/// (skipped and counted).
fn finite<'a>(
    e: &Element,
    values: &[f64],
    mut used: impl Iterator<Item = &'a usize>,
    i: u64,
) -> Result<(), Fail> {
    match used.find(|&&k| !values[k].is_finite()) {
        None => Ok(()),
        Some(&k) => Err(Fail::at(
            format!("vertex {i}"),
            format!(
                "`{}` is not a finite number (got {})",
                e.props[k].name, values[k]
            ),
        )),
    }
}

/// A face row as most binary files write it: a `uchar` count of 3, then three little-endian
/// 32-bit indices.
const TRIANGLE_ROW: usize = 13;

/// The leading rows of `rows` (whole `TRIANGLE_ROW`s) that are triangles of valid indices
/// (below `count`, and not negative for `int`), pushed as they are; how many. The first other
/// row (a longer list, or an index to refuse) stops it, and the general reader takes that row
/// on, with the same result as if it had read them all: a triangle's fan is itself.
fn triangle_rows(rows: &[u8], count: u32, ty: Scalar, out: &mut Vec<[u32; 3]>) -> usize {
    let limit = match ty {
        Scalar::I32 => count.min(1 << 31),
        _ => count,
    };
    let mut taken = 0;
    for row in rows.chunks_exact(TRIANGLE_ROW) {
        let at = |k: usize| u32::from_le_bytes(row[1 + 4 * k..5 + 4 * k].try_into().unwrap());
        let t = [at(0), at(1), at(2)];
        if row[0] != 3 || t.iter().any(|&v| v >= limit) {
            break;
        }
        out.push(t);
        taken += 1;
    }
    taken
}

/// The `face` element, which may come before or after `vertex`: indices are checked at once
/// when the vertices are known, else the largest is kept and checked at the end.
#[derive(Default)]
pub(super) struct Faces {
    seen: bool,
    /// The largest index of faces read before the vertices, and its face.
    largest: Option<(f64, u64)>,
    /// Faces skipped for having fewer than 3 corners, and the first.
    short: (u64, u64),
}

impl Faces {
    pub(super) fn read<R: BufRead>(
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
        // A binary element whose only property is the index list is decoded in place.
        let alone = body.format != Format::Ascii && e.props.len() == 1;
        let mut i = 0;
        while i < e.count {
            if alone {
                let took = self.in_place(e, body, soup, (i, known), &mut polygon)?;
                i += took;
                if took > 0 {
                    continue;
                }
            }
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
                if k == list {
                    self.keep(&polygon, i, soup)?;
                }
            }
            body.end_row("face", i)?;
            i += 1;
        }
        Ok(())
    }

    /// The faces from `first` on whose rows lie whole in the read buffer, decoded there (the
    /// element's only property is the index list); how many.
    fn in_place<R: BufRead>(
        &mut self,
        e: &Element,
        body: &mut Body<R>,
        soup: &mut Soup,
        (first, known): (u64, (f64, bool)),
        polygon: &mut Vec<u32>,
    ) -> Result<u64, Fail> {
        let (c, ty) = (e.props[0].list.expect("the index list"), e.props[0].ty);
        let (cs, ts) = (c.size() as usize, ty.size() as usize);
        let big = body.format == Format::Big;
        let buf = body.input.buffered()?;
        let (mut at, mut i) = (0, first);
        if let (Scalar::U8, Scalar::I32 | Scalar::U32, false, (count, true)) = (c, ty, big, known) {
            let rows =
                (buf.len() / TRIANGLE_ROW).min(usize::try_from(e.count - i).unwrap_or(usize::MAX));
            budget::grow(&mut soup.triangles, rows, || "the mesh's triangles".into())?;
            let taken = triangle_rows(
                &buf[..rows * TRIANGLE_ROW],
                count as u32,
                ty,
                &mut soup.triangles,
            );
            (at, i) = (taken * TRIANGLE_ROW, i + taken as u64);
        }
        while i < e.count && at + cs <= buf.len() {
            let len = list_len(decode(c, big, &buf[at..]), "face", i)?;
            let end = usize::try_from(len)
                .ok()
                .and_then(|n| n.checked_mul(ts))
                .and_then(|b| b.checked_add(at + cs))
                .filter(|&end| end <= buf.len());
            let Some(end) = end else { break };
            polygon.clear();
            for v in buf[at + cs..end].chunks_exact(ts) {
                let v = decode(ty, big, v);
                self.index(v, i, known)?;
                polygon.push(v as u32);
            }
            self.keep(polygon, i, soup)?;
            (at, i) = (end, i + 1);
        }
        body.input.consume(at)?;
        Ok(i - first)
    }

    /// Face `i`'s corners fanned into triangles, or counted as skipped under 3.
    fn keep(&mut self, polygon: &[u32], i: u64, soup: &mut Soup) -> Result<(), Fail> {
        if polygon.len() < 3 {
            if self.short.0 == 0 {
                self.short.1 = i;
            }
            self.short.0 += 1;
            return Ok(());
        }
        budget::grow(&mut soup.triangles, polygon.len() - 2, || {
            "the mesh's triangles".into()
        })?;
        fan(polygon, &mut soup.triangles);
        Ok(())
    }

    /// A vertex index of face `i`: a whole number ≥ 0, below the vertex count when known.
    fn index(&mut self, v: f64, i: u64, (count, known): (f64, bool)) -> Result<(), Fail> {
        if !(v.is_finite() && v.fract() == 0.0) {
            return Err(Fail::at(
                format!("face {i}"),
                format!("vertex index {v} is not a whole number"),
            ));
        }
        if v < 0.0 || v > f64::from(u32::MAX) || (known && v >= count) {
            let range = match known {
                true => format!("{count} vertices"),
                false => "a vertex index is 0 or more".into(),
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
    pub(super) fn finish(&self, elements: &[Element], soup: &mut Soup) -> Result<(), Fail> {
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

/// Reads past the rows of an element rayreel does not use. One without properties has no
/// values to read, however many rows it declares (a header may claim 3e18 of them).
pub(super) fn skip<R: BufRead>(e: &Element, body: &mut Body<R>) -> Result<(), Fail> {
    if e.props.is_empty() {
        return Ok(());
    }
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
