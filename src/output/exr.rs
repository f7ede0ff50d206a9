//! OpenEXR frames: the linear, unclamped colour as R, G, B (half floats by default, 32-bit on
//! request; beyond the largest half, 65504, a half holds 65504), premultiplied by A when the
//! frame has alpha, an optional Z channel (planar depth, 1e10 for background, always 32-bit),
//! ZIP compression, and header attributes for the frame number, time, fps (an exact
//! fraction), fingerprint and the standard `worldToCamera` and `worldToNDC`.

use super::fingerprint;
use super::format::{EncodeError, Existing, Expected, ExrPrecision, FileFormat};
use super::identity::FrameMeta;
use crate::frame::Frame;
use exr::prelude::*;
use std::io::Cursor;

/// The largest finite half float.
pub(crate) const MAX_HALF: f32 = 65504.0;

/// The file's bytes, and how many colour samples were beyond the largest half float and hold
/// it instead (half precision only; +Inf would poison every filter downstream).
pub(crate) fn encode(
    frame: &Frame,
    precision: ExrPrecision,
    meta: &FrameMeta,
) -> std::result::Result<(Vec<u8>, u64), EncodeError> {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let plane = |c: usize| -> Vec<f32> { frame.rgb.iter().skip(c).step_by(3).copied().collect() };
    let clamped = std::cell::Cell::new(0u64);
    let half = |v: f32| {
        if v.abs() > MAX_HALF {
            clamped.set(clamped.get() + 1);
            return f16::from_f32(v.clamp(-MAX_HALF, MAX_HALF));
        }
        f16::from_f32(v)
    };
    let samples = |v: Vec<f32>| match precision {
        ExrPrecision::Half => FlatSamples::F16(v.into_iter().map(half).collect()),
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
    // Passes are always 32-bit: ids, positions and motion must be exact.
    for (name, values) in frame.aov.iter().flat_map(|p| &p.channels) {
        channels.push(AnyChannel::new(*name, FlatSamples::F32(values.clone())));
    }
    let attributes = attributes(meta, frame);
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
    Ok((bytes, clamped.get()))
}

/// The header attributes that say what the frame is: its rate, number, time, fingerprint,
/// settings record, object id table and camera matrices.
fn attributes(meta: &FrameMeta, frame: &Frame) -> LayerAttributes {
    let mut attributes = LayerAttributes {
        frames_per_second: Some(meta.fps),
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
    other.insert(
        Text::from(super::record::KEY),
        AttributeValue::Text(Text::from(meta.record.as_str())),
    );
    if let Some(passes) = frame.aov.as_ref().filter(|p| has_ids(p)) {
        other.insert(
            Text::from(OBJECTS_KEY),
            AttributeValue::Text(Text::from(passes.objects.as_str())),
        );
    }
    if let Some([to_camera, to_ndc]) = meta.matrices {
        // glam's columns are the rows OpenEXR stores (row vectors).
        attributes.world_to_camera = Some(to_camera.to_cols_array().map(|v| v as f32));
        attributes.world_to_normalized_device = Some(to_ndc.to_cols_array().map(|v| v as f32));
    }
    attributes
}

/// The header attribute holding the table of object ids (`tracer::aov::objects`).
pub(crate) const OBJECTS_KEY: &str = "rayreel:objectIds";

fn has_ids(p: &crate::frame::Passes) -> bool {
    p.channels.iter().any(|c| c.0 == "objectId")
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

/// The string attribute `key` (our fingerprint or settings record) of an EXR header, read from
/// the start of a file (the header is its first few kilobytes); `None` when it is not an EXR
/// file or has no such attribute there.
pub(crate) fn header_text(head: &[u8], key: &str) -> Option<String> {
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
        if attribute.name == key.as_bytes() && attribute.kind == b"string" {
            return Some(String::from_utf8_lossy(attribute.value).into_owned());
        }
        at = attribute.end;
    }
}

/// `framesPerSecond` as OpenEXR stores it, an i32 over a u32: the exact fraction in lowest
/// terms when it fits, otherwise the closest one that fits (by continued fractions). A fraction
/// in the file (`30000/1001`) is taken as written; a decimal (`23.976`) as the shortest decimal
/// that reads back as the same f64, which is the number as written up to 15 significant
/// digits. A rate under 1/(2·(2³² − 1)), whose closest fraction would be 0, is stored as
/// 1/(2³² − 1), the smallest positive one.
pub(crate) fn frames_per_second(fps: f64, fraction: Option<(u64, u64)>) -> (i32, u32) {
    const SMALLEST: (i32, u32) = (1, u32::MAX);
    if fps.is_nan() || fps <= 0.5 / f64::from(u32::MAX) {
        return SMALLEST;
    }
    let exact = match fraction {
        Some((num, den)) => Some((u128::from(num), u128::from(den))),
        None => decimal(fps),
    };
    if let Some(stored) = exact.and_then(|(n, d)| fits(n, d)) {
        return stored;
    }
    let (num, den) = match fraction {
        Some((num, den)) => (u128::from(num), u128::from(den)),
        None => binary(fps),
    };
    let g = gcd(num, den);
    match closest(num / g, den / g, (MAX_NUM, MAX_DEN)) {
        (0, _) => SMALLEST,
        (num, den) => (num as i32, den as u32),
    }
}

/// The largest numerator and denominator `framesPerSecond` can hold.
const MAX_NUM: u128 = i32::MAX as u128;
const MAX_DEN: u128 = u32::MAX as u128;

/// `num/den` in lowest terms, if that fits.
fn fits(num: u128, den: u128) -> Option<(i32, u32)> {
    let g = gcd(num, den);
    let (num, den) = (num / g, den / g);
    (num <= MAX_NUM && den <= MAX_DEN).then_some((num as i32, den as u32))
}

fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.max(1)
}

/// The decimal `{}` prints for `v` (its shortest round-trip form) as a fraction, when both
/// parts fit in a u128.
fn decimal(v: f64) -> Option<(u128, u128)> {
    let text = format!("{v}");
    let (whole, frac) = text.split_once('.').unwrap_or((&text, ""));
    let digits = format!("{whole}{frac}");
    let digits = digits.trim_start_matches('0');
    if digits.len() > 38 || frac.len() > 38 {
        return None;
    }
    let num = if digits.is_empty() {
        0
    } else {
        digits.parse().ok()?
    };
    Some((num, 10u128.pow(frac.len() as u32)))
}

/// `v` (positive and normal, at most 1000, at least 2⁻³³) exactly: its mantissa over a power
/// of two.
fn binary(v: f64) -> (u128, u128) {
    let bits = v.to_bits();
    let mantissa = u128::from(bits & ((1 << 52) - 1) | (1 << 52));
    let exponent = ((bits >> 52) & 0x7ff) as i32 - 1075;
    match exponent {
        e if e >= 0 => (mantissa << e, 1),
        e => (mantissa, 1 << -e),
    }
}

/// The fraction closest to `p/q` (in lowest terms, too large to store) with a numerator and
/// denominator within `max_num` and `max_den`: the last convergent of its continued fraction that fits, or the
/// largest semiconvergent after it that fits, whichever is closer (the convergent on a tie).
fn closest(p: u128, q: u128, (max_num, max_den): (u128, u128)) -> (u128, u128) {
    let (mut h0, mut k0, mut h1, mut k1) = (0u128, 1u128, 1u128, 0u128);
    let (mut a, mut b) = (p, q);
    loop {
        let t = a / b;
        let next = |h: u128, h0: u128| t.checked_mul(h).and_then(|x| x.checked_add(h0));
        match (next(h1, h0), next(k1, k0)) {
            (Some(h2), Some(k2)) if h2 <= max_num && k2 <= max_den => {
                (h0, k0, h1, k1) = (h1, k1, h2, k2);
                if a % b == 0 {
                    return (h1, k1);
                }
                (a, b) = (b, a % b);
            }
            _ => {
                if k1 == 0 {
                    return (max_num, 1);
                }
                let s = [
                    (max_num - h0).checked_div(h1),
                    (max_den - k0).checked_div(k1),
                ]
                .into_iter()
                .flatten()
                .min()
                .unwrap_or(t)
                .min(t);
                if s == 0 {
                    return (h1, k1);
                }
                return nearer(p, q, (h1, k1), (s * h1 + h0, s * k1 + k0));
            }
        }
    }
}

/// Whichever of `x` and `y` is nearer to `p/q`; `x` on a tie.
fn nearer(p: u128, q: u128, x: (u128, u128), y: (u128, u128)) -> (u128, u128) {
    // |p/q − h/k| = |p·k − h·q| / (q·k): compare |p·kx − hx·q|·ky with |p·ky − hy·q|·kx.
    let off = |(h, k): (u128, u128)| Some(p.checked_mul(k)?.abs_diff(h.checked_mul(q)?));
    let exact = (|| Some((off(x)?.checked_mul(y.1)?, off(y)?.checked_mul(x.1)?)))();
    let y_nearer = match exact {
        Some((dx, dy)) => dy < dx,
        None => {
            let v = p as f64 / q as f64;
            let d = |(h, k): (u128, u128)| (v - h as f64 / k as f64).abs();
            d(y) < d(x)
        }
    };
    if y_nearer { y } else { x }
}

/// The most channels a file is decoded with: every channel rayreel writes (R, G, B, A, Z and
/// every compositing pass), since every channel costs a plane of the job's size to decode.
const MAX_CHANNELS: usize = crate::output::format::MOST_EXR_CHANNELS as usize;

/// The verdict on a file from its header alone, when the header already decides it: decoding
/// allocates what the header claims (a 920-byte file claiming 262144×3 pixels in 4 channels
/// asked for 2 GB, found by the `frame_files` fuzzer), so a file is only decoded when every
/// part is single, of the job's size, and has few channels.
fn judged_by_header(bytes: &[u8], expected: &Expected) -> Option<Existing> {
    let meta = match exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false) {
        Err(e) => return Some(Existing::Corrupt(format!("unreadable EXR: {e}"))),
        Ok(meta) => meta,
    };
    let header = meta.headers.first()?;
    let fingerprint = match header
        .own_attributes
        .other
        .get(&Text::from(fingerprint::KEY))
    {
        Some(AttributeValue::Text(f)) => f.to_string(),
        _ => return Some(Existing::Foreign(super::png::NO_FINGERPRINT.into())),
    };
    let (w, h) = (header.layer_size.width(), header.layer_size.height());
    let why = if meta.headers.len() != 1 {
        format!("{} parts; rayreel writes one", meta.headers.len())
    } else if (w, h) != (expected.width as usize, expected.height as usize) {
        format!(
            "the header says {w}x{h}; this job renders {}x{}",
            expected.width, expected.height
        )
    } else if header.channels.list.len() > MAX_CHANNELS {
        format!("{} channels", header.channels.list.len())
    } else {
        return None;
    };
    Some(Existing::Damaged { fingerprint, why })
}

/// Reads the whole file (EXR has no checksums, so decoding every block is the check); a file
/// with our fingerprint must also have the job's size and colour channels.
pub(crate) fn inspect(bytes: &[u8], expected: &Expected) -> Existing {
    if let Some(verdict) = judged_by_header(bytes, expected) {
        return verdict;
    }
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
    let float = expected.format
        == (FileFormat::Exr {
            precision: ExrPrecision::Float,
        });
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_rates_are_exact_fractions_or_the_closest_that_fit() {
        assert_eq!(frames_per_second(24.0, None), (24, 1));
        assert_eq!(frames_per_second(0.5, None), (1, 2));
        assert_eq!(frames_per_second(23.976, None), (2997, 125));
        assert_eq!(frames_per_second(29.97, None), (2997, 100));
        assert_eq!(frames_per_second(0.001, None), (1, 1000));
        let ntsc = 30000.0 / 1001.0;
        assert_eq!(frames_per_second(ntsc, Some((30000, 1001))), (30000, 1001));
        assert_eq!(frames_per_second(ntsc, Some((60000, 2002))), (30000, 1001));
        // Too many digits to fit: the closest fraction that does, no farther than 30000/1001.
        let (n, d) = frames_per_second(ntsc, None);
        let off = |n: i32, d: u32| (f64::from(n) / f64::from(d) - ntsc).abs();
        assert!(off(n, d) <= off(30000, 1001), "{n}/{d}");
        // A fraction beyond i32 over u32: the closest that fits.
        let (n, d) = frames_per_second(30.0000000005, Some((60_000_000_001, 2_000_000_000)));
        assert!(
            n > 0 && (f64::from(n) / f64::from(d) - 30.0000000005).abs() < 1e-9,
            "{n}/{d}"
        );
        // Against every fraction within small bounds: none is closer.
        for (p, q) in [
            (314159, 100000),
            (2, 7),
            (1000, 999),
            (7, 1000),
            (355, 113),
            (61, 60),
        ] {
            for bounds in [(50, 40), (40, 50), (7, 3), (1000, 1), (3, 997)] {
                let (h, k) = closest(p, q, bounds);
                assert!(
                    h <= bounds.0 && (1..=bounds.1).contains(&k),
                    "{p}/{q} {bounds:?}"
                );
                let off = |h: u128, k: u128| (p * k).abs_diff(h * q) as f64 / k as f64;
                for k2 in 1..=bounds.1 {
                    for h2 in 0..=bounds.0 {
                        assert!(
                            off(h, k) <= off(h2, k2) * (1.0 + 1e-12),
                            "{p}/{q} {bounds:?}: {h}/{k} but {h2}/{k2}"
                        );
                    }
                }
            }
        }
        assert_eq!(nearer(2, 7, (1, 3), (1, 4)), (1, 4));
        assert_eq!(nearer(1, 2, (0, 1), (1, 1)), (0, 1));
        // Nothing is 0 fps: below half the smallest step, the smallest positive fraction.
        assert_eq!(frames_per_second(1e-300, None), (1, u32::MAX));
        assert_eq!(frames_per_second(1e-10, None), (1, u32::MAX));
        assert_eq!(frames_per_second(1.0 / 3e9, None), (1, 3_000_000_000));
    }
}
