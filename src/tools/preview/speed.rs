//! The speed panel under the path plot: the camera's speed (scene units per second) against
//! time, with the keyframes marked where the camera passes them and stops labelled. A jump or
//! a spike here is a jerk on screen.

use super::{
    AXIS, BAD, BORDER, Canvas, GRID, KEYFRAME, MUTED, PANEL, PATH, Rect, fmt_num, nice_step,
    text_width,
};
use crate::camera::Pose;
use crate::sequence::Sequence;
use crate::timeline::{Ease, Path as TimelinePath};

/// Height of the panel in pixels.
pub(crate) const HEIGHT: u32 = 220;
/// Inner padding: room for the axis labels and the key numbers.
const PAD_X: f64 = 56.0;
const PAD_TOP: f64 = 26.0;
const PAD_BOTTOM: f64 = 24.0;

/// Maps time and speed to pixels inside the panel.
struct Axes {
    rect: Rect,
    t0: f64,
    span: f64,
    top: f64,
}

impl Axes {
    fn x(&self, t: f64) -> f64 {
        let w = (self.rect.x1 - self.rect.x0) as f64 - 2.0 * PAD_X;
        self.rect.x0 as f64 + PAD_X + (t - self.t0) / self.span * w
    }

    fn y(&self, v: f64) -> f64 {
        let h = (self.rect.y1 - self.rect.y0) as f64 - PAD_TOP - PAD_BOTTOM;
        self.rect.y1 as f64 - PAD_BOTTOM - (v / self.top).clamp(0.0, 1.05) * h
    }
}

/// A key as the panel marks it: index, when it is passed, speed there, whether it stops.
type KeyMark = (usize, f64, f64, bool);

/// Draws the panel into `rect` for the sampled frames (`bad` ones in red).
pub(crate) fn draw(
    c: &mut Canvas,
    rect: Rect,
    seq: &Sequence,
    samples: &[(u64, Pose)],
    bad: &[bool],
) {
    let t = &seq.timeline;
    let times: Vec<f64> = samples.iter().map(|(n, _)| t.time_of(*n)).collect();
    let speeds: Vec<f64> = times.iter().map(|&s| t.speed_at(s)).collect();
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let keys = key_marks(seq, t0, t1);
    let most = speeds
        .iter()
        .chain(keys.iter().map(|k| &k.2))
        .fold(0.0f64, |a, &b| a.max(b));
    let top = if most > 0.0 && most.is_finite() {
        most * 1.1
    } else {
        1.0
    };
    let span = if t1 > t0 { t1 - t0 } else { 1.0 / t.fps };
    let axes = Axes {
        rect,
        t0,
        span,
        top,
    };
    c.fill(PANEL);
    grid(c, &axes);
    for &(i, time, speed, stop) in &keys {
        let (x, y) = (axes.x(time), axes.y(speed));
        c.dashed((x, rect.y0 as f64 + PAD_TOP), (x, axes.y(0.0)), 4.0, AXIS);
        c.square_outline((x, y), 5.0, 2.0, KEYFRAME);
        let label = if stop {
            format!("{i} stop")
        } else {
            i.to_string()
        };
        let lx = (x - text_width(&label, 1) as f64 / 2.0) as i64;
        c.text(lx, rect.y0 + 8, &label, 1, KEYFRAME);
    }
    let pts: Vec<(f64, f64)> = times
        .iter()
        .zip(&speeds)
        .map(|(&s, &v)| (axes.x(s), axes.y(v)))
        .collect();
    for i in 1..pts.len() {
        let colour = if bad[i - 1] || bad[i] { BAD } else { PATH };
        c.line(pts[i - 1], pts[i], 2.0, colour);
    }
    if pts.len() == 1 {
        c.disc(pts[0], 2.5, if bad[0] { BAD } else { PATH });
    }
    c.frame_rect(rect, BORDER);
}

/// The keys passed between t0 and t1.
fn key_marks(seq: &Sequence, t0: f64, t1: f64) -> Vec<KeyMark> {
    let TimelinePath::Keys(k) = &seq.timeline.path else {
        return Vec::new();
    };
    if k.keys.len() < 2 {
        return Vec::new();
    }
    let inside = |&(_, time, _, _): &KeyMark| time >= t0 && time <= t1;
    let mark = |(i, key): (usize, &crate::timeline::Key)| {
        let time = k.passes[i];
        (i, time, seq.timeline.speed_at(time), key.ease == Ease::Stop)
    };
    k.keys.iter().enumerate().map(mark).filter(inside).collect()
}

/// Speed lines with their values on the left, time ticks along the bottom.
fn grid(c: &mut Canvas, a: &Axes) {
    let r = a.rect;
    let (left, right) = (r.x0 as f64 + PAD_X, r.x1 as f64 - PAD_X);
    let step = nice_step(a.top / 4.0);
    for k in 0..=((a.top / step).floor() as i64) {
        let v = k as f64 * step;
        let y = a.y(v);
        c.line((left, y), (right, y), 1.0, if k == 0 { AXIS } else { GRID });
        let label = fmt_num(v);
        let x = left as i64 - 6 - text_width(&label, 1);
        c.text(x, y as i64 - 3, &label, 1, MUTED);
    }
    let tstep = nice_step(a.span / 8.0);
    let first = (a.t0 / tstep).ceil() as i64;
    for k in first..=((a.t0 + a.span) / tstep).floor() as i64 {
        let x = a.x(k as f64 * tstep);
        let label = format!("{}s", fmt_num(k as f64 * tstep));
        c.line((x, a.y(0.0)), (x, a.y(0.0) + 4.0), 1.0, MUTED);
        let lx = (x - text_width(&label, 1) as f64 / 2.0) as i64;
        c.text(lx, r.y1 - 14, &label, 1, MUTED);
    }
}
