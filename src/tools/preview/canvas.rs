//! Pixel drawing clipped to a rectangle: lines, discs, masks and text on an `RgbImage`.

use super::*;

/// Half-open pixel rectangle [x0, x1) × [y0, y1).
#[derive(Debug, Clone, Copy)]
pub(super) struct Rect {
    pub(super) x0: i64,
    pub(super) y0: i64,
    pub(super) x1: i64,
    pub(super) y1: i64,
}

impl Rect {
    pub(super) fn new(x0: i64, y0: i64, x1: i64, y1: i64) -> Rect {
        Rect { x0, y0, x1, y1 }
    }

    /// The square of half-size `r` around a continuous point, clamped far out so huge
    /// discs cost no more than the picture.
    pub(super) fn around((x, y): (f64, f64), r: f64) -> Rect {
        let c = |v: f64| v.clamp(-1e6, 1e6) as i64;
        Rect::new(c(x - r), c(y - r), c(x + r) + 1, c(y + r) + 1)
    }

    pub(super) fn intersect(&self, o: &Rect) -> Rect {
        Rect::new(
            self.x0.max(o.x0),
            self.y0.max(o.y0),
            self.x1.min(o.x1),
            self.y1.min(o.y1),
        )
    }

    pub(super) fn contains(&self, x: i64, y: i64) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }
}

pub(super) struct Canvas<'a> {
    pub(super) img: &'a mut RgbImage,
    pub(super) clip: Rect,
}

impl<'a> Canvas<'a> {
    pub(super) fn new(img: &'a mut RgbImage, clip: Rect) -> Canvas<'a> {
        let all = Rect::new(0, 0, i64::from(img.width()), i64::from(img.height()));
        Canvas {
            clip: clip.intersect(&all),
            img,
        }
    }

    pub(super) fn whole(img: &'a mut RgbImage) -> Canvas<'a> {
        Canvas::new(img, Rect::new(0, 0, i64::MAX, i64::MAX))
    }

    pub(super) fn put(&mut self, x: i64, y: i64, c: Rgb<u8>) {
        if self.clip.contains(x, y) {
            self.img.put_pixel(x as u32, y as u32, c);
        }
    }

    pub(super) fn fill(&mut self, c: Rgb<u8>) {
        let r = self.clip;
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                self.put(x, y, c);
            }
        }
    }

    pub(super) fn frame_rect(&mut self, r: Rect, c: Rgb<u8>) {
        for x in r.x0..r.x1 {
            self.put(x, r.y0, c);
            self.put(x, r.y1 - 1, c);
        }
        for y in r.y0..r.y1 {
            self.put(r.x0, y, c);
            self.put(r.x1 - 1, y, c);
        }
    }

    /// A `w`×`w` pixel square centred on a continuous point.
    pub(super) fn stamp(&mut self, (x, y): (f64, f64), w: f64, c: Rgb<u8>) {
        let n = w.max(1.0).round() as i64;
        let half = n as f64 / 2.0;
        let (x0, y0) = ((x - half).round() as i64, (y - half).round() as i64);
        for dy in 0..n {
            for dx in 0..n {
                self.put(x0 + dx, y0 + dy, c);
            }
        }
    }

    /// A straight line `w` pixels thick, clipped first so far-off ends cost nothing.
    pub(super) fn line(&mut self, a: (f64, f64), b: (f64, f64), w: f64, c: Rgb<u8>) {
        let r = &self.clip;
        let pad = w + 1.0;
        let bounds = (
            r.x0 as f64 - pad,
            r.y0 as f64 - pad,
            r.x1 as f64 + pad,
            r.y1 as f64 + pad,
        );
        let Some((a, b)) = clip_segment(a, b, bounds) else {
            return;
        };
        let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0) as i64;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            self.stamp((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), w, c);
        }
    }

    pub(super) fn polyline(&mut self, pts: impl Iterator<Item = (f64, f64)>, w: f64, c: Rgb<u8>) {
        let mut prev: Option<(f64, f64)> = None;
        for p in pts {
            if let Some(q) = prev {
                self.line(q, p, w, c);
            }
            prev = Some(p);
        }
    }

    pub(super) fn dashed(&mut self, a: (f64, f64), b: (f64, f64), dash: f64, c: Rgb<u8>) {
        let n = (dist(a, b) / dash).floor() as i64;
        let at = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
        for i in (0..n.min(2000)).step_by(2) {
            let (t0, t1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
            self.line(at(t0), at(t1), 1.0, c);
        }
    }

    /// A line with a small head at `b`.
    pub(super) fn arrow(&mut self, a: (f64, f64), b: (f64, f64), w: f64, c: Rgb<u8>) {
        self.line(a, b, w, c);
        let len = dist(a, b).max(1e-9);
        let (ux, uy) = ((b.0 - a.0) / len, (b.1 - a.1) / len);
        let head = 6.0;
        for side in [-1.0, 1.0] {
            let (px, py) = (-uy * side, ux * side);
            let tip = (
                b.0 - head * ux + 0.6 * head * px,
                b.1 - head * uy + 0.6 * head * py,
            );
            self.line(b, tip, w, c);
        }
    }

    pub(super) fn disc(&mut self, (cx, cy): (f64, f64), r: f64, c: Rgb<u8>) {
        let bbox = Rect::around((cx, cy), r + 1.0).intersect(&self.clip);
        for y in bbox.y0..bbox.y1 {
            for x in bbox.x0..bbox.x1 {
                if (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy) <= r {
                    self.put(x, y, c);
                }
            }
        }
    }

    /// A circle of radius r, w pixels wide.
    pub(super) fn ring(&mut self, (cx, cy): (f64, f64), r: f64, w: f64, c: Rgb<u8>) {
        let bbox = Rect::around((cx, cy), r + w + 1.0).intersect(&self.clip);
        for y in bbox.y0..bbox.y1 {
            for x in bbox.x0..bbox.x1 {
                let d = (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy);
                if (d - r).abs() <= w / 2.0 {
                    self.put(x, y, c);
                }
            }
        }
    }

    pub(super) fn square(&mut self, (x, y): (f64, f64), half: f64, c: Rgb<u8>) {
        self.stamp((x, y), 2.0 * half, c);
    }

    pub(super) fn square_outline(&mut self, (x, y): (f64, f64), half: f64, w: f64, c: Rgb<u8>) {
        let (l, r, t, b) = (x - half, x + half, y - half, y + half);
        self.line((l, t), (r, t), w, c);
        self.line((l, b), (r, b), w, c);
        self.line((l, t), (l, b), w, c);
        self.line((r, t), (r, b), w, c);
    }

    pub(super) fn cross(&mut self, (x, y): (f64, f64), half: f64, w: f64, c: Rgb<u8>) {
        self.line((x - half, y - half), (x + half, y + half), w, c);
        self.line((x - half, y + half), (x + half, y - half), w, c);
    }

    pub(super) fn diamond(&mut self, (cx, cy): (f64, f64), r: f64, fill: Rgb<u8>, edge: Rgb<u8>) {
        let inside = |x: f64, y: f64| (x - cx).abs() + (y - cy).abs() < r;
        self.mask(Rect::around((cx, cy), r + 1.0), inside, fill, edge);
    }

    /// Fills the pixels of `bbox` whose centre is `inside`, outlining the boundary. The clip
    /// edge is not a boundary: a shape cut off by the panel border gets no outline there.
    pub(super) fn mask(
        &mut self,
        bbox: Rect,
        inside: impl Fn(f64, f64) -> bool,
        fill: Rgb<u8>,
        edge: Rgb<u8>,
    ) {
        let r = Rect::new(bbox.x0 - 1, bbox.y0 - 1, bbox.x1 + 1, bbox.y1 + 1).intersect(&self.clip);
        if r.x0 >= r.x1 || r.y0 >= r.y1 {
            return;
        }
        let w = (r.x1 - r.x0) as usize;
        let mut m = Vec::with_capacity(w * (r.y1 - r.y0) as usize);
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                m.push(inside(x as f64 + 0.5, y as f64 + 0.5));
            }
        }
        let at = |x: i64, y: i64| {
            // Outside the evaluated area counts as inside, so clip edges stay unoutlined.
            !r.contains(x, y) || m[(y - r.y0) as usize * w + (x - r.x0) as usize]
        };
        for y in r.y0..r.y1 {
            for x in r.x0..r.x1 {
                if !at(x, y) {
                    continue;
                }
                let border = !(at(x - 1, y) && at(x + 1, y) && at(x, y - 1) && at(x, y + 1));
                self.put(x, y, if border { edge } else { fill });
            }
        }
    }

    /// Draws `s` with its top-left at (x, y); returns the x after the last glyph.
    pub(super) fn text(&mut self, x: i64, y: i64, s: &str, scale: i64, c: Rgb<u8>) -> i64 {
        let mut x = x;
        for ch in s.chars() {
            for (row, bits) in glyph(ch).split('/').enumerate() {
                for (col, b) in bits.bytes().enumerate() {
                    if b == b'#' {
                        let (px, py) = (x + col as i64 * scale, y + row as i64 * scale);
                        for d in 0..scale * scale {
                            self.put(px + d % scale, py + d / scale, c);
                        }
                    }
                }
            }
            x += ADVANCE * scale;
        }
        x
    }

    /// A label beside a marker at the panel edge, on the inner side and kept inside the panel.
    pub(super) fn text_near(&mut self, p: &Panel, at: (f64, f64), s: &str, c: Rgb<u8>) {
        let r = p.rect();
        let w = text_width(s, 1);
        let y = if at.1 < p.centre_px().1 {
            at.1 + 10.0
        } else {
            at.1 - 18.0
        } as i64;
        let x = ((at.0 - w as f64 / 2.0) as i64).clamp(r.x0 + 4, (r.x1 - 4 - w).max(r.x0 + 4));
        // A backing box keeps the label readable over the grid and the path.
        for yy in y - 2..y + 9 {
            for xx in x - 2..x + w + 1 {
                self.put(xx, yy, PANEL);
            }
        }
        self.text(x, y, s, 1, c);
    }
}

/// Liang–Barsky: the part of segment a–b inside (x0, y0, x1, y1), if any.
pub(super) fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    (x0, y0, x1, y1): (f64, f64, f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
            continue;
        }
        let t = q / p;
        if p < 0.0 {
            t0 = t0.max(t);
        } else {
            t1 = t1.min(t);
        }
    }
    if t0.is_nan() || t0 > t1 {
        return None;
    }
    let at = |t: f64| (a.0 + t * dx, a.1 + t * dy);
    Some((at(t0), at(t1)))
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_clip_to_the_box() {
        let b = (0.0, 0.0, 10.0, 10.0);
        assert_eq!(
            clip_segment((-5.0, 5.0), (15.0, 5.0), b),
            Some(((0.0, 5.0), (10.0, 5.0)))
        );
        assert_eq!(clip_segment((-5.0, -5.0), (-1.0, 20.0), b), None);
    }
}
