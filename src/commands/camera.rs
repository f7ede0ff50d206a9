//! `rayreel camera FILE [--format csv|json|chan] [--frames SPEC]`: every frame's camera (or,
//! with `--object`/`--light`, a moving thing's poses: `poses`) on stdout, for compositing tools and for checking a path by numbers. Numbers are printed in
//! their shortest form that reads back as the same f64, so a still camera given a printed pose
//! renders that frame exactly. `chan` is Nuke's channel file (`chan`, below).

use super::{Error, poses, print_warnings};
use crate::camera::Camera;
use crate::cli::{CameraArgs, CameraFormat};
use crate::frameset::FrameSet;
use crate::sequence::{self, Sequence};
use glam::DVec3;
use std::io::Write;

const CSV_HEADER: &str = "frame,time,position_x,position_y,position_z,look_at_x,look_at_y,look_at_z,up_x,up_y,up_z,fov,speed,focus_distance";

pub(crate) fn camera(args: CameraArgs) -> Result<(), Error> {
    let seq = sequence::load_with(&args.file, &super::assets(&args.assets)?)?;
    print_warnings(&seq);
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    let frames = match &args.frames {
        Some(spec) => spec
            .frames(first, last)
            .map_err(|e| Error::Usage(format!("--frames: {e}")))?,
        None => FrameSet::range(first, last, 1),
    };
    let lines = match poses::find(&seq, args.object.as_deref(), args.light)? {
        Some(rig) => poses::lines(&seq, rig, &frames, args.format)?,
        None => camera_lines(&seq, &frames, args.format),
    };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let written = lines
        .iter()
        .try_for_each(|l| writeln!(out, "{l}"))
        .and_then(|()| out.flush());
    match written {
        // The reader stopped early (`| head`): a normal end.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Error::Failed(format!("stdout: {e}"))),
        Ok(()) => Ok(()),
    }
}

/// The camera's lines over `frames` (a CSV header first).
fn camera_lines(seq: &Sequence, frames: &FrameSet, format: CameraFormat) -> Vec<String> {
    // chan's angles continue from the line before (see `unwrap`).
    let mut before = None;
    let header = (format == CameraFormat::Csv).then(|| CSV_HEADER.to_string());
    let lines = frames.iter().map(|n| match format {
        CameraFormat::Chan => chan_line(seq, n, &mut before),
        format => line(seq, n, format),
    });
    header.into_iter().chain(lines).collect()
}

/// Frame n as one CSV or JSON line.
fn line(seq: &Sequence, n: u64, format: CameraFormat) -> String {
    let t = seq.timeline.time_of(n);
    let (pose, lens) = seq.timeline.view_at(t);
    let speed = seq.timeline.speed_at(t);
    let focus = lens.focus_distance;
    let (position, look_at, up) = (pose.position, pose.look_at, pose.up);
    match format {
        CameraFormat::Csv => {
            let v = |v: DVec3| format!("{:?},{:?},{:?}", v.x, v.y, v.z);
            format!(
                "{n},{t:?},{},{},{},{:?},{speed:?},{focus:?}",
                v(position),
                v(look_at),
                v(up),
                pose.fov
            )
        }
        CameraFormat::Chan => chan_line(seq, n, &mut None),
        CameraFormat::Json => {
            let v = |v: DVec3| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z);
            format!(
                "{{\"frame\": {n}, \"time\": {t:?}, \"position\": {}, \"look_at\": {}, \"up\": {}, \"fov\": {:?}, \"speed\": {speed:?}, \"focus_distance\": {focus:?}}}",
                v(position),
                v(look_at),
                v(up),
                pose.fov
            )
        }
    }
}

/// Frame n as a line of Nuke's channel file: `frame tx ty tz rx ry rz vfov`. Translation is
/// the camera position; rotations are Euler angles in degrees for Nuke's default order ZXY
/// (world_from_camera = Ry·Rx·Rz, column vectors: roll about z first, then tilt about x, then
/// pan about y), of the camera frame whose columns are right, up and −forward (Nuke's camera,
/// like rayreel's, is y up and looks down −z); vfov is the vertical field of view in degrees
/// for the file's render size. A pose whose camera cannot be built (never rendered) prints
/// zero rotations. Pan and roll continue from `before`, the line printed before (`unwrap`),
/// which this line's angles then replace.
fn chan_line(seq: &Sequence, n: u64, before: &mut Option<[f64; 3]>) -> String {
    let (pose, _) = seq.timeline.view_at(seq.timeline.time_of(n));
    let [rx, ry, rz] = match Camera::new(&pose) {
        Ok(c) => unwrap(zxy_degrees(c.forward, c.up), *before),
        Err(_) => [0.0; 3],
    };
    *before = Some([rx, ry, rz]);
    let (width, height) = (seq.settings.width, seq.settings.height);
    let s = libm::tan(pose.fov.to_radians() * 0.5) * f64::from(height) / f64::from(width);
    let vfov = (2.0 * libm::atan(s)).to_degrees();
    // `+ 0.0` turns −0 into 0: a channel file has no use for the sign of zero.
    let [x, y, z, rx, ry, rz] = [
        pose.position.x,
        pose.position.y,
        pose.position.z,
        rx,
        ry,
        rz,
    ]
    .map(|v| v + 0.0);
    format!("{n} {x:?} {y:?} {z:?} {rx:?} {ry:?} {rz:?} {vfov:?}")
}

/// Pan and roll each moved by the whole turns that bring them nearest the line before's, as
/// Nuke's and Blender's exporters do, so that importers interpolating between frames turn the
/// short way (an orbit's pan goes 172.5, 180, 187.5, not 172.5, 180, −172.5). The tilt, in
/// [−90, 90], never wraps. The first line's angles are as `zxy_degrees` gives them.
pub(super) fn unwrap([rx, ry, rz]: [f64; 3], before: Option<[f64; 3]>) -> [f64; 3] {
    let Some([_, py, pz]) = before else {
        return [rx, ry, rz];
    };
    let near = |v: f64, p: f64| v + 360.0 * ((p - v) / 360.0).round();
    [rx, near(ry, py), near(rz, pz)]
}

/// Euler angles (rx, ry, rz) in degrees with Ry(ry)·Rx(rx)·Rz(rz) = [right, up, −forward]:
/// rx = asin(forward.y) (tilt), ry = atan2(−forward.x, −forward.z) (pan), and rz (roll) from
/// where `up` lies in the plane the pan and tilt leave it. Looking straight up or down
/// (forward.x and forward.z both zero), the pan is 0 and the roll takes the rest. Pan and
/// roll are in (−180, 180]: a half turn is 180, never −180.
pub(crate) fn zxy_degrees(forward: DVec3, up: DVec3) -> [f64; 3] {
    let rx = libm::asin(forward.y.clamp(-1.0, 1.0));
    // atan2(±0, ±0) is 0 or ±π by the zeros' signs: straight up or down, the pan is 0.
    let ry = match forward.x == 0.0 && forward.z == 0.0 {
        true => 0.0,
        false => libm::atan2(-forward.x, -forward.z),
    };
    let (sx, cx, sy, cy) = (libm::sin(rx), libm::cos(rx), libm::sin(ry), libm::cos(ry));
    // Rz·ŷ = (−sin rz, cos rz, 0) in the frame Ry·Rx leaves: its x and y axes in world space.
    let x_axis = DVec3::new(cy, 0.0, -sy);
    let y_axis = DVec3::new(sx * sy, cx, sx * cy);
    let rz = libm::atan2(-up.dot(x_axis), up.dot(y_axis));
    // atan2 gives −π for a −0 first argument (a camera on −z looking at the origin, up −y):
    // the documented range is (−180, 180], so a half turn reads 180.
    [rx, ry, rz]
        .map(f64::to_degrees)
        .map(|d| if d <= -180.0 { d + 360.0 } else { d })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pose;
    use glam::DMat3;

    #[test]
    fn zxy_angles_rebuild_the_camera_frame() {
        let cases = [
            (DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, DVec3::Y),
            (
                DVec3::new(3.0, 2.0, -1.0),
                DVec3::new(0.5, -1.0, 4.0),
                DVec3::Y,
            ),
            (
                DVec3::new(-2.0, 5.0, 0.3),
                DVec3::ZERO,
                DVec3::new(0.3, 1.0, -0.2),
            ),
            (DVec3::new(0.0, 4.0, 0.0), DVec3::ZERO, DVec3::Z),
            (DVec3::ZERO, DVec3::new(0.0, 4.0, 0.0), DVec3::Z),
            (DVec3::ZERO, DVec3::new(-0.0, -4.0, -0.0), DVec3::NEG_X),
        ];
        for (position, look_at, up) in cases {
            let pose = Pose {
                position,
                look_at,
                up,
                fov: 60.0,
            };
            let c = Camera::new(&pose).unwrap();
            let [rx, ry, rz] = zxy_degrees(c.forward, c.up).map(f64::to_radians);
            let m = DMat3::from_rotation_y(ry)
                * DMat3::from_rotation_x(rx)
                * DMat3::from_rotation_z(rz);
            let (rot, _) = c.world_from_camera();
            for (a, b) in [
                (m.x_axis, rot.x_axis),
                (m.y_axis, rot.y_axis),
                (m.z_axis, rot.z_axis),
            ] {
                assert!((a - b).length() < 1e-12, "{position}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn straight_up_or_down_the_pan_is_zero_and_angles_unwrap() {
        for (look, up) in [
            (DVec3::Y, DVec3::Z),
            (DVec3::new(-0.0, -1.0, -0.0), DVec3::NEG_Z),
        ] {
            let [_, ry, _] = zxy_degrees(look, up);
            assert_eq!(ry, 0.0);
        }
        // Half turns read 180: pan from (0, 0, −5) to the origin, roll with up −y, and
        // straight down with up +z.
        let [_, ry, rz] = zxy_degrees(DVec3::new(0.0, 0.0, 1.0), DVec3::NEG_Y);
        assert_eq!((ry, rz), (180.0, 180.0));
        let [_, ry, rz] = zxy_degrees(DVec3::new(-0.0, -1.0, -0.0), DVec3::Z);
        assert_eq!((ry, rz), (0.0, 180.0));
        assert_eq!(
            unwrap([1.0, -172.5, 10.0], Some([0.0, 180.0, 0.0])),
            [1.0, 187.5, 10.0]
        );
        assert_eq!(unwrap([1.0, 170.0, -350.0], None), [1.0, 170.0, -350.0]);
        assert_eq!(
            unwrap([0.0, 5.0, 0.0], Some([0.0, 725.0, -3.0])),
            [0.0, 725.0, 0.0]
        );
    }
}
