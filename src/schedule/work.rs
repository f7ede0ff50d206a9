//! A worker's side of a run: frames rendered one after the other, each on every thread, and
//! each encoded for the sinks that want it while the next one renders. Workers only compute;
//! what they make goes back to the run's thread (`delivery`).
//!
//! Frames render in turn rather than side by side: with several frames on a work-stealing
//! pool, a thread waiting inside one frame takes up another and must finish it first, so
//! frames ended in any order (frame 0 once came 22nd) and an interrupted run left holes. In
//! turn, the lowest frame in flight has every thread, frames finish in ascending order and a
//! stopped run leaves a prefix; encoding still overlaps the next frame's rendering.

use super::{RunError, Task};
use crate::frame::Frame;
use crate::output::{self, Files, RunIdentity, stream::StreamFormat};
use crate::sequence::Sequence;
use crate::shutter::FrameView;
use crate::tracer::{self, World};
use std::collections::VecDeque;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, mpsc};
use std::time::Instant;

/// A frame a worker finished: how long it took and its encoded bytes for each sink.
pub(super) struct Encoded {
    pub(super) seconds: f64,
    pub(super) file: Option<Vec<u8>>,
    /// Colour samples of the file beyond the largest half float, held at it.
    pub(super) clamped: u64,
    pub(super) stream: Option<Vec<u8>>,
}

/// What a worker sends back: the frame's bytes, `None` if it was cancelled, or why it failed.
pub(super) type Produced = Result<Option<Encoded>, RunError>;

/// What every frame of a run is rendered with and where its result goes.
pub(super) struct Renderer {
    pub(super) world: World,
    pub(super) seq: Arc<Sequence>,
    pub(super) files: Option<(Files, RunIdentity)>,
    pub(super) stream: Option<(StreamFormat, bool)>,
    pub(super) cancel: Arc<AtomicBool>,
    pub(super) results: mpsc::Sender<(u64, Produced)>,
    /// Frames waiting to render, lowest first, and whether a frame is rendering.
    pub(super) queue: Mutex<(VecDeque<Task>, bool)>,
}

impl Renderer {
    /// Queues `task` behind the frames already queued; starts rendering on `pool` if idle.
    pub(super) fn queue(self: &Arc<Self>, pool: &rayon::ThreadPool, task: Task) {
        let mut queue = self.queue.lock().unwrap_or_else(|e| e.into_inner());
        queue.0.push_back(task);
        if !std::mem::replace(&mut queue.1, true) {
            let me = Arc::clone(self);
            pool.spawn(move || me.render_next());
        }
    }

    /// Renders the first queued frame on every thread, then starts the next one (on the
    /// threads this one leaves) and encodes this one meanwhile.
    fn render_next(self: Arc<Self>) {
        let task = {
            let mut queue = self.queue.lock().unwrap_or_else(|e| e.into_inner());
            let next = queue.0.pop_front();
            queue.1 = next.is_some();
            next
        };
        let Some(task) = task else { return };
        let start = Instant::now();
        let view = self.seq.settings.frame_view(&self.seq.timeline, task.frame);
        let rendered = self.render(task.frame, &view);
        let me = Arc::clone(&self);
        rayon::spawn(move || me.render_next());
        let produced = rendered.and_then(|frame| match frame {
            Some(frame) => self.encode(task, &view, frame, start).map(Some),
            None => Ok(None),
        });
        // The run may have stopped waiting for this frame (a stop's grace ran out).
        let _ = self.results.send((task.frame, produced));
    }

    /// The frame `view` shows, or `None` when the run was cancelled first.
    fn render(&self, n: u64, view: &FrameView) -> Result<Option<Frame>, RunError> {
        let exposure =
            (view.exposure.as_ref()).map_err(|&source| RunError::Camera { frame: n, source })?;
        let settings = &self.seq.settings;
        let Some(mut frame) = tracer::render_or_stop(
            &self.world,
            exposure,
            settings,
            n,
            &self.cancel,
            self.wants8(),
        )?
        else {
            return Ok(None);
        };
        let next = view.next.as_ref();
        if !settings.aov.is_empty() {
            let world = self.world.at_frame(exposure);
            frame.aov = tracer::aov::render(&world, &exposure.camera, next, settings, &self.cancel);
        }
        if self.cancel.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(None);
        }
        Ok(Some(frame))
    }

    /// Whether a sink takes 8-bit levels (`Frame::take_rgb8`): an 8-bit PNG file or stream,
    /// or a raw 8-bit stream.
    fn wants8(&self) -> bool {
        let file = self.files.as_ref().is_some_and(|(files, _)| {
            matches!(
                files.format,
                output::FileFormat::Png {
                    sixteen_bit: false,
                    ..
                }
            )
        });
        file || self.stream.is_some_and(|(_, sixteen)| !sixteen)
    }

    /// `frame`'s bytes for each sink that wants them.
    fn encode(
        &self,
        task: Task,
        view: &FrameView,
        mut frame: Frame,
        start: Instant,
    ) -> Result<Encoded, RunError> {
        let n = task.frame;
        let (file, clamped) = match self.files.as_ref().filter(|_| task.write_file) {
            Some((files, identity)) => {
                let meta = identity.meta(view);
                let path = files.frame_path(n);
                let (bytes, clamped) = output::encode_file(&mut frame, &files.format, &meta)
                    .map_err(|source| RunError::Encode { path, source })?;
                (Some(bytes), clamped)
            }
            None => (None, 0),
        };
        let stream = match self.stream {
            Some((format, sixteen)) => Some(
                output::stream::encode(&mut frame, format, sixteen)
                    .map_err(|source| RunError::EncodeStream { frame: n, source })?,
            ),
            None => None,
        };
        frame.recycle();
        Ok(Encoded {
            seconds: start.elapsed().as_secs_f64(),
            file,
            clamped,
            stream,
        })
    }
}
