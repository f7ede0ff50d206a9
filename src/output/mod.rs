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
pub(crate) mod stream;

pub(crate) use format::{Compression, EncodeError, ExrPrecision};
pub use format::{Existing, Expected, FileFormat};
pub(crate) use identity::{Files, FrameMeta, RunIdentity};

use crate::frame::Frame;
use std::path::Path;

/// The bytes of `frame`'s file in `format`, recording `meta`.
pub(crate) fn encode_file(
    frame: &Frame,
    format: &FileFormat,
    meta: &FrameMeta,
) -> Result<Vec<u8>, EncodeError> {
    match *format {
        FileFormat::Png {
            sixteen_bit,
            compression,
        } => {
            let text = [
                (fingerprint::KEY, meta.fingerprint.clone()),
                ("rayreel:frame", meta.frame.to_string()),
                ("rayreel:time", format!("{}", meta.time)),
            ];
            png::encode(frame, sixteen_bit, compression, &text)
        }
        FileFormat::Exr { precision } => exr::encode(frame, precision, meta),
    }
}

/// What the file at `path` is, against what this job would write there.
pub(crate) fn inspect(path: &Path, expected: &Expected) -> Existing {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Existing::Missing,
        Err(e) => return Existing::Corrupt(format!("unreadable: {e}")),
    };
    match expected.format {
        FileFormat::Png { .. } => png::inspect(&bytes, expected),
        FileFormat::Exr { .. } => exr::inspect(&bytes, expected),
    }
}
