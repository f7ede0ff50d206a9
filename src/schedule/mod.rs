//! The frame scheduler: renders the selected frames on a rayon pool in ascending order, each
//! on every thread (its rows in parallel), the next one starting as soon as one is rendered
//! while that one is encoded, so both cores stay busy, frames are written in order and an
//! interrupted run leaves a prefix. A bounded window of frames is handed over at a time, so
//! memory does not grow with the length of the sequence or with a slow reader. Workers only
//! compute (render, encode); this thread does all I/O: atomic file writes in frame order, the
//! stream strictly in frame order.
//!
//! `work` is what the workers do with the frames (render in turn, encode); `delivery` is what
//! this thread does with a finished one (claims, atomic writes, progress); `stream` keeps the
//! stream's order and writes it on a thread of its own.

mod delivery;
pub(crate) mod memory;
mod stream;
mod work;

use crate::claim::Claims;
use crate::frame::Frame;
use crate::output::{EncodeError, Files, RunIdentity, stream::StreamFormat};
use crate::progress::Progress;
use crate::sequence::Sequence;
use crate::settings::Settings;
use crate::tracer::{self, World};
use delivery::Delivery;
use std::io::Write;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, mpsc};
use std::time::Duration;
use work::{Produced, Renderer};

/// One frame of a run: its number, and whether its file must be written (with a stream, frames
/// whose files are up to date are still rendered for the stream but not rewritten).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Task {
    pub(crate) frame: u64,
    pub(crate) write_file: bool,
}

/// What a run renders and where it goes: the frames (tasks), the file sink, the stream, the
/// threads and, when processes cooperate, their claims.
pub(crate) struct Batch {
    pub(crate) sequence: Arc<Sequence>,
    /// Ascending frame numbers, each inside the timeline.
    pub(crate) tasks: Vec<Task>,
    pub(crate) files: Option<Files>,
    pub(crate) stream: Option<(StreamFormat, bool)>,
    /// Where the stream goes: stdout for users, a sink for benchmarks.
    pub(crate) stream_out: Option<Box<dyn Write + Send>>,
    pub(crate) threads: usize,
    /// Cooperate with other processes through claim files (files only, no stream).
    pub(crate) claims: Option<Arc<Claims>>,
}

/// How a run ended when nothing failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// Every task done, except `held`: frames another live process has claimed.
    Complete { written: usize, held: Vec<u64> },
    /// Ctrl-C or SIGTERM: frames in flight were cancelled, nothing new was started; frames
    /// finished before stay written (and streamed).
    Interrupted { written: usize, streamed: usize },
    /// The stream's reader closed the pipe; the remaining work was cancelled.
    ReaderClosed { streamed: usize },
}

/// Frames rendered in parallel beyond one per thread: enough to hide encoding and writing
/// behind rendering, few enough that memory stays a handful of frames.
const EXTRA_IN_FLIGHT: usize = 2;

/// Why a run stopped short of its frames (the command maps every one to exit 1).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("cannot start {threads} worker threads: {source}")]
    Workers {
        threads: usize,
        source: rayon::ThreadPoolBuildError,
    },
    #[error("frame {frame}: {source}")]
    Camera {
        frame: u64,
        source: crate::shutter::NoCamera,
    },
    #[error("{}: cannot encode: {source}", path.display())]
    Encode {
        path: std::path::PathBuf,
        source: EncodeError,
    },
    #[error("frame {frame}: cannot encode the stream: {source}")]
    EncodeStream { frame: u64, source: EncodeError },
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("{}: cannot create claim: {source}", path.display())]
    Claim {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("stdout: cannot write the stream: {0}")]
    Stream(std::io::Error),
    #[error("not enough memory: {0}")]
    Memory(String),
    /// The system refused memory the budget admitted (or does not look at), named.
    #[error(transparent)]
    Allocation(#[from] crate::budget::OutOfMemory),
    #[error("worker lost: {0}")]
    WorkerLost(mpsc::RecvTimeoutError),
}

/// `window` frames in flight, or as many as the memory the process may use holds beside the
/// meshes' hierarchies (saying so), or an error before any frame starts when not even one does.
fn memory_window(batch: &Batch, window: usize, progress: &Progress) -> Result<usize, RunError> {
    let format = batch.files.as_ref().map(|f| f.format);
    let per_frame = memory::frame_bytes(&batch.sequence.settings, format);
    let hierarchies = memory::hierarchies(&batch.sequence);
    let arenas = memory::arenas_to_come(threads_to_come(batch));
    let available = memory::available(arenas);
    let fits =
        memory::fit(window, per_frame, hierarchies, arenas, available).map_err(RunError::Memory)?;
    if let (true, Some(free)) = (fits < window, available) {
        progress.note(&format!(
            "note: {fits} frame{} at a time instead of {window}: each needs about {} and {} is free under {}",
            if fits == 1 { "" } else { "s" },
            crate::budget::size(per_frame),
            crate::budget::size(free.bytes.saturating_sub(hierarchies)),
            free.limit
        ));
    }
    Ok(fits)
}

/// Threads that may still take an allocator arena of their own once the workers have theirs
/// (`run_on` has each allocate first): those running besides the workers and this one (a
/// progress bar's ticker, the reader of ffmpeg's messages), which may not have allocated yet,
/// and the stream's writer, started later.
fn threads_to_come(batch: &Batch) -> u64 {
    let running = memory::threads_now().unwrap_or(0);
    let others = running.saturating_sub(1 + batch.threads as u64);
    others + u64::from(batch.stream.is_some())
}

/// How often the run looks at signals, claims and workers.
const TICK: Duration = Duration::from_millis(100);

/// How long a stopping run waits for frames in flight to give up (they check at every pixel,
/// so this only matters while one is being encoded) before it leaves them behind.
const STOP_GRACE: Duration = Duration::from_secs(2);

pub(crate) fn run(batch: Batch, progress: &mut Progress) -> Result<Outcome, RunError> {
    run_on(&worker_pool(batch.threads)?, batch, progress)
}

/// The worker threads of a run; an error when the machine cannot start that many.
pub(crate) fn worker_pool(threads: usize) -> Result<rayon::ThreadPool, RunError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("rayreel-{i}"))
        .build()
        .map_err(|source| RunError::Workers { threads, source })
}

/// Standard output for frames, written straight to its descriptor: `std::io::stdout()` is
/// line-buffered, so every frame's megabytes would be searched for a newline (1% of the
/// talk's f32 stream).
fn unbuffered_stdout() -> Box<dyn Write + Send> {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        if let Ok(fd) = std::io::stdout().as_fd().try_clone_to_owned() {
            return Box::new(std::fs::File::from(fd));
        }
    }
    Box::new(std::io::stdout())
}

/// `run` on threads already started (claim mode runs several passes on them).
pub(crate) fn run_on(
    pool: &rayon::ThreadPool,
    mut batch: Batch,
    progress: &mut Progress,
) -> Result<Outcome, RunError> {
    return_frame_buffers_to_the_os();
    // Each worker allocates once, so that its allocator arena is in the address space the
    // memory check reads rather than one it must keep room for.
    pool.broadcast(|_| drop(std::hint::black_box(Box::new(0u64))));
    let window = match batch.stream {
        // A stream has its order to keep: one frame rendering (on every thread) while the one
        // before is written keeps memory to two frames whatever the reader does.
        Some(_) => 2,
        None => batch.threads + EXTRA_IN_FLIGHT,
    };
    let window = memory_window(&batch, window, progress)?;
    let (tx, rx) = mpsc::channel::<(u64, Produced)>();
    let out = batch.stream_out.take().unwrap_or_else(unbuffered_stdout);
    let mut d = Delivery::new(&batch, progress, out);
    let renderer = renderer(&batch, &d.cancel, tx)?;
    let mut pending = batch.tasks.iter().copied();
    let mut in_flight = 0;
    loop {
        d.notice_signal(in_flight);
        // Frames rendered but held for the stream's order count too: a slow frame must not
        // let the others run ahead without bound.
        while d.stop.is_none() && in_flight + d.held_for_order() < window {
            let Some(task) = pending.next() else { break };
            if d.claim(task.frame) {
                d.started(task.frame);
                renderer.queue(pool, task);
                in_flight += 1;
            }
        }
        if in_flight == 0 || d.signalled.is_some_and(|t| t.elapsed() > STOP_GRACE) {
            break;
        }
        d.heartbeat();
        match rx.recv_timeout(TICK) {
            Ok((frame, done)) => {
                in_flight -= 1;
                d.deliver(frame, done);
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(e) => return Err(RunError::WorkerLost(e)),
        }
    }
    d.finish()
}

/// What renders the batch's frames, in turn; their results come back through `tx`.
fn renderer(
    batch: &Batch,
    cancel: &Arc<AtomicBool>,
    tx: mpsc::Sender<(u64, Produced)>,
) -> Result<Arc<Renderer>, RunError> {
    let seq = Arc::clone(&batch.sequence);
    let files = (batch.files.clone()).map(|f| {
        let identity = RunIdentity::new(&seq, &f.format);
        (f, identity)
    });
    Ok(Arc::new(Renderer {
        world: World::try_new(seq.scene.clone())?,
        seq,
        files,
        stream: batch.stream,
        cancel: Arc::clone(cancel),
        results: tx,
        queue: Mutex::new(Default::default()),
    }))
}

/// Renders frame `n` of the sequence (building its geometry; a run builds it once).
pub fn render_frame(seq: &Sequence, n: u64) -> Result<Frame, RunError> {
    render_with(&World::try_new(seq.scene.clone())?, seq, n, &seq.settings)
}

/// Renders frame `n` in `world` (built once from the sequence's scene) with `settings`.
pub(crate) fn render_with(
    world: &World,
    seq: &Sequence,
    n: u64,
    settings: &Settings,
) -> Result<Frame, RunError> {
    render_seeded(world, seq, n, n, settings)
}

/// `render_with`, its samples seeded as frame `seed`'s would be (`measure`'s references are
/// frame n seen with other seeds).
pub(crate) fn render_seeded(
    world: &World,
    seq: &Sequence,
    n: u64,
    seed: u64,
    settings: &Settings,
) -> Result<Frame, RunError> {
    let view = settings.frame_view(&seq.timeline, n);
    let exposure =
        (view.exposure.as_ref()).map_err(|&source| RunError::Camera { frame: n, source })?;
    let never = std::sync::atomic::AtomicBool::new(false);
    let mut frame = tracer::render_or_stop(world, exposure, settings, seed, &never, false)?
        .expect("never stopped");
    if !settings.aov.is_empty() {
        frame.aov = tracer::aov::render(
            &world.at_frame(exposure),
            &exposure.camera,
            view.next.as_ref(),
            settings,
            &never,
        );
    }
    Ok(frame)
}

/// Frame buffers are large and short-lived. glibc raises its mmap threshold after the first
/// ones are freed and then keeps such blocks in fragmented arenas, so peak memory creeps up
/// with the length of a sequence; a fixed threshold maps and unmaps each buffer instead.
fn return_frame_buffers_to_the_os() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only tunes the allocator; called before the worker threads allocate.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 256 * 1024);
    }
}
