//! Sinks: where finished frames go. Encoders turn a frame into bytes without I/O; `atomic`
//! puts bytes under a final name only once they are complete on disk; `inspect` tells what an
//! existing frame file is, so a rerun can resume.

pub mod atomic;
pub mod exr;
pub mod fingerprint;
pub mod pattern;
pub mod png;
pub mod stream;

use crate::frame::Frame;
use std::path::Path;

/// The file format of the frames, with every option that changes their bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FileFormat {
    Png {
        sixteen_bit: bool,
        compression: png::Compression,
    },
    Exr {
        precision: exr::Precision,
    },
}

impl FileFormat {
    /// From the pattern's extension and the format flags.
    pub fn for_extension(
        ext: &str,
        sixteen_bit: bool,
        compression: png::Compression,
        precision: exr::Precision,
    ) -> Result<FileFormat, String> {
        match ext {
            "png" => Ok(FileFormat::Png {
                sixteen_bit,
                compression,
            }),
            "exr" => Ok(FileFormat::Exr { precision }),
            other => Err(format!(
                "unsupported file type `.{other}` (use .png or .exr)"
            )),
        }
    }

    /// A PNG frame's bit depth, colour type (2: RGB, 6: RGBA) and channels per pixel.
    pub fn png_layout(&self, alpha: bool) -> (u8, u8, u64) {
        let depth = match self {
            FileFormat::Png {
                sixteen_bit: true, ..
            } => 16,
            _ => 8,
        };
        if alpha { (depth, 6, 4) } else { (depth, 2, 3) }
    }
}

/// What a frame file records about itself.
#[derive(Debug, Clone)]
pub struct FrameMeta {
    pub frame: u64,
    pub time: f64,
    pub fps: f64,
    pub fingerprint: String,
    /// `worldToCamera` and `worldToNDC` (row-major, row vectors) when the frame has a camera.
    pub matrices: Option<[glam::DMat4; 2]>,
}

pub fn encode_file(
    frame: &Frame,
    format: &FileFormat,
    meta: &FrameMeta,
) -> Result<Vec<u8>, String> {
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

/// What is at a frame path before rendering.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Existing {
    Missing,
    /// A complete file written by rayreel, with its fingerprint.
    Ours(String),
    /// A file with our fingerprint whose image is not what this job would write (another size
    /// or format, missing or garbage pixels): corrupt if the fingerprint is this frame's,
    /// stale otherwise.
    Damaged {
        fingerprint: String,
        why: String,
    },
    /// A complete image without our fingerprint: someone else's, never overwritten unforced.
    Foreign,
    /// Truncated, damaged or not an image at all.
    Corrupt(String),
}

/// What a frame file of this job must be: its size and format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Expected {
    pub width: u32,
    pub height: u32,
    pub format: FileFormat,
    /// RGBA PNGs and an A channel in EXR.
    pub alpha: bool,
}

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
