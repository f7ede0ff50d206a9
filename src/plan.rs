//! Which frames a run must render: each selected frame's file is inspected and compared with
//! the fingerprint it would get now. Up-to-date frames are skipped; missing, stale and corrupt
//! ones are rendered; foreign files (images rayreel did not write) are left alone unforced.

use crate::output::{self, Existing, fingerprint};
use crate::schedule::{Files, frame_meta};
use crate::sequence::Sequence;
use rayon::prelude::*;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum State {
    UpToDate,
    Stale,
    Missing,
    Corrupt(String),
    Foreign,
}

#[derive(Debug, Clone)]
pub struct Plan {
    /// Every selected frame with the state of its file, ascending.
    pub frames: Vec<(u64, State)>,
    pub force: bool,
}

pub fn plan(seq: &Sequence, frames: &[u64], files: &Files, force: bool) -> Plan {
    let run = fingerprint::of_run(&seq.scene, &seq.settings, &files.format);
    let frames = frames
        .par_iter()
        .map(|&n| {
            let state = match output::inspect(&files.pattern.frame_path(n), &files.format) {
                Existing::Missing => State::Missing,
                Existing::Foreign => State::Foreign,
                Existing::Corrupt(why) => State::Corrupt(why),
                Existing::Ours(f) if f == frame_meta(seq, n, &run).fingerprint => State::UpToDate,
                Existing::Ours(_) => State::Stale,
            };
            (n, state)
        })
        .collect();
    Plan { frames, force }
}

impl Plan {
    /// Whether frame `n` in state `s` gets rendered and written.
    pub fn renders(&self, s: &State) -> bool {
        self.force || matches!(s, State::Stale | State::Missing | State::Corrupt(_))
    }

    pub fn to_render(&self) -> Vec<u64> {
        self.frames
            .iter()
            .filter(|(_, s)| self.renders(s))
            .map(|(n, _)| *n)
            .collect()
    }

    /// Frames whose files are foreign and stay untouched.
    pub fn blocked(&self) -> Vec<u64> {
        if self.force {
            return Vec::new();
        }
        self.frames
            .iter()
            .filter(|(_, s)| *s == State::Foreign)
            .map(|(n, _)| *n)
            .collect()
    }

    fn count(&self, f: impl Fn(&State) -> bool) -> usize {
        self.frames.iter().filter(|(_, s)| f(s)).count()
    }

    /// `48 frames: 30 up to date, 2 stale, 16 missing → rendering 18`.
    pub fn summary(&self) -> String {
        format!(
            "{} → rendering {}{}",
            self.status_line(),
            self.to_render().len(),
            if self.force { " (--force)" } else { "" }
        )
    }

    /// `48 frames: 30 up to date, 2 stale, 16 missing`.
    pub fn status_line(&self) -> String {
        let parts: Vec<String> = [
            ("up to date", self.count(|s| *s == State::UpToDate)),
            ("stale", self.count(|s| *s == State::Stale)),
            ("missing", self.count(|s| *s == State::Missing)),
            ("corrupt", self.count(|s| matches!(s, State::Corrupt(_)))),
            ("foreign", self.count(|s| *s == State::Foreign)),
        ]
        .iter()
        .filter(|(_, n)| *n > 0)
        .map(|(what, n)| format!("{n} {what}"))
        .collect();
        let n = self.frames.len();
        let parts = if parts.is_empty() {
            "none selected".to_string()
        } else {
            parts.join(", ")
        };
        format!("{n} frame{}: {parts}", if n == 1 { "" } else { "s" })
    }
}

/// Task `k` of `n` (1-based) takes every n-th frame starting at its own: shares differ by at
/// most one frame, and each task sweeps the whole timeline, so close-ups and wide shots (which
/// cluster in time and cost differently) spread evenly over the tasks.
pub fn shard(frames: &[u64], k: u64, n: u64) -> Vec<u64> {
    frames
        .iter()
        .enumerate()
        .filter(|(i, _)| *i as u64 % n == k - 1)
        .map(|(_, f)| *f)
        .collect()
}

/// Frame numbers as a compact spec: `0-11,14,20-47`.
pub fn compress(frames: &[u64]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < frames.len() {
        let mut j = i;
        while j + 1 < frames.len() && frames[j + 1] == frames[j] + 1 {
            j += 1;
        }
        out.push(if j == i {
            frames[i].to_string()
        } else {
            format!("{}-{}", frames[i], frames[j])
        });
        i = j + 1;
    }
    out.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_are_disjoint_cover_everything_and_balance() {
        for count in [0u64, 1, 2, 7, 48, 101, 1000] {
            let frames: Vec<u64> = (0..count).map(|f| f * 3 + 1).collect();
            for n in 1..=9 {
                let shares: Vec<Vec<u64>> = (1..=n).map(|k| shard(&frames, k, n)).collect();
                let mut all: Vec<u64> = shares.concat();
                all.sort_unstable();
                assert_eq!(all, frames, "{count} frames over {n}");
                let sizes: Vec<usize> = shares.iter().map(Vec::len).collect();
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{sizes:?}");
            }
        }
    }

    #[test]
    fn compresses_runs() {
        assert_eq!(compress(&[0, 1, 2, 3, 5, 7, 8]), "0-3,5,7-8");
        assert_eq!(compress(&[]), "");
        assert_eq!(compress(&[4]), "4");
    }
}
