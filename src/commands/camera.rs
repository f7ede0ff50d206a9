//! `rayreel camera FILE [--format csv|json] [--frames SPEC]`: every frame's camera on stdout,
//! for compositing tools and for checking a path by numbers. Numbers are printed in their
//! shortest form that reads back as the same f64, so a still camera given a printed pose
//! renders that frame exactly.

use super::{Error, print_warnings};
use crate::cli::{CameraArgs, CameraFormat};
use crate::sequence::{self, Sequence};
use glam::DVec3;
use std::io::Write;

const CSV_HEADER: &str = "frame,time,position_x,position_y,position_z,look_at_x,look_at_y,look_at_z,up_x,up_y,up_z,fov,speed,focus_distance";

pub(crate) fn camera(args: CameraArgs) -> Result<(), Error> {
    let seq = sequence::load(&args.file)?;
    print_warnings(&seq);
    let (first, last) = (seq.timeline.first_frame(), seq.timeline.last_frame());
    let frames = match &args.frames {
        Some(spec) => spec
            .frames(first, last)
            .map_err(|e| Error::Usage(format!("--frames: {e}")))?,
        None => crate::frameset::FrameSet::range(first, last, 1),
    };
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let mut lines = frames.iter().map(|n| line(&seq, n, args.format));
    let header = (args.format == CameraFormat::Csv).then(|| CSV_HEADER.to_string());
    let written = header
        .into_iter()
        .chain(&mut lines)
        .try_for_each(|l| writeln!(out, "{l}"))
        .and_then(|()| out.flush());
    match written {
        // The reader stopped early (`| head`): a normal end.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Error::Failed(format!("stdout: {e}"))),
        Ok(()) => Ok(()),
    }
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
