//! Keyframes → `camera_at(t)`. Frame n shows t = (n − first_frame) / fps, computed in f64 from
//! the integer n (see `Clock`).
//!
//! ```yaml
//! timeline:
//!   fps: 24                  # default 24
//!   duration: 4.0            # optional; frames = round(duration * fps); default: end on the last key
//!   interpolation: smooth    # linear | smooth (centripetal Catmull-Rom through every key)
//!   speed: keys              # keys (reach each key at its time) | constant (along the whole path)
//!   keyframes:
//!     - { time: 0.0, position: [0, 0.3, 1.5], look_at: [0, 0, -0.5] }
//!     - { time: 2.0, position: [1.5, 0.5, -0.5], fov: 70, ease: stop }
//!     - { time: 3.0, aperture: 0.05, focus_distance: 2.5 }   # focus pulled from the key before
//!   # or, instead of keyframes:
//!   orbit: { center: [0, 0, -1], radius: 1.6, height: 0.35, start_angle: 0, turns: 1, duration: 6 }
//! ```
//! Position, look-at, up, fov, aperture and focus distance are separate tracks; each key holds
//! them all (absent values carry over from the previous key). Without any focus distance the
//! focus follows look_at: it is |look_at − position| at every t. Every track has a shape
//! through its key values (`shape`) and a timing along it (`timing`), so its speed is
//! continuous through the keys. A key's `ease: stop` halts every track there.

pub mod motion;
mod shape;
mod timing;
mod track;

use crate::camera::{Lens, Pose};
use glam::DVec3;
use track::{Timing, Track};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Interpolation {
    Linear,
    Smooth,
}

/// How the camera meets a key.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Ease {
    /// Passes through at whatever speed the timing gives (the default).
    Pass,
    /// Speed 0 there: arrives and leaves smoothly.
    Stop,
}

/// What times the camera's progress along its path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Speed {
    /// Each key is reached at its own time.
    Keys,
    /// One speed from the first key to the last; the keys between only shape the path.
    Constant,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    pub time: f64,
    pub pose: Pose,
    pub ease: Ease,
    /// Lens diameter in scene units (0: a pinhole).
    pub aperture: f64,
    /// The distance in focus; None: the distance to look_at.
    pub focus_distance: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    pub center: DVec3,
    pub radius: f64,
    pub height: f64,
    /// Degrees; 0 puts the camera on the +z side of the centre, 90 on the +x side.
    pub(crate) start_angle: f64,
    pub(crate) turns: f64,
    pub(crate) duration: f64,
    pub look_at: DVec3,
    pub(crate) up: DVec3,
    pub(crate) fov: f64,
    pub(crate) aperture: f64,
    /// None: the distance to look_at.
    pub(crate) focus_distance: Option<f64>,
}

/// A keyframed move with its tracks built once, so `camera_at` only evaluates.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyed {
    /// Sorted strictly by time; one key is a still camera.
    pub keys: Vec<Key>,
    pub interpolation: Interpolation,
    pub speed: Speed,
    /// When the camera is at each key: its time, or under constant speed the time it gets there.
    pub(crate) passes: Vec<f64>,
    /// Position, look_at, up, fov (as x).
    tracks: [Track; 4],
    /// Aperture, and the focus distance when some key gives one (as x).
    aperture: Track,
    focus: Option<Track>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Path {
    Keys(Box<Keyed>),
    Orbit(Orbit),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Timeline {
    /// Frames per second: `num / den` rounded to f64 when the file gives a fraction.
    pub fps: f64,
    pub frame_count: u64,
    pub path: Path,
    /// Frame numbers and their times.
    pub clock: Clock,
    /// The objects and lights that move, in file order (objects first); empty when only the
    /// camera can.
    pub motion: Vec<motion::Rig>,
}

/// How frame numbers map to time: frames are numbered `first_frame` … `first_frame +
/// frame_count − 1`, and frame n shows t = (n − first_frame) / fps, or exactly
/// ((n − first_frame) · den) / num in f64 when fps is the fraction num/den (`24000/1001`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Clock {
    /// The number of the first frame (`timeline.first_frame`, `--first-frame`; default 0).
    pub(crate) first_frame: u64,
    /// `timeline.fps` as written when it is a fraction num/den.
    pub(crate) fraction: Option<(u64, u64)>,
    /// The length the file gives (`timeline.duration`, the orbit's, the last key's time).
    pub(crate) duration: Option<f64>,
}

impl Clock {
    /// The time frame `n` shows at `fps` (see `Clock`); a key given by frame number is placed
    /// at exactly this time, so it falls on its frame bit for bit.
    pub(crate) fn time_of(&self, n: u64, fps: f64) -> f64 {
        let i = n.saturating_sub(self.first_frame) as f64;
        match self.fraction {
            Some((num, den)) => (i * den as f64) / num as f64,
            None => i / fps,
        }
    }
}

/// A key may end this much of a frame after the frame that shows it (rounding in t × fps).
const FRAME_SLACK: f64 = 1e-6;

/// Frames of a keyframed timeline that ends on its last key: 0 … ceil(t_last·fps − 1e-6),
/// which is round(t_last·fps) when the key falls on a frame.
pub(crate) fn frames_to(t_last: f64, fps: f64) -> f64 {
    (t_last * fps - FRAME_SLACK).ceil().max(0.0) + 1.0
}

impl Keyed {
    /// Builds the tracks. Under constant speed a path with a zero-length segment cannot be
    /// timed by distance, so it falls back to the keys' times (the loader rejects it first).
    pub fn new(keys: Vec<Key>, interpolation: Interpolation, speed: Speed) -> Keyed {
        let times: Vec<f64> = keys.iter().map(|k| k.time).collect();
        let stops: Vec<bool> = keys.iter().map(|k| k.ease == Ease::Stop).collect();
        let curved = interpolation == Interpolation::Smooth;
        let timing = match interpolation {
            Interpolation::Linear => Timing::Linear,
            Interpolation::Smooth => Timing::Smooth,
        };
        let values = |get: fn(&Pose) -> DVec3| keys.iter().map(|k| get(&k.pose)).collect();
        let positions: Vec<DVec3> = values(|p| p.position);
        let mut position = Track::new(times.clone(), positions.clone(), &stops, curved, timing);
        let mut passes = times.clone();
        let moves = position.reach().windows(2).all(|w| w[1] > w[0]);
        let speed = match (speed, moves && keys.len() > 1) {
            (Speed::Constant, true) => {
                position = Track::new(times.clone(), positions, &stops, curved, Timing::Constant);
                passes = constant_passes(&times, position.reach());
                Speed::Constant
            }
            _ => Speed::Keys,
        };
        let track = |values: Vec<DVec3>, curved: bool| {
            Track::new(passes.clone(), values, &stops, curved, timing)
        };
        // A number's path is the number line: always straight.
        let number = |get: &dyn Fn(&Key) -> f64| {
            track(
                keys.iter().map(|k| DVec3::new(get(k), 0.0, 0.0)).collect(),
                false,
            )
        };
        let tracks = [
            position,
            track(values(|p| p.look_at), curved),
            track(values(|p| p.up), curved),
            number(&|k| k.pose.fov),
        ];
        let aperture = number(&|k| k.aperture);
        // Keys before the first focus distance focus on their look_at.
        let focus = keys.iter().any(|k| k.focus_distance.is_some()).then(|| {
            number(&|k| {
                k.focus_distance
                    .unwrap_or_else(|| k.pose.position.distance(k.pose.look_at))
            })
        });
        Keyed {
            keys,
            interpolation,
            speed,
            passes,
            tracks,
            aperture,
            focus,
        }
    }

    fn at(&self, t: f64) -> Pose {
        let [position, look_at, up, fov] = &self.tracks;
        Pose {
            position: position.at(t).0,
            look_at: look_at.at(t).0,
            up: up.at(t).0,
            fov: fov.at(t).0.x,
        }
    }

    fn lens_at(&self, t: f64, pose: &Pose) -> Lens {
        Lens {
            aperture: self.aperture.at(t).0.x,
            focus_distance: match &self.focus {
                Some(focus) => focus.at(t).0.x,
                None => pose.position.distance(pose.look_at),
            },
        }
    }
}

/// Under constant speed key k is passed when the camera has covered its share of the path:
/// τ_k = τ_0 + (τ_last − τ_0)·S_k / S_last.
fn constant_passes(times: &[f64], reach: &[f64]) -> Vec<f64> {
    let last = times.len() - 1;
    let (t0, span, total) = (times[0], times[last] - times[0], reach[last]);
    let mut out: Vec<f64> = reach.iter().map(|s| t0 + span * (s / total)).collect();
    out[last] = times[last];
    out
}

impl Timeline {
    /// Whether the camera can move: an orbit, or more than one key.
    pub fn moves(&self) -> bool {
        match &self.path {
            Path::Orbit(_) => true,
            Path::Keys(k) => k.keys.len() > 1,
        }
    }

    /// The widest aperture any key (or the orbit) opens the lens to.
    pub fn widest_aperture(&self) -> f64 {
        match &self.path {
            Path::Orbit(o) => o.aperture,
            Path::Keys(k) => k.keys.iter().map(|k| k.aperture).fold(0.0, f64::max),
        }
    }

    /// A single frame of a still camera (its key's time is ignored).
    pub(crate) fn still(key: Key) -> Timeline {
        let key = Key { time: 0.0, ..key };
        Timeline {
            fps: 24.0,
            frame_count: 1,
            path: Path::Keys(Box::new(Keyed::new(
                vec![key],
                Interpolation::Linear,
                Speed::Keys,
            ))),
            clock: Clock::default(),
            motion: Vec::new(),
        }
    }

    /// The time frame `n` shows, exact for any n (no accumulation): see `Clock`.
    pub fn time_of(&self, n: u64) -> f64 {
        self.clock.time_of(n, self.fps)
    }

    /// The number of the first frame.
    pub(crate) fn first_frame(&self) -> u64 {
        self.clock.first_frame
    }

    /// The number of the last frame.
    pub(crate) fn last_frame(&self) -> u64 {
        self.clock.first_frame + (self.frame_count - 1)
    }

    /// `24` or `23.976`, or the fraction as written (`24000/1001`), as ffmpeg's `-r` takes it.
    pub(crate) fn fps_text(&self) -> String {
        match self.clock.fraction {
            Some((num, den)) => format!("{num}/{den}"),
            None => crate::console::num(self.fps),
        }
    }

    /// How long the film runs: frame_count / fps seconds, each frame showing for 1/fps, as
    /// `10.04` (two decimals, trailing zeros dropped). `check` and `preview` both say this.
    pub(crate) fn running_time_text(&self) -> String {
        let text = format!("{:.2}", self.frame_count as f64 / self.fps);
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    }

    /// The poses of every object and light that moves, at time t (empty when none does).
    pub fn poses_at(&self, t: f64) -> motion::Poses {
        motion::poses_at(&self.motion, t)
    }

    pub fn pose_of(&self, n: u64) -> Pose {
        self.camera_at(self.time_of(n))
    }

    pub fn camera_at(&self, t: f64) -> Pose {
        match &self.path {
            Path::Orbit(o) => orbit_at(o, t),
            Path::Keys(k) => k.at(t),
        }
    }

    /// The camera and its lens at time t.
    pub(crate) fn view_at(&self, t: f64) -> (Pose, Lens) {
        let pose = self.camera_at(t);
        let lens = match &self.path {
            Path::Orbit(o) => Lens {
                aperture: o.aperture,
                focus_distance: o
                    .focus_distance
                    .unwrap_or_else(|| pose.position.distance(pose.look_at)),
            },
            Path::Keys(k) => k.lens_at(t, &pose),
        };
        (pose, lens)
    }

    /// The camera's speed along its path at time t, in scene units per second: at a key time
    /// the rate of the segment ending there for the last key, starting there otherwise.
    pub(crate) fn speed_at(&self, t: f64) -> f64 {
        match &self.path {
            Path::Orbit(o) => {
                let circle = std::f64::consts::TAU * o.radius * o.turns.abs();
                circle / o.duration
            }
            Path::Keys(k) => k.tracks[0].at(t).1,
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

#[cfg(test)]
mod tests;
