//! Progress on stderr: an indicatif bar on a terminal, one plain line per finished frame
//! otherwise (so farm wrappers can follow), nothing with `--quiet`. stdout is never touched.

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
    Bar(ProgressBar),
}

impl Progress {
    pub fn new(total: u64, sequence_frames: u64, quiet: bool) -> Progress {
        let mode = if quiet {
            Mode::Quiet
        } else if std::io::stderr().is_terminal() {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template(
                    "{bar:40.cyan/blue} {pos}/{len} frames  {per_sec:.1}  eta {eta}  {msg}",
                )
                .expect("static template")
                .progress_chars("##-"),
            );
            bar.enable_steady_tick(Duration::from_millis(200));
            Mode::Bar(bar)
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

    /// A line for the user that is not about one frame (plans, warnings).
    pub fn note(&self, text: &str) {
        match &self.mode {
            Mode::Quiet => {}
            Mode::Lines => eprintln!("{text}"),
            Mode::Bar(bar) => bar.println(text),
        }
    }

    /// A warning: shown even with `--quiet`.
    pub fn warn(&self, text: &str) {
        match &self.mode {
            Mode::Bar(bar) => bar.println(text),
            _ => eprintln!("{text}"),
        }
    }

    pub fn frame_done(&mut self, n: u64, destination: &str, seconds: f64) {
        self.done += 1;
        match &self.mode {
            Mode::Quiet => {}
            Mode::Lines => eprintln!(
                "frame {n}/{} written {destination} ({seconds:.2} s, {} of {} done)",
                self.sequence_frames, self.done, self.total
            ),
            Mode::Bar(bar) => {
                bar.set_message(destination.to_string());
                bar.inc(1);
            }
        }
    }

    /// Clears the bar and prints the closing summary line.
    pub fn finish(&self) {
        let wall = self.start.elapsed().as_secs_f64();
        if let Mode::Bar(bar) = &self.mode {
            bar.finish_and_clear();
        }
        if matches!(self.mode, Mode::Quiet) || self.total == 0 {
            return;
        }
        {
            let rate = if wall > 0.0 {
                self.done as f64 / wall
            } else {
                0.0
            };
            eprintln!(
                "rendered {} frame{} in {wall:.2} s ({rate:.2} frames/s)",
                self.done,
                if self.done == 1 { "" } else { "s" }
            );
        }
    }
}
