//! `measure.svg`: error against time, log-log.

use super::Report;
use std::fmt::Write as _;

impl Report {
    /// Error against time, log-log, uniform and adaptive as lines, presets labelled, the
    /// precision rows as two diamonds.
    pub(crate) fn svg(&self) -> String {
        let pts: Vec<(f64, f64)> = self.rows.iter().map(point).collect();
        let a = Axes {
            w: 720.0,
            h: 460.0,
            m: 60.0,
            x: bounds(pts.iter().map(|p| p.0)),
            y: bounds(pts.iter().map(|p| p.1)),
        };
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
            a.w, a.h
        );
        a.frame(&mut s);
        a.ticks(&mut s);
        self.group_lines(&mut s, &a);
        self.presets(&mut s, &a);
        self.precision_marks(&mut s, &a);
        legend(&mut s, &a);
        s.push_str("</svg>\n");
        s
    }

    /// The uniform, adaptive and depth rows, each as a polyline with dots.
    fn group_lines(&self, s: &mut String, a: &Axes) {
        for (group, color) in [
            ("uniform", "#1f77b4"),
            ("adaptive", "#2ca02c"),
            ("depth", "#9467bd"),
            ("lights", "#ff7f0e"),
        ] {
            let line: Vec<String> = self
                .rows
                .iter()
                .filter(|r| r.group == group)
                .map(|r| {
                    let (x, y) = point(r);
                    format!("{:.1},{:.1}", a.px(x), a.py(y))
                })
                .collect();
            if line.is_empty() {
                continue;
            }
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"/>",
                line.join(" ")
            );
            for p in &line {
                let (x, y) = p.split_once(',').expect("x,y");
                let _ = writeln!(
                    s,
                    "<circle cx=\"{x}\" cy=\"{y}\" r=\"3\" fill=\"{color}\"/>"
                );
            }
        }
    }

    /// The presets as labelled squares.
    fn presets(&self, s: &mut String, a: &Axes) {
        for r in self.rows.iter().filter(|r| r.group == "preset") {
            let (x, y) = point(r);
            let (x, y) = (a.px(x), a.py(y));
            let _ = writeln!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"9\" height=\"9\" fill=\"#d62728\"/>",
                x - 4.5,
                y - 4.5
            );
            let _ = writeln!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" fill=\"#d62728\">{}</text>",
                x + 8.0,
                y - 6.0,
                r.label
            );
        }
    }

    /// The precision rows as labelled diamonds joined by a dashed line (f64 to f32).
    fn precision_marks(&self, s: &mut String, a: &Axes) {
        let marks: Vec<(f64, f64, &str)> = self
            .rows
            .iter()
            .filter(|r| r.group == "precision")
            .map(|r| {
                let (x, y) = point(r);
                (a.px(x), a.py(y), r.settings.precision.name())
            })
            .collect();
        let line: Vec<String> = marks
            .iter()
            .map(|(x, y, _)| format!("{x:.1},{y:.1}"))
            .collect();
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{PRECISION_COLOR}\" stroke-width=\"1.5\" stroke-dasharray=\"4 3\"/>",
            line.join(" ")
        );
        for (x, y, name) in marks {
            let _ = writeln!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"8\" height=\"8\" fill=\"{PRECISION_COLOR}\" transform=\"rotate(45 {x:.1} {y:.1})\"/>",
                x - 4.0,
                y - 4.0
            );
            let _ = writeln!(
                s,
                "<text x=\"{:.1}\" y=\"{:.1}\" fill=\"{PRECISION_COLOR}\">{name}</text>",
                x + 8.0,
                // f64 above, f32 below: the two points are often close.
                if name == "f64" { y - 6.0 } else { y + 14.0 }
            );
        }
    }
}

/// A row's point: its median time and its RMSE (at least 0.001, for the log scale).
fn point(r: &super::Row) -> (f64, f64) {
    (r.seconds[0], r.error.rmse.max(1e-3))
}

/// The plot's size and margin (pixels) and its log10 ranges: where a value lands.
struct Axes {
    w: f64,
    h: f64,
    m: f64,
    x: (f64, f64),
    y: (f64, f64),
}

impl Axes {
    fn px(&self, x: f64) -> f64 {
        let (x0, x1) = self.x;
        self.m + (x.log10() - x0) / (x1 - x0) * (self.w - 2.0 * self.m)
    }

    fn py(&self, y: f64) -> f64 {
        let (y0, y1) = self.y;
        self.h - self.m - (y.log10() - y0) / (y1 - y0) * (self.h - 2.0 * self.m)
    }

    /// The axis titles and the plot's box.
    fn frame(&self, s: &mut String) {
        let (w, h, m) = (self.w, self.h, self.m);
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">render time per frame (s, log)</text>",
            w / 2.0,
            h - 15.0
        );
        let _ = writeln!(
            s,
            "<text x=\"15\" y=\"{}\" transform=\"rotate(-90 15 {})\" text-anchor=\"middle\">RMSE vs reference (8-bit levels, log)</text>",
            h / 2.0,
            h / 2.0
        );
        let _ = writeln!(
            s,
            "<rect x=\"{m}\" y=\"{m}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>",
            w - 2.0 * m,
            h - 2.0 * m
        );
    }

    /// A label at every decade inside each axis' range.
    fn ticks(&self, s: &mut String) {
        let ((x0, x1), (y0, y1)) = (self.x, self.y);
        for (decade, axis_x) in [(x0, true), (y0, false)] {
            let end = if axis_x { x1 } else { y1 };
            let mut d = decade.floor();
            while d <= end.ceil() {
                let v = 10f64.powf(d);
                if axis_x && (x0..=x1).contains(&d) {
                    let _ = writeln!(
                        s,
                        "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{v}</text>",
                        self.px(v),
                        self.h - self.m + 16.0
                    );
                } else if !axis_x && (y0..=y1).contains(&d) {
                    let _ = writeln!(
                        s,
                        "<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{v}</text>",
                        self.m - 4.0,
                        self.py(v) + 4.0
                    );
                }
                d += 1.0;
            }
        }
    }
}

/// What each colour stands for, in the top right corner.
fn legend(s: &mut String, a: &Axes) {
    let legend = [
        ("#1f77b4", "uniform 1-256 spp"),
        ("#2ca02c", "adaptive 4-64"),
        ("#9467bd", "max_depth 1-8 @16 spp"),
        ("#d62728", "presets"),
        (PRECISION_COLOR, "file's settings f64, f32"),
    ];
    for (i, (color, text)) in legend.iter().enumerate() {
        let y = a.m + 16.0 + 16.0 * i as f64;
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"10\" height=\"10\" fill=\"{color}\"/><text x=\"{}\" y=\"{}\">{text}</text>",
            a.w - a.m - 170.0,
            y - 9.0,
            a.w - a.m - 155.0,
            y
        );
    }
}

/// The colour of the precision rows in the plot.
const PRECISION_COLOR: &str = "#ff7f0e";

/// Log10 bounds with a little room.
fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let (lo, hi) = (lo.log10() - 0.1, hi.log10() + 0.1);
    if hi - lo < 0.5 {
        (lo - 0.25, hi + 0.25)
    } else {
        (lo, hi)
    }
}
