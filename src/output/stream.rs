//! Frame streams on stdout for ffmpeg: raw rgb24 / rgb48le bytes (rgba / rgba64le with
//! alpha), or a sequence of PNGs.
//! Nothing but frame bytes is ever written here.

use super::png::{self, Compression};
use crate::frame::Frame;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum StreamFormat {
    /// Raw rgb24 (rgb48le with --bit-depth 16), for `ffmpeg -f rawvideo`.
    Raw,
    /// Concatenated PNGs, for `ffmpeg -f image2pipe`.
    Png,
}

pub fn encode(frame: &Frame, format: StreamFormat, sixteen_bit: bool) -> Result<Vec<u8>, String> {
    match (format, sixteen_bit) {
        (StreamFormat::Raw, false) => Ok(frame.to_rgb8()),
        (StreamFormat::Raw, true) => Ok(frame
            .to_rgb16()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()),
        (StreamFormat::Png, _) => png::encode(frame, sixteen_bit, Compression::Fast, &[]),
    }
}

/// The ffmpeg command that reads this stream and makes an H.264 video.
/// The stream's pixels as ffmpeg names them.
pub fn pix_fmt(sixteen_bit: bool, alpha: bool) -> &'static str {
    match (sixteen_bit, alpha) {
        (false, false) => "rgb24",
        (true, false) => "rgb48le",
        (false, true) => "rgba",
        (true, true) => "rgba64le",
    }
}

/// The ffmpeg command that reads this stream: H.264 for colour, or (with alpha, which
/// H.264 cannot carry) ProRes 4444 with its alpha channel.
pub fn ffmpeg_command(
    format: StreamFormat,
    (sixteen_bit, alpha): (bool, bool),
    width: u32,
    height: u32,
    fps: f64,
) -> String {
    let input = match format {
        StreamFormat::Raw => format!(
            "-f rawvideo -pix_fmt {} -s {width}x{height} -r {fps}",
            pix_fmt(sixteen_bit, alpha)
        ),
        StreamFormat::Png => format!("-f image2pipe -framerate {fps}"),
    };
    let pad = if width % 2 == 1 || height % 2 == 1 {
        " -vf pad=ceil(iw/2)*2:ceil(ih/2)*2"
    } else {
        ""
    };
    match alpha {
        true => format!(
            "ffmpeg {input} -i - -c:v prores_ks -profile:v 4444 -pix_fmt yuva444p10le out.mov"
        ),
        false => format!("ffmpeg {input} -i -{pad} -c:v libx264 -pix_fmt yuv420p out.mp4"),
    }
}
