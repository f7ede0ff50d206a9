//! A worker's side of a run: one frame rendered, then encoded for each sink that wants it.
//! Workers only compute; what they make goes back to the run's thread (`delivery`).

use super::{RunError, Task};
use crate::output::{self, Files, RunIdentity, stream::StreamFormat};
use crate::sequence::Sequence;
use crate::shutter::FrameView;
use crate::tracer::{self, World};
use std::sync::atomic::AtomicBool;
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

/// A worker's whole job for one frame: render, then encode for each sink that wants it;
/// `None` when `cancel` stopped it.
pub(super) fn produce(
    world: &World,
    seq: &Sequence,
    task: Task,
    files: Option<(&Files, &RunIdentity)>,
    stream: Option<(StreamFormat, bool)>,
    cancel: &AtomicBool,
) -> Produced {
    let start = Instant::now();
    let n = task.frame;
    let view = FrameView::for_settings(&seq.timeline, &seq.settings, n);
    let exposure =
        (view.exposure.as_ref()).map_err(|&source| RunError::Camera { frame: n, source })?;
    let Some(mut frame) = tracer::render_or_stop(world, exposure, &seq.settings, n, cancel) else {
        return Ok(None);
    };
    let next = view.next.as_ref();
    frame.aov = tracer::aov::render(world, &exposure.camera, next, &seq.settings, cancel);
    if cancel.load(std::sync::atomic::Ordering::Relaxed) {
        return Ok(None);
    }
    let (file, clamped) = match files.filter(|_| task.write_file) {
        Some((files, identity)) => {
            let meta = identity.meta(&view);
            let path = files.frame_path(n);
            let (bytes, clamped) = output::encode_file(&frame, &files.format, &meta)
                .map_err(|source| RunError::Encode { path, source })?;
            (Some(bytes), clamped)
        }
        None => (None, 0),
    };
    let stream = match stream {
        Some((format, sixteen)) => Some(
            output::stream::encode(&frame, format, sixteen)
                .map_err(|source| RunError::EncodeStream { frame: n, source })?,
        ),
        None => None,
    };
    frame.recycle();
    Ok(Some(Encoded {
        seconds: start.elapsed().as_secs_f64(),
        file,
        clamped,
        stream,
    }))
}
