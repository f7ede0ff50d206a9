//! The I/O side of a run, on the thread that runs it: claims taken, refreshed and released,
//! finished frames written atomically and put on the stream in order, progress reported, and
//! the first signal noticed.

use super::stream::{Reorder, StreamWriter};
use super::work::{Encoded, Produced};
use super::{Batch, Outcome, RunError};
use crate::claim::{Attempt, Claims};
use crate::output;
use crate::progress::Progress;
use crate::signals::{interrupt_code, interrupted, signal_name};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// The I/O side of a run: everything this thread does with finished frames.
pub(super) struct Delivery<'a> {
    batch: &'a Batch,
    progress: &'a mut Progress,
    stream: Option<Reorder>,
    written: usize,
    held: Vec<u64>,
    /// Frames in flight under a claim, with when they were last refreshed.
    claimed: Vec<(u64, Instant)>,
    /// Frames started and not yet back, and frames back before a lower one: files are
    /// written in frame order, so what is on disk is always a prefix of the run's frames.
    in_flight: BTreeSet<u64>,
    early: BTreeMap<u64, Encoded>,
    pub(super) stop: Option<Result<Outcome, RunError>>,
    /// Set once the run stops: frames in flight give up at their next pixel.
    pub(super) cancel: Arc<AtomicBool>,
    /// When a signal was noticed.
    pub(super) signalled: Option<Instant>,
}

impl<'a> Delivery<'a> {
    /// Nothing delivered yet; the stream, if the batch has one, goes to `out`.
    pub(super) fn new(
        batch: &'a Batch,
        progress: &'a mut Progress,
        out: Box<dyn Write + Send>,
    ) -> Delivery<'a> {
        Delivery {
            batch,
            progress,
            stream: batch.stream.map(|(format, sixteen)| {
                // Raw 8-bit frames are `to_rgb8`'s buffers: given back once written.
                let recycle = format == crate::output::stream::StreamFormat::Raw && !sixteen;
                Reorder::new(&batch.tasks, StreamWriter::start(out, recycle))
            }),
            written: 0,
            held: Vec::new(),
            claimed: Vec::new(),
            in_flight: BTreeSet::new(),
            early: BTreeMap::new(),
            stop: None,
            cancel: Arc::new(AtomicBool::new(false)),
            signalled: None,
        }
    }
}

impl Delivery<'_> {
    /// On the first Ctrl-C or SIGTERM: stop starting frames, cancel those in flight, and say
    /// so at once.
    pub(super) fn notice_signal(&mut self, in_flight: usize) {
        if self.signalled.is_some() || !interrupted() {
            return;
        }
        self.signalled = Some(Instant::now());
        self.stop = Some(Ok(Outcome::Interrupted {
            written: 0,
            streamed: 0,
        }));
        self.cancel.store(true, Ordering::SeqCst);
        let what = match in_flight {
            0 => "no frame is in flight".to_string(),
            1 => "the frame in flight is cancelled at the next pixel".to_string(),
            n => format!("the {n} frames in flight are cancelled at the next pixel"),
        };
        let again = match signal_name() {
            "SIGINT" => "Ctrl-C again to abort at once",
            _ => "a second signal aborts at once",
        };
        // A run without frame files (a stream, `--video` without -o) keeps nothing.
        let kept = match self.batch.files.is_some() {
            true => "frames already written stay",
            false => "this run writes no frame files, so nothing it rendered is kept",
        };
        let text = format!(
            "rayreel: stopping on {}: {what}; {kept}; exit code {} follows ({again})",
            signal_name(),
            interrupt_code()
        );
        self.progress.interrupt(signal_name(), in_flight, &text);
    }

    /// The run's outcome; claims still held for frames left behind are released.
    pub(super) fn finish(mut self) -> Result<Outcome, RunError> {
        self.cancel.store(true, Ordering::SeqCst);
        // Frames finished while a lower one was left behind are kept all the same.
        while let Some((n, done)) = self.early.pop_first() {
            self.write(n, done);
        }
        for (n, _) in self.claimed.clone() {
            self.release(n);
        }
        let (written, held) = (self.written, self.held);
        let streamed = self.stream.as_ref().map_or(0, |r| r.sent);
        match self.stop {
            None => Ok(Outcome::Complete { written, held }),
            Some(Ok(Outcome::Interrupted { .. })) => Ok(Outcome::Interrupted { written, streamed }),
            Some(other) => other,
        }
    }

    pub(super) fn held_for_order(&self) -> usize {
        self.early.len() + self.stream.as_ref().map_or(0, |r| r.held.len())
    }

    /// Frame `n` has been handed to the workers.
    pub(super) fn started(&mut self, n: u64) {
        self.in_flight.insert(n);
    }

    /// Claims frame `n` when cooperating; false if another process holds it.
    pub(super) fn claim(&mut self, n: u64) -> bool {
        let (Some(claims), Some(files)) = (&self.batch.claims, &self.batch.files) else {
            return true;
        };
        match claims.try_claim(&files.frame_path(n)) {
            Ok(Attempt::Claimed) => {
                self.claimed.push((n, Instant::now()));
                true
            }
            Ok(Attempt::Held(_)) => {
                self.held.push(n);
                false
            }
            Err(e) => {
                let path = Claims::path(&files.frame_path(n));
                self.stop
                    .get_or_insert(Err(RunError::Claim { path, source: e }));
                false
            }
        }
    }

    pub(super) fn heartbeat(&mut self) {
        let (Some(claims), Some(files)) = (&self.batch.claims, &self.batch.files) else {
            return;
        };
        for (n, last) in &mut self.claimed {
            if last.elapsed() >= claims.heartbeat_every() {
                claims.heartbeat(&files.frame_path(*n));
                *last = Instant::now();
            }
        }
    }

    fn release(&mut self, n: u64) {
        if let (Some(claims), Some(files)) = (&self.batch.claims, &self.batch.files) {
            claims.release(&files.frame_path(n));
            self.claimed.retain(|(f, _)| *f != n);
        }
    }

    /// Takes a frame back from the workers: records why it failed, or writes it and every
    /// frame held for it once no lower frame is in flight.
    pub(super) fn deliver(&mut self, frame: u64, done: Produced) {
        self.in_flight.remove(&frame);
        match done {
            Ok(Some(d)) => {
                self.early.insert(frame, d);
            }
            Ok(None) => self.release(frame),
            Err(e) => {
                self.release(frame);
                self.progress.frame_failed(frame, &e.to_string());
                self.stop.get_or_insert(Err(e));
                self.cancel.store(true, Ordering::SeqCst);
            }
        }
        let due = self.in_flight.first().copied().unwrap_or(u64::MAX);
        while let Some(entry) = self.early.first_entry().filter(|e| *e.key() < due) {
            let (n, done) = entry.remove_entry();
            self.write(n, done);
        }
    }

    /// Writes a finished frame's file and stream bytes.
    fn write(&mut self, frame: u64, done: Encoded) {
        if let (Some(bytes), Some(files)) = (&done.file, &self.batch.files) {
            let path = files.frame_path(frame);
            let result = output::atomic::write_atomic(&path, bytes);
            self.release(frame);
            if let Err(source) = result {
                let e = RunError::Write { path, source };
                self.progress.frame_failed(frame, &e.to_string());
                self.stop.get_or_insert(Err(e));
                self.cancel.store(true, Ordering::SeqCst);
                return;
            }
            self.written += 1;
            if done.clamped > 0 {
                self.progress
                    .half_overflow(frame, &path.display().to_string(), done.clamped);
            }
            self.progress
                .frame_done(frame, &path.display().to_string(), done.seconds);
        }
        // Once stopping, the stream is cut where it is.
        let (Some(order), Some(bytes), None) = (self.stream.as_mut(), done.stream, &self.stop)
        else {
            return;
        };
        match order.push(frame, bytes, done.seconds) {
            Ok(sent) => {
                for (n, seconds) in sent.into_iter().filter(|_| done.file.is_none()) {
                    let to = self.progress.stream_to;
                    self.progress.frame_done(n, to, seconds);
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.stop = Some(Ok(Outcome::ReaderClosed {
                    streamed: order.sent,
                }));
                self.cancel.store(true, Ordering::SeqCst);
            }
            // A signal came while the reader was not reading: `notice_signal` takes it up.
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => {
                self.stop.get_or_insert(Err(RunError::Stream(e)));
            }
        }
    }
}
