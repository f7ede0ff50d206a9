//! The frame scheduler: renders the selected frames on a rayon pool, a bounded window of frames
//! at a time (rows of each frame are parallel too), so both cores stay busy from the first
//! frame to the last, the first file appears early, and memory does not grow with the length
//! of the sequence or with a slow reader. Workers only compute (render, encode); this thread
//! does all I/O: atomic file writes as frames finish, the stream strictly in frame order.

use crate::claim::{Attempt, Claims};
use crate::exposure::{self, Exposure};
use crate::frame::Frame;
use crate::output::{
    self, FileFormat, FrameMeta, fingerprint, pattern::Pattern, stream::StreamFormat,
};
use crate::progress::Progress;
use crate::sequence::Sequence;
use crate::tracer::{self, Settings, World};
use std::collections::BTreeMap;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

/// Where frame files go and in which format.
#[derive(Clone)]
pub struct Files {
    pub pattern: Pattern,
    pub format: FileFormat,
}

/// One frame of a run: its number, and whether its file must be written (with a stream, frames
/// whose files are up to date are still rendered for the stream but not rewritten).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Task {
    pub frame: u64,
    pub write_file: bool,
}

pub struct Job {
    pub sequence: Arc<Sequence>,
    /// Ascending frame numbers, each inside the timeline.
    pub tasks: Vec<Task>,
    pub files: Option<Files>,
    pub stream: Option<(StreamFormat, bool)>,
    /// Where the stream goes: stdout for users, a sink for benchmarks.
    pub stream_out: Option<Box<dyn Write + Send>>,
    pub threads: usize,
    /// Cooperate with other processes through claim files (files only, no stream).
    pub claims: Option<Arc<Claims>>,
}

/// How a run ended when nothing failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    /// Every task done, except `held`: frames another live process has claimed.
    Complete { written: usize, held: Vec<u64> },
    /// Ctrl-C or SIGTERM: frames in flight were finished, nothing new was started.
    Interrupted { written: usize },
    /// The stream's reader closed the pipe; the remaining work was cancelled.
    ReaderClosed { streamed: usize },
}

/// Frames rendered in parallel beyond one per thread: enough to hide encoding and writing
/// behind rendering, few enough that memory stays a handful of frames.
const EXTRA_IN_FLIGHT: usize = 2;

struct Done {
    seconds: f64,
    file: Option<Vec<u8>>,
    stream: Option<Vec<u8>>,
}

/// The I/O side of a run: everything this thread does with finished frames.
struct Delivery<'a> {
    job: &'a Job,
    progress: &'a mut Progress,
    stream: Option<Reorder>,
    written: usize,
    held: Vec<u64>,
    /// Frames in flight under a claim, with when they were last refreshed.
    claimed: Vec<(u64, Instant)>,
    stop: Option<Result<Outcome, String>>,
}

pub fn run(mut job: Job, progress: &mut Progress) -> Result<Outcome, String> {
    return_frame_buffers_to_the_os();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(job.threads)
        .thread_name(|i| format!("rayreel-{i}"))
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    let run_hash = job
        .files
        .as_ref()
        .map(|f| fingerprint::of_run(&job.sequence.scene, &job.sequence.settings, &f.format));
    let window = match job.stream {
        // A stream has its order to keep: one frame rendering (on every thread) while the one
        // before is written keeps memory to two frames whatever the reader does.
        Some(_) => 2,
        None => job.threads + EXTRA_IN_FLIGHT,
    };
    let world = Arc::new(World::new(job.sequence.scene.clone()));
    let (tx, rx) = mpsc::channel::<(u64, Result<Done, String>)>();
    let mut pending = job.tasks.iter().copied();
    let out = job
        .stream_out
        .take()
        .unwrap_or_else(|| Box::new(std::io::stdout()));
    let mut d = Delivery {
        job: &job,
        progress,
        stream: job.stream.map(|_| Reorder::new(&job.tasks, out)),
        written: 0,
        held: Vec::new(),
        claimed: Vec::new(),
        stop: None,
    };
    let mut in_flight = 0;
    loop {
        // Frames rendered but held for the stream's order count too: a slow frame must not
        // let the others run ahead without bound.
        while d.stop.is_none() && in_flight + d.held_for_order() < window {
            if interrupted() {
                d.stop = Some(Ok(Outcome::Interrupted { written: 0 }));
                break;
            }
            let Some(task) = pending.next() else { break };
            if !d.claim(task.frame) {
                continue;
            }
            let (tx, seq, files) = (tx.clone(), Arc::clone(&job.sequence), job.files.clone());
            let world = Arc::clone(&world);
            let stream_format = job.stream;
            in_flight += 1;
            pool.spawn(move || {
                let files = files.as_ref().zip(run_hash.as_ref());
                let _ = tx.send((
                    task.frame,
                    produce(&world, &seq, task, files, stream_format),
                ));
            });
        }
        if in_flight == 0 {
            break;
        }
        d.heartbeat();
        match rx.recv_timeout(Duration::from_millis(500)) {
            Ok((frame, done)) => {
                in_flight -= 1;
                d.deliver(frame, done);
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(e) => return Err(format!("worker lost: {e}")),
        }
    }
    let (written, held) = (d.written, d.held);
    match d.stop {
        None => Ok(Outcome::Complete { written, held }),
        Some(Ok(Outcome::Interrupted { .. })) => Ok(Outcome::Interrupted { written }),
        Some(other) => other,
    }
}

impl Delivery<'_> {
    fn held_for_order(&self) -> usize {
        self.stream.as_ref().map_or(0, |r| r.held.len())
    }

    /// Claims frame `n` when cooperating; false if another process holds it.
    fn claim(&mut self, n: u64) -> bool {
        let (Some(claims), Some(files)) = (&self.job.claims, &self.job.files) else {
            return true;
        };
        match claims.try_claim(&files.pattern.frame_path(n)) {
            Ok(Attempt::Claimed) => {
                self.claimed.push((n, Instant::now()));
                true
            }
            Ok(Attempt::Held(_)) => {
                self.held.push(n);
                false
            }
            Err(e) => {
                let path = Claims::path(&files.pattern.frame_path(n));
                self.stop
                    .get_or_insert(Err(format!("{}: cannot create claim: {e}", path.display())));
                false
            }
        }
    }

    fn heartbeat(&mut self) {
        let (Some(claims), Some(files)) = (&self.job.claims, &self.job.files) else {
            return;
        };
        for (n, last) in &mut self.claimed {
            if last.elapsed() >= claims.heartbeat_every() {
                claims.heartbeat(&files.pattern.frame_path(*n));
                *last = Instant::now();
            }
        }
    }

    fn release(&mut self, n: u64) {
        if let (Some(claims), Some(files)) = (&self.job.claims, &self.job.files) {
            claims.release(&files.pattern.frame_path(n));
            self.claimed.retain(|(f, _)| *f != n);
        }
    }

    /// Writes a finished frame's file and stream bytes, or records why it failed.
    fn deliver(&mut self, frame: u64, done: Result<Done, String>) {
        let done = match done {
            Ok(d) => d,
            Err(e) => {
                self.release(frame);
                self.progress.frame_failed(frame, &e);
                self.stop.get_or_insert(Err(e));
                return;
            }
        };
        if let (Some(bytes), Some(files)) = (&done.file, &self.job.files) {
            let path = files.pattern.frame_path(frame);
            let result = output::atomic::write_atomic(&path, bytes);
            self.release(frame);
            if let Err(e) = result {
                let e = format!("{}: cannot write: {e}", path.display());
                self.progress.frame_failed(frame, &e);
                self.stop.get_or_insert(Err(e));
                return;
            }
            self.written += 1;
            self.progress
                .frame_done(frame, &path.display().to_string(), done.seconds);
        }
        let closed = matches!(self.stop, Some(Ok(Outcome::ReaderClosed { .. })));
        let (Some(order), Some(bytes)) = (self.stream.as_mut(), done.stream) else {
            return;
        };
        if closed {
            return;
        }
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
            }
            Err(e) => {
                self.stop
                    .get_or_insert(Err(format!("stdout: cannot write the stream: {e}")));
            }
        }
    }
}

/// Renders frame `n` of the sequence (building its geometry; a run builds it once).
pub fn render_frame(seq: &Sequence, n: u64) -> Result<Frame, String> {
    render_with(&World::new(seq.scene.clone()), seq, n, &seq.settings)
}

/// Renders frame `n` in `world` (built once from the sequence's scene) with `settings`.
pub fn render_with(
    world: &World,
    seq: &Sequence,
    n: u64,
    settings: &Settings,
) -> Result<Frame, String> {
    let exposure = Exposure::of_frame(&seq.timeline, settings.shutter, n)
        .map_err(|e| format!("frame {n}: {e}"))?;
    Ok(tracer::render(world, &exposure, settings, n))
}

/// A worker's whole job for one frame: render, then encode for each sink that wants it.
fn produce(
    world: &World,
    seq: &Sequence,
    task: Task,
    files: Option<(&Files, &fingerprint::Hasher)>,
    stream: Option<(StreamFormat, bool)>,
) -> Result<Done, String> {
    let start = Instant::now();
    let n = task.frame;
    let frame = render_with(world, seq, n, &seq.settings)?;
    let file = match files.filter(|_| task.write_file) {
        Some((files, run_hash)) => {
            let meta = frame_meta(seq, n, run_hash);
            let path = files.pattern.frame_path(n);
            Some(
                output::encode_file(&frame, &files.format, &meta)
                    .map_err(|e| format!("{}: cannot encode: {e}", path.display()))?,
            )
        }
        None => None,
    };
    let stream = match stream {
        Some((format, sixteen)) => Some(
            output::stream::encode(&frame, format, sixteen)
                .map_err(|e| format!("frame {n}: cannot encode the stream: {e}"))?,
        ),
        None => None,
    };
    frame.recycle();
    Ok(Done {
        seconds: start.elapsed().as_secs_f64(),
        file,
        stream,
    })
}

pub fn frame_meta(seq: &Sequence, n: u64, run_hash: &fingerprint::Hasher) -> FrameMeta {
    FrameMeta {
        frame: n,
        time: seq.timeline.time_of(n),
        fps: seq.timeline.fps,
        fingerprint: fingerprint::of_frame(
            run_hash,
            &exposure::describe(&seq.timeline, seq.settings.shutter, n),
        ),
    }
}

/// Puts stream bytes on stdout strictly in frame order, holding early arrivals.
struct Reorder {
    out: Box<dyn Write + Send>,
    order: Vec<u64>,
    next: usize,
    held: BTreeMap<u64, (Vec<u8>, f64)>,
    sent: usize,
}

impl Reorder {
    fn new(tasks: &[Task], out: Box<dyn Write + Send>) -> Reorder {
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
        let out = &mut self.out;
        let mut sent = Vec::new();
        while let Some(&n) = self.order.get(self.next) {
            let Some((bytes, seconds)) = self.held.remove(&n) else {
                break;
            };
            out.write_all(&bytes)?;
            self.next += 1;
            self.sent += 1;
            sent.push((n, seconds));
        }
        out.flush()?;
        Ok(sent)
    }
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// The first Ctrl-C or SIGTERM asks the run to stop after the frames in flight; a second one
/// exits at once (a later run removes any temporary file that leaves behind).
pub fn install_interrupt_handler() {
    extern "C" fn on_signal(_: libc::c_int) {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            // SAFETY: _exit is async-signal-safe.
            unsafe { libc::_exit(130) };
        }
    }
    for signal in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: installs a handler that only touches an atomic and calls _exit.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as *const () as usize;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(signal, &action, std::ptr::null_mut());
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
