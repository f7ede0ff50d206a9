//! The measurement as text: the table on stdout, `measure.csv` and `measure.json` (one row
//! per setting, the same columns in both).

use super::{F32_TARGET_OFF2, REFERENCE_PRECISION, Report, Row, Versus};
use crate::output::png::Compression;
use crate::tracer::Precision;
use std::fmt::Write as _;

impl Report {
    /// The reference's time over the row's, or `-` for a reference taken from the cache.
    fn speedup(&self, r: &Row) -> String {
        match self.reference_seconds > 0.0 {
            true => format!("{:.1}x", self.reference_seconds / r.seconds[0]),
            false => "-".into(),
        }
    }

    /// The reference as an 8-bit PNG in the frame's encoding, to see what rows were held to.
    pub(crate) fn reference_png(&self) -> Vec<u8> {
        crate::output::png::encode(
            &mut self.reference_frame.clone(),
            false,
            Compression::Fast,
            &[],
        )
        .expect("an 8-bit PNG of a frame in memory")
    }

    pub(crate) fn table(&self) -> String {
        let mut s = format!(
            "errors on the 8-bit {} values of each frame (render.encoding)\n",
            self.encoding.name()
        );
        if self.rows.first().map(|r| r.settings.precision) == Some(Precision::F32) {
            s += "the ladder in f32 (render.precision); the reference in f64\n";
        }
        let _ = writeln!(
            s,
            "{:<24} {:>9} {:>9} {:>9} {:>8} {:>8} {:>7} {:>4} {:>7} {:>7}",
            "settings",
            "spp",
            "time s",
            "speed-up",
            "rmse",
            "psnr dB",
            "max",
            "",
            ">1/255",
            ">8/255"
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "{:<24} {:>9.2} {:>9.4} {:>9} {:>8.3} {:>8.2} {:>7} {:>4} {:>6.2}% {:>6.2}%",
                r.label,
                r.samples_per_pixel,
                r.seconds[0],
                self.speedup(r),
                r.error.rmse,
                r.error.psnr,
                r.error.max,
                "",
                100.0 * r.error.off,
                100.0 * r.error.off8
            );
        }
        let (samples, check) = self.convergence;
        let _ = writeln!(
            s,
            "reference: {} spp, max_depth {}; {samples} spp of other seeds differ from it by rmse {:.3} ({:.2} dB)",
            self.reference.0, self.reference.1, check.rmse, check.psnr
        );
        match self.rows.iter().any(|r| r.versus_f64.is_some()) {
            true => s + &self.precision_table(),
            false => s,
        }
    }

    /// The precision rows against the f64 row, with issue 19's target for f32.
    fn precision_table(&self) -> String {
        let rows: Vec<(&Row, Versus)> = self
            .rows
            .iter()
            .filter_map(|r| Some((r, r.versus_f64?)))
            .collect();
        let mut s = String::from(
            "\nthe file's settings in f64 and f32, rendered in turn; against the f64 image\n",
        );
        let _ = writeln!(
            s,
            "{:<24} {:>9} {:>8} {:>8} {:>7} {:>8} {:>8}",
            "settings", "speed-up", "rmse", "psnr dB", "max", ">1/255", ">2/255"
        );
        for (r, v) in &rows {
            let _ = writeln!(
                s,
                "{:<24} {:>8.2}x {:>8.3} {:>8.2} {:>7} {:>7.3}% {:>7.3}%",
                r.label,
                v.speedup,
                v.error.rmse,
                v.error.psnr,
                v.error.max,
                100.0 * v.error.off,
                100.0 * v.error.off2
            );
        }
        let f32_row = rows
            .iter()
            .find(|(r, _)| r.settings.precision == Precision::F32);
        if let Some((_, v)) = f32_row {
            let met = v.error.off2 <= F32_TARGET_OFF2;
            let _ = writeln!(
                s,
                "target: f32 at most {}% of pixels off by more than 2/255: {} ({:.3}%)",
                100.0 * F32_TARGET_OFF2,
                if met { "met" } else { "NOT met" },
                100.0 * v.error.off2
            );
        }
        s
    }

    /// Each row as (column, value) pairs, shared by the CSV and the JSON.
    fn records(&self) -> Vec<Vec<(&'static str, String)>> {
        self.rows
            .iter()
            .map(|r| {
                vec![
                    ("group", format!("\"{}\"", r.group)),
                    ("settings", format!("\"{}\"", r.label)),
                    ("samples_per_pixel", format!("{:.4}", r.samples_per_pixel)),
                    ("max_depth", r.settings.max_depth.to_string()),
                    ("seconds_median", format!("{:.6}", r.seconds[0])),
                    ("seconds_min", format!("{:.6}", r.seconds[1])),
                    ("seconds_max", format!("{:.6}", r.seconds[2])),
                    (
                        "speedup",
                        format!("{:.3}", self.reference_seconds / r.seconds[0]),
                    ),
                    ("rmse", format!("{:.5}", r.error.rmse)),
                    ("psnr_db", format!("{:.3}", finite_or(r.error.psnr, 999.0))),
                    ("max_error", r.error.max.to_string()),
                    ("share_off", format!("{:.6}", r.error.off)),
                    ("share_off_2", format!("{:.6}", r.error.off2)),
                    ("share_off_8", format!("{:.6}", r.error.off8)),
                ]
                .into_iter()
                .chain(versus_record(r.versus_f64))
                .chain([
                    ("precision", format!("\"{}\"", r.settings.precision.name())),
                    ("encoding", format!("\"{}\"", self.encoding.name())),
                ])
                .collect()
            })
            .collect()
    }

    pub(crate) fn csv(&self) -> String {
        let records = self.records();
        let header: Vec<&str> = records
            .first()
            .map_or(Vec::new(), |r| r.iter().map(|(k, _)| *k).collect());
        let mut s = header.join(",") + "\n";
        for r in &records {
            let cells: Vec<&str> = r
                .iter()
                .map(|(_, v)| match v.as_str() {
                    "null" => "",
                    v => v.trim_matches('"'),
                })
                .collect();
            s += &(cells.join(",") + "\n");
        }
        s
    }

    pub(crate) fn json(&self) -> String {
        let rows: Vec<String> = self
            .records()
            .iter()
            .map(|r| {
                let fields: Vec<String> = r.iter().map(|(k, v)| format!("\"{k}\": {v}")).collect();
                format!("    {{{}}}", fields.join(", "))
            })
            .collect();
        format!(
            "{{\n  \"reference\": {{\"samples_per_pixel\": {}, \"max_depth\": {}, \"precision\": \"{}\", \"seconds\": {:.6}, \"check_samples_per_pixel\": {}, \"check_rmse\": {:.5}}},\n  \"rows\": [\n{}\n  ]\n}}\n",
            self.reference.0,
            self.reference.1,
            REFERENCE_PRECISION.name(),
            self.reference_seconds,
            self.convergence.0,
            self.convergence.1.rmse,
            rows.join(",\n")
        )
    }
}

/// The columns against the f64 image of the same settings: `null` (empty in the CSV) outside
/// the precision rows.
fn versus_record(v: Option<Versus>) -> Vec<(&'static str, String)> {
    let cells = v.map(|v| {
        [
            format!("{:.3}", v.speedup),
            format!("{:.5}", v.error.rmse),
            format!("{:.3}", finite_or(v.error.psnr, 999.0)),
            v.error.max.to_string(),
            format!("{:.6}", v.error.off),
            format!("{:.6}", v.error.off2),
        ]
    });
    let names = [
        "speedup_vs_f64",
        "rmse_vs_f64",
        "psnr_db_vs_f64",
        "max_error_vs_f64",
        "share_off_vs_f64",
        "share_off_2_vs_f64",
    ];
    let cells = cells.unwrap_or_else(|| ["null"; 6].map(String::from));
    names.into_iter().zip(cells).collect()
}

fn finite_or(v: f64, fallback: f64) -> f64 {
    if v.is_finite() { v } else { fallback }
}
