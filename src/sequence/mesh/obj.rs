//! Wavefront OBJ: `v`, `vn`, `vt` and `f` (any polygon size, `v`, `v/vt`, `v//vn`, `v/vt/vn`,
//! negative indices counting back from the latest element). Groups, objects and smoothing
//! groups are read past; `mtllib`/`usemtl` are ignored with a note; other statements too.
//!
//! Read line by line as bytes: a line ending in `\` continues on the next; only the
//! statements read (`v`, `vn`, `vt`, `f`) must be text, so a Latin-1 byte in a comment, a group
//! or a material name costs nothing. A file that starts with a UTF-16 byte-order mark is read
//! as UTF-16 (a UTF-8 one is skipped). What lenient readers drop, this one drops too, and says
//! so in a note: faces of fewer than 3 corners, and texture coordinates or normals a corner
//! refers to that the file has not defined.

use super::input::Input;
use super::{Fail, Soup, fan};
use crate::budget;
use glam::{DVec2, DVec3};
use std::collections::HashMap;
use std::io::BufRead;

/// One face corner: indices (0-based) into positions, texture coordinates and normals.
type Corner = (u32, u32, u32);
const NONE: u32 = u32::MAX;

/// What the file holds so far.
#[derive(Default)]
struct Obj {
    v: Vec<DVec3>,
    vt: Vec<DVec2>,
    vn: Vec<DVec3>,
    /// Each distinct corner once, numbered in order of first use: the mesh's vertices.
    corners: HashMap<Corner, u32>,
    order: Vec<Corner>,
    triangles: Vec<[u32; 3]>,
    polygon: Vec<u32>,
    /// Statements read past, by keyword (the first 16; `more_ignored` when there were others).
    ignored: Vec<String>,
    more_ignored: bool,
    /// Faces skipped for having fewer than 3 corners, and the first one's line.
    short_faces: (usize, usize),
    /// Corners whose `vt` or `vn` index the file had not defined (dropped), first line each.
    missing_uv: (usize, usize),
    missing_normal: (usize, usize),
}

pub(super) fn read<R: BufRead>(input: &mut Input<R>) -> Result<Soup, Fail> {
    let start = input.peek(3)?;
    let utf16 = match start.get(..2) {
        Some([0xff, 0xfe]) => Some(false),
        Some([0xfe, 0xff]) => Some(true),
        _ => None,
    };
    let Some(big_endian) = utf16 else {
        return statements(input, start.starts_with(&[0xef, 0xbb, 0xbf]));
    };
    let text = utf16_to_utf8(&input.rest()?, big_endian)?;
    let size = text.len() as u64;
    let mut soup = statements(&mut Input::new(&text[..], size), false)?;
    soup.notes.push("read as UTF-16 text".into());
    Ok(soup)
}

/// UTF-16 (after its byte-order mark) as UTF-8; a lone surrogate becomes U+FFFD, which only
/// matters if it falls in a statement that is read (and is then refused there).
fn utf16_to_utf8(bytes: &[u8], big_endian: bool) -> Result<Vec<u8>, Fail> {
    let units = bytes[2..].chunks_exact(2).map(|c| match big_endian {
        true => u16::from_be_bytes([c[0], c[1]]),
        false => u16::from_le_bytes([c[0], c[1]]),
    });
    let mut out = Vec::new();
    budget::grow(&mut out, bytes.len() * 3 / 2, || {
        "the file's text as UTF-8".into()
    })?;
    for c in char::decode_utf16(units) {
        let mut buf = [0u8; 4];
        out.extend_from_slice(c.unwrap_or('\u{fffd}').encode_utf8(&mut buf).as_bytes());
    }
    Ok(out)
}

/// Every statement of the file, in order.
fn statements<R: BufRead>(input: &mut Input<R>, bom: bool) -> Result<Soup, Fail> {
    let mut obj = Obj::default();
    let mut statement: Vec<u8> = Vec::new();
    let mut first = bom;
    loop {
        // A statement: one line, or several joined where a line without a comment ends in `\`.
        statement.clear();
        let mut at = 0;
        let mut more = true;
        while more {
            let number = input.line_number + 1;
            let Some(line) = input.line()? else { break };
            let line = match first {
                true => line.get(3..).unwrap_or(&[]),
                false => line,
            };
            first = false;
            if at == 0 {
                at = number;
            }
            // A comment ends its line: `# exported to C:\models\` does not swallow the next.
            more = line.last() == Some(&b'\\') && !line.contains(&b'#');
            let line = if more { &line[..line.len() - 1] } else { line };
            budget::grow(&mut statement, line.len() + 1, || {
                format!("line {at} of the file")
            })?;
            statement.extend_from_slice(line);
            statement.push(b' ');
        }
        if at == 0 {
            break;
        }
        obj.statement(&statement, at)?;
    }
    obj.soup(input.line_number)
}

type Refusal = Fail;

/// A refusal naming line `line`.
fn at(line: usize, message: impl Into<String>) -> Fail {
    Fail::at(format!("line {line}"), message)
}

impl Obj {
    fn statement(&mut self, bytes: &[u8], n: usize) -> Result<(), Refusal> {
        // A comment runs to the end of the line, whatever bytes it holds.
        let bytes = bytes.split(|&b| b == b'#').next().unwrap_or(&[]);
        let mut words = bytes
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        let Some(word) = words.next() else {
            return Ok(());
        };
        // Words are read one at a time: a face may have millions of corners.
        let mut words = words.map(|w| std::str::from_utf8(w).map_err(|_| not_text(n, w)));
        match word {
            b"v" => {
                let c = coords::<3>(&mut words, n, "v", 3)?;
                budget::grow(&mut self.v, 1, || "the file's `v` positions".into())?;
                self.v.push(c.into());
            }
            b"vn" => {
                let c = coords::<3>(&mut words, n, "vn", 3)?;
                budget::grow(&mut self.vn, 1, || "the file's `vn` normals".into())?;
                self.vn.push(c.into());
            }
            b"vt" => {
                let c = coords::<2>(&mut words, n, "vt", 1)?;
                budget::grow(&mut self.vt, 1, || "the file's `vt` coordinates".into())?;
                self.vt.push(DVec2::new(c[0], c[1]));
            }
            b"f" => self.face(&mut words, n)?,
            b"g" | b"o" | b"s" => {}
            other => {
                let name = super::quoted(&String::from_utf8_lossy(other));
                if !self.ignored.contains(&name) {
                    match self.ignored.len() < 16 {
                        true => self.ignored.push(name),
                        false => self.more_ignored = true,
                    }
                }
            }
        }
        Ok(())
    }

    fn face<'a>(
        &mut self,
        words: &mut impl Iterator<Item = Result<&'a str, Refusal>>,
        n: usize,
    ) -> Result<(), Refusal> {
        self.polygon.clear();
        for w in words {
            let c = self.corner(w?, n)?;
            budget::grow(&mut self.polygon, 1, || format!("the face on line {n}"))?;
            let next = self.order.len() as u32;
            if self.corners.len() == self.corners.capacity() {
                let entries = 2 * self.corners.capacity().max(16) as u64;
                // A table entry is the corner and its number, and a control byte, at 7/8 load.
                budget::admit(entries * 18 * 8 / 7, || {
                    "the file's distinct face corners".into()
                })?;
                self.corners
                    .try_reserve(self.corners.capacity().max(16))
                    .map_err(|_| at(n, "out of memory for the file's face corners"))?;
            }
            let v = *self.corners.entry(c).or_insert(next);
            if v == next {
                budget::grow(&mut self.order, 1, || "the mesh's vertices".into())?;
                self.order.push(c);
            }
            self.polygon.push(v);
        }
        if self.polygon.len() < 3 {
            if self.short_faces.0 == 0 {
                self.short_faces.1 = n;
            }
            self.short_faces.0 += 1;
            return Ok(());
        }
        budget::grow(&mut self.triangles, self.polygon.len() - 2, || {
            "the mesh's triangles".into()
        })?;
        fan(&self.polygon, &mut self.triangles);
        Ok(())
    }

    /// `v`, `v/vt`, `v//vn` or `v/vt/vn`, each 1-based or negative (relative to the end). A
    /// `vt` or `vn` the file has not defined is dropped (and counted).
    fn corner(&mut self, w: &str, line: usize) -> Result<Corner, Refusal> {
        let mut parts = w.split('/');
        let v = index(parts.next(), self.v.len(), w, line, "vertex")?;
        let Some(v) = v else {
            return Err(at(line, format!("face corner `{w}` has no vertex index")));
        };
        let t = index(parts.next(), self.vt.len(), w, line, "texture");
        let n = index(parts.next(), self.vn.len(), w, line, "normal");
        if parts.next().is_some() {
            return Err(at(line, format!("face corner `{w}` has more than 3 parts")));
        }
        let kept = |i: Result<Option<u32>, Refusal>, count: &mut (usize, usize)| match i {
            Ok(i) => i.unwrap_or(NONE),
            Err(_) => {
                if count.0 == 0 {
                    count.1 = line;
                }
                count.0 += 1;
                NONE
            }
        };
        let t = kept(t, &mut self.missing_uv);
        let n = kept(n, &mut self.missing_normal);
        Ok((v, t, n))
    }

    /// The mesh: one vertex per distinct corner, with its texture coordinates when every
    /// corner has them, and its normal where the corner has one.
    fn soup(self, lines: usize) -> Result<Soup, Fail> {
        if self.triangles.is_empty() {
            let why = match self.short_faces.0 {
                0 => "the file has no faces (`f`)".to_string(),
                n => format!("the file has no faces of 3 or more corners ({n} with fewer)"),
            };
            return Err(Fail::at(format!("line {}", lines.max(1)), why));
        }
        let order = &self.order;
        let mut soup = Soup {
            positions: order.iter().map(|c| self.v[c.0 as usize]).collect(),
            triangles: self.triangles,
            ..Soup::default()
        };
        if order.iter().all(|c| c.1 != NONE) {
            soup.uvs = Some(order.iter().map(|c| self.vt[c.1 as usize]).collect());
        }
        if order.iter().any(|c| c.2 != NONE) {
            soup.normals = Some(
                order
                    .iter()
                    .map(|c| self.vn.get(c.2 as usize).copied().unwrap_or(DVec3::ZERO))
                    .collect(),
            );
            soup.has_normal = Some(order.iter().map(|c| c.2 != NONE).collect());
        }
        let notes = &mut soup.notes;
        if self.short_faces.0 > 0 {
            notes.push(format!(
                "{} with fewer than 3 corners skipped (the first on line {})",
                plural(self.short_faces.0, "face"),
                self.short_faces.1
            ));
        }
        let missing = [
            (self.missing_uv, "texture coordinates (`vt`)"),
            (self.missing_normal, "normals (`vn`)"),
        ];
        for ((count, line), what) in missing {
            if count > 0 {
                notes.push(format!(
                    "{} refer to {what} the file has not defined (the first on line {line}); those were dropped",
                    plural(count, "face corner")
                ));
            }
        }
        if !self.ignored.is_empty() {
            notes.push(format!(
                "ignored statements: {}{} (materials come from the sequence file)",
                self.ignored.join(", "),
                if self.more_ignored { " and others" } else { "" }
            ));
        }
        Ok(soup)
    }
}

fn plural(n: usize, what: &str) -> String {
    format!("{n} {what}{}", if n == 1 { "" } else { "s" })
}

fn not_text(line: usize, word: &[u8]) -> Refusal {
    at(
        line,
        format!(
            "`{}` is not UTF-8 text",
            String::from_utf8_lossy(word).escape_debug()
        ),
    )
}

/// `N` numbers (at least `need`; missing ones are 0; more are read past).
fn coords<'a, const N: usize>(
    words: &mut impl Iterator<Item = Result<&'a str, Refusal>>,
    line: usize,
    what: &str,
    need: usize,
) -> Result<[f64; N], Refusal> {
    let mut out = [0.0; N];
    for (i, o) in out.iter_mut().enumerate() {
        let w = match words.next() {
            Some(w) => w?,
            None if i < need => {
                return Err(at(
                    line,
                    format!("`{what}` needs {need} coordinates (got {i})"),
                ));
            }
            None => break,
        };
        *o = w.parse::<f64>().map_err(|_| {
            at(
                line,
                format!("`{what}` coordinate {} is not a number (got `{w}`)", i + 1),
            )
        })?;
        // `nan`, `inf` and `1e999` parse, but a NaN normal or texture coordinate would reach
        // the shading, and a non-finite position only drop its triangles unseen.
        if !o.is_finite() {
            return Err(at(
                line,
                format!(
                    "`{what}` coordinate {} is not a finite number (got `{w}`)",
                    i + 1
                ),
            ));
        }
    }
    Ok(out)
}

/// One part of a corner: `None` when empty, else its 0-based index among `count` elements.
fn index(
    part: Option<&str>,
    count: usize,
    w: &str,
    line: usize,
    what: &str,
) -> Result<Option<u32>, Refusal> {
    let Some(p) = part.filter(|p| !p.is_empty()) else {
        return Ok(None);
    };
    let i: i64 = p
        .parse()
        .map_err(|_| at(line, format!("face corner `{w}`: `{p}` is not an index")))?;
    let k = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || k < 0 || k >= count as i64 {
        return Err(at(
            line,
            format!("face corner `{w}`: {what} index {i} is out of range ({count} defined so far)"),
        ));
    }
    Ok(Some(k as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_text(t: &[u8]) -> Result<Soup, Fail> {
        read(&mut Input::new(t, t.len() as u64))
    }

    #[test]
    fn reads_quads_negative_indices_and_attributes() {
        let text = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\ng side\nusemtl red\nf -4/1/1 -3/2/1 -2/3/1 -1/4/1\n";
        let s = read_text(text.as_bytes()).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(s.positions.len(), 4);
        assert_eq!(s.uvs.as_ref().unwrap()[2], DVec2::new(1.0, 1.0));
        assert_eq!(s.normals.as_ref().unwrap()[0], DVec3::Z);
        assert!(s.notes[0].contains("usemtl"));
    }

    #[test]
    fn errors_name_the_line() {
        let e = |t: &str| read_text(t.as_bytes()).err().unwrap();
        let line = |t: &str| e(t).where_.unwrap();
        assert_eq!(line("v 0 0 0\nv 1 0 0\nf 1 2 3\n"), "line 3");
        assert!(
            e("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
                .message
                .contains("out of range")
        );
        assert_eq!(line("v 0 0\n"), "line 1");
        assert!(e("v 0 0 x\n").message.contains("not a number"));
        assert!(e("v 0 0 0\n").message.contains("no faces"));
        assert_eq!(line("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 9\n"), "line 4");
    }

    #[test]
    fn lenient_where_lenient_readers_are() {
        // Latin-1 in a comment, a group and a material name; a face continued with `\`; a
        // two-corner face; corners naming `vt` and `vn` the file never defines.
        let text = b"# caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng gr\xfcn\nusemtl r\xf6d\nf 1/1/1 2/2/2 \\\n 3/3/3\nf 1 2\n";
        let s = read_text(text).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2]]);
        assert!(s.uvs.is_none() && s.normals.is_none());
        let notes = s.notes.join("\n");
        assert!(
            notes.contains("1 face with fewer than 3 corners skipped (the first on line 9)"),
            "{notes}"
        );
        assert!(
            notes.contains("3 face corners refer to texture coordinates"),
            "{notes}"
        );
        assert!(notes.contains("3 face corners refer to normals"), "{notes}");
        // Non-text bytes in a statement that is read are refused, naming the line.
        let e = read_text(b"v 0 0 0\nv 1 \xe9 0\n").err().unwrap();
        assert_eq!(e.where_.as_deref(), Some("line 2"));
    }

    #[test]
    fn utf16_and_byte_order_marks() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        for big in [false, true] {
            let mut b = if big {
                vec![0xfe, 0xff]
            } else {
                vec![0xff, 0xfe]
            };
            for u in text.encode_utf16() {
                b.extend(if big {
                    u.to_be_bytes()
                } else {
                    u.to_le_bytes()
                });
            }
            let s = read_text(&b).unwrap();
            assert_eq!(s.triangles, vec![[0, 1, 2]]);
        }
        let mut b = vec![0xef, 0xbb, 0xbf];
        b.extend(text.as_bytes());
        assert_eq!(read_text(&b).unwrap().triangles, vec![[0, 1, 2]]);
    }
}
