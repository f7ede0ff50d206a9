//! Wavefront OBJ: `v`, `vn`, `vt` and `f` (any polygon size, `v`, `v/vt`, `v//vn`, `v/vt/vn`,
//! negative indices counting back from the latest element). Groups, objects and smoothing
//! groups are read past; `mtllib`/`usemtl` are ignored with a note; other statements too.

use super::{Soup, fan};
use glam::{DVec2, DVec3};
use std::collections::HashMap;

type Fail = (usize, String);

/// One face corner: indices (0-based) into positions, texture coordinates and normals.
type Corner = (u32, u32, u32);
const NONE: u32 = u32::MAX;

pub(super) fn read(bytes: &[u8]) -> Result<Soup, Fail> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        (line, "is not UTF-8 text".to_string())
    })?;
    let (mut v, mut vt, mut vn) = (Vec::new(), Vec::new(), Vec::new());
    let mut corners: HashMap<Corner, u32> = HashMap::new();
    let mut order: Vec<Corner> = Vec::new();
    let mut triangles = Vec::new();
    let mut polygon: Vec<u32> = Vec::new();
    let mut ignored: Vec<&str> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let n = n + 1;
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        let Some(word) = words.next() else { continue };
        match word {
            "v" => v.push(coords::<3>(&mut words, n, "v", 3)?.into()),
            "vn" => vn.push(coords::<3>(&mut words, n, "vn", 3)?.into()),
            "vt" => {
                let c = coords::<2>(&mut words, n, "vt", 1)?;
                vt.push(DVec2::new(c[0], c[1]));
            }
            "f" => {
                polygon.clear();
                for w in words {
                    let c = corner(w, n, v.len(), vt.len(), vn.len())?;
                    let next = order.len() as u32;
                    polygon.push(*corners.entry(c).or_insert_with(|| {
                        order.push(c);
                        next
                    }));
                }
                if polygon.len() < 3 {
                    return Err((
                        n,
                        format!("a face needs at least 3 vertices (got {})", polygon.len()),
                    ));
                }
                fan(&polygon, &mut triangles);
            }
            "g" | "o" | "s" => {}
            other => {
                if !ignored.contains(&other) {
                    ignored.push(other);
                }
            }
        }
    }
    if triangles.is_empty() {
        return Err((
            text.lines().count().max(1),
            "the file has no faces (`f`)".into(),
        ));
    }
    let mut soup = Soup {
        positions: order.iter().map(|c| v[c.0 as usize]).collect(),
        triangles,
        ..Soup::default()
    };
    if order.iter().all(|c| c.1 != NONE) {
        soup.uvs = Some(order.iter().map(|c| vt[c.1 as usize]).collect());
    }
    if order.iter().any(|c| c.2 != NONE) {
        soup.normals = Some(
            order
                .iter()
                .map(|c| vn.get(c.2 as usize).copied().unwrap_or(DVec3::ZERO))
                .collect(),
        );
        soup.has_normal = Some(order.iter().map(|c| c.2 != NONE).collect());
    }
    if !ignored.is_empty() {
        soup.notes.push(format!(
            "ignored statements: {} (materials come from the sequence file)",
            ignored.join(", ")
        ));
    }
    Ok(soup)
}

/// `N` numbers (at least `need`; missing ones are 0), finite.
fn coords<'a, const N: usize>(
    words: &mut impl Iterator<Item = &'a str>,
    line: usize,
    what: &str,
    need: usize,
) -> Result<[f64; N], Fail> {
    let mut out = [0.0; N];
    for (i, o) in out.iter_mut().enumerate() {
        match words.next() {
            Some(w) => {
                *o = w.parse::<f64>().map_err(|_| {
                    (
                        line,
                        format!("`{what}` coordinate {} is not a number (got `{w}`)", i + 1),
                    )
                })?;
            }
            None if i < need => {
                return Err((line, format!("`{what}` needs {need} coordinates (got {i})")));
            }
            None => break,
        }
    }
    Ok(out)
}

/// `v`, `v/vt`, `v//vn` or `v/vt/vn`, each 1-based or negative (relative to the end).
fn corner(w: &str, line: usize, nv: usize, nvt: usize, nvn: usize) -> Result<Corner, Fail> {
    let mut parts = w.split('/');
    let index = |part: Option<&str>, count: usize, what: &str| -> Result<u32, Fail> {
        let Some(p) = part.filter(|p| !p.is_empty()) else {
            return Ok(NONE);
        };
        let i: i64 = p
            .parse()
            .map_err(|_| (line, format!("face corner `{w}`: `{p}` is not an index")))?;
        let at = if i > 0 { i - 1 } else { count as i64 + i };
        if i == 0 || at < 0 || at >= count as i64 {
            return Err((
                line,
                format!(
                    "face corner `{w}`: {what} index {i} is out of range ({count} defined so far)"
                ),
            ));
        }
        Ok(at as u32)
    };
    let v = index(parts.next(), nv, "vertex")?;
    if v == NONE {
        return Err((line, format!("face corner `{w}` has no vertex index")));
    }
    let t = index(parts.next(), nvt, "texture")?;
    let n = index(parts.next(), nvn, "normal")?;
    if parts.next().is_some() {
        return Err((line, format!("face corner `{w}` has more than 3 parts")));
    }
    Ok((v, t, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_quads_negative_indices_and_attributes() {
        let text = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\ng side\nusemtl red\nf -4/1/1 -3/2/1 -2/3/1 -1/4/1\n";
        let s = read(text.as_bytes()).unwrap();
        assert_eq!(s.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(s.positions.len(), 4);
        assert_eq!(s.uvs.as_ref().unwrap()[2], DVec2::new(1.0, 1.0));
        assert_eq!(s.normals.as_ref().unwrap()[0], DVec3::Z);
        assert!(s.notes[0].contains("usemtl"));
    }

    #[test]
    fn errors_name_the_line() {
        let e = |t: &str| read(t.as_bytes()).err().unwrap();
        assert_eq!(e("v 0 0 0\nv 1 0 0\nf 1 2 3\n").0, 3);
        assert!(e("v 0 0 0\nv 1 0 0\nf 1 2 3\n").1.contains("out of range"));
        assert_eq!(e("v 0 0\n").0, 1);
        assert_eq!(e("v 0 0 0\nv 1 0 0\nf 1 2\n").0, 3);
        assert!(e("v 0 0 x\n").1.contains("not a number"));
        assert!(e("v 0 0 0\n").1.contains("no faces"));
    }
}
