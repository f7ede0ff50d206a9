//! PNG encoding: 8- or 16-bit RGB (RGBA with alpha, straight as PNG requires) in the frame's
//! encoding, tagged for colour management (sRGB: `sRGB` with the matching `gAMA` and `cHRM`
//! for readers that know only those; linear: `gAMA` 1.0), with the fingerprint in a tEXt
//! chunk ahead of the image data; and the check of an existing file.

use super::fingerprint;
pub use super::format::Compression;
use super::format::{EncodeError, Existing, Expected};
use crate::frame::Frame;
use crate::transfer::Encoding;
use png::{ScaledFloat, SourceChromaticities};

pub(crate) fn encode(
    frame: &mut Frame,
    sixteen_bit: bool,
    compression: Compression,
    text: &[(&str, String)],
) -> Result<Vec<u8>, EncodeError> {
    let mut out = Vec::with_capacity(frame.rgb.len() / 2);
    let mut enc = png::Encoder::new(&mut out, frame.width, frame.height);
    enc.set_color(match frame.alpha {
        Some(_) => png::ColorType::Rgba,
        None => png::ColorType::Rgb,
    });
    tag_colour(&mut enc, frame.encoding);
    enc.set_compression(match compression {
        Compression::Fast => png::Compression::Fast,
        Compression::Default => png::Compression::Balanced,
        Compression::Best => png::Compression::High,
    });
    for (key, value) in text {
        enc.add_text_chunk(key.to_string(), value.clone())?;
    }
    let data: Vec<u8> = if sixteen_bit {
        enc.set_depth(png::BitDepth::Sixteen);
        frame
            .to_rgb16()
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect()
    } else {
        enc.set_depth(png::BitDepth::Eight);
        frame.take_rgb8()
    };
    let mut writer = enc.write_header()?;
    writer.write_image_data(&data)?;
    writer.finish()?;
    if !sixteen_bit {
        crate::frame::recycle_bytes(data);
    }
    Ok(out)
}

/// The colour chunks: sRGB's are written (before PLTE/IDAT, as required) with the gAMA and
/// cHRM values the PNG specification gives as its fallback; linear values are gamma 1.0 in
/// the same primaries.
fn tag_colour<W: std::io::Write>(enc: &mut png::Encoder<W>, encoding: Encoding) {
    let chroma = |(x, y): (u32, u32)| (ScaledFloat::from_scaled(x), ScaledFloat::from_scaled(y));
    enc.set_source_chromaticities(SourceChromaticities {
        white: chroma((31270, 32900)),
        red: chroma((64000, 33000)),
        green: chroma((30000, 60000)),
        blue: chroma((15000, 6000)),
    });
    match encoding {
        Encoding::Srgb => {
            enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            enc.set_source_gamma(ScaledFloat::from_scaled(45455));
        }
        Encoding::Linear => enc.set_source_gamma(ScaledFloat::from_scaled(100_000)),
    }
}

/// Walks the chunks of a PNG file checking every CRC: intact without our fingerprint
/// (foreign), or corrupt. A file with our fingerprint must also have the job's header (size,
/// bit depth, colour type, no interlace) and image data that inflates to exactly the bytes
/// that header needs, or it is damaged: valid checksums around missing or garbage pixels do
/// not make a frame done.
pub fn inspect(bytes: &[u8], expected: &Expected) -> Existing {
    let chunks = match walk(bytes) {
        Ok(chunks) => chunks,
        Err(why) => return Existing::Corrupt(why),
    };
    let Some(fingerprint) = chunks.fingerprint else {
        return Existing::Foreign(NO_FINGERPRINT.into());
    };
    match check_header(chunks.header, expected).and_then(|rows| check_data(&chunks.data, rows)) {
        Ok(()) => Existing::Ours(fingerprint),
        Err(why) => Existing::Damaged { fingerprint, why },
    }
}

/// What the chunk walk found.
struct Chunks<'a> {
    header: &'a [u8],
    fingerprint: Option<String>,
    /// The IDAT chunks' contents, in order: one zlib stream.
    data: Vec<&'a [u8]>,
}

/// Why a complete image counts as someone else's.
pub(crate) const NO_FINGERPRINT: &str = "not written by rayreel (no fingerprint)";

const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

fn walk(bytes: &[u8]) -> Result<Chunks<'_>, String> {
    let rest = bytes.strip_prefix(SIGNATURE).ok_or("not a PNG file")?;
    let mut found = Chunks {
        header: &[],
        fingerprint: None,
        data: Vec::new(),
    };
    let mut first = true;
    for chunk in chunks(rest) {
        let (kind, data) = chunk?;
        if first && kind != b"IHDR" {
            return Err("no PNG header".into());
        }
        match kind {
            b"IHDR" if first => found.header = data,
            b"IDAT" => found.data.push(data),
            b"IEND" => return Ok(found),
            b"tEXt" => {
                if let Some(f) = text_value(data, fingerprint::KEY) {
                    found.fingerprint = Some(f);
                }
            }
            _ => {}
        }
        first = false;
    }
    Err("truncated".into())
}

/// The text under `key` (our fingerprint or settings record) among the chunks ahead of the
/// image data, read from the start of a file (rayreel writes them there, so the first
/// kilobytes are enough); `None` when a checksum fails or the image data comes first.
pub(crate) fn header_text(head: &[u8], key: &str) -> Option<String> {
    for chunk in chunks(head.strip_prefix(SIGNATURE)?) {
        match chunk.ok()? {
            (b"IDAT" | b"IEND", _) => return None,
            (b"tEXt", data) => {
                if let Some(f) = text_value(data, key) {
                    return Some(f);
                }
            }
            _ => {}
        }
    }
    None
}

/// The value of a `tEXt` chunk with the keyword `key`.
fn text_value(data: &[u8], key: &str) -> Option<String> {
    let value = data.strip_prefix(key.as_bytes())?.strip_prefix(b"\0")?;
    Some(String::from_utf8_lossy(value).into_owned())
}

/// The chunks after the signature, each (type, data) once its CRC is checked, or why the
/// walk cannot go on; they end where fewer bytes than a chunk's framing (12) remain.
fn chunks(bytes: &[u8]) -> impl Iterator<Item = Result<(&[u8], &[u8]), String>> {
    let mut rest = Some(bytes);
    std::iter::from_fn(move || {
        let r = rest.take().filter(|r| r.len() >= 12)?;
        let len = u32::from_be_bytes(r[..4].try_into().expect("4 bytes")) as usize;
        if r.len() - 12 < len {
            return Some(Err("truncated".into()));
        }
        let (kind, data) = (&r[4..8], &r[8..8 + len]);
        let crc = u32::from_be_bytes(r[8 + len..12 + len].try_into().expect("4 bytes"));
        let mut h = crc32fast::Hasher::new();
        h.update(kind);
        h.update(data);
        if h.finalize() != crc {
            return Some(Err(format!(
                "bad checksum in a {} chunk",
                String::from_utf8_lossy(kind)
            )));
        }
        rest = Some(&r[12 + len..]);
        Some(Ok((kind, data)))
    })
}

/// The header against the job; returns the length of one filtered row and the row count.
fn check_header(header: &[u8], expected: &Expected) -> Result<(u64, u64), String> {
    let [
        w0,
        w1,
        w2,
        w3,
        h0,
        h1,
        h2,
        h3,
        depth,
        color,
        _,
        _,
        interlace,
    ] = *header
    else {
        return Err(format!("a PNG header of {} bytes", header.len()));
    };
    let (w, h) = (
        u32::from_be_bytes([w0, w1, w2, w3]),
        u32::from_be_bytes([h0, h1, h2, h3]),
    );
    let (want_depth, want_color, channels) = expected.format.png_layout(expected.alpha);
    if (w, h) != (expected.width, expected.height) {
        return Err(format!(
            "the header says {w}x{h}; this job renders {}x{}",
            expected.width, expected.height
        ));
    }
    if (depth, color) != (want_depth, want_color) {
        return Err(format!(
            "the header says {depth}-bit {}; this job writes {want_depth}-bit {}",
            color_name(color),
            color_name(want_color)
        ));
    }
    if interlace != 0 {
        return Err("the image is interlaced; rayreel never writes that".into());
    }
    let row = 1 + u64::from(w) * channels * u64::from(depth / 8);
    Ok((row, u64::from(h)))
}

fn color_name(color: u8) -> &'static str {
    match color {
        0 => "grey",
        2 => "RGB",
        3 => "palette",
        4 => "grey+alpha",
        6 => "RGBA",
        _ => "unknown colour type",
    }
}

/// The zlib stream of the IDAT chunks inflates, with a valid checksum, to exactly
/// `rows` rows of `row` bytes (a filter byte and the pixels). Inflated through a small
/// window, so checking a huge frame takes no memory to speak of.
fn check_data(data: &[&[u8]], (row, rows): (u64, u64)) -> Result<(), String> {
    const WINDOW: usize = 32 << 10;
    let want = row * rows;
    let stream: Vec<u8> = data.concat();
    let mut input = stream.as_slice();
    let mut inflater = fdeflate::Decompressor::new();
    let mut out = vec![0u8; 4 * WINDOW];
    let (mut at, mut total) = (0usize, 0u64);
    while !inflater.is_done() {
        let (used, made) = inflater
            .read(input, &mut out, at, true)
            .map_err(|e| format!("the image data does not inflate: {e:?}"))?;
        (input, at, total) = (&input[used..], at + made, total + made as u64);
        if total > want {
            return Err(format!(
                "the image data holds more than the {want} bytes it should"
            ));
        }
        if used == 0 && made == 0 && !inflater.is_done() {
            return Err(format!(
                "the image data stops after {total} of {want} bytes"
            ));
        }
        if at > out.len() - WINDOW {
            // Keep the last 32 KiB, all that deflate may refer back to.
            out.copy_within(at - WINDOW..at, 0);
            at = WINDOW;
        }
    }
    if total != want {
        return Err(format!("the image data holds {total} of {want} bytes"));
    }
    Ok(())
}
