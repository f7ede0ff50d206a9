//! OpenEXR frames: the linear, unclamped colour as R, G, B (half floats by default, 32-bit on
//! request), premultiplied by A when the frame has alpha, an optional Z channel (planar depth,
//! 1e10 for background, always 32-bit), ZIP compression, and header attributes for the
//! frame number, time, fps, fingerprint and the standard `worldToCamera` and `worldToNDC`.

use super::fingerprint;
use super::format::{EncodeError, Existing, Expected, ExrPrecision, FileFormat};
use super::identity::FrameMeta;
use crate::frame::Frame;
use exr::prelude::*;
use std::io::Cursor;

pub(crate) fn encode(
    frame: &Frame,
    precision: ExrPrecision,
    meta: &FrameMeta,
) -> std::result::Result<Vec<u8>, EncodeError> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let plane = |c: usize| -> Vec<f32> { frame.rgb.iter().skip(c).step_by(3).copied().collect() };
    let samples = |v: Vec<f32>| match precision {
        ExrPrecision::Half => FlatSamples::F16(v.into_iter().map(f16::from_f32).collect()),
        ExrPrecision::Float => FlatSamples::F32(v),
    };
    let mut channels = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for (name, c) in [("R", 0), ("G", 1), ("B", 2)] {
        channels.push(AnyChannel::new(name, samples(plane(c))));
    }
    if let Some(alpha) = &frame.alpha {
        channels.push(AnyChannel::new("A", samples(alpha.clone())));
    }
    if let Some(depth) = &frame.depth {
        channels.push(AnyChannel::new("Z", FlatSamples::F32(depth.clone())));
    }
    let mut attributes = LayerAttributes {
        frames_per_second: Some(rational(meta.fps)),
        ..LayerAttributes::default()
    };
    let other = &mut attributes.other;
    other.insert(
        Text::from(fingerprint::KEY),
        AttributeValue::Text(Text::from(meta.fingerprint.as_str())),
    );
    other.insert(
        Text::from("rayreel:frame"),
        AttributeValue::I32(i32::try_from(meta.frame).unwrap_or(i32::MAX)),
    );
    other.insert(Text::from("rayreel:time"), AttributeValue::F64(meta.time));
    if let Some([to_camera, to_ndc]) = meta.matrices {
        // glam's columns are the rows OpenEXR stores (row vectors).
        attributes.world_to_camera = Some(to_camera.to_cols_array().map(|v| v as f32));
        attributes.world_to_normalized_device = Some(to_ndc.to_cols_array().map(|v| v as f32));
    }
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new((w, h), attributes, encoding, AnyChannels::sort(channels));
    let mut out = Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut out)?;
    let mut bytes = out.into_inner();
    sort_attributes(&mut bytes)?;
    Ok(bytes)
}

/// The exr crate writes custom attributes in hash-map order, which differs from process to
/// process; same inputs must give the same bytes, so the header's attributes are put in name
/// order. The header keeps its length, so the offset table behind it stays valid.
fn sort_attributes(bytes: &mut [u8]) -> std::result::Result<(), EncodeError> {
    let spans = attribute_spans(bytes).ok_or(EncodeError::ExrHeader)?;
    let (start, end) = match (spans.first(), spans.last()) {
        (Some(first), Some(last)) => (first.0, last.1),
        _ => return Ok(()),
    };
    let name = |s: usize| bytes[s..].split(|&b| b == 0).next().unwrap_or_default();
    let mut sorted = spans;
    sorted.sort_by(|a, b| name(a.0).cmp(name(b.0)));
    let header: Vec<u8> = sorted
        .iter()
        .flat_map(|&(s, e)| bytes[s..e].to_vec())
        .collect();
    bytes[start..end].copy_from_slice(&header);
    Ok(())
}

/// Byte ranges of the header's attributes (name, type, size, value) of a single-part file.
fn attribute_spans(bytes: &[u8]) -> Option<Vec<(usize, usize)>> {
    let mut spans = Vec::new();
    let mut at = 8; // magic number and version
    loop {
        let attribute = attribute_at(bytes, at)?;
        if attribute.name.is_empty() {
            return Some(spans);
        }
        spans.push((at, attribute.end));
        at = attribute.end;
    }
}

/// One header attribute, as stored.
struct Attribute<'a> {
    name: &'a [u8],
    kind: &'a [u8],
    value: &'a [u8],
    /// Where the next one starts.
    end: usize,
}

/// The attribute that starts at `at` (an empty name: the header's end), or `None` when it
/// does not fit in `bytes`.
fn attribute_at(bytes: &[u8], at: usize) -> Option<Attribute<'_>> {
    let until_nul = |from: usize| -> Option<usize> {
        Some(from + bytes.get(from..)?.iter().position(|&b| b == 0)?)
    };
    let name_end = until_nul(at)?;
    let name = &bytes[at..name_end];
    if name.is_empty() {
        return Some(Attribute {
            name,
            kind: &[],
            value: &[],
            end: at + 1,
        });
    }
    let type_end = until_nul(name_end + 1)?;
    let size = bytes.get(type_end + 1..type_end + 5)?;
    let size = i32::from_le_bytes(size.try_into().ok()?);
    let end = type_end + 5 + usize::try_from(size).ok()?;
    Some(Attribute {
        name,
        kind: &bytes[name_end + 1..type_end],
        value: bytes.get(type_end + 5..end)?,
        end,
    })
}

/// The fingerprint attribute of an EXR header, read from the start of a file (the header is
/// its first few kilobytes); `None` when it is not an EXR file or has no such attribute there.
pub(crate) fn header_fingerprint(head: &[u8]) -> Option<String> {
    const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    if head.get(..4)? != MAGIC {
        return None;
    }
    let mut at = 8;
    loop {
        let attribute = attribute_at(head, at)?;
        if attribute.name.is_empty() {
            return None;
        }
        if attribute.name == fingerprint::KEY.as_bytes() && attribute.kind == b"string" {
            return Some(String::from_utf8_lossy(attribute.value).into_owned());
        }
        at = attribute.end;
    }
}

/// fps as a fraction, exact for whole and common NTSC-style rates.
fn rational(fps: f64) -> (i32, u32) {
    let den = if fps.fract() == 0.0 { 1 } else { 1000 };
    ((fps * f64::from(den)).round() as i32, den)
}

/// Reads the whole file (EXR has no checksums, so decoding every block is the check); a file
/// with our fingerprint must also have the job's size and colour channels.
pub(crate) fn inspect(bytes: &[u8], expected: &Expected) -> Existing {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes));
    let image = match image {
        Err(e) => return Existing::Corrupt(format!("unreadable EXR: {e}")),
        Ok(image) => image,
    };
    let layer = &image.layer_data;
    let Some(AttributeValue::Text(fingerprint)) =
        layer.attributes.other.get(&Text::from(fingerprint::KEY))
    else {
        return Existing::Foreign(super::png::NO_FINGERPRINT.into());
    };
    let (w, h) = (layer.size.width(), layer.size.height());
    if (w, h) != (expected.width as usize, expected.height as usize) {
        return Existing::Damaged {
            fingerprint: fingerprint.to_string(),
            why: format!(
                "the header says {w}x{h}; this job renders {}x{}",
                expected.width, expected.height
            ),
        };
    }
    let float = matches!(
        expected.format,
        FileFormat::Exr {
            precision: ExrPrecision::Float
        }
    );
    let colour = |name: &str| {
        layer.channel_data.list.iter().any(|c| {
            c.name == *name
                && matches!(
                    (&c.sample_data, float),
                    (FlatSamples::F32(_), true) | (FlatSamples::F16(_), false)
                )
        })
    };
    if expected.alpha && !colour("A") {
        return Existing::Damaged {
            fingerprint: fingerprint.to_string(),
            why: "no A channel".into(),
        };
    }
    if !["R", "G", "B"].into_iter().all(colour) {
        let kind = if float { "32-bit float" } else { "half" };
        return Existing::Damaged {
            fingerprint: fingerprint.to_string(),
            why: format!("no {kind} R, G and B channels"),
        };
    }
    Existing::Ours(fingerprint.to_string())
}
