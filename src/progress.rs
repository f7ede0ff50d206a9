//! Progress on stderr: an indicatif bar on a terminal, one plain line per finished frame
//! otherwise (so farm wrappers can follow), one JSON object per frame event with
//! `--progress json`, nothing with `--quiet`. stdout is never touched.

use crate::claim::Held;
use crate::console::printable;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

pub struct Progress {
    mode: Mode,
    /// Frames this run will render.
    total: u64,
    /// Frames in the whole sequence, for the `frame n/N` lines.
    sequence_frames: u64,
    done: u64,
    start: Instant,
}

enum Mode {
    Quiet,
    Lines,
    Json,
    Bar(ProgressBar),
}

impl Progress {
    pub fn new(total: u64, sequence_frames: u64, quiet: bool) -> Progress {
        let mode = if quiet {
            Mode::Quiet
        } else if std::io::stderr().is_terminal() {
            Mode::Bar(bar(total))
        } else {
            Mode::Lines
        };
        Progress {
            mode,
            total,
            sequence_frames,
            done: 0,
            start: Instant::now(),
        }
    }

    /// One JSON object per line on stderr, for render farms.
    pub fn json(total: u64, sequence_frames: u64) -> Progress {
        Progress {
            mode: Mode::Json,
            ..Progress::new(total, sequence_frames, true)
        }
    }

    /// Frames a new pass of work will render (claim mode re-plans).
    pub fn add_total(&mut self, more: u64) {
        self.total += more;
        if let Mode::Bar(bar) = &self.mode {
            bar.set_length(self.total);
        }
    }

    /// A line for the user that is not about one frame (plans).
    pub fn note(&self, text: &str) {
        match &self.mode {
            Mode::Quiet => {}
            Mode::Lines => eprintln!("{}", printable(text)),
            Mode::Json => eprintln!("{{\"event\": \"note\", \"text\": {}}}", quote(text)),
            Mode::Bar(bar) => bar.println(printable(text)),
        }
    }

    /// A warning: shown even with `--quiet`.
    pub fn warn(&self, text: &str) {
        match &self.mode {
            Mode::Bar(bar) => bar.println(printable(text)),
            Mode::Json => eprintln!("{{\"event\": \"warning\", \"text\": {}}}", quote(text)),
            _ => eprintln!("{}", printable(text)),
        }
    }

    /// Frames other processes hold, and the first few of their claims: shown even with
    /// `--quiet`, since a worker that waits must say on what.
    pub fn waiting(&self, frames: &str, count: usize, claims: &[Held]) {
        let age = |h: &Held| h.heartbeat.map_or(-1.0, |a| a.as_secs_f64());
        if let Mode::Json = self.mode {
            let claims: Vec<String> = claims
                .iter()
                .map(|h| {
                    format!(
                        "{{\"path\": {}, \"owner\": {}, \"heartbeat_seconds\": {:.0}}}",
                        quote(&h.path.display().to_string()),
                        quote(&h.owner),
                        age(h)
                    )
                })
                .collect();
            eprintln!(
                "{{\"event\": \"waiting\", \"frames\": {}, \"claims\": [{}]}}",
                quote(frames),
                claims.join(", ")
            );
            return;
        }
        let claims: Vec<String> = claims
            .iter()
            .map(|h| {
                format!(
                    "{} ({}, heartbeat {:.0} s ago)",
                    h.path.display(),
                    h.owner,
                    age(h)
                )
            })
            .collect();
        let more = count.saturating_sub(claims.len());
        self.warn(&format!(
            "waiting for {count} frame{} ({frames}) that other processes hold: {}{}",
            if count == 1 { "" } else { "s" },
            claims.join(", "),
            if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            }
        ));
    }

    /// Whether `frame_skipped` shows anything (one JSON line per frame).
    pub fn reports_skipped(&self) -> bool {
        matches!(self.mode, Mode::Json)
    }

    /// A frame that needs no work (`up-to-date`) or may not be touched (`foreign`).
    pub fn frame_skipped(&self, n: u64, path: &str, status: &str) {
        if let Mode::Json = self.mode {
            eprintln!(
                "{{\"event\": \"frame\", \"frame\": {n}, \"path\": {}, \"status\": \"{status}\", \"seconds\": 0}}",
                quote(path)
            );
        }
    }

    pub fn frame_done(&mut self, n: u64, destination: &str, seconds: f64) {
        self.done += 1;
        match &self.mode {
            Mode::Quiet => {}
            Mode::Lines => eprintln!(
                "frame {n}/{} written {} ({seconds:.2} s, {} of {} done)",
                self.sequence_frames,
                printable(destination),
                self.done,
                self.total
            ),
            Mode::Json => eprintln!(
                "{{\"event\": \"frame\", \"frame\": {n}, \"path\": {}, \"status\": \"written\", \"seconds\": {seconds:.4}}}",
                quote(destination)
            ),
            Mode::Bar(bar) => {
                bar.set_message(printable(destination).into_owned());
                bar.inc(1);
            }
        }
    }

    pub fn frame_failed(&self, n: u64, error: &str) {
        if let Mode::Json = self.mode {
            eprintln!(
                "{{\"event\": \"frame\", \"frame\": {n}, \"status\": \"failed\", \"error\": {}}}",
                quote(error)
            );
        }
    }

    /// Clears the bar and prints the closing summary line.
    pub fn finish(&self) {
        let wall = self.start.elapsed().as_secs_f64();
        let rate = if wall > 0.0 {
            self.done as f64 / wall
        } else {
            0.0
        };
        match &self.mode {
            Mode::Quiet => return,
            Mode::Json => {
                eprintln!(
                    "{{\"event\": \"summary\", \"frames\": {}, \"seconds\": {wall:.3}, \"frames_per_second\": {rate:.3}}}",
                    self.done
                );
                return;
            }
            Mode::Bar(bar) => bar.finish_and_clear(),
            Mode::Lines => {}
        }
        if self.total > 0 {
            eprintln!(
                "rendered {} frame{} in {wall:.2} s ({rate:.2} frames/s)",
                self.done,
                if self.done == 1 { "" } else { "s" }
            );
        }
    }
}

fn bar(total: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40.cyan/blue} {pos}/{len} frames  {per_sec:.1}  eta {eta}  {msg}",
        )
        .expect("static template")
        .progress_chars("##-"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// A JSON string literal.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
