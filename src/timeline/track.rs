//! One interpolated quantity of the camera (position, look_at, up or fov): its values at the
//! key times, the shape through them and the timing along that shape.

use super::shape::{self, Curve};
use super::timing;
use glam::DVec3;

/// How a track moves along its shape in time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Timing {
    /// Piecewise linear in time, eased next to stops (`interpolation: linear`).
    Linear,
    /// Monotone C1 cubic arc length through the keys (see `timing`).
    Smooth,
    /// Arc length proportional to time from the first key to the last (`speed: constant`).
    Constant,
}

#[derive(Debug, Clone, PartialEq)]
enum Segment {
    /// Both keys hold the same value.
    Hold,
    Line {
        length: f64,
    },
    Curve(Box<Curve>),
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Track {
    times: Vec<f64>,
    values: Vec<DVec3>,
    segments: Vec<Segment>,
    /// Per key: the track halts there (asked for, or it turns straight back).
    stops: Vec<bool>,
    /// Smooth timing: ds/dt at each key.
    slopes: Vec<f64>,
    /// Arc length of each segment, and from the first key to each key.
    lengths: Vec<f64>,
    reach: Vec<f64>,
    timing: Timing,
}

impl Track {
    /// `curved` picks centripetal Catmull-Rom segments over straight ones.
    pub(crate) fn new(
        times: Vec<f64>,
        values: Vec<DVec3>,
        stops: &[bool],
        curved: bool,
        timing: Timing,
    ) -> Track {
        let segments = segments(&values, curved);
        let lengths: Vec<f64> = segments.iter().map(length).collect();
        let mut reach = vec![0.0];
        for l in &lengths {
            reach.push(reach.last().unwrap() + l);
        }
        let n = values.len();
        let turns = |k: usize| {
            timing == Timing::Smooth
                && k > 0
                && k + 1 < n
                && shape::turns_back(values[k - 1], values[k], values[k + 1])
        };
        let stops: Vec<bool> = (0..n).map(|k| stops[k] || turns(k)).collect();
        let slopes = match (timing, n) {
            (Timing::Smooth, 2..) => timing::slopes(&times, &lengths, &stops),
            _ => Vec::new(),
        };
        Track {
            times,
            values,
            segments,
            stops,
            slopes,
            lengths,
            reach,
            timing,
        }
    }

    /// Arc length from the first key to each key.
    pub(crate) fn reach(&self) -> &[f64] {
        &self.reach
    }

    /// The value at time t and the rate ds/dt along the shape; still before the first key
    /// and after the last, exactly the key's value at each key time.
    pub(crate) fn at(&self, t: f64) -> (DVec3, f64) {
        let last = self.times.len() - 1;
        if last == 0 || t.is_nan() || t < self.times[0] || t > self.times[last] {
            let held = if t > self.times[0] { last } else { 0 };
            return (self.values[held], 0.0);
        }
        let (k, s, rate) = match self.timing {
            Timing::Constant => self.constant(t),
            _ => self.keyed(t),
        };
        let value = if t == self.times[last] {
            self.values[last]
        } else {
            self.point(k, s)
        };
        (value, rate)
    }

    /// Segment, arc length into it and rate under key-timed motion.
    fn keyed(&self, t: f64) -> (usize, f64, f64) {
        let last = self.times.len() - 1;
        let k = (self.times.partition_point(|&x| x <= t) - 1).min(last - 1);
        let h = self.times[k + 1] - self.times[k];
        let u = if h > 0.0 {
            ((t - self.times[k]) / h).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let length = self.lengths[k];
        match self.timing {
            Timing::Linear => {
                let (e, de) = timing::eased(u, self.stops[k], self.stops[k + 1]);
                (k, length * e, timing::mean_rate(length, h) * de)
            }
            _ => {
                let (m0, m1) = (self.slopes[k], self.slopes[k + 1]);
                let (s, rate) = timing::hermite(u, h, length, m0, m1);
                (k, s, rate)
            }
        }
    }

    /// Segment, arc length into it and rate at constant speed from the first key to the last.
    fn constant(&self, t: f64) -> (usize, f64, f64) {
        let last = self.times.len() - 1;
        let (t0, duration) = (self.times[0], self.times[last] - self.times[0]);
        let total = self.reach[last];
        let s = (total * ((t - t0) / duration)).clamp(0.0, total);
        let k = (self.reach.partition_point(|&r| r <= s) - 1).min(last - 1);
        (k, s - self.reach[k], timing::mean_rate(total, duration))
    }

    /// The point `s` along segment k.
    fn point(&self, k: usize, s: f64) -> DVec3 {
        let (a, b) = (self.values[k], self.values[k + 1]);
        match &self.segments[k] {
            Segment::Hold => a,
            Segment::Line { length } if s >= *length => b,
            Segment::Line { length } => a.lerp(b, s / length),
            Segment::Curve(c) => c.at_length(s),
        }
    }
}

fn segments(values: &[DVec3], curved: bool) -> Vec<Segment> {
    let n = values.len();
    (0..n.saturating_sub(1))
        .map(|k| {
            let (p1, p2) = (values[k], values[k + 1]);
            let length = p1.distance(p2);
            if p1 == p2 || length.is_nan() || length <= 0.0 {
                return Segment::Hold;
            }
            if !curved {
                return Segment::Line { length };
            }
            let p0 = k.checked_sub(1).map(|i| values[i]);
            let p3 = values.get(k + 2).copied();
            let t1 = shape::start_tangent(p0, p1, p2);
            let t2 = shape::end_tangent(p1, p2, p3);
            Segment::Curve(Box::new(Curve::new(p1, p2, t1, t2)))
        })
        .collect()
}

fn length(s: &Segment) -> f64 {
    match s {
        Segment::Hold => 0.0,
        Segment::Line { length } => *length,
        Segment::Curve(c) => c.length(),
    }
}
