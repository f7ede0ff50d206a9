//! The contact sheet: a few frames rendered small at draft depth, `columns = ceil(sqrt(N))`
//! tiles per row, each with its frame number and time underneath.

use super::*;

pub(super) const SHEET_BACKGROUND: Rgb<u8> = Rgb([34, 34, 38]);

pub(super) const SHEET_TEXT: Rgb<u8> = Rgb([235, 235, 235]);

pub(super) const SHEET_DIM: Rgb<u8> = Rgb([150, 150, 160]);

pub(super) const SHEET_GAP: u32 = 8;

pub(super) const SHEET_HEADER: u32 = 34;

pub(super) const LABEL_STRIP: u32 = 24;

/// Where the tiles of a contact sheet go: `columns = ceil(sqrt(tiles))`, row by row, with a
/// header line on top and a label strip under every tile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SheetLayout {
    pub columns: u32,
    pub rows: u32,
    pub(crate) tile_w: u32,
    pub(crate) tile_h: u32,
    pub width: u32,
    pub height: u32,
}

impl SheetLayout {
    pub fn new(tiles: usize, tile_w: u32, tile_h: u32) -> SheetLayout {
        let tiles = tiles.max(1) as u32;
        let columns = (f64::from(tiles).sqrt().ceil() as u32).max(1);
        let rows = tiles.div_ceil(columns);
        SheetLayout {
            columns,
            rows,
            tile_w,
            tile_h,
            width: SHEET_GAP + columns * (tile_w + SHEET_GAP),
            height: SHEET_HEADER + rows * (tile_h + LABEL_STRIP + SHEET_GAP),
        }
    }

    /// Top-left pixel of tile `k`.
    pub fn origin(&self, k: usize) -> (u32, u32) {
        let (col, row) = (k as u32 % self.columns, k as u32 / self.columns);
        (
            SHEET_GAP + col * (self.tile_w + SHEET_GAP),
            SHEET_HEADER + row * (self.tile_h + LABEL_STRIP + SHEET_GAP),
        )
    }
}

/// (frame, x, y): which frame a contact-sheet tile shows and its top-left pixel.
pub type TileOrigin = (u64, u32, u32);

/// Renders `frames` at draft quality, `tile_w` pixels wide, into one picture; returns it with
/// each tile's (frame, x, y) origin.
pub fn contact_sheet(
    seq: &Sequence,
    frames: &[u64],
    tile_w: u32,
) -> Result<(RgbImage, Vec<TileOrigin>), PreviewError> {
    let count = seq.timeline.frame_count;
    if frames.is_empty() {
        return Err(PreviewError::NoFrames);
    }
    if let Some(&frame) = frames.iter().find(|&&n| n >= count) {
        let last = count - 1;
        return Err(PreviewError::OutsideTimeline { frame, last });
    }
    let tile_h = tile_height(seq, tile_w);
    let small = draft(seq, tile_w, tile_h);
    let layout = SheetLayout::new(frames.len(), tile_w, tile_h);
    let mut img = RgbImage::from_pixel(layout.width, layout.height, SHEET_BACKGROUND);
    sheet_header(
        &mut img,
        seq,
        frames.len(),
        tile_w,
        tile_h,
        small.settings.max_depth,
    );
    let mut origins = Vec::with_capacity(frames.len());
    let world = World::new(small.scene.clone());
    for (k, &n) in frames.iter().enumerate() {
        let (x, y) = layout.origin(k);
        match render_with(&world, &small, n, &small.settings) {
            Ok(frame) => paste(&mut img, &frame.to_rgb8(), (x, y), (tile_w, tile_h)),
            // An invalid path (see `sequence::load_drawable`) has frames with no camera.
            Err(_) => no_camera(&mut img, (x, y), (tile_w, tile_h)),
        }
        tile_label(&mut img, seq, n, (x, y + tile_h), tile_w);
        origins.push((n, x, y));
    }
    Ok((img, origins))
}

pub(super) fn sheet_header(
    img: &mut RgbImage,
    seq: &Sequence,
    tiles: usize,
    w: u32,
    h: u32,
    depth: u32,
) {
    let mut c = Canvas::whole(img);
    let t = &seq.timeline;
    let head = format!("{}: {tiles} of {} frames", seq.name, t.frame_count);
    let x = c.text(SHEET_GAP as i64, 10, &head, 2, SHEET_TEXT);
    let note = format!("   draft {w}x{h}, max_depth {depth}");
    c.text(x, 10, &note, 2, SHEET_DIM);
}

/// Copies rgb8 bytes of a `size` picture into `img` at `at`.
pub(super) fn paste(img: &mut RgbImage, pixels: &[u8], at: (u32, u32), size: (u32, u32)) {
    for row in 0..size.1 {
        for col in 0..size.0 {
            let i = 3 * (row * size.0 + col) as usize;
            let p = Rgb([pixels[i], pixels[i + 1], pixels[i + 2]]);
            img.put_pixel(at.0 + col, at.1 + row, p);
        }
    }
}

/// A red tile saying that this frame has no camera.
pub(super) fn no_camera(img: &mut RgbImage, at: (u32, u32), size: (u32, u32)) {
    let (x, y) = (i64::from(at.0), i64::from(at.1));
    let rect = Rect::new(x, y, x + i64::from(size.0), y + i64::from(size.1));
    let mut c = Canvas::new(img, rect);
    c.fill(Rgb([90, 20, 20]));
    c.text(x + 6, y + 6, "no camera", 2, SHEET_TEXT);
}

/// `12  0.50s` under a tile: the number bright, the time dimmer, clipped to the tile's width.
pub(super) fn tile_label(img: &mut RgbImage, seq: &Sequence, n: u64, at: (u32, u32), w: u32) {
    let (x, y) = (i64::from(at.0), i64::from(at.1));
    let clip = Rect::new(x, y, x + i64::from(w), y + i64::from(LABEL_STRIP));
    let mut c = Canvas::new(img, clip);
    let after = c.text(x + 2, y + 5, &n.to_string(), 2, SHEET_TEXT);
    let time = format!("  {:.2}s", seq.timeline.time_of(n));
    c.text(after, y + 5, &time, 2, SHEET_DIM);
}
