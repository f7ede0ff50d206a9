//! Sinks: where finished frames go. `format` says what a frame file is; `identity` what names,
//! fingerprints and describes one frame's file (built once per frame); the encoders (`png`,
//! `exr`, `stream`) turn a frame into bytes without I/O; `atomic` puts bytes under a final
//! name only once they are complete on disk; `inspect` tells what an existing frame file is,
//! so a rerun can resume. The modules here depend on their siblings only, never on this one.

pub(crate) mod atomic;
pub(crate) mod exr;
pub(crate) mod fingerprint;
pub(crate) mod format;
pub(crate) mod identity;
pub mod png;
pub(crate) mod record;
pub(crate) mod reread;
pub(crate) mod stream;
pub(crate) mod video;

pub(crate) use format::{Compression, EncodeError, ExrPrecision};
pub use format::{Existing, Expected, FileFormat};
pub(crate) use identity::{Files, FrameMeta, RunIdentity};

use crate::frame::Frame;
use std::path::Path;

/// The bytes of `frame`'s file in `format`, recording `meta`, and how many colour samples
/// were beyond the largest half float and hold it instead (EXR half only).
pub(crate) fn encode_file(
    frame: &mut Frame,
    format: &FileFormat,
    meta: &FrameMeta,
) -> Result<(Vec<u8>, u64), EncodeError> {
    match *format {
        FileFormat::Png {
            sixteen_bit,
            compression,
        } => {
            let text = [
                (fingerprint::KEY, meta.fingerprint.clone()),
                ("rayreel:frame", meta.frame.to_string()),
                ("rayreel:time", format!("{}", meta.time)),
                (record::KEY, meta.record.clone()),
            ];
            Ok((png::encode(frame, sixteen_bit, compression, &text)?, 0))
        }
        FileFormat::Exr { precision } => exr::encode(frame, precision, meta),
    }
}

/// What the file at `path` is, against what this job would write there. Only a regular file
/// is read (anything else at a frame's name, a FIFO, a device, a directory or a link to one,
/// is someone else's and is left alone), without ever blocking, and only as far as a frame of
/// this job can reach: a larger file is judged by its header.
pub(crate) fn inspect(path: &Path, expected: &Expected) -> Existing {
    use crate::regular::{self, Links, Refused};
    let (file, meta) = match regular::open(path, Links::Follow) {
        Ok(opened) => opened,
        Err(Refused::Missing) => return Existing::Missing,
        Err(Refused::NotRegular(what)) => {
            return Existing::Foreign(format!("{what}, not a regular file"));
        }
        Err(Refused::Io(e)) => return Existing::Corrupt(format!("unreadable: {e}")),
    };
    let limit = expected.max_file_bytes();
    let want = match meta.len() > limit {
        true => HEADER_BYTES,
        false => limit + 1,
    };
    let bytes = match regular::read_at_most(&file, meta.len(), want) {
        Ok(b) => b,
        Err(e) => return Existing::Corrupt(format!("unreadable: {e}")),
    };
    let size = meta.len().max(bytes.len() as u64);
    if size > limit {
        return oversized(&bytes, size, limit, expected);
    }
    match expected.format {
        FileFormat::Png { .. } => png::inspect(&bytes, expected),
        FileFormat::Exr { .. } => exr::inspect(&bytes, expected),
    }
}

/// The settings record (`record::KEY`) in the header of the file at `path`, if it has one:
/// read again, and only for frames whose fingerprint differs, to say what differs.
pub(crate) fn read_record(path: &Path, format: &FileFormat) -> Option<String> {
    use crate::regular::{self, Links};
    let (file, meta) = regular::open(path, Links::Follow).ok()?;
    let head = regular::read_at_most(&file, meta.len(), HEADER_BYTES).ok()?;
    match format {
        FileFormat::Png { .. } => png::header_text(&head, record::KEY),
        FileFormat::Exr { .. } => exr::header_text(&head, record::KEY),
    }
}

/// How much of a file larger than any frame of the job is read: enough for the header, where
/// rayreel puts the fingerprint (before a PNG's image data, in an EXR's header).
const HEADER_BYTES: u64 = 64 << 10;

/// A file larger than any frame of this job, by the start of it: ours (an earlier job's,
/// larger frame: stale, or this frame's, damaged) when the header holds our fingerprint,
/// otherwise someone else's.
fn oversized(head: &[u8], size: u64, limit: u64, expected: &Expected) -> Existing {
    let fingerprint = match expected.format {
        FileFormat::Png { .. } => png::header_text(head, fingerprint::KEY),
        FileFormat::Exr { .. } => exr::header_text(head, fingerprint::KEY),
    };
    match fingerprint {
        Some(fingerprint) => Existing::Damaged {
            fingerprint,
            why: format!("{size} bytes, more than a frame of this job can take ({limit})"),
        },
        None => Existing::Foreign(format!(
            "{size} bytes, more than a frame of this job can take, and no rayreel fingerprint in its header"
        )),
    }
}
