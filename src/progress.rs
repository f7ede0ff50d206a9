//! Progress on stderr: an indicatif bar on a terminal, one plain line per finished frame
//! otherwise (so farm wrappers can follow), one JSON object per frame event with
//! `--progress json`, nothing with `--quiet`. stdout is never touched.

use crate::claim::Held;
use crate::console::{printable, quote};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::cell::Cell;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

pub(crate) struct Progress {
    mode: Mode,
    /// Frames this run will render.
    total: u64,
    /// Frames in the whole sequence, for the `frame n/N` lines.
    sequence_frames: u64,
    done: u64,
    /// Frames reported up to date or foreign, and frames that failed.
    skipped: Cell<u64>,
    failed: Cell<u64>,
    /// Whether a frame's colour beyond the largest half float has been reported.
    half_overflow_told: Cell<bool>,
    /// Where streamed frames go, as frame lines say it: `to stdout`, or `to ffmpeg` (--video).
    pub(crate) stream_to: &'static str,
    /// What the closing line says was done with the frames: `rendered`, or `encoded`.
    pub(crate) verb: &'static str,
    start: Instant,
}

enum Mode {
    Quiet,
    Lines,
    Json,
    Bar(ProgressBar),
}

impl Progress {
    pub(crate) fn new(total: u64, sequence_frames: u64, quiet: bool) -> Progress {
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
            stream_to: "to stdout",
            verb: "rendered",
            skipped: Cell::new(0),
            failed: Cell::new(0),
            half_overflow_told: Cell::new(false),
            start: Instant::now(),
        }
    }

    /// One JSON object per line on stderr, for render farms.
    pub(crate) fn json(total: u64, sequence_frames: u64) -> Progress {
        crate::console::set_json(true);
        Progress {
            mode: Mode::Json,
            ..Progress::new(total, sequence_frames, true)
        }
    }

    /// Frames a new pass of work will render (claim mode re-plans).
    pub(crate) fn add_total(&mut self, more: u64) {
        self.total += more;
        if let Mode::Bar(bar) = &self.mode {
            bar.set_length(self.total);
        }
    }

    /// The plan before the first frame: its summary (`48 frames: 30 up to date, 18 missing →
    /// rendering 18`), or in JSON a `start` event with the count of frames in every state
    /// (streams without files have no plan: every selected frame is rendered).
    pub(crate) fn start(&self, plan: Option<(&str, &[(&str, u64)])>, selected: u64) {
        let Mode::Json = self.mode else {
            return plan.into_iter().for_each(|(summary, _)| self.note(summary));
        };
        let counts = plan.map_or(String::new(), |(_, states)| {
            let states = states
                .iter()
                .map(|(what, n)| format!(", \"{}\": {n}", what.replace(' ', "_")));
            states.collect()
        });
        eprintln!(
            "{{\"event\": \"start\", \"selected\": {selected}, \"rendering\": {}{counts}, \"sequence_frames\": {}}}",
            self.total, self.sequence_frames
        );
    }

    /// The first Ctrl-C or SIGTERM: said at once, whatever the mode.
    pub(crate) fn interrupt(&self, signal: &str, in_flight: usize, text: &str) {
        match &self.mode {
            Mode::Json => eprintln!(
                "{{\"event\": \"interrupt\", \"signal\": \"{signal}\", \"in_flight\": {in_flight}, \"done\": {}, \"text\": {}}}",
                self.done,
                quote(text)
            ),
            Mode::Bar(bar) => {
                bar.set_message("stopping");
                bar.println(printable(text));
            }
            _ => eprintln!("{}", printable(text)),
        }
    }

    /// A line for the user that is not about one frame (plans).
    pub(crate) fn note(&self, text: &str) {
        match &self.mode {
            Mode::Quiet => {}
            Mode::Lines => eprintln!("{}", printable(text)),
            Mode::Json => eprintln!("{{\"event\": \"note\", \"text\": {}}}", quote(text)),
            Mode::Bar(bar) => bar.println(printable(text)),
        }
    }

    /// A command line the user asked for (`--print-ffmpeg`): shown even with `--quiet`.
    pub(crate) fn command(&self, text: &str) {
        match &self.mode {
            Mode::Bar(bar) => bar.println(printable(text)),
            Mode::Json => eprintln!("{{\"event\": \"command\", \"text\": {}}}", quote(text)),
            _ => eprintln!("{}", printable(text)),
        }
    }

    /// A warning: shown even with `--quiet`.
    pub(crate) fn warn(&self, text: &str) {
        match &self.mode {
            Mode::Bar(bar) => bar.println(printable(text)),
            Mode::Json => eprintln!("{{\"event\": \"warning\", \"text\": {}}}", quote(text)),
            _ => eprintln!("{}", printable(text)),
        }
    }

    /// The first frame of the run whose colour went beyond the largest half float (65504) and
    /// was clamped to it: a warning, once a run.
    pub(crate) fn half_overflow(&self, n: u64, path: &str, samples: u64) {
        if self.half_overflow_told.replace(true) {
            return;
        }
        self.warn(&format!(
            "warning: frame {n} ({path}): {samples} colour sample{} beyond 65504, the largest half float, {} stored as 65504 instead of infinity; later frames are clamped alike without a word (use --exr-precision float to keep such values)",
            if samples == 1 { "" } else { "s" },
            if samples == 1 { "was" } else { "were" }
        ));
    }

    /// Frames other processes hold, and the first few of their claims: shown even with
    /// `--quiet`, since a worker that waits must say on what.
    pub(crate) fn waiting(&self, frames: &str, count: usize, claims: &[Held]) {
        if let Mode::Json = self.mode {
            let claims: Vec<String> = claims
                .iter()
                .map(|h| {
                    format!(
                        "{{\"path\": {}, \"owner\": {}, \"heartbeat_seconds\": {}}}",
                        quote(&h.path.display().to_string()),
                        quote(&h.owner),
                        h.heartbeat
                            .map_or("null".into(), |a| format!("{:.0}", a.as_secs_f64()))
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
            .map(|h| match h.heartbeat {
                // An owner line that cannot be read (permissions, or empty) is said so, not
                // shown as nothing before the comma.
                Some(age) => format!(
                    "{} ({}, heartbeat {:.0} s ago)",
                    h.path.display(),
                    if h.owner.is_empty() {
                        "owner unknown"
                    } else {
                        &h.owner
                    },
                    age.as_secs_f64()
                ),
                None => format!("{} (released just now)", h.path.display()),
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
    pub(crate) fn reports_skipped(&self) -> bool {
        matches!(self.mode, Mode::Json)
    }

    /// A frame that needs no work (`up-to-date`) or may not be touched (`foreign`).
    pub(crate) fn frame_skipped(&self, n: u64, path: &str, status: &str) {
        self.skipped.set(self.skipped.get() + 1);
        if let Mode::Json = self.mode {
            eprintln!(
                "{{\"event\": \"frame\", \"frame\": {n}, \"path\": {}, \"status\": \"{status}\", \"seconds\": 0, \"done\": {}, \"total\": {}}}",
                quote(path),
                self.done,
                self.total
            );
        }
    }

    pub(crate) fn frame_done(&mut self, n: u64, destination: &str, seconds: f64) {
        self.done += 1;
        match &self.mode {
            Mode::Quiet => {}
            // The frame's own number (from `first_frame`), then this run's count.
            Mode::Lines => eprintln!(
                "frame {n} written {} ({seconds:.2} s, {} of {} done)",
                printable(destination),
                self.done,
                self.total
            ),
            Mode::Json => eprintln!(
                "{{\"event\": \"frame\", \"frame\": {n}, \"path\": {}, \"status\": \"written\", \"seconds\": {seconds:.3}, \"done\": {}, \"total\": {}}}",
                quote(destination),
                self.done,
                self.total
            ),
            Mode::Bar(bar) => {
                if self.done == 1 {
                    bar.set_style(style(true));
                }
                bar.inc(1);
            }
        }
    }

    pub(crate) fn frame_failed(&self, n: u64, error: &str) {
        self.failed.set(self.failed.get() + 1);
        if let Mode::Json = self.mode {
            eprintln!(
                "{{\"event\": \"frame\", \"frame\": {n}, \"status\": \"failed\", \"error\": {}, \"done\": {}, \"total\": {}}}",
                quote(error),
                self.done,
                self.total
            );
        }
    }

    /// Clears the bar and prints the closing summary line.
    pub(crate) fn finish(&self, interrupted: bool) {
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
                    "{{\"event\": \"summary\", \"frames\": {}, \"total\": {}, \"skipped\": {}, \"failed\": {}, \"interrupted\": {interrupted}, \"seconds\": {wall:.3}, \"frames_per_second\": {rate:.3}}}",
                    self.done,
                    self.total,
                    self.skipped.get(),
                    self.failed.get()
                );
                return;
            }
            Mode::Bar(bar) => bar.finish_and_clear(),
            Mode::Lines => {}
        }
        // A job refused before its first frame (memory, a bad output) has nothing to sum up.
        if self.total > 0 && (self.done > 0 || interrupted || self.failed.get() > 0) {
            eprintln!(
                "{} {} frame{} in {wall:.2} s ({rate:.2} frames/s)",
                self.verb,
                self.done,
                if self.done == 1 { "" } else { "s" }
            );
        }
    }
}

fn bar(total: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
    bar.set_style(style(false));
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}

/// The bar fills what the terminal's width leaves (`wide_bar`; the text beside it takes 40
/// columns at most, so a 60-column terminal still has a bar and no wrapped line); the rate
/// and the ETA appear once a frame is done (before that they would be guesses from nothing),
/// and `stopping` once a signal came.
fn style(timed: bool) -> ProgressStyle {
    let template = match timed {
        true => "{wide_bar:.cyan/blue} {pos}/{len} frames  {rate}  eta {eta} {msg}",
        false => "{wide_bar:.cyan/blue} {pos}/{len} frames {msg}",
    };
    ProgressStyle::with_template(template)
        .expect("static template")
        .with_key(
            "rate",
            |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = write!(w, "{}", rate(s.per_sec()));
            },
        )
        .progress_chars("##-")
}

/// `3.6 frames/s`, or `14 s/frame` when frames take longer than a second.
pub(crate) fn rate(per_second: f64) -> String {
    match per_second {
        r if r >= 1.0 => format!("{r:.1} frames/s"),
        r if r > 0.0 => format!("{:.1} s/frame", 1.0 / r),
        _ => "0 frames/s".into(),
    }
}
