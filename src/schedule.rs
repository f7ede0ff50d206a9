//! The frame scheduler: renders the selected frames on a rayon pool, a bounded window of frames
//! at a time (rows of each frame are parallel too), so both cores stay busy from the first
//! frame to the last, the first file appears early, and memory does not grow with the length
//! of the sequence.

use crate::camera::Camera;
use crate::output::{atomic, pattern::Pattern, png};
use crate::progress::Progress;
use crate::sequence::Sequence;
use crate::tracer;
use std::path::PathBuf;
use std::sync::{Arc, mpsc};
use std::time::Instant;

/// What one `render` run does.
pub struct Job {
    pub sequence: Arc<Sequence>,
    /// Ascending frame numbers, each inside the timeline.
    pub frames: Vec<u64>,
    pub pattern: Pattern,
    pub threads: usize,
}

/// Frames rendered in parallel beyond one per thread: enough to hide encoding and writing
/// behind rendering, few enough that memory stays a handful of frames.
const EXTRA_IN_FLIGHT: usize = 1;

pub fn run(job: Job, progress: &mut Progress) -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(job.threads)
        .thread_name(|i| format!("rayreel-{i}"))
        .build()
        .map_err(|e| format!("cannot start worker threads: {e}"))?;
    let window = job.threads + EXTRA_IN_FLIGHT;
    let (tx, rx) = mpsc::channel::<(u64, PathBuf, f64, Result<(), String>)>();
    let mut pending = job.frames.iter().copied();
    let mut in_flight = 0;
    let mut failure: Option<String> = None;
    loop {
        while failure.is_none() && in_flight < window {
            let Some(n) = pending.next() else { break };
            let (tx, seq, path) = (
                tx.clone(),
                Arc::clone(&job.sequence),
                job.pattern.frame_path(n),
            );
            in_flight += 1;
            pool.spawn(move || {
                let start = Instant::now();
                let result = render_to_file(&seq, n, &path);
                let _ = tx.send((n, path, start.elapsed().as_secs_f64(), result));
            });
        }
        if in_flight == 0 {
            break;
        }
        let (n, path, seconds, result) = rx.recv().map_err(|e| format!("worker lost: {e}"))?;
        in_flight -= 1;
        match result {
            Ok(()) => progress.frame_done(n, &path, seconds),
            Err(e) => {
                failure.get_or_insert(e);
            }
        }
    }
    failure.map_or(Ok(()), Err)
}

/// Renders frame `n` of the sequence.
pub fn render_frame(seq: &Sequence, n: u64) -> Result<crate::frame::Frame, String> {
    let pose = seq.timeline.pose_of(n);
    let camera = Camera::new(&pose).map_err(|e| format!("frame {n}: {e}"))?;
    Ok(tracer::render(&seq.scene, &camera, &seq.settings))
}

fn render_to_file(seq: &Sequence, n: u64, path: &std::path::Path) -> Result<(), String> {
    let frame = render_frame(seq, n)?;
    let bytes =
        png::encode(&frame).map_err(|e| format!("{}: cannot encode PNG: {e}", path.display()))?;
    atomic::write_atomic(path, &bytes).map_err(|e| format!("{}: cannot write: {e}", path.display()))
}
