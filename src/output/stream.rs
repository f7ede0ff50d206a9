//! Frame streams on stdout for ffmpeg: raw rgb24 / rgb48le bytes, or a sequence of PNGs.
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
pub fn ffmpeg_command(
    format: StreamFormat,
    sixteen_bit: bool,
    width: u32,
    height: u32,
    fps: f64,
) -> String {
    let input = match format {
        StreamFormat::Raw => format!(
            "-f rawvideo -pix_fmt {} -s {width}x{height} -r {fps}",
            if sixteen_bit { "rgb48le" } else { "rgb24" }
        ),
        StreamFormat::Png => format!("-f image2pipe -framerate {fps}"),
    };
    let pad = if width % 2 == 1 || height % 2 == 1 {
        " -vf pad=ceil(iw/2)*2:ceil(ih/2)*2"
    } else {
        ""
    };
    format!("ffmpeg {input} -i -{pad} -c:v libx264 -pix_fmt yuv420p out.mp4")
}
