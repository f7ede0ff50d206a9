//! The frame scheduler: renders the selected frames on a rayon pool, a bounded window of frames
//! at a time (rows of each frame are parallel too), so both cores stay busy from the first
//! frame to the last, the first file appears early, and memory does not grow with the length
//! of the sequence or with a slow reader. Workers only compute (render, encode); this thread
//! does all I/O: atomic file writes as frames finish, the stream strictly in frame order.

use crate::claim::{Attempt, Claims};
use crate::frame::Frame;
use crate::output::{self, EncodeError, Files, RunIdentity, stream::StreamFormat};
use crate::progress::Progress;
use crate::sequence::Sequence;
use crate::settings::Settings;
use crate::shutter::{Exposure, FrameView};
use crate::signals::{interrupt_code, interrupted, signal_name};
use crate::tracer::{self, World};
use std::collections::BTreeMap;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

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

/// A frame a worker finished: how long it took and its encoded bytes for each sink.
struct Encoded {
    seconds: f64,
    file: Option<Vec<u8>>,
    stream: Option<Vec<u8>>,
}

/// The I/O side of a run: everything this thread does with finished frames.
struct Delivery<'a> {
    batch: &'a Batch,
    progress: &'a mut Progress,
    stream: Option<Reorder>,
    written: usize,
    held: Vec<u64>,
    /// Frames in flight under a claim, with when they were last refreshed.
    claimed: Vec<(u64, Instant)>,
    stop: Option<Result<Outcome, RunError>>,
    /// Set once the run stops: frames in flight give up at their next pixel.
    cancel: Arc<AtomicBool>,
    /// When a signal was noticed.
    signalled: Option<Instant>,
}

/// What a worker sends back: the frame's bytes, `None` if it was cancelled, or why it failed.
type Produced = Result<Option<Encoded>, RunError>;

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
    #[error("worker lost: {0}")]
    WorkerLost(mpsc::RecvTimeoutError),
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

/// `run` on threads already started (claim mode runs several passes on them).
pub(crate) fn run_on(
    pool: &rayon::ThreadPool,
    mut batch: Batch,
    progress: &mut Progress,
) -> Result<Outcome, RunError> {
    return_frame_buffers_to_the_os();
    let window = match batch.stream {
        // A stream has its order to keep: one frame rendering (on every thread) while the one
        // before is written keeps memory to two frames whatever the reader does.
        Some(_) => 2,
        None => batch.threads + EXTRA_IN_FLIGHT,
    };
    let (tx, rx) = mpsc::channel::<(u64, Produced)>();
    let out = batch
        .stream_out
        .take()
        .unwrap_or_else(|| Box::new(std::io::stdout()));
    let mut d = Delivery {
        batch: &batch,
        progress,
        stream: batch
            .stream
            .map(|_| Reorder::new(&batch.tasks, StreamWriter::start(out))),
        written: 0,
        held: Vec::new(),
        claimed: Vec::new(),
        stop: None,
        cancel: Arc::new(AtomicBool::new(false)),
        signalled: None,
    };
    let spawn = spawner(pool, &batch, &d.cancel, tx);
    let mut pending = batch.tasks.iter().copied();
    let mut in_flight = 0;
    loop {
        d.notice_signal(in_flight);
        // Frames rendered but held for the stream's order count too: a slow frame must not
        // let the others run ahead without bound.
        while d.stop.is_none() && in_flight + d.held_for_order() < window {
            let Some(task) = pending.next() else { break };
            if d.claim(task.frame) {
                spawn(task);
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

/// Starts one frame on the pool; its result comes back through `tx`.
fn spawner<'a>(
    pool: &'a rayon::ThreadPool,
    batch: &Batch,
    cancel: &Arc<AtomicBool>,
    tx: mpsc::Sender<(u64, Produced)>,
) -> impl Fn(Task) + 'a {
    let seq = Arc::clone(&batch.sequence);
    let world = Arc::new(World::new(seq.scene.clone()));
    let files = batch.files.clone();
    let identity = files.as_ref().map(|f| RunIdentity::new(&seq, &f.format));
    let (stream, cancel) = (batch.stream, Arc::clone(cancel));
    move |task| {
        let (tx, seq, world, cancel) = (
            tx.clone(),
            Arc::clone(&seq),
            Arc::clone(&world),
            Arc::clone(&cancel),
        );
        let files = files.clone();
        pool.spawn(move || {
            let files = files.as_ref().zip(identity.as_ref());
            let _ = tx.send((
                task.frame,
                produce(&world, &seq, task, files, stream, &cancel),
            ));
        });
    }
}

impl Delivery<'_> {
    /// On the first Ctrl-C or SIGTERM: stop starting frames, cancel those in flight, and say
    /// so at once.
    fn notice_signal(&mut self, in_flight: usize) {
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
        let text = format!(
            "rayreel: stopping on {}: {what}; frames already written stay; exit code {} follows ({again})",
            signal_name(),
            interrupt_code()
        );
        self.progress.interrupt(signal_name(), in_flight, &text);
    }

    /// The run's outcome; claims still held for frames left behind are released.
    fn finish(mut self) -> Result<Outcome, RunError> {
        self.cancel.store(true, Ordering::SeqCst);
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

    fn held_for_order(&self) -> usize {
        self.stream.as_ref().map_or(0, |r| r.held.len())
    }

    /// Claims frame `n` when cooperating; false if another process holds it.
    fn claim(&mut self, n: u64) -> bool {
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

    fn heartbeat(&mut self) {
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

    /// Writes a finished frame's file and stream bytes, or records why it failed.
    fn deliver(&mut self, frame: u64, done: Produced) {
        let done = match done {
            Ok(Some(d)) => d,
            Ok(None) => return self.release(frame),
            Err(e) => {
                self.release(frame);
                self.progress.frame_failed(frame, &e.to_string());
                self.stop.get_or_insert(Err(e));
                self.cancel.store(true, Ordering::SeqCst);
                return;
            }
        };
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
                    self.progress.frame_done(n, "to stdout", seconds);
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

/// Renders frame `n` of the sequence (building its geometry; a run builds it once).
pub fn render_frame(seq: &Sequence, n: u64) -> Result<Frame, RunError> {
    render_with(&World::new(seq.scene.clone()), seq, n, &seq.settings)
}

/// Renders frame `n` in `world` (built once from the sequence's scene) with `settings`.
pub(crate) fn render_with(
    world: &World,
    seq: &Sequence,
    n: u64,
    settings: &Settings,
) -> Result<Frame, RunError> {
    let exposure = Exposure::of_frame(&seq.timeline, settings.shutter, n)
        .map_err(|source| RunError::Camera { frame: n, source })?;
    Ok(tracer::render(world, &exposure, settings, n))
}

/// A worker's whole job for one frame: render, then encode for each sink that wants it;
/// `None` when `cancel` stopped it.
fn produce(
    world: &World,
    seq: &Sequence,
    task: Task,
    files: Option<(&Files, &RunIdentity)>,
    stream: Option<(StreamFormat, bool)>,
    cancel: &AtomicBool,
) -> Produced {
    let start = Instant::now();
    let n = task.frame;
    let view = FrameView::of_frame(&seq.timeline, seq.settings.shutter, n);
    let exposure =
        (view.exposure.as_ref()).map_err(|&source| RunError::Camera { frame: n, source })?;
    let Some(frame) = tracer::render_or_stop(world, exposure, &seq.settings, n, cancel) else {
        return Ok(None);
    };
    let file = match files.filter(|_| task.write_file) {
        Some((files, identity)) => {
            let meta = identity.meta(&view);
            let path = files.frame_path(n);
            Some(
                output::encode_file(&frame, &files.format, &meta)
                    .map_err(|source| RunError::Encode { path, source })?,
            )
        }
        None => None,
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
        stream,
    }))
}

/// Puts stream bytes on stdout strictly in frame order, holding early arrivals.
struct Reorder {
    out: StreamWriter,
    order: Vec<u64>,
    next: usize,
    held: BTreeMap<u64, (Vec<u8>, f64)>,
    sent: usize,
}

impl Reorder {
    fn new(tasks: &[Task], out: StreamWriter) -> Reorder {
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
    fn push(
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
struct StreamWriter {
    frames: mpsc::Sender<Vec<u8>>,
    written: mpsc::Receiver<std::io::Result<()>>,
}

impl StreamWriter {
    fn start(mut out: Box<dyn Write + Send>) -> StreamWriter {
        let (frames, todo) = mpsc::channel::<Vec<u8>>();
        let (done, written) = mpsc::channel();
        std::thread::spawn(move || {
            for bytes in todo {
                let result = out.write_all(&bytes).and_then(|()| out.flush());
                if done.send(result).is_err() {
                    break;
                }
            }
        });
        StreamWriter { frames, written }
    }

    /// Writes one frame; `Interrupted` if a signal comes first.
    fn write(&mut self, bytes: Vec<u8>) -> std::io::Result<()> {
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
