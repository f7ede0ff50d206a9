//! What a job's frames in flight take, against what the process may use, worked out before the
//! first frame starts: a job that cannot fit is refused with the figures (or runs fewer frames
//! at once), where it once ran until an allocation failed and aborted with a backtrace (an
//! 8192×8192 alpha+depth EXR under a 3 GB limit: exit 134).
//!
//! Per frame (bytes a pixel): the tracer's planes, 12 for RGB, 4 each for alpha and depth, 4 a
//! channel of compositing passes, and with adaptive sampling 4 for each pixel's spread or error
//! estimate and 28 for a pass that extends every pixel (its index, its new mean, coverage and
//! estimate, the estimate copied out: film's first round does), or, after the rounds, for the
//! film filter (each pixel's variance, guide and new mean; also without adaptive sampling when
//! the filter is on); then, while that frame is encoded,
//! EXR's channel planes (2 a colour sample in half, 4 in float, depth and passes 4), one f32 plane copied out before conversion, and the file's
//! bytes (at most the channels again: ZIP never doubles them); PNG's or the stream's integer
//! samples and the file's bytes. What may be used is the budget's figure (`crate::budget`: the
//! smallest of the cgroup's memory.max less its memory.current, RLIMIT_AS less the process's
//! address space now, and MemAvailable), with the address space each worker thread reserves
//! for its arena and stack kept aside under RLIMIT_AS, less the meshes' hierarchies, which the
//! run builds after this check.

use crate::budget::{self, Free, size};
use crate::output::{ExrPrecision, FileFormat};
use crate::settings::Settings;

/// Address space a thread's malloc arena reserves (glibc, 64-bit: HEAP_MAX_SIZE, 64 MiB; mapped
/// as twice that for a moment while it is aligned, which `reserved` keeps once). Threads'
/// stacks are not counted: the workers are started before the check, so theirs are in the
/// address space the budget reads already, as is the main thread's arena.
const ARENA: u64 = 64 << 20;
/// The threads a run has besides its workers (main, stream, signals, progress).
const OTHER_THREADS: u64 = 4;
/// Room kept for everything else: buffers of rows in flight, the encoders' own.
const SLACK: u64 = 128 << 20;

/// The most bytes one frame in flight takes, rendered and then encoded.
pub(crate) fn frame_bytes(settings: &Settings, format: Option<FileFormat>) -> u64 {
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let (a, d) = (u64::from(settings.alpha), u64::from(settings.depth));
    let adaptive = u64::from(settings.adaptive.is_some() || settings.denoise);
    // Compositing passes: f32 planes, copied once more into the EXR's channels.
    let passes: u64 = settings.aov.iter().map(|p| 4 * p.channels()).sum();
    let render = 12 + 4 * a + 4 * d + 32 * adaptive + passes;
    let encode = match format {
        Some(FileFormat::Exr { precision }) => {
            let s = match precision {
                ExrPrecision::Half => 2,
                ExrPrecision::Float => 4,
            };
            2 * (s * (3 + a) + 4 * d + passes) + 4
        }
        Some(FileFormat::Png { sixteen_bit, .. }) => 2 * (3 + a) * (1 + u64::from(sixteen_bit)),
        // A stream: 16-bit RGBA at most, and a PNG stream's compressed copy.
        None => 2 * 8,
    };
    pixels * (render + encode)
}

/// What the process may take for a run of `threads` workers: the budget's figure with the
/// address space their stacks and arenas reserve kept aside, and `SLACK` under every limit.
pub(crate) fn available(threads: usize) -> Option<Free> {
    let reserved = reserved(threads);
    budget::free(reserved).map(|f| Free {
        bytes: f.bytes.saturating_sub(SLACK),
        ..f
    })
}

/// The address space the run's threads' arenas reserve beyond the frames: glibc makes at most
/// 8 arenas a core (M_ARENA_MAX's default on 64-bit, cores as online CPUs), the main thread's
/// among them, and threads beyond share them. It once kept 136 MiB for each thread, stacks
/// counted twice and arenas beyond glibc's cap: a 32×24 frame whose process peaks at 144 MB
/// (VmPeak, --threads 1) was refused under 800 MB, one peaking at 1.12 GB with 32 threads
/// on 2 cores under 4 GB.
fn reserved(threads: usize) -> u64 {
    arenas(threads as u64 + OTHER_THREADS)
}

/// The address space the arenas of `threads` threads besides the main one may add.
fn arenas(threads: u64) -> u64 {
    // SAFETY: sysconf reads a system value and has no preconditions.
    let online = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) }.max(1) as u64;
    ARENA * (threads.min(8 * online - 1) + 1)
}

/// How many of `window` frames fit in `available` bytes beside `fixed` bytes the run needs
/// once (the meshes' hierarchies), `Err` with the figures when none does.
pub(crate) fn fit(
    window: usize,
    per_frame: u64,
    fixed: u64,
    threads: usize,
    available: Option<Free>,
) -> Result<usize, String> {
    let Some(free) = available else {
        return Ok(window);
    };
    let room = free.bytes.saturating_sub(fixed);
    let fits = (room / per_frame.max(1)).min(window as u64) as usize;
    if fits > 0 {
        return Ok(fits);
    }
    let hierarchies = match fixed {
        0 => String::new(),
        n => format!(" beside {} for the meshes' hierarchies", size(n)),
    };
    let kept = kept(&free, reserved(threads), threads as u64 + OTHER_THREADS);
    Err(format!(
        "one frame needs about {} (rendered, then encoded){hierarchies}, and only {} is free under {} of {}{kept}; render a smaller size (--size), fewer channels, or raise the limit",
        size(per_frame),
        size(free.bytes),
        free.limit,
        size(free.of),
    ))
}

/// `, once … is kept for N threads' allocator arenas` under RLIMIT_AS, where it is.
fn kept(free: &Free, reserved: u64, threads: u64) -> String {
    match free.limit.starts_with("RLIMIT_AS") {
        true => format!(
            ", once {} of address space is kept for {threads} threads' allocator arenas",
            size(reserved)
        ),
        false => String::new(),
    }
}

/// The bytes the hierarchies of the scene's meshes will take once built (the run builds them
/// after this check).
pub(crate) fn hierarchies(scene: &crate::scene::Scene) -> u64 {
    scene
        .meshes
        .iter()
        .map(|m| budget::hierarchy_bytes(m.triangles.len() as u64))
        .sum()
}

/// `Ok` when the meshes' hierarchies (`hierarchies`) fit in what the process may take now,
/// otherwise the figures: `check` and `render --dry-run` build them for their probe, which
/// runs on `threads` workers.
pub(crate) fn admit_hierarchies(scene: &crate::scene::Scene, threads: usize) -> Result<(), String> {
    let need = hierarchies(scene);
    // Only the probe's workers: no stream, signal or progress thread, no rows in flight.
    let reserved = arenas(threads as u64);
    match budget::free(reserved) {
        Some(free) if need > free.bytes => {
            let triangles: usize = scene.meshes.iter().map(|m| m.triangles.len()).sum();
            Err(format!(
                "not enough memory for the meshes' hierarchies and triangle copies ({triangles} triangles): they need about {}, and only {} is free under {} of {}{}",
                size(need),
                size(free.bytes),
                free.limit,
                size(free.of),
                kept(&free, reserved, threads as u64)
            ))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_shrink_to_what_fits_and_none_is_refused() {
        let free = |gb: u64| {
            Some(Free {
                bytes: gb << 30,
                limit: "a limit",
                of: 16 << 30,
            })
        };
        assert_eq!(fit(4, 1 << 30, 0, 2, free(10)), Ok(4));
        assert_eq!(fit(4, 1 << 30, 0, 2, free(2)), Ok(2));
        assert_eq!(fit(4, 1 << 30, 1 << 30, 2, free(2)), Ok(1));
        assert_eq!(fit(4, 1 << 30, 0, 2, None), Ok(4));
        let refused = fit(4, 3 << 30, 0, 2, free(2)).unwrap_err();
        assert!(
            refused.contains("3.22 GB") && refused.contains("under a limit of 17.18 GB"),
            "{refused}"
        );
        let tiny = fit(4, 12_288, 0, 2, free(0)).unwrap_err();
        assert!(
            tiny.contains("about 12.3 kB") && tiny.contains("only 0 bytes"),
            "{tiny}"
        );
    }
}
