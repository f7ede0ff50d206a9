//! A finished frame file read back as the bytes the raw stream carries for that frame, so
//! `--video` with `-o` encodes the frames on disk instead of rendering them again. A PNG's
//! pixels are the stream's bytes exactly (the same levels of the same frame; 16-bit values
//! turned from PNG's big-endian to the stream's little-endian). An EXR frame holds the linear
//! colour (premultiplied by A with alpha), which is encoded as the stream encodes a rendered
//! frame: from `--exr-precision float` files the bytes are the stream's exactly, from half
//! floats they may differ by the rounding to half.

use super::format::{Expected, FileFormat};
use crate::frame::Frame;
use crate::transfer::Encoding;
use std::path::Path;

/// The raw stream's bytes of the frame file at `path`: a file of `expected`'s size, format
/// and channels, or a message saying what it is instead.
pub(crate) fn raw_frame(
    path: &Path,
    expected: &Expected,
    encoding: Encoding,
) -> Result<Vec<u8>, String> {
    use crate::regular::{self, Links, Refused};
    let (file, meta) = regular::open(path, Links::Follow).map_err(|e| match e {
        Refused::Missing => "no such file".to_string(),
        Refused::NotRegular(what) => format!("{what}, not a regular file"),
        Refused::Io(e) => e.to_string(),
    })?;
    // Compositing passes may follow the colour in an EXR: room for them too.
    let limit = 8 * expected.max_file_bytes();
    let bytes = regular::read_at_most(&file, meta.len(), limit).map_err(|e| e.to_string())?;
    match expected.format {
        FileFormat::Png { sixteen_bit, .. } => png_bytes(&bytes, expected, sixteen_bit),
        FileFormat::Exr { .. } => exr_bytes(&bytes, expected, encoding),
    }
}

/// The PNG's pixels as stored (RGB or RGBA, 8 or 16 bits), 16-bit values little-endian.
fn png_bytes(bytes: &[u8], expected: &Expected, sixteen_bit: bool) -> Result<Vec<u8>, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("unreadable PNG: {e}"))?;
    let info = reader.info();
    let channels = if expected.alpha { 4 } else { 3 };
    let (colour, depth) = (info.color_type, info.bit_depth);
    let want_colour = match expected.alpha {
        true => png::ColorType::Rgba,
        false => png::ColorType::Rgb,
    };
    let want_depth = match sixteen_bit {
        true => png::BitDepth::Sixteen,
        false => png::BitDepth::Eight,
    };
    let size = (info.width, info.height);
    if size != (expected.width, expected.height) || colour != want_colour || depth != want_depth {
        return Err(format!(
            "it is {}x{} {colour:?} {depth:?}-bit, the video takes {}x{} {want_colour:?} {want_depth:?}-bit",
            size.0, size.1, expected.width, expected.height
        ));
    }
    let per_value = if sixteen_bit { 2 } else { 1 };
    let len = expected.width as usize * expected.height as usize * channels * per_value;
    let mut out = vec![0u8; reader.output_buffer_size().unwrap_or(len).max(len)];
    let frame = reader
        .next_frame(&mut out)
        .map_err(|e| format!("unreadable PNG: {e}"))?;
    out.truncate(frame.buffer_size());
    if out.len() != len {
        return Err("its image data is not the frame's size".into());
    }
    if sixteen_bit {
        out.chunks_exact_mut(2).for_each(|v| v.swap(0, 1));
    }
    Ok(out)
}

/// The EXR's R, G, B (and A) as a frame, encoded as the 8-bit stream encodes one (EXR frames
/// take no `--bit-depth 16`).
fn exr_bytes(bytes: &[u8], expected: &Expected, encoding: Encoding) -> Result<Vec<u8>, String> {
    use exr::prelude::*;
    type Pixels = (usize, Vec<[f32; 4]>);
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| -> Pixels { (res.width(), vec![[0f32; 4]; res.width() * res.height()]) },
            |(width, px): &mut Pixels, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                px[pos.y() * *width + pos.x()] = [r, g, b, a];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| format!("unreadable EXR: {e}"))?;
    let size = image.layer_data.size;
    if (size.width(), size.height()) != (expected.width as usize, expected.height as usize) {
        return Err(format!(
            "it is {}x{}, the video takes {}x{}",
            size.width(),
            size.height(),
            expected.width,
            expected.height
        ));
    }
    let pixels = image.layer_data.channel_data.pixels.1;
    let frame = Frame {
        width: expected.width,
        height: expected.height,
        rgb: pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect(),
        depth: None,
        alpha: expected
            .alpha
            .then(|| pixels.iter().map(|p| p[3]).collect()),
        aov: None,
        encoding,
        non_finite: 0,
        samples: 0,
        rays: 0,
        levels8: None,
    };
    Ok(frame.to_rgb8())
}
