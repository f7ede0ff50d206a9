//! The two panels of the path plot: world coordinates ↔ pixels, one scale per panel.

use super::*;

pub(super) const PANEL_H: u32 = 600;

pub(super) const PANEL_MIN_W: u32 = 380;

pub(super) const PANEL_MAX_W: u32 = 860;

/// Inner padding, so markers and labels at the edge of the fitted box stay inside.
pub(super) const PAD: f64 = 34.0;

pub(super) const MARGIN: u32 = 20;

pub(super) const TITLE_H: u32 = 40;

pub(super) const CAPTION_H: u32 = 26;

pub(super) const PANEL_GAP: u32 = 24;

pub(super) const LEGEND_ROW: u32 = 26;

pub(super) const WARNING_ROW: u32 = 20;

/// Warnings written into the picture; the rest are only counted (all go to stderr).
pub(super) const MAX_WARNING_LINES: usize = 4;

/// One panel of the path plot: a pixel rectangle showing two world axes at one scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Panel {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    /// World axis shown left to right (0 = x, 1 = y, 2 = z).
    pub(crate) across: usize,
    /// World axis shown vertically.
    pub(crate) down: usize,
    /// Whether `down` grows downwards on screen (the top view's z) rather than up (side's y).
    pub(crate) flipped: bool,
    /// Pixels per scene unit, the same on both axes.
    pub scale: f64,
    /// World (across, down) coordinates at the panel's centre.
    pub(crate) centre: (f64, f64),
    /// Where the slice plane for planes and giant spheres cuts the third axis.
    pub(crate) slice: f64,
}

impl Panel {
    /// Pixel coordinates of `p` (continuous: pixel (i, j) covers [i, i+1) × [j, j+1)).
    pub fn to_px(&self, p: DVec3) -> (f64, f64) {
        let (a, b) = (p[self.across] - self.centre.0, p[self.down] - self.centre.1);
        let sign = if self.flipped { 1.0 } else { -1.0 };
        (
            f64::from(self.x) + f64::from(self.width) / 2.0 + a * self.scale,
            f64::from(self.y) + f64::from(self.height) / 2.0 + sign * b * self.scale,
        )
    }

    /// The point on the slice plane under pixel position (x, y).
    pub(super) fn world_at(&self, x: f64, y: f64) -> DVec3 {
        let sign = if self.flipped { 1.0 } else { -1.0 };
        let a = (x - f64::from(self.x) - f64::from(self.width) / 2.0) / self.scale;
        let b = sign * (y - f64::from(self.y) - f64::from(self.height) / 2.0) / self.scale;
        let mut p = DVec3::splat(self.slice);
        p[self.across] = self.centre.0 + a;
        p[self.down] = self.centre.1 + b;
        p
    }

    /// The axis the panel looks along.
    pub(super) fn depth_axis(&self) -> usize {
        3 - self.across - self.down
    }

    /// +1 when larger coordinates along the depth axis are nearer the viewer.
    pub(super) fn toward_viewer(&self) -> f64 {
        // Right-handed: right × up points at the viewer.
        let (mut r, mut u) = (DVec3::ZERO, DVec3::ZERO);
        r[self.across] = 1.0;
        u[self.down] = if self.flipped { -1.0 } else { 1.0 };
        r.cross(u)[self.depth_axis()]
    }

    pub(super) fn rect(&self) -> Rect {
        let (x, y) = (i64::from(self.x), i64::from(self.y));
        Rect::new(x, y, x + i64::from(self.width), y + i64::from(self.height))
    }

    pub(super) fn centre_px(&self) -> (f64, f64) {
        (
            f64::from(self.x) + f64::from(self.width) / 2.0,
            f64::from(self.y) + f64::from(self.height) / 2.0,
        )
    }
}

/// The top view (x across, z down: seen from above) and the side view (z across, y up: seen
/// from −x), as `path_plot` draws them.
pub fn panels(seq: &Sequence) -> [Panel; 2] {
    layout(&Plot::new(seq))
}

pub(super) fn layout(plot: &Plot) -> [Panel; 2] {
    let mean = plot
        .samples
        .iter()
        .fold(DVec3::ZERO, |s, (_, p)| s + p.position)
        / plot.samples.len() as f64;
    let y = MARGIN + TITLE_H + CAPTION_H;
    let top = fit_panel(&plot.fit, (0, 2, true), mean.y, (MARGIN, y));
    let side_x = MARGIN + top.width + PANEL_GAP;
    let side = fit_panel(&plot.fit, (2, 1, false), mean.x, (side_x, y));
    [top, side]
}

/// A panel whose width follows the box's aspect ratio (within limits) and whose scale fits it.
pub(super) fn fit_panel(
    b: &Bounds,
    axes: (usize, usize, bool),
    slice: f64,
    at: (u32, u32),
) -> Panel {
    let (across, down, flipped) = axes;
    let size = b.size();
    let (ra, rb) = (size[across], size[down]);
    let inner_h = f64::from(PANEL_H) - 2.0 * PAD;
    let want = inner_h * ra / rb + 2.0 * PAD;
    let width = (want.round() as u32).clamp(PANEL_MIN_W, PANEL_MAX_W);
    let scale = ((f64::from(width) - 2.0 * PAD) / ra).min(inner_h / rb);
    let mid = (b.min + b.max) / 2.0;
    Panel {
        x: at.0,
        y: at.1,
        width,
        height: PANEL_H,
        across,
        down,
        flipped,
        scale,
        centre: (mid[across], mid[down]),
        slice,
    }
}
