//! `timeline:` → `Timeline`: keyframes or an orbit, the frame count, the warnings a valid
//! timeline can still deserve, and the check of every frame's camera.

use super::{
    Check, Invalid, MAX_FPS, MAX_FRAMES, MAX_ROLL_PER_FRAME_DEGREES, aperture, focus_distance, fov,
    got, got_num, in_range, invalid, num, number, positive, raw, unit, vector,
};
use crate::camera::{Camera, Degenerate, Pose};
use crate::shutter::{INSTANTS, Shutter};
use crate::timeline::{
    Clock, Ease, Interpolation, Key, Keyed, Orbit, Path as TimelinePath, Speed, Timeline, frames_to,
};

/// Largest `timeline.first_frame`: frame numbers stay below 2^53, exact in f64.
pub(crate) const MAX_FIRST_FRAME: u64 = 1 << 50;
use crate::timeline::motion::Rig;
use glam::DVec3;

/// A timeline that loaded, with what is worth a warning and, separately, the first problem
/// that makes some frame's camera impossible (a file that `preview` can still draw).
pub(super) struct Loaded {
    pub(crate) timeline: Timeline,
    pub(crate) warnings: Vec<String>,
    pub(crate) problem: Option<Invalid>,
}

/// Things that move, keyed on the clock of the timeline being loaded.
pub(super) type Things<'a> = &'a dyn Fn(Frames) -> Check<Vec<Rig>>;

pub(super) fn timeline(
    t: &raw::Timeline,
    camera: Option<Key>,
    shutter: Option<Shutter>,
    things: Things,
) -> Check<Loaded> {
    let (fps, fraction) = match t.fps.unwrap_or(raw::Fps::Number(24.0)) {
        raw::Fps::Number(fps) => (fps, None),
        raw::Fps::Fraction(num, den) => (num as f64 / den as f64, Some((num, den))),
    };
    in_range("timeline.fps", fps, 0.0, MAX_FPS, "in (0, 1000]")?;
    if fps == 0.0 {
        return invalid(
            "timeline.fps",
            format!("must be greater than 0 {}", got_num(fps)),
        );
    }
    let first_frame = t.first_frame.unwrap_or(0);
    if first_frame > MAX_FIRST_FRAME {
        return invalid(
            "timeline.first_frame",
            format!("must be at most {MAX_FIRST_FRAME} {}", got(first_frame)),
        );
    }
    let mut clock = Clock {
        first_frame,
        fraction,
        duration: None,
    };
    let path = path(t, camera, (&clock, fps))?;
    let motion = things((&clock, fps))?;
    // Without a duration the film ends on the last key, the camera's or a moving thing's.
    let last_key = |k: &Keyed| {
        let camera = k.keys.last().map_or(0.0, |k| k.time);
        last_thing_key(&motion).map_or(camera, |m| camera.max(m))
    };
    clock.duration = match (&path, t.duration) {
        (_, Some(d)) => Some(d),
        (TimelinePath::Orbit(o), None) => Some(o.duration),
        (TimelinePath::Keys(k), None) => Some(last_key(k)),
    };
    let frame_count = match (&path, t.duration) {
        (TimelinePath::Keys(k), None) => keyed_frames(last_key(k), fps)?,
        _ => frame_count(t, &path, fps)?,
    };
    let timeline = Timeline {
        fps,
        frame_count,
        path,
        clock,
        motion,
    };
    let warnings = t
        .duration
        .map_or_else(Vec::new, |d| unseen_keys(&timeline, d));
    let problem = check_keys(&timeline)
        .and_then(|()| check_every_frame(&timeline, shutter))
        .err();
    Ok(Loaded {
        timeline,
        warnings,
        problem,
    })
}

/// The clock's frame numbers and rate, for keys given by `frame:`.
pub(super) type Frames<'a> = (&'a Clock, f64);

fn path(t: &raw::Timeline, camera: Option<Key>, frames: Frames) -> Check<TimelinePath> {
    match (&t.keyframes, &t.orbit) {
        (Some(_), Some(_)) => invalid(
            "timeline.orbit",
            "give either `keyframes:` or `orbit:`, not both",
        ),
        (None, None) => invalid("timeline", "needs `keyframes:` or `orbit:`"),
        (Some(keys), None) => Ok(TimelinePath::Keys(Box::new(keyed(
            t,
            keyframes(keys, camera, frames)?,
        )?))),
        (None, Some(_)) if t.speed.is_some() => invalid(
            "timeline.speed",
            "an orbit always moves at constant speed; `speed` is for keyframes",
        ),
        (None, Some(o)) => Ok(TimelinePath::Orbit(orbit(o, camera)?)),
    }
}

/// The time of the last key of anything that moves besides the camera.
pub(super) fn last_thing_key(motion: &[Rig]) -> Option<f64> {
    motion
        .iter()
        .filter_map(|r| r.times.last().copied())
        .reduce(f64::max)
}

/// The frames of a film that ends on its last key, at `last` seconds.
pub(super) fn keyed_frames(last: f64, fps: f64) -> Check<u64> {
    let frames = frames_to(last, fps);
    if (1.0..=MAX_FRAMES as f64).contains(&frames) {
        return Ok(frames as u64);
    }
    invalid(
        "timeline.duration",
        format!(
            "duration × fps must give 1 to {MAX_FRAMES} frames {}",
            got(format!(
                "ending on the last keyframe at {} s at {} fps takes {} frames",
                num(last),
                num(fps),
                num(frames)
            ))
        ),
    )
}

/// round(duration × fps) with a duration (an orbit has its own); otherwise up to the last key.
fn frame_count(t: &raw::Timeline, path: &TimelinePath, fps: f64) -> Check<u64> {
    let frames = match (t.duration, path) {
        (Some(d), _) => (positive("timeline.duration", d)? * fps).round(),
        (None, TimelinePath::Orbit(o)) => (o.duration * fps).round(),
        (None, TimelinePath::Keys(k)) => frames_to(k.keys.last().expect("non-empty").time, fps),
    };
    if (1.0..=MAX_FRAMES as f64).contains(&frames) {
        return Ok(frames as u64);
    }
    let how = match (t.duration, path) {
        (Some(d), _) => format!("{} s × {} fps = {} frames", num(d), num(fps), num(frames)),
        (None, TimelinePath::Keys(k)) => format!(
            "ending on the last keyframe at {} s at {} fps takes {} frames",
            num(k.keys.last().expect("non-empty").time),
            num(fps),
            num(frames)
        ),
        (None, TimelinePath::Orbit(o)) => {
            format!(
                "{} s × {} fps = {} frames",
                num(o.duration),
                num(fps),
                num(frames)
            )
        }
    };
    invalid(
        "timeline.duration",
        format!(
            "duration × fps must give 1 to {MAX_FRAMES} frames {}",
            got(how)
        ),
    )
}

/// The keys with the file's interpolation and speed, after the checks constant speed needs.
fn keyed(t: &raw::Timeline, keys: Vec<Key>) -> Check<Keyed> {
    let interpolation = match t.interpolation.unwrap_or(raw::Interpolation::Smooth) {
        raw::Interpolation::Linear => Interpolation::Linear,
        raw::Interpolation::Smooth => Interpolation::Smooth,
    };
    let speed = match t.speed.unwrap_or(raw::Speed::Keys) {
        raw::Speed::Keys => Speed::Keys,
        raw::Speed::Constant => Speed::Constant,
    };
    if speed == Speed::Constant {
        constant_speed_keys(&keys)?;
    }
    Ok(Keyed::new(keys, interpolation, speed))
}

/// Constant speed times keys by distance, so each must move the camera and none may stop.
fn constant_speed_keys(keys: &[Key]) -> Check<()> {
    if keys.len() < 2 {
        return invalid(
            "timeline.speed",
            "`speed: constant` needs at least two keyframes",
        );
    }
    for (i, k) in keys.iter().enumerate() {
        if k.ease == Ease::Stop {
            return invalid(
                format!("timeline.keyframes[{i}].ease"),
                "a camera at constant speed never stops; remove `ease: stop` or `speed: constant`",
            );
        }
        if i > 0 && k.pose.position == keys[i - 1].pose.position {
            return invalid(
                format!("timeline.keyframes[{i}]"),
                format!(
                    "with `speed: constant` keys are passed in order of distance, so each needs its own position; keyframe {i} is where keyframe {} is (got {})",
                    i - 1,
                    k.pose.position
                ),
            );
        }
    }
    Ok(())
}

/// With an explicit duration, keys after the last frame are never seen.
fn unseen_keys(t: &Timeline, duration: f64) -> Vec<String> {
    let TimelinePath::Keys(k) = &t.path else {
        return Vec::new();
    };
    let last_frame = t.last_frame();
    let end = t.time_of(last_frame);
    let late: Vec<usize> = (0..k.keys.len())
        .filter(|&i| k.passes[i] > end + 1e-6 / t.fps)
        .collect();
    if late.is_empty() {
        return Vec::new();
    }
    let names: Vec<String> = late.iter().map(|i| i.to_string()).collect();
    let times: Vec<String> = late.iter().map(|&i| num(k.passes[i])).collect();
    let (noun, verb) = if late.len() == 1 {
        ("keyframe", "is")
    } else {
        ("keyframes", "are")
    };
    vec![format!(
        "timeline.duration: {} s at {} fps ends with frame {last_frame} (t = {} s), so {noun} {} (t = {} s) {verb} never shown; remove `duration` to end on the last keyframe",
        num(duration),
        t.fps_text(),
        num(end),
        names.join(", "),
        times.join(", ")
    )]
}

fn keyframes(keys: &[raw::Keyframe], camera: Option<Key>, frames: Frames) -> Check<Vec<Key>> {
    if keys.is_empty() {
        return invalid("timeline.keyframes", "needs at least one keyframe");
    }
    let mut out: Vec<Key> = Vec::with_capacity(keys.len());
    for (i, k) in keys.iter().enumerate() {
        let path = format!("timeline.keyframes[{i}]");
        let (time, field) = key_time(&path, (k.time, k.frame), frames)?;
        increasing(
            &format!("{path}.{field}"),
            "keyframe",
            i,
            out.last().map(|k| k.time),
            time,
        )?;
        let before = out.last().copied().or(camera);
        let pose = key_pose(&path, k, before.map(|b| b.pose))?;
        let ease = ease(&path, i, keys.len(), k.ease.as_deref())?;
        let aperture = match k.aperture {
            Some(a) => aperture(&format!("{path}.aperture"), a)?,
            None => before.map_or(0.0, |b| b.aperture),
        };
        let focus_distance = match k.focus_distance {
            Some(f) => Some(focus_distance(&format!("{path}.focus_distance"), f)?),
            None => before.and_then(|b| b.focus_distance),
        };
        out.push(Key {
            time,
            pose,
            ease,
            aperture,
            focus_distance,
        });
    }
    Ok(out)
}

/// A key's time in seconds, and the field that gave it: `time:` as a number, or a fraction
/// divided once in f64; or `frame:`, at exactly the time that frame shows (`Clock::time_of`).
pub(super) fn key_time(
    path: &str,
    (time, frame): (Option<raw::KeyTime>, Option<u64>),
    (clock, fps): Frames,
) -> Check<(f64, &'static str)> {
    let time = match (time, frame) {
        (Some(_), Some(_)) => {
            return invalid(
                format!("{path}.frame"),
                "give either `time:` (seconds) or `frame:` (a frame number), not both",
            );
        }
        (None, None) => {
            return invalid(
                path,
                "needs `time:` (seconds, e.g. 2.5 or 71/24) or `frame:` (a frame number)",
            );
        }
        (Some(raw::Amount::Number(s)), None) => s,
        (Some(raw::Amount::Fraction(num, den)), None) => num as f64 / den as f64,
        (None, Some(n)) if n < clock.first_frame => {
            return invalid(
                format!("{path}.frame"),
                format!(
                    "frame {n} is before the first frame, timeline.first_frame ({})",
                    clock.first_frame
                ),
            );
        }
        (None, Some(n)) => return Ok((clock.time_of(n, fps), "frame")),
    };
    Ok((number(&format!("{path}.time"), time)?, "time"))
}

/// A key's pose: given values, else the previous key's, else `camera:`'s. Ups are unit vectors
/// so that they interpolate by direction.
fn key_pose(path: &str, k: &raw::Keyframe, before: Option<Pose>) -> Check<Pose> {
    let field = |name: &str, v: Option<raw::V3>, carried: Option<DVec3>| -> Check<DVec3> {
        match (v, carried) {
            (Some(v), _) => vector(&format!("{path}.{name}"), v),
            (None, Some(c)) => Ok(c),
            (None, None) => invalid(
                path,
                format!("the first keyframe needs `{name}` (or give a `camera:` section)"),
            ),
        }
    };
    let up = match k.up {
        Some(v) => unit(&format!("{path}.up"), v)?,
        None => before.map_or(DVec3::Y, |p| p.up).normalize(),
    };
    Ok(Pose {
        position: field("position", k.position, before.map(|p| p.position))?,
        look_at: field(
            "look_at",
            k.look_at.as_ref().map(raw::Target::point),
            before.map(|p| p.look_at),
        )?,
        up,
        fov: match k.fov {
            Some(f) => fov(&format!("{path}.fov"), f)?,
            None => before.map_or(90.0, |p| p.fov),
        },
    })
}

/// Key `i` of a list (a `noun`) at `time` comes strictly after the one before, at `before`.
pub(super) fn increasing(
    path: &str,
    noun: &str,
    i: usize,
    before: Option<f64>,
    time: f64,
) -> Check<()> {
    match before {
        Some(prev) if time <= prev => invalid(
            path,
            format!(
                "{noun} times must increase strictly; {noun} {} is at {} {}",
                i - 1,
                num(prev),
                got_num(time)
            ),
        ),
        _ => Ok(()),
    }
}

/// `stop` or `pass`; the per-segment eases of earlier versions are refused with what to write.
pub(super) fn ease(path: &str, i: usize, count: usize, value: Option<&str>) -> Check<Ease> {
    let next = |what: &str| match i + 1 < count {
        true => format!("{what} and on keyframe {}", i + 1),
        false => what.to_string(),
    };
    let instead = match value {
        None | Some("pass") => return Ok(Ease::Pass),
        Some("stop") => return Ok(Ease::Stop),
        Some("linear") => "every key is passed through smoothly by default, so remove it".into(),
        Some("in") => "for the same slow start write `ease: stop` here".into(),
        Some("out") if i + 1 < count => format!(
            "for the same slow arrival remove it and write `ease: stop` on keyframe {}",
            i + 1
        ),
        Some("out") => "it never did anything on the last keyframe, so remove it".into(),
        Some("in-out") => format!("for the same slow-down write `ease: stop` {}", next("here")),
        Some(other) => {
            return invalid(
                format!("{path}.ease"),
                format!("unknown ease `{other}` (expected `stop` or `pass`)"),
            );
        }
    };
    let old = value.unwrap_or_default();
    invalid(
        format!("{path}.ease"),
        format!(
            "`{old}` is no longer an ease: ease now says how the camera meets this key (`stop` or `pass`, the default) and speed stays smooth through keys; {instead}"
        ),
    )
}

fn orbit(o: &raw::Orbit, camera: Option<Key>) -> Check<Orbit> {
    let p = "timeline.orbit";
    let center = vector(&format!("{p}.center"), o.center.point())?;
    Ok(Orbit {
        center,
        radius: positive(&format!("{p}.radius"), o.radius)?,
        height: number(&format!("{p}.height"), o.height)?,
        start_angle: number(&format!("{p}.start_angle"), o.start_angle)?,
        turns: number(&format!("{p}.turns"), o.turns.unwrap_or(1.0))?,
        duration: positive(&format!("{p}.duration"), o.duration)?,
        look_at: match &o.look_at {
            Some(v) => vector(&format!("{p}.look_at"), v.point())?,
            None => center,
        },
        up: match o.up {
            Some(v) => super::direction(&format!("{p}.up"), v)?,
            None => camera.map_or(DVec3::Y, |c| c.pose.up),
        },
        fov: match o.fov {
            Some(f) => fov(&format!("{p}.fov"), f)?,
            None => camera.map_or(90.0, |c| c.pose.fov),
        },
        aperture: camera.map_or(0.0, |c| c.aperture),
        focus_distance: camera.and_then(|c| c.focus_distance),
    })
}

/// Every key must make a camera, whatever the frames show.
fn check_keys(t: &Timeline) -> Check<()> {
    let TimelinePath::Keys(k) = &t.path else {
        return Ok(());
    };
    for (i, key) in k.keys.iter().enumerate() {
        super::check_pose(&format!("timeline.keyframes[{i}]"), &key.pose)?;
    }
    Ok(())
}

/// Interpolation can pass where no key is (a look-at flipping through up, a fov overshooting),
/// so every frame's camera is built once here rather than failing mid-render; with a shutter,
/// also the cameras at which it opens and closes (the instants between are built when the
/// frame renders, which fails that frame with the same message should one be impossible).
fn check_every_frame(t: &Timeline, shutter: Option<Shutter>) -> Check<()> {
    // Beyond this many frames the check would dominate loading; paths are smooth, so a dense
    // sample (every frame up to the limit, then evenly spaced) still finds any bad stretch.
    const FULL_CHECK: u64 = 1_000_000;
    let step = t.frame_count.div_ceil(FULL_CHECK).max(1);
    let mut previous: Option<(f64, Camera)> = None;
    for n in (t.first_frame()..=t.last_frame()).step_by(step as usize) {
        let frame_time = t.time_of(n);
        let times = match shutter {
            Some(s) => vec![
                s.instant(t.fps, frame_time, 0),
                frame_time,
                s.instant(t.fps, frame_time, INSTANTS - 1),
            ],
            None => vec![frame_time],
        };
        for time in times {
            let pose = t.camera_at(time);
            let camera = Camera::new(&pose).and_then(|c| match previous {
                Some(before) if rolls_over(t, before, (time, c)) => Err(Degenerate::Flip),
                _ => Ok(c),
            });
            match camera {
                Ok(c) => previous = Some((time, c)),
                Err(e) => return frame_problem(t, n, time, &pose, e),
            }
        }
    }
    Ok(())
}

/// Halvings of the time between two checked cameras at most, and the turn of the right vector
/// below which a piece is not halved again (its roll is then measured directly). A piece's
/// roll is measured well however small it is (a pass by up turns the right vector half round
/// while the view barely moves); halving only keeps a fast pan's pieces short enough that
/// carrying the right vector along the view's shortest turn follows the pan. Six halvings
/// resolve a pan of 320° a frame in 5° pieces and cost at most 127 cameras for a frame.
const ROLL_HALVINGS: u32 = 6;
const SMOOTH_TURN_DEGREES: f64 = 5.0;

/// Whether the camera rolls over between `a` and `b` (two checked cameras, each with its time):
/// its picture turns about the view axis by more than `MAX_ROLL_PER_FRAME_DEGREES`, as when
/// the view swings through or close by `up`. A right vector that turns that far may also be
/// a fast pan (a whip pan, or `fps: 0.5`), which is legitimate and renders; so only the roll is
/// counted: the turn of the right vector beyond the one that carrying it along the view's own
/// turn makes, summed over pieces of the interval small enough to turn smoothly.
pub(crate) fn rolls_over(t: &Timeline, a: (f64, Camera), b: (f64, Camera)) -> bool {
    let limit = MAX_ROLL_PER_FRAME_DEGREES.to_radians();
    a.1.right.dot(b.1.right) < libm::cos(limit) && roll(t, a, b, 0).abs() > limit
}

/// The signed roll, in radians about the view axis, from camera `a` to camera `b`.
fn roll(t: &Timeline, (ta, a): (f64, Camera), (tb, b): (f64, Camera), depth: u32) -> f64 {
    let mid = ta + 0.5 * (tb - ta);
    let smooth = a.right.dot(b.right) >= libm::cos(SMOOTH_TURN_DEGREES.to_radians());
    if smooth || depth == ROLL_HALVINGS || mid <= ta || mid >= tb {
        return piece_roll(&a, &b);
    }
    match Camera::new(&t.camera_at(mid)) {
        Ok(m) => roll(t, (ta, a), (mid, m), depth + 1) + roll(t, (mid, m), (tb, b), depth + 1),
        // The view passes through up itself.
        Err(_) => std::f64::consts::PI,
    }
}

/// The angle from `a`'s right vector, carried along the shortest turn of the view from `a`'s
/// forward to `b`'s (Rodrigues' rotation), to `b`'s right vector, about `b`'s forward.
fn piece_roll(a: &Camera, b: &Camera) -> f64 {
    let axis = a.forward.cross(b.forward);
    let (sin, cos) = (axis.length(), a.forward.dot(b.forward));
    if sin == 0.0 {
        return match cos > 0.0 {
            true => signed_angle(a.right, b.right, b.forward),
            false => std::f64::consts::PI,
        };
    }
    let k = axis / sin;
    let r = a.right;
    let carried = r * cos + k.cross(r) * sin + k * k.dot(r) * (1.0 - cos);
    signed_angle(carried, b.right, b.forward)
}

/// The angle from `u` to `v` about `axis`, in (−π, π].
fn signed_angle(u: DVec3, v: DVec3, axis: DVec3) -> f64 {
    libm::atan2(u.cross(v).dot(axis), u.dot(v))
}

/// The message for frame `n`, whose camera at `time` (its own time, or one while the shutter
/// is open) cannot be built.
fn frame_problem(t: &Timeline, n: u64, time: f64, pose: &Pose, e: Degenerate) -> Check<()> {
    let (path, between) = match &t.path {
        TimelinePath::Orbit(_) => ("timeline.orbit".to_string(), String::new()),
        TimelinePath::Keys(keyed) => {
            // A time at or past the last key is in the last interval (keys n−2 and n−1).
            let k = keyed
                .passes
                .partition_point(|&p| p <= time)
                .saturating_sub(1)
                .min(keyed.keys.len().saturating_sub(2));
            let next = (k + 1).min(keyed.keys.len() - 1);
            (
                format!("timeline.keyframes[{k}]"),
                format!(" between keyframes {k} and {next}"),
            )
        }
    };
    let frame_time = t.time_of(n);
    let when = if time == frame_time {
        format!("t = {} s", num(time))
    } else {
        format!(
            "t = {} s, shutter open at t = {} s",
            num(frame_time),
            num(time)
        )
    };
    invalid(
        path,
        format!(
            "frame {n} ({when}){between}: {e} (position {}, look_at {}, up {}, fov {})",
            super::num3(pose.position),
            super::num3(pose.look_at),
            super::num3(pose.up),
            num(pose.fov)
        ),
    )
}
