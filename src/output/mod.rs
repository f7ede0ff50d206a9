//! Sinks: where finished frames go. `format` says what a frame file is; `identity` what names,
//! fingerprints and describes one frame's file (built once per frame); the encoders (`png`,
//! `exr`, `stream`) turn a frame into bytes without I/O; `atomic` puts bytes under a final
//! name only once they are complete on disk; `inspect` tells what an existing frame file is,
//! so a rerun can resume. The modules here depend on their siblings only, never on this one.

pub mod atomic;
pub mod exr;
pub mod fingerprint;
pub mod format;
pub mod identity;
pub mod png;
pub mod stream;

pub use format::{
    Compression, EncodeError, Existing, Expected, ExrPrecision, FileFormat, UnsupportedType,
};
pub use identity::{Files, FrameMeta, RunIdentity};

use crate::frame::Frame;
use std::path::Path;

/// The bytes of `frame`'s file in `format`, recording `meta`.
pub fn encode_file(
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
pub fn inspect(path: &Path, expected: &Expected) -> Existing {
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
