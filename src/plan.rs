//! Which frames a run must render: each selected frame's file is inspected and compared with
//! the fingerprint it would get now. Up-to-date frames are skipped; missing, stale and corrupt
//! ones are rendered; foreign files (images rayreel did not write) are left alone unforced.
//! Where the fingerprint differs, the settings records say what differs: a frame whose
//! difference is only of quality is kept unless the job raises every quality setting (or
//! `--force`), since a rerun without the original flags must not replace a finished frame
//! with a worse one, and so is one whose difference is its size (and quality); `--skip-existing`
//! keeps every complete frame of the job's size.
//!
//! The directory is listed once: a selected frame whose name is not in it is missing without a
//! look of its own, so a plan costs the selection's runs plus the files that exist, and each
//! state is kept as a `FrameSet`.

use crate::frameset::FrameSet;
use crate::output::record::{self, Difference};
use crate::output::{self, Existing, Expected, Files, RunIdentity};
use crate::sequence::Sequence;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum State {
    UpToDate,
    /// Made with other quality settings and kept (what differs, in words).
    Kept(String),
    /// Made from something else (what differs, in words): re-rendered.
    Stale(String),
    Missing,
    Corrupt(String),
    /// Someone else's file (why, in words), left alone unforced.
    Foreign(String),
}

/// What the user said about frames that exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Resume {
    /// Re-render stale frames; keep frames whose quality only differs unless raised.
    #[default]
    Normal,
    /// Render every selected frame, whatever is there (`--force`).
    Force,
    /// Keep every complete frame of the job's size, whatever made it (`--skip-existing`).
    SkipExisting,
}

impl Resume {
    /// The same without `--force`: what a re-plan after rendering, or `status`, goes by
    /// (forcing again would never end, and `status` only looks).
    pub(crate) fn unforced(self) -> Resume {
        match self {
            Resume::Force => Resume::Normal,
            other => other,
        }
    }
}

/// Frames grouped by why they are in their state (`size: 160x90 → 80x45`), in order of
/// first appearance.
pub(crate) type Reasons = Vec<(String, FrameSet)>;

/// Every selected frame, by the state of its file.
#[derive(Debug, Clone, Default)]
pub(crate) struct Plan {
    pub(crate) up_to_date: FrameSet,
    pub(crate) kept: FrameSet,
    pub(crate) stale: FrameSet,
    pub(crate) missing: FrameSet,
    pub(crate) corrupt: FrameSet,
    pub(crate) foreign: FrameSet,
    /// What is wrong with each corrupt file.
    pub(crate) why: Vec<(u64, String)>,
    /// What each foreign file is.
    pub(crate) why_foreign: Vec<(u64, String)>,
    /// What differs in kept and stale frames.
    pub(crate) why_kept: Reasons,
    pub(crate) why_stale: Reasons,
    pub(crate) force: bool,
}

/// Frames inspected in parallel at a time: bounds memory whatever the selection.
const CHUNK: usize = 4096;

pub(crate) fn plan(seq: &Sequence, frames: &FrameSet, files: &Files, resume: Resume) -> Plan {
    let mut plan = Plan {
        force: resume == Resume::Force,
        ..Plan::default()
    };
    let (present, missing) = match listed(files, frames) {
        Some(present) => {
            let missing = frames.without(&present);
            (present, missing)
        }
        // Unlisted (unreadable directory): look at every selected frame's file.
        None => (frames.iter().collect(), FrameSet::new()),
    };
    let job = Job {
        seq,
        files,
        identity: RunIdentity::new(seq, &files.format),
        expected: Expected {
            width: seq.settings.width,
            height: seq.settings.height,
            format: files.format,
            alpha: seq.settings.alpha,
        },
        resume,
    };
    let mut previous = None;
    for chunk in present.chunks(CHUNK) {
        let states: Vec<State> = chunk.par_iter().map(|&n| job.state(n)).collect();
        for (&n, state) in chunk.iter().zip(states) {
            // Runs of a state join only frames that follow each other in the selection, so
            // no state's run strides over another's frames and sets stay runs when joined.
            let after = previous.filter(|&p| frames.next_after(p) == Some(n));
            plan.add(n, state, after);
            previous = Some(n);
        }
    }
    // Frames that vanished between the listing and their inspection join the missing ones.
    plan.missing = FrameSet::union(&[&plan.missing, &missing]);
    plan
}

/// What a plan compares each frame's file with.
struct Job<'a> {
    seq: &'a Sequence,
    files: &'a Files,
    identity: RunIdentity,
    expected: Expected,
    resume: Resume,
}

impl Job<'_> {
    /// The state of frame `n`'s file.
    fn state(&self, n: u64) -> State {
        let seq = self.seq;
        let view = seq.settings.frame_view(&seq.timeline, n);
        let path = self.files.frame_path(n);
        let ours = |f: &str| f == self.identity.fingerprint(&view);
        let differs = || {
            let old = output::read_record(&path, &self.files.format);
            let new = self.identity.record(&view);
            (old.is_some(), record::compare(old.as_deref(), &new))
        };
        match output::inspect(&path, &self.expected) {
            Existing::Missing => State::Missing,
            Existing::Foreign(why) => State::Foreign(why),
            Existing::Corrupt(why) => State::Corrupt(why),
            Existing::Ours(f) if ours(&f) => State::UpToDate,
            Existing::Damaged { fingerprint, why } if ours(&fingerprint) => State::Corrupt(why),
            Existing::Ours(_) => judge(differs(), true, self.resume),
            // Not of this job's size or channels, or broken: say why when the records cannot.
            Existing::Damaged { why, .. } => match judge(differs(), false, self.resume) {
                State::Stale(what) if what.ends_with("unknown") => State::Stale(why),
                state => state,
            },
        }
    }
}

/// The state of a frame whose fingerprint is not this job's, from how its record differs
/// (`has_record`: whether it has one); `complete` when its file is intact and of the job's
/// size and channels.
fn judge((has_record, difference): (bool, Difference), complete: bool, resume: Resume) -> State {
    let what = match difference {
        Difference::Unknown if !has_record => "made by an older rayreel; differs: unknown".into(),
        Difference::Unknown => "differs: unknown".into(),
        Difference::Quality { what, raise: false } if complete && resume != Resume::Force => {
            let again = "--force re-renders them";
            return State::Kept(format!(
                "made with other quality settings ({what}); {again}"
            ));
        }
        Difference::Resized(what) if resume != Resume::Force => {
            return State::Kept(format!(
                "made at another size ({what}); a finished frame is not replaced by one of another size: --force replaces them, or write them elsewhere with -o"
            ));
        }
        Difference::Quality { what, .. }
        | Difference::Resized(what)
        | Difference::Content(what) => what,
    };
    match complete && resume == Resume::SkipExisting {
        true => State::Kept(format!("by --skip-existing ({what})")),
        false => State::Stale(what),
    }
}

/// The selected frames whose names the directory holds, ascending; `None` when it cannot be
/// listed for another reason than not existing.
fn listed(files: &Files, frames: &FrameSet) -> Option<Vec<u64>> {
    let dir = directory(&files.frame_path(0));
    let entries = match std::fs::read_dir(&dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Some(Vec::new()),
        Err(_) => return None,
    };
    let mut present = Vec::new();
    for entry in entries {
        let entry = entry.ok()?;
        if let Some(n) = entry
            .file_name()
            .to_str()
            .and_then(|name| files.pattern.frame_number(name))
            .filter(|&n| frames.contains(n))
        {
            present.push(n);
        }
    }
    present.sort_unstable();
    Some(present)
}

/// The directory a frame file lives in (`.` for a bare name).
pub(crate) fn directory(frame: &Path) -> PathBuf {
    match frame.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

impl Plan {
    /// Records frame `n`, which follows every frame recorded so far, and in the selection
    /// directly follows `after` if given.
    fn add(&mut self, n: u64, state: State, after: Option<u64>) {
        let set = match state {
            State::UpToDate => &mut self.up_to_date,
            State::Kept(why) => {
                group(&mut self.why_kept, why, n, after);
                &mut self.kept
            }
            State::Stale(why) => {
                group(&mut self.why_stale, why, n, after);
                &mut self.stale
            }
            State::Missing => &mut self.missing,
            State::Corrupt(why) => {
                self.why.push((n, why));
                &mut self.corrupt
            }
            State::Foreign(why) => {
                self.why_foreign.push((n, why));
                &mut self.foreign
            }
        };
        follow(set, n, after);
    }

    /// Every selected frame.
    pub(crate) fn selected(&self) -> FrameSet {
        FrameSet::union(&self.by_state().map(|(_, s)| s))
    }

    /// Frames that get rendered and written.
    pub(crate) fn to_render(&self) -> FrameSet {
        if self.force {
            return self.selected();
        }
        FrameSet::union(&[&self.stale, &self.missing, &self.corrupt])
    }

    /// Frames whose files are foreign and stay untouched.
    pub(crate) fn blocked(&self) -> FrameSet {
        match self.force {
            true => FrameSet::new(),
            false => self.foreign.clone(),
        }
    }

    /// Every state with its frames, in the order reports list them.
    pub(crate) fn by_state(&self) -> [(&'static str, &FrameSet); 6] {
        [
            ("up to date", &self.up_to_date),
            ("kept", &self.kept),
            ("stale", &self.stale),
            ("missing", &self.missing),
            ("corrupt", &self.corrupt),
            ("foreign", &self.foreign),
        ]
    }

    /// How many frames each state has, in the order of `by_state`.
    pub(crate) fn counts(&self) -> [(&'static str, u64); 6] {
        self.by_state().map(|(what, set)| (what, set.len()))
    }

    /// How many frames are selected.
    pub(crate) fn selected_count(&self) -> u64 {
        self.by_state().iter().map(|(_, s)| s.len()).sum()
    }

    /// `48 frames: 30 up to date, 2 stale, 16 missing → rendering 18`.
    pub(crate) fn summary(&self) -> String {
        format!(
            "{} → rendering {}{}",
            self.status_line(),
            self.to_render().len(),
            if self.force { " (--force)" } else { "" }
        )
    }

    /// `48 frames: 30 up to date, 2 stale, 16 missing`.
    pub(crate) fn status_line(&self) -> String {
        let parts: Vec<String> = self
            .by_state()
            .iter()
            .filter(|(_, s)| !s.is_empty())
            .map(|(what, s)| format!("{} {what}", s.len()))
            .collect();
        let n = self.selected_count();
        let parts = if parts.is_empty() {
            "none selected".to_string()
        } else {
            parts.join(", ")
        };
        format!("{n} frame{}: {parts}", if n == 1 { "" } else { "s" })
    }

    /// What differs in kept and stale frames, a line per group of frames with the same
    /// difference: `stale 0-5: size: 160x90 → 80x45`, `kept 0-5 made with other quality
    /// settings (samples: 16 → 4); --force re-renders them`.
    pub(crate) fn reasons(&self) -> Vec<String> {
        const SHOWN: usize = 8;
        let kept = self.why_kept.iter().map(|(w, s)| format!("kept {s} {w}"));
        let stale = self
            .why_stale
            .iter()
            .map(|(w, s)| format!("stale {s}: {w}"));
        let mut lines: Vec<String> = kept.chain(stale).collect();
        if lines.len() > SHOWN {
            let more = lines.len() - SHOWN + 1;
            lines.truncate(SHOWN - 1);
            lines.push(format!("… and {more} more differences"));
        }
        lines
    }
}

/// Adds `n` to the group of frames with reason `why`.
fn group(reasons: &mut Reasons, why: String, n: u64, after: Option<u64>) {
    match reasons.iter_mut().find(|(w, _)| *w == why) {
        Some((_, set)) => follow(set, n, after),
        None => {
            let mut set = FrameSet::new();
            set.push(n);
            reasons.push((why, set));
        }
    }
}

/// Adds `n`, which in the selection directly follows `after` if given, to `set`: a run goes
/// on only over frames that follow each other in the selection, so it strides over no other
/// state's frames.
fn follow(set: &mut FrameSet, n: u64, after: Option<u64>) {
    match after.is_some() && set.last() == after {
        true => set.push(n),
        false => set.push_apart(n),
    }
}
