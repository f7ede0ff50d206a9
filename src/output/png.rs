//! PNG encoding: 8-bit (round(255 · clamp(c, 0, 1)), no gamma, as the talk) or 16-bit, with
//! the fingerprint in a tEXt chunk ahead of the image data; and the check of an existing file.

use super::{Existing, fingerprint};
use crate::frame::Frame;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Compression {
    /// Quick deflate: the default, so encoding never holds back rendering.
    Fast,
    /// The png crate's balanced level.
    Default,
    /// Smallest files, slowest.
    Best,
}

pub fn encode(
    frame: &Frame,
    sixteen_bit: bool,
    compression: Compression,
    text: &[(&str, String)],
) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(frame.rgb.len() / 2);
    let mut enc = png::Encoder::new(&mut out, frame.width, frame.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_compression(match compression {
        Compression::Fast => png::Compression::Fast,
        Compression::Default => png::Compression::Balanced,
        Compression::Best => png::Compression::High,
    });
    for (key, value) in text {
        enc.add_text_chunk(key.to_string(), value.clone())
            .map_err(|e| e.to_string())?;
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
        frame.to_rgb8()
    };
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(&data).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(out)
}

/// Walks the chunks of a PNG file and checks every CRC (no decompression, so checking a
/// directory of frames is fast): intact with our fingerprint, intact without, or damaged.
pub fn inspect(bytes: &[u8]) -> Existing {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    let Some(mut rest) = bytes.strip_prefix(SIGNATURE) else {
        return Existing::Corrupt("not a PNG file".into());
    };
    let mut fingerprint = None;
    let mut first = true;
    while rest.len() >= 12 {
        let len = u32::from_be_bytes(rest[..4].try_into().expect("4 bytes")) as usize;
        if rest.len() < 12 + len {
            return Existing::Corrupt("truncated".into());
        }
        let (kind, data) = (&rest[4..8], &rest[8..8 + len]);
        let crc = u32::from_be_bytes(rest[8 + len..12 + len].try_into().expect("4 bytes"));
        let mut h = crc32fast::Hasher::new();
        h.update(kind);
        h.update(data);
        if h.finalize() != crc {
            return Existing::Corrupt(format!(
                "bad checksum in a {} chunk",
                String::from_utf8_lossy(kind)
            ));
        }
        if first && kind != b"IHDR" {
            return Existing::Corrupt("no PNG header".into());
        }
        first = false;
        if kind == b"tEXt"
            && let Some(value) = data
                .strip_prefix(fingerprint::KEY.as_bytes())
                .and_then(|v| v.strip_prefix(b"\0"))
        {
            fingerprint = Some(String::from_utf8_lossy(value).into_owned());
        }
        if kind == b"IEND" {
            return match fingerprint {
                Some(f) => Existing::Ours(f),
                None => Existing::Foreign,
            };
        }
        rest = &rest[12 + len..];
    }
    Existing::Corrupt("truncated".into())
}
