//! What a frame file is: its format with every option that changes its bytes, what a job
//! expects the file at a frame path to be, and what is found there. The encoders, the
//! fingerprint and the resume check all speak of files in these terms.

/// PNG compression level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Compression {
    /// Quick deflate: the default, so encoding never holds back rendering.
    Fast,
    /// The png crate's balanced level.
    Default,
    /// Smallest files, slowest.
    Best,
}

/// The float precision of the R, G, B (and A) channels of EXR files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum ExrPrecision {
    /// 16-bit half floats.
    Half,
    /// 32-bit floats.
    Float,
}

/// The file format of the frames, with every option that changes their bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FileFormat {
    Png {
        sixteen_bit: bool,
        compression: Compression,
    },
    Exr {
        precision: ExrPrecision,
    },
}

impl FileFormat {
    /// From the pattern's extension and the format flags.
    pub(crate) fn for_extension(
        ext: &str,
        sixteen_bit: bool,
        compression: Compression,
        precision: ExrPrecision,
    ) -> Result<FileFormat, UnsupportedType> {
        match ext {
            "png" => Ok(FileFormat::Png {
                sixteen_bit,
                compression,
            }),
            "exr" => Ok(FileFormat::Exr { precision }),
            other => Err(UnsupportedType(other.to_string())),
        }
    }

    /// A PNG frame's bit depth, colour type (2: RGB, 6: RGBA) and channels per pixel.
    pub(crate) fn png_layout(&self, alpha: bool) -> (u8, u8, u64) {
        let depth = match self {
            FileFormat::Png {
                sixteen_bit: true, ..
            } => 16,
            _ => 8,
        };
        if alpha { (depth, 6, 4) } else { (depth, 2, 3) }
    }
}

/// A frame file extension rayreel does not write.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unsupported file type `.{0}` (use .png or .exr)")]
pub(crate) struct UnsupportedType(pub(crate) String);

/// Why a frame could not be turned into the bytes of a file or of the stream.
#[derive(Debug, thiserror::Error)]
pub enum EncodeError {
    #[error(transparent)]
    Png(#[from] png::EncodingError),
    #[error(transparent)]
    Exr(#[from] exr::error::Error),
    /// The EXR header as written could not be parsed again to sort its attributes.
    #[error("the EXR header could not be read back")]
    ExrHeader,
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

/// The compositing passes' channels, all of them: 32-bit floats.
const PASS_CHANNELS: u64 = {
    let mut n = 0;
    let mut i = 0;
    while i < crate::settings::Aov::ALL.len() {
        n += crate::settings::Aov::ALL[i].channels();
        i += 1;
    }
    n
};

/// The most channels an EXR frame of rayreel's has: R, G, B, A, Z and every pass.
pub(crate) const MOST_EXR_CHANNELS: u64 = 5 + PASS_CHANNELS;

impl Expected {
    /// The most bytes a frame file of this job can take: twice its samples uncompressed (a
    /// frame's channels at most — in EXR every channel rayreel may write, passes included —
    /// with a filter byte per PNG row; no encoder doubles its input) and 1 MiB for
    /// signatures, headers, chunk and block framing and metadata.
    pub fn max_file_bytes(&self) -> u64 {
        let per_pixel = match self.format {
            FileFormat::Png { .. } => {
                let (depth, _, channels) = self.format.png_layout(self.alpha);
                channels * u64::from(depth / 8)
            }
            // R, G, B and A in the colour precision, a 32-bit Z and 32-bit passes.
            FileFormat::Exr { precision } => match precision {
                ExrPrecision::Half => 4 * 2 + 4 + 4 * PASS_CHANNELS,
                ExrPrecision::Float => 4 * 4 + 4 + 4 * PASS_CHANNELS,
            },
        };
        let (w, h) = (u64::from(self.width), u64::from(self.height));
        2 * (w * h * per_pixel + h) + (1 << 20)
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
    /// Someone else's, never overwritten unforced: a complete image without our fingerprint,
    /// or something that is not a regular file (why, in words).
    Foreign(String),
    /// Truncated, damaged or not an image at all.
    Corrupt(String),
}
