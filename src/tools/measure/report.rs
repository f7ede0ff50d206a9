//! The measurement as text: the table on stdout, `measure.csv` and `measure.json` (one row
//! per setting, the same columns in both).

use super::Report;
use std::fmt::Write as _;

impl Report {
    pub fn table(&self) -> String {
        let mut s = format!(
            "errors on the 8-bit {} values of each frame (render.encoding)\n",
            self.encoding.name()
        );
        let _ = writeln!(
            s,
            "{:<24} {:>9} {:>9} {:>9} {:>8} {:>8} {:>7} {:>4} {:>7}",
            "settings", "spp", "time s", "speed-up", "rmse", "psnr dB", "max", "", ">1/255"
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "{:<24} {:>9.2} {:>9.4} {:>8.1}x {:>8.3} {:>8.2} {:>7} {:>4} {:>6.2}%",
                r.label,
                r.samples_per_pixel,
                r.seconds[0],
                self.reference_seconds / r.seconds[0],
                r.error.rmse,
                r.error.psnr,
                r.error.max,
                "",
                100.0 * r.error.off
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
                    ("encoding", format!("\"{}\"", self.encoding.name())),
                ]
            })
            .collect()
    }

    pub fn csv(&self) -> String {
        let records = self.records();
        let header: Vec<&str> = records
            .first()
            .map_or(Vec::new(), |r| r.iter().map(|(k, _)| *k).collect());
        let mut s = header.join(",") + "\n";
        for r in &records {
            let cells: Vec<&str> = r.iter().map(|(_, v)| v.trim_matches('"')).collect();
            s += &(cells.join(",") + "\n");
        }
        s
    }

    pub fn json(&self) -> String {
        let rows: Vec<String> = self
            .records()
            .iter()
            .map(|r| {
                let fields: Vec<String> = r.iter().map(|(k, v)| format!("\"{k}\": {v}")).collect();
                format!("    {{{}}}", fields.join(", "))
            })
            .collect();
        format!(
            "{{\n  \"reference\": {{\"samples_per_pixel\": {}, \"max_depth\": {}, \"seconds\": {:.6}, \"half_samples_rmse\": {:.5}}},\n  \"rows\": [\n{}\n  ]\n}}\n",
            self.reference.0,
            self.reference.1,
            self.reference_seconds,
            self.convergence.rmse,
            rows.join(",\n")
        )
    }
}

fn finite_or(v: f64, fallback: f64) -> f64 {
    if v.is_finite() { v } else { fallback }
}
