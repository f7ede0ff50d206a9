//! Keyframes → `camera_at(t)`. Frame n shows t = n / fps, computed in f64 from the integer n.
//!
//! ```yaml
//! timeline:
//!   fps: 24                  # default 24
//!   duration: 4.0            # seconds; frames = round(duration * fps)
//!   interpolation: smooth    # linear | smooth (centripetal Catmull-Rom through every key)
//!   keyframes:
//!     - { time: 0.0, position: [0, 0.3, 1.5], look_at: [0, 0, -0.5] }
//!     - { time: 2.0, position: [1.5, 0.5, -0.5], fov: 70, ease: in-out }
//!   # or, instead of keyframes:
//!   orbit: { center: [0, 0, -1], radius: 1.6, height: 0.35, start_angle: 0, turns: 1, duration: 6 }
//! ```
//! Position, look-at, up and fov are separate tracks; each key holds all four (absent values
//! carry over from the previous key). A key's `ease` reshapes the segment that starts at it.

use crate::camera::Pose;
use glam::DVec3;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Interpolation {
    Linear,
    Smooth,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Ease {
    Linear,
    In,
    Out,
    InOut,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    pub time: f64,
    pub pose: Pose,
    pub ease: Ease,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    pub center: DVec3,
    pub radius: f64,
    pub height: f64,
    /// Degrees; 0 puts the camera on the +z side of the centre, 90 on the +x side.
    pub start_angle: f64,
    pub turns: f64,
    pub duration: f64,
    pub look_at: DVec3,
    pub up: DVec3,
    pub fov: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Path {
    /// Keys sorted strictly by time; one key is a still camera.
    Keys {
        keys: Vec<Key>,
        interpolation: Interpolation,
    },
    Orbit(Orbit),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    pub fps: f64,
    pub frame_count: u64,
    pub path: Path,
}

impl Timeline {
    /// A single frame of a still camera.
    pub fn still(pose: Pose) -> Timeline {
        Timeline {
            fps: 24.0,
            frame_count: 1,
            path: Path::Keys {
                keys: vec![Key {
                    time: 0.0,
                    pose,
                    ease: Ease::Linear,
                }],
                interpolation: Interpolation::Linear,
            },
        }
    }

    /// The time frame `n` shows, exact for any n (no accumulation).
    pub fn time_of(&self, n: u64) -> f64 {
        n as f64 / self.fps
    }

    pub fn pose_of(&self, n: u64) -> Pose {
        self.camera_at(self.time_of(n))
    }

    pub fn camera_at(&self, t: f64) -> Pose {
        match &self.path {
            Path::Orbit(o) => orbit_at(o, t),
            Path::Keys {
                keys,
                interpolation,
            } => keys_at(keys, *interpolation, t),
        }
    }
}

fn orbit_at(o: &Orbit, t: f64) -> Pose {
    let turns = o.turns * t / o.duration;
    // Whole turns are reduced first so the angle stays exact however long the orbit runs.
    let angle = o.start_angle.to_radians() + std::f64::consts::TAU * turns.fract();
    let offset = DVec3::new(
        o.radius * libm::sin(angle),
        o.height,
        o.radius * libm::cos(angle),
    );
    Pose {
        position: o.center + offset,
        look_at: o.look_at,
        up: o.up,
        fov: o.fov,
    }
}

fn keys_at(keys: &[Key], interpolation: Interpolation, t: f64) -> Pose {
    let last = keys.len() - 1;
    if keys.len() == 1 || t <= keys[0].time {
        return keys[0].pose;
    }
    if t >= keys[last].time {
        return keys[last].pose;
    }
    // Segment k holds t in [keys[k].time, keys[k+1].time).
    let k = keys.partition_point(|key| key.time <= t) - 1;
    let (a, b) = (&keys[k], &keys[k + 1]);
    let s = ease(a.ease, (t - a.time) / (b.time - a.time));
    let track = |get: fn(&Pose) -> DVec3| {
        let p1 = get(&a.pose);
        let p2 = get(&b.pose);
        match interpolation {
            Interpolation::Linear => p1.lerp(p2, s),
            Interpolation::Smooth => {
                let p0 = (k > 0).then(|| get(&keys[k - 1].pose));
                let p3 = keys.get(k + 2).map(|key| get(&key.pose));
                centripetal(p0, p1, p2, p3, s)
            }
        }
    };
    Pose {
        position: track(|p| p.position),
        look_at: track(|p| p.look_at),
        up: track(|p| p.up),
        fov: track(|p| DVec3::splat(p.fov)).x,
    }
}

fn ease(e: Ease, s: f64) -> f64 {
    match e {
        Ease::Linear => s,
        Ease::In => s * s,
        Ease::Out => s * (2.0 - s),
        Ease::InOut => s * s * (3.0 - 2.0 * s),
    }
}

/// Centripetal Catmull-Rom between p1 (s = 0) and p2 (s = 1), passing through both exactly.
/// A missing or coincident neighbour is replaced by the mirror image of the far point, which
/// keeps the end segments tangent to the chord instead of dividing by a zero knot interval.
fn centripetal(p0: Option<DVec3>, p1: DVec3, p2: DVec3, p3: Option<DVec3>, s: f64) -> DVec3 {
    if p1 == p2 || s <= 0.0 {
        return p1;
    }
    if s >= 1.0 {
        return p2;
    }
    let p0 = p0.filter(|p| *p != p1).unwrap_or(2.0 * p1 - p2);
    let p3 = p3.filter(|p| *p != p2).unwrap_or(2.0 * p2 - p1);
    let knot = |a: DVec3, b: DVec3| a.distance(b).sqrt();
    let t1 = knot(p0, p1);
    let t2 = t1 + knot(p1, p2);
    let t3 = t2 + knot(p2, p3);
    let t = t1 + s * (t2 - t1);
    // Barry–Goldman pyramid.
    let lerp = |a: DVec3, b: DVec3, ta: f64, tb: f64| a + (b - a) * ((t - ta) / (tb - ta));
    let a1 = lerp(p0, p1, 0.0, t1);
    let a2 = lerp(p1, p2, t1, t2);
    let a3 = lerp(p2, p3, t2, t3);
    let b1 = lerp(a1, a2, 0.0, t2);
    let b2 = lerp(a2, a3, t1, t3);
    lerp(b1, b2, t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f64, x: f64, fov: f64) -> Key {
        Key {
            time,
            pose: Pose {
                position: DVec3::new(x, x * x, 0.0),
                look_at: DVec3::new(0.0, 0.0, -5.0),
                up: DVec3::Y,
                fov,
            },
            ease: Ease::Linear,
        }
    }

    fn timeline(keys: Vec<Key>, interpolation: Interpolation) -> Timeline {
        Timeline {
            fps: 24.0,
            frame_count: 100,
            path: Path::Keys {
                keys,
                interpolation,
            },
        }
    }

    fn four_keys() -> Vec<Key> {
        vec![
            key(0.0, 0.0, 90.0),
            key(1.0, 1.0, 60.0),
            key(2.5, 3.0, 80.0),
            key(4.0, -1.0, 50.0),
        ]
    }

    #[test]
    fn every_key_is_hit_exactly() {
        let keys = four_keys();
        for interp in [Interpolation::Linear, Interpolation::Smooth] {
            let tl = timeline(keys.clone(), interp);
            for k in &keys {
                assert_eq!(tl.camera_at(k.time), k.pose, "{interp:?} at {}", k.time);
            }
        }
    }

    #[test]
    fn paths_are_continuous() {
        let keys = four_keys();
        for interp in [Interpolation::Linear, Interpolation::Smooth] {
            let tl = timeline(keys.clone(), interp);
            let dt = 1e-4;
            let mut t = 0.0;
            while t < 4.0 {
                let (a, b) = (tl.camera_at(t), tl.camera_at(t + dt));
                assert!(
                    a.position.distance(b.position) < 1e-2,
                    "{interp:?} jump at {t}"
                );
                assert!((a.fov - b.fov).abs() < 1e-1, "{interp:?} fov jump at {t}");
                t += dt;
            }
        }
    }

    #[test]
    fn coincident_points_hold_still() {
        let mut keys = vec![
            key(0.0, 1.0, 90.0),
            key(1.0, 1.0, 90.0),
            key(2.0, 2.0, 90.0),
        ];
        keys[1].pose.position = keys[0].pose.position;
        let tl = timeline(keys.clone(), Interpolation::Smooth);
        assert_eq!(tl.camera_at(0.5).position, keys[0].pose.position);
        assert!(tl.camera_at(1.5).position.is_finite());
    }

    #[test]
    fn orbit_has_constant_radius_and_speed_and_loops() {
        let o = Orbit {
            center: DVec3::new(-0.1, 0.0, -0.6),
            radius: 1.6,
            height: 0.35,
            start_angle: 30.0,
            turns: 1.0,
            duration: 6.0,
            look_at: DVec3::ZERO,
            up: DVec3::Y,
            fov: 90.0,
        };
        let tl = Timeline {
            fps: 24.0,
            frame_count: 144,
            path: Path::Orbit(o),
        };
        let step = tl.pose_of(1).position.distance(tl.pose_of(0).position);
        for n in 0..144 {
            let p = tl.pose_of(n).position - o.center;
            assert!((DVec3::new(p.x, 0.0, p.z).length() - 1.6).abs() < 1e-12);
            assert!((p.y - 0.35).abs() < 1e-12);
            let next = tl.pose_of(n + 1).position;
            assert!((next.distance(tl.pose_of(n).position) - step).abs() < 1e-12);
        }
        // Frame 144 would be the first pose again: the loop is seamless.
        assert!(tl.pose_of(144).position.distance(tl.pose_of(0).position) < 1e-12);
    }

    #[test]
    fn frame_time_is_exact_far_out() {
        let tl = Timeline {
            fps: 60.0,
            ..Timeline::still(key(0.0, 0.0, 90.0).pose)
        };
        assert_eq!(tl.time_of(10_000_000), 10_000_000.0 / 60.0);
        assert_eq!(tl.time_of(600), 10.0);
    }

    #[test]
    fn late_keys_interpolate() {
        let keys = vec![key(1e6, 0.0, 90.0), key(1e6 + 2.0, 2.0, 90.0)];
        let tl = timeline(keys, Interpolation::Linear);
        let p = tl.camera_at(1e6 + 1.0).position;
        assert!((p.x - 1.0).abs() < 1e-9, "{p}");
    }
}
