//! The path plot as a whole: title, captions, the two panels, the speed panel, the legend and
//! the warnings written in red.

use super::*;

/// Draws the path plot and, under it, the speed panel; returns the picture with the warnings
/// (without a `warning: ` prefix). `invalid` is why the file cannot render, written in red.
pub fn path_plot(seq: &Sequence, invalid: Option<&str>) -> (RgbImage, Vec<String>) {
    let plot = Plot::new(seq);
    let [top, side] = layout(&plot);
    let width = (side.x + side.width + MARGIN).max(LEGEND_MIN_W);
    let speed_y = top.y + PANEL_H + CAPTION_H + 16;
    let speed_rect = Rect::new(
        i64::from(MARGIN),
        i64::from(speed_y),
        i64::from(width - MARGIN),
        i64::from(speed_y + speed::HEIGHT),
    );
    let legend_y = speed_y + speed::HEIGHT + 16;
    let columns = ((width - 2 * MARGIN) / (ADVANCE as u32 * 2)) as usize;
    let invalid = invalid.map(|why| format!("invalid: {}", why.replace('`', "'")));
    let warned = plot.warnings.iter().take(MAX_WARNING_LINES);
    let notes = invalid
        .into_iter()
        .chain(warned.map(|w| format!("warning: {w}")));
    let mut lines: Vec<String> = notes.flat_map(|n| wrap(&n, columns)).collect();
    if plot.warnings.len() > MAX_WARNING_LINES {
        let more = plot.warnings.len() - MAX_WARNING_LINES;
        lines.push(format!("... and {more} more warnings (on stderr)"));
    }
    // A third legend row for moving things, only when something moves: a still scene's plot
    // keeps its bytes.
    let rows = if plot.moving.is_empty() { 2 } else { 3 };
    let notes_y = legend_y + rows * LEGEND_ROW + 8;
    let height = notes_y + lines.len() as u32 * WARNING_ROW + MARGIN;
    let mut img = RgbImage::from_pixel(width, height, BACKGROUND);
    title(&mut img, seq);
    for panel in [&top, &side] {
        caption(&mut img, panel);
        draw_panel(&mut img, panel, seq, &plot);
    }
    let mut c = Canvas::whole(&mut img);
    let what = "speed along the path (scene units per second) against time; squares: keyframes";
    c.text(i64::from(MARGIN), speed_rect.y0 - 22, what, 2, INK);
    let mut c = Canvas::new(&mut img, speed_rect);
    speed::draw(&mut c, speed_rect, seq, &plot.samples, &plot.bad);
    legend(&mut img, legend_y, rows == 3);
    red_lines(&mut img, &lines, notes_y);
    (img, plot.warnings)
}

/// Words of `text` in lines of at most `columns` characters (a longer word gets its own line).
pub(super) fn wrap(text: &str, columns: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(line) if line.chars().count() + 1 + word.chars().count() <= columns => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

pub(super) fn title(img: &mut RgbImage, seq: &Sequence) {
    let t = &seq.timeline;
    let motion = match &t.path {
        TimelinePath::Orbit(o) => format!("orbit of radius {}", fmt_num(o.radius)),
        TimelinePath::Keys(k) if k.keys.len() == 1 => "still camera".into(),
        TimelinePath::Keys(k) => {
            format!("{} keyframes, {:?}", k.keys.len(), k.interpolation).to_lowercase()
        }
    };
    let frames = match t.frame_count {
        1 => "1 frame".to_string(),
        n => format!("{n} frames"),
    };
    let text = format!(
        "{}: {frames} at {} fps ({} s), {motion}",
        seq.name,
        fmt_num(t.fps),
        t.running_time_text()
    );
    Canvas::whole(img).text(i64::from(MARGIN), i64::from(MARGIN), &text, 2, INK);
}

pub(super) fn caption(img: &mut RgbImage, p: &Panel) {
    let text = if p.flipped {
        "top view: x across, z down"
    } else {
        "side view: z across, y up"
    };
    let y = i64::from(p.y) - 22;
    Canvas::whole(img).text(i64::from(p.x), y, text, 2, INK);
}

pub(super) const LEGEND_MIN_W: u32 = 1000;

pub(super) fn legend(img: &mut RgbImage, y: u32, moving: bool) {
    let mut c = Canvas::whole(img);
    let y = i64::from(y);
    let rows: [&[(&str, Marker)]; 3] = [
        &[
            ("camera path", Marker::Line(PATH)),
            ("inside an object / no camera", Marker::Line(BAD)),
            ("keyframe", Marker::Key),
            ("start", Marker::Start),
            ("end", Marker::End),
        ],
        &[
            ("look-at target", Marker::Target),
            ("view direction", Marker::Tick),
            ("light", Marker::Light),
            ("object [index]", Marker::Object),
        ],
        &[
            ("moving object [index]", Marker::Line(OBJECT_PATH)),
            ("moving light L<index>", Marker::Line(LIGHT_PATH)),
        ],
    ];
    let shown = if moving { 3 } else { 2 };
    for (row, items) in rows.iter().take(shown).enumerate() {
        let mut x = i64::from(MARGIN);
        let yy = y + row as i64 * i64::from(LEGEND_ROW);
        for (label, marker) in items.iter() {
            marker.draw(&mut c, (x as f64 + 14.0, yy as f64 + 7.0));
            x = c.text(x + 34, yy, label, 2, INK) + 28;
        }
    }
}

#[derive(Clone, Copy)]
pub(super) enum Marker {
    Line(Rgb<u8>),
    Key,
    Start,
    End,
    Target,
    Tick,
    Light,
    Object,
}

impl Marker {
    pub(super) fn draw(self, c: &mut Canvas, (x, y): (f64, f64)) {
        match self {
            Marker::Line(colour) => {
                let w = if colour == BAD { 4.0 } else { 2.0 };
                c.line((x - 12.0, y), (x + 12.0, y), w, colour);
                c.disc((x, y), 2.5, colour);
            }
            Marker::Key => c.square_outline((x, y), 8.0, 2.0, KEYFRAME),
            Marker::Start => c.disc((x, y), 5.5, START),
            Marker::End => c.square((x, y), 6.0, END),
            Marker::Target => c.cross((x, y), 6.0, 2.0, TARGET),
            Marker::Tick => c.arrow((x - 12.0, y), (x + 12.0, y), 2.0, TICK),
            Marker::Light => c.diamond((x, y), 8.0, LIGHT, INK),
            Marker::Object => {
                let grey = Rgb([200, 200, 200]);
                c.mask(
                    Rect::around((x, y), 9.0),
                    |a, b| (a - x).hypot(b - y) < 7.0,
                    grey,
                    MUTED,
                )
            }
        }
    }
}

pub(super) fn red_lines(img: &mut RgbImage, lines: &[String], y: u32) {
    let mut c = Canvas::whole(img);
    for (i, line) in lines.iter().enumerate() {
        let y = i64::from(y + i as u32 * WARNING_ROW);
        c.text(i64::from(MARGIN), y, line, 2, BAD);
    }
}
