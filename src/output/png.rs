//! PNG encoding of a frame: 8-bit RGB, round(255 · clamp(c, 0, 1)), no gamma.

use crate::frame::Frame;

pub fn encode(frame: &Frame) -> Result<Vec<u8>, png::EncodingError> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, frame.width, frame.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    let mut writer = enc.write_header()?;
    writer.write_image_data(&frame.to_rgb8())?;
    writer.finish()?;
    Ok(out)
}
