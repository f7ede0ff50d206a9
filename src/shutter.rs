//! What one frame's image integrates: the camera at the frame's time, or, with a shutter, the
//! camera over the frame's open interval, taken at `INSTANTS` evenly spaced instants.
//!
//! ```yaml
//! render:
//!   shutter: 180          # degrees of a 360° shutter: open (180/360)/fps seconds a frame; 0 = off
//!   shutter_offset: 0     # where the open interval sits, in open intervals: 0 centred on the
//!                         # frame time n/fps, 0.5 opening at it, −0.5 closing at it
//! ```
//! Each sample of a pixel picks one instant (`tracer::sample::Dims`), and its ray comes from
//! the camera there. The cameras are exact `camera_at` evaluations, built once a frame: a smooth
//! keyframed camera costs about 2 µs to evaluate, far too much for every sample.

use crate::camera::{Camera, Degenerate, Pose};
use crate::timeline::Timeline;
use crate::timeline::motion::Poses;
use glam::DVec3;
use std::sync::Arc;

/// Instants an open interval is divided into. With 256, the ghosts of a streak up to 256
/// pixels long stay within a pixel of each other: a continuous blur.
pub const INSTANTS: usize = 256;

/// A film camera's rotary shutter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shutter {
    /// Degrees of the 360° a frame lasts, in (0, 360].
    pub angle: f64,
    /// Where the open interval sits, in open intervals from centred on the frame time, in
    /// [−0.5, 0.5].
    pub offset: f64,
}

impl Shutter {
    /// The time of instant `j` of the frame shown at time `t`: the middle of the j-th of
    /// `INSTANTS` equal parts of [t + (offset − ½)·Δ, t + (offset + ½)·Δ], Δ = angle/360/fps.
    pub(crate) fn instant(&self, fps: f64, t: f64, j: usize) -> f64 {
        let open = self.angle / 360.0 / fps;
        let fraction = (self.offset - 0.5) + (j as f64 + 0.5) / INSTANTS as f64;
        t + open * fraction
    }
}

/// The cameras a frame is rendered with.
#[derive(Debug, Clone, PartialEq)]
pub struct Exposure {
    /// The camera (and lens) at the frame's time.
    pub camera: Camera,
    /// With a shutter and a camera (or some object or light) that moves while it is open,
    /// the camera at each instant; otherwise empty.
    pub instants: Vec<Camera>,
    /// The poses of the objects and lights that move (None when none does).
    pub motion: Option<Arc<Staged>>,
}

/// Where the objects and lights that move are during one frame: at its time, and at each
/// instant of its open shutter when one of them moves while it is open (else no instants).
#[derive(Debug, Clone, PartialEq)]
pub struct Staged {
    pub at: Poses,
    pub instants: Vec<Poses>,
}

/// Frame `n` worked out once: its time, the camera's pose there (what the fingerprint records)
/// and the cameras it is exposed with, or why there are none. Every stage that needs a frame's
/// camera takes it from here.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FrameView {
    pub(crate) frame: u64,
    pub(crate) time: f64,
    pub(crate) pose: Pose,
    pub(crate) exposure: Result<Exposure, NoCamera>,
    /// One frame later, for the motion pass: set only when the settings ask for it
    /// (`Settings::frame_view`).
    pub(crate) next: Option<Next>,
}

/// The frame one later, as the motion pass sees it: the pinhole camera at its time and the
/// poses there of the objects and lights that move (empty when nothing does).
#[derive(Debug, Clone, PartialEq)]
pub struct Next {
    pub camera: Camera,
    pub poses: Poses,
}

impl FrameView {
    /// Frame `n` of `timeline` seen through `shutter`.
    pub(crate) fn of_frame(timeline: &Timeline, shutter: Option<Shutter>, n: u64) -> FrameView {
        let time = timeline.time_of(n);
        let (pose, lens) = timeline.view_at(time);
        let exposure = Camera::new(&pose)
            .map(|c| c.with_lens(lens))
            .map_err(|reason| NoCamera { time, reason })
            .and_then(|camera| Exposure::around(camera, timeline, shutter, time));
        FrameView {
            frame: n,
            time,
            pose,
            exposure,
            next: None,
        }
    }

    /// Frame `n`, and when `next` (the motion pass) the camera and the moving things at the
    /// time of frame n + 1 (what the timeline gives there, beyond the last frame too: keys
    /// hold still after the last one, an orbit goes on turning). Should that camera not
    /// exist, the frame's own stands in (no motion).
    pub(crate) fn with_next(
        timeline: &Timeline,
        shutter: Option<Shutter>,
        next: bool,
        n: u64,
    ) -> FrameView {
        let mut view = FrameView::of_frame(timeline, shutter, n);
        if next && let Ok(e) = &view.exposure {
            let t = timeline.time_of(n.saturating_add(1));
            let (pose, _) = timeline.view_at(t);
            let camera = Camera::new(&pose).unwrap_or(Camera {
                lens_radius: 0.0,
                ..e.camera
            });
            let poses = crate::timeline::motion::poses_at(&timeline.motion, t);
            view.next = Some(Next { camera, poses });
        }
        view
    }
}

/// A time at which the camera cannot be built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoCamera {
    pub time: f64,
    pub reason: Degenerate,
}

impl std::error::Error for NoCamera {}

impl std::fmt::Display for NoCamera {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{} (t = {} s)", self.reason, self.time)
    }
}

impl Exposure {
    /// These cameras in coordinates whose origin is `by`.
    pub(crate) fn shifted(&self, by: DVec3) -> Exposure {
        let shift = |c: &Camera| Camera {
            origin: c.origin - by,
            ..*c
        };
        Exposure {
            camera: shift(&self.camera),
            instants: self.instants.iter().map(shift).collect(),
            motion: self.motion.clone(),
        }
    }

    /// One camera for the whole frame.
    pub fn still(camera: Camera) -> Exposure {
        Exposure {
            camera,
            instants: Vec::new(),
            motion: None,
        }
    }

    /// Frame `n` of `timeline` seen through `shutter` (the exposure of its `FrameView`).
    pub fn of_frame(
        timeline: &Timeline,
        shutter: Option<Shutter>,
        n: u64,
    ) -> Result<Exposure, NoCamera> {
        FrameView::of_frame(timeline, shutter, n).exposure
    }

    /// `camera`, the camera at time `t`, and with a shutter the cameras of its open interval;
    /// the poses of what moves.
    fn around(
        camera: Camera,
        timeline: &Timeline,
        shutter: Option<Shutter>,
        t: f64,
    ) -> Result<Exposure, NoCamera> {
        let mut exposure = Exposure::cameras(camera, timeline, shutter, t)?;
        if timeline.motion.is_empty() {
            return Ok(exposure);
        }
        let staged = Staged::of(timeline, shutter, t);
        // Objects that move while the shutter is open are sampled in time even where the
        // camera holds still.
        if !staged.instants.is_empty() && exposure.instants.is_empty() {
            exposure.instants = vec![camera; INSTANTS];
        }
        exposure.motion = Some(Arc::new(staged));
        Ok(exposure)
    }

    /// `camera`, and with a shutter the cameras of its open interval when the camera moves
    /// while it is open.
    fn cameras(
        camera: Camera,
        timeline: &Timeline,
        shutter: Option<Shutter>,
        t: f64,
    ) -> Result<Exposure, NoCamera> {
        let Some(shutter) = shutter else {
            return Ok(Exposure::still(camera));
        };
        let instants = (0..INSTANTS)
            .map(|j| camera_at(timeline, shutter.instant(timeline.fps, t, j)))
            .collect::<Result<Vec<_>, _>>()?;
        // A camera that holds still while the shutter is open is rendered as without one.
        if instants.iter().all(|c| *c == camera) {
            return Ok(Exposure::still(camera));
        }
        Ok(Exposure {
            camera,
            instants,
            motion: None,
        })
    }

    /// Whether eye rays leave from more than one point: through a lens, or from a moving camera.
    pub(crate) fn sampled(&self) -> bool {
        self.camera.lens_radius > 0.0 || !self.instants.is_empty()
    }

    /// Whether some camera the samples use has an open lens: one of the open shutter's
    /// instants, or without instants the frame's own (the film filter's wide case).
    pub(crate) fn lens_open(&self) -> bool {
        match self.instants.is_empty() {
            true => self.camera.lens_radius > 0.0,
            false => self.instants.iter().any(|c| c.lens_radius > 0.0),
        }
    }
}

impl Staged {
    /// The poses of `timeline`'s moving things at time t, and at each instant of the open
    /// interval of `shutter` unless they all hold still while it is open.
    pub(crate) fn of(timeline: &Timeline, shutter: Option<Shutter>, t: f64) -> Staged {
        let at = timeline.poses_at(t);
        let instants: Vec<Poses> = match shutter {
            Some(s) => (0..INSTANTS)
                .map(|j| timeline.poses_at(s.instant(timeline.fps, t, j)))
                .collect(),
            None => Vec::new(),
        };
        let still = instants.iter().all(|p| *p == at);
        Staged {
            at,
            instants: if still { Vec::new() } else { instants },
        }
    }
}

/// The camera and lens of `timeline` at time t.
pub(crate) fn camera_at(timeline: &Timeline, t: f64) -> Result<Camera, NoCamera> {
    let (pose, lens) = timeline.view_at(t);
    Camera::new(&pose)
        .map(|c| c.with_lens(lens))
        .map_err(|reason| NoCamera { time: t, reason })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instants_split_the_open_interval_evenly() {
        let centred = Shutter {
            angle: 180.0,
            offset: 0.0,
        };
        // 24 fps, 180°: open 1/48 s, centred on t = 1.
        let first = centred.instant(24.0, 1.0, 0);
        let last = centred.instant(24.0, 1.0, INSTANTS - 1);
        let step = 1.0 / 48.0 / INSTANTS as f64;
        assert!((first - (1.0 - 1.0 / 96.0 + step / 2.0)).abs() < 1e-15);
        assert!((last - (1.0 + 1.0 / 96.0 - step / 2.0)).abs() < 1e-15);
        let opening = Shutter {
            offset: 0.5,
            ..centred
        };
        assert!((opening.instant(24.0, 1.0, 0) - (1.0 + step / 2.0)).abs() < 1e-15);
    }
}
