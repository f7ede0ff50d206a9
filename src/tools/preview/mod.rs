//! `rayreel preview FILE`: two pictures to check a sequence before spending hours rendering it.
//!
//! * The **path plot** shows the scene from above (x across, z down) and from the side (z
//!   across, y up), each panel to scale (one scale for both of its axes). Spheres are discs in
//!   their material's colour; planes and giant spheres (a floor of radius 9000) would cover
//!   everything, so they are drawn as the solid region they cut from the panel's slice plane,
//!   which passes through the camera path's mean height (top) or mean x (side). On top: the
//!   camera at every frame (a polyline, with dots when they are far enough apart to show
//!   speed), numbered keyframes, look-at targets, view-direction ticks, start, end and lights,
//!   and the paths of objects and lights that move.
//!   Frames where the camera is inside a sphere, behind a plane or rolling over are red and
//!   come back as warnings.
//! * The **contact sheet** renders a few frames small at draft depth, `columns = ceil(sqrt(N))`
//!   tiles per row, each with its frame number and time underneath.
//!
//! Everything is drawn with plain pixel writes and a built-in 5×7 font, so the preview needs
//! no font or plotting crate and is byte-identical everywhere.

mod canvas;
mod checks;
mod draw;
mod font;
mod panel;
mod path_plot;
mod plot;
mod sheet;
mod speed;
mod style;

use canvas::*;
use checks::*;
use draw::*;
use font::*;
use panel::*;
use plot::*;
use style::*;

pub use crate::frameset::evenly_spaced;
pub use panel::{Panel, panels};
pub use path_plot::path_plot;
pub use sheet::{SheetLayout, TileOrigin, contact_sheet};
pub use style::{BAD, LIGHT_PATH, OBJECT_PATH, PATH};

use crate::camera::{Camera, Pose};
use crate::scene::{Material, Shape};
use crate::schedule::render_with;
use crate::sequence::Sequence;
use crate::timeline::motion::{Posed, Thing};
use crate::timeline::{Path as TimelinePath, Timeline};
use crate::tracer::World;
use glam::DVec3;
use image::{Rgb, RgbImage};
use std::path::{Path, PathBuf};

/// Why a preview picture could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    #[error("no frames to put on the contact sheet")]
    NoFrames,
    #[error("frame {frame} is outside the timeline, which has frames 0-{last}")]
    OutsideTimeline { frame: u64, last: u64 },
    #[error("{}: cannot encode: {source}", path.display())]
    Encode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Default number of contact-sheet tiles.
pub(crate) const DEFAULT_TILES: u64 = 12;
/// Most tiles one sheet holds: beyond this the picture stops being a glance.
pub(crate) const MAX_TILES: u64 = 400;
/// Default tile width in pixels; the height follows the sequence's aspect ratio.
pub const TILE_WIDTH: u32 = 256;

// ---------------------------------------------------------------------------------------------
// How small

/// The sequence as the contact sheet renders it: the draft preset (1 sample, 2 surfaces per
/// path, which keeps reflections visible but cheap) at `tile_w`×`tile_h` pixels, opaque (the
/// sheet shows the background), in the file's encoding and exposure.
pub fn draft(seq: &Sequence, tile_w: u32, tile_h: u32) -> Sequence {
    let mut d = seq.clone();
    crate::sequence::preset(
        &mut d.settings,
        crate::sequence::Quality::Draft,
        crate::sequence::Film::Pinhole,
    );
    d.settings.width = tile_w;
    d.settings.height = tile_h;
    d.settings.alpha = false;
    d
}

/// The tile height for `tile_w` with the sequence's aspect ratio, rounded, at least 1.
pub fn tile_height(seq: &Sequence, tile_w: u32) -> u32 {
    let (w, h) = (
        f64::from(seq.settings.width),
        f64::from(seq.settings.height),
    );
    ((f64::from(tile_w) * h / w).round() as u32).max(1)
}

/// Encodes `img` as PNG and writes it atomically (a complete file or none) to `path`.
pub(crate) fn write_png(path: &Path, img: &RgbImage) -> Result<(), PreviewError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    let path_buf = || path.to_path_buf();
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|source| PreviewError::Encode {
            path: path_buf(),
            source,
        })?;
    crate::output::atomic::write_atomic(path, bytes.get_ref()).map_err(|source| {
        PreviewError::Write {
            path: path_buf(),
            source,
        }
    })
}
