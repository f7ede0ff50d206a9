//! The stream's side of a run: frames put on stdout strictly in frame order, by a thread of
//! their own so a reader that stops reading never blocks the run.

use super::{TICK, Task};
use crate::signals::interrupted;
use std::collections::BTreeMap;
use std::io::Write;
use std::sync::mpsc;

/// Puts stream bytes on stdout strictly in frame order, holding early arrivals.
pub(super) struct Reorder {
    out: StreamWriter,
    order: Vec<u64>,
    next: usize,
    pub(super) held: BTreeMap<u64, (Vec<u8>, f64)>,
    pub(super) sent: usize,
}

impl Reorder {
    pub(super) fn new(tasks: &[Task], out: StreamWriter) -> Reorder {
        Reorder {
            out,
            order: tasks.iter().map(|t| t.frame).collect(),
            next: 0,
            held: BTreeMap::new(),
            sent: 0,
        }
    }

    /// Holds `bytes` of `frame` and writes every frame now due; returns those frames with
    /// their render times.
    pub(super) fn push(
        &mut self,
        frame: u64,
        bytes: Vec<u8>,
        seconds: f64,
    ) -> std::io::Result<Vec<(u64, f64)>> {
        self.held.insert(frame, (bytes, seconds));
        let mut sent = Vec::new();
        while let Some(&n) = self.order.get(self.next) {
            let Some((bytes, seconds)) = self.held.remove(&n) else {
                break;
            };
            self.out.write(bytes)?;
            self.next += 1;
            self.sent += 1;
            sent.push((n, seconds));
        }
        Ok(sent)
    }
}

/// Writes the stream on a thread of its own: a reader that stops reading blocks that thread
/// only, so the run still notices a signal, and one Ctrl-C ends it.
pub(super) struct StreamWriter {
    frames: mpsc::Sender<Vec<u8>>,
    written: mpsc::Receiver<std::io::Result<()>>,
}

impl StreamWriter {
    /// `recycle`: the frames are `Frame::to_rgb8`'s bytes, given back for the next frame's
    /// once written.
    pub(super) fn start(mut out: Box<dyn Write + Send>, recycle: bool) -> StreamWriter {
        let (frames, todo) = mpsc::channel::<Vec<u8>>();
        let (done, written) = mpsc::channel();
        std::thread::spawn(move || {
            for bytes in todo {
                let result = out.write_all(&bytes).and_then(|()| out.flush());
                if recycle {
                    crate::frame::recycle_bytes(bytes);
                }
                if done.send(result).is_err() {
                    break;
                }
            }
        });
        StreamWriter { frames, written }
    }

    /// Writes one frame; `Interrupted` if a signal comes first.
    pub(super) fn write(&mut self, bytes: Vec<u8>) -> std::io::Result<()> {
        let gone = || std::io::Error::from(std::io::ErrorKind::BrokenPipe);
        self.frames.send(bytes).map_err(|_| gone())?;
        loop {
            match self.written.recv_timeout(TICK) {
                Ok(result) => return result,
                Err(mpsc::RecvTimeoutError::Timeout) if interrupted() => {
                    return Err(std::io::ErrorKind::Interrupted.into());
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => return Err(gone()),
            }
        }
    }
}
