//! What a job's frames in flight take, against what the process may use, worked out before the
//! first frame starts: a job that cannot fit is refused with the figures (or runs fewer frames
//! at once), where it once ran until an allocation failed and aborted with a backtrace (an
//! 8192×8192 alpha+depth EXR under a 3 GB limit: exit 134).
//!
//! Per frame (bytes a pixel): the tracer's planes, 12 for RGB, 4 each for alpha and depth, 4 a
//! channel of compositing passes, and with adaptive sampling 4 for each pixel's spread or error
//! estimate and, the larger of the two, 28 for a pass that extends every pixel (its index, its
//! new mean, coverage and estimate, the estimate copied out: film's first round does) or 44,
//! after the rounds, for a pass of the film filter (each pixel's planar mean, variance and
//! guide, and its new mean and variance; also without adaptive sampling when the filter is
//! on); then, while that frame is encoded,
//! EXR's channel planes (2 a colour sample in half, 4 in float, depth and passes 4), one f32 plane copied out before conversion, and the file's
//! bytes (at most the channels again: ZIP never doubles them); PNG's or the stream's integer
//! samples and the file's bytes. What may be used is the budget's figure (`crate::budget`: the
//! smallest of the cgroup's memory.max less its memory.current, RLIMIT_AS less the process's
//! address space now, and MemAvailable), with the address space of the allocator arenas that
//! threads may still add kept aside under RLIMIT_AS, less the meshes' hierarchies and triangle
//! copies, which the run builds after this check.

use crate::budget::{self, Free, size};
use crate::output::{ExrPrecision, FileFormat};
use crate::settings::Settings;

/// Address space a thread's malloc arena reserves (glibc, 64-bit: HEAP_MAX_SIZE, 64 MiB; mapped
/// as twice that for a moment while it is aligned, which `arenas_to_come` keeps once).
/// Threads' stacks are not counted: a run's workers are started before the check, so theirs
/// are in the address space the budget reads already, as are the arenas the process has.
const ARENA: u64 = 64 << 20;
/// Room kept for everything else: buffers of rows in flight, the encoders' own.
const SLACK: u64 = 128 << 20;

/// The most bytes one frame in flight takes, rendered and then encoded.
pub(crate) fn frame_bytes(settings: &Settings, format: Option<FileFormat>) -> u64 {
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let (a, d) = (u64::from(settings.alpha), u64::from(settings.depth));
    let adaptive = u64::from(settings.adaptive.is_some() || settings.denoise);
    // Compositing passes: f32 planes, copied once more into the EXR's channels.
    let passes: u64 = settings.aov.iter().map(|p| 4 * p.channels()).sum();
    let render = 12 + 4 * a + 4 * d + 48 * adaptive + passes;
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

/// The malloc arenas threads still to start (or not yet allocating) may add, and the address
/// space they reserve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Arenas {
    pub(crate) count: u64,
    pub(crate) bytes: u64,
}

/// The arenas `threads` more threads may add to those the process has: glibc gives a thread
/// that allocates an arena of its own until there are 8 a core (M_ARENA_MAX's default on
/// 64-bit, cores as online CPUs, the main thread's arena among them); threads beyond share
/// them. Arenas present (glibc's `malloc_info` counts them) are in the address space the
/// budget reads already, so they are not counted again. It once kept an arena for each
/// worker already running and for 4 other threads a run may not start: 32 threads of a 32×24
/// frame were refused under 2 GB, where the process peaks at 1.13 GB (VmPeak, 2 cores).
pub(crate) fn arenas_to_come(threads: u64) -> Arenas {
    // SAFETY: sysconf reads a system value and has no preconditions.
    let online = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) }.max(1) as u64;
    let cap = 8 * online;
    let now = arenas_now().unwrap_or(1).clamp(1, cap);
    let count = (now + threads).min(cap) - now;
    Arenas {
        count,
        bytes: ARENA * (count + u64::from(count > 0)),
    }
}

/// How many malloc arenas the process has (glibc: one `<heap>` in `malloc_info`'s report
/// each); None where that cannot be read, and then only the main thread's is taken as there.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn arenas_now() -> Option<u64> {
    let mut buffer: *mut libc::c_char = std::ptr::null_mut();
    let mut len: libc::size_t = 0;
    // SAFETY: open_memstream writes the buffer's address and length into the two locals,
    // which outlive the stream; malloc_info writes into the stream, and after fclose the
    // buffer holds `len` bytes, read once and then freed with the allocator that made it.
    unsafe {
        let stream = libc::open_memstream(&mut buffer, &mut len);
        if stream.is_null() {
            return None;
        }
        let written = libc::malloc_info(0, stream);
        libc::fclose(stream);
        if buffer.is_null() {
            return None;
        }
        let text = std::slice::from_raw_parts(buffer as *const u8, len);
        let heaps = text.windows(10).filter(|w| w == b"<heap nr=\"").count() as u64;
        libc::free(buffer.cast());
        (written == 0 && heaps > 0).then_some(heaps)
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn arenas_now() -> Option<u64> {
    None
}

/// The threads a process has now (`Threads:` in /proc/self/status), the calling one among them.
pub(crate) fn threads_now() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find_map(|l| l.strip_prefix("Threads:"))?;
    line.trim().parse().ok()
}

/// What the process may take for a run: the budget's figure with the address space the
/// `arenas` still to come reserve kept aside, and `SLACK` under every limit.
pub(crate) fn available(arenas: Arenas) -> Option<Free> {
    budget::free(arenas.bytes).map(|f| Free {
        bytes: f.bytes.saturating_sub(SLACK),
        ..f
    })
}

/// How many of `window` frames fit in `available` bytes beside `fixed` bytes the run needs
/// once (the meshes' hierarchies), `Err` with the figures when none does.
pub(crate) fn fit(
    window: usize,
    per_frame: u64,
    fixed: u64,
    arenas: Arenas,
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
    let kept = kept(&free, arenas);
    Err(format!(
        "one frame needs about {} (rendered, then encoded){hierarchies}, and only {} is free under {} of {}{kept}; render a smaller size (--size), fewer channels, or raise the limit",
        size(per_frame),
        size(free.bytes),
        free.limit,
        size(free.of),
    ))
}

/// `, once … is kept for N more allocator arenas` under RLIMIT_AS, where some are.
fn kept(free: &Free, arenas: Arenas) -> String {
    match free.limit.starts_with("RLIMIT_AS") && arenas.count > 0 {
        true => format!(
            ", once {} of address space is kept for {} more allocator arena{}",
            size(arenas.bytes),
            arenas.count,
            if arenas.count == 1 { "" } else { "s" }
        ),
        false => String::new(),
    }
}

/// The bytes the hierarchies of the scene's meshes and their triangle copies will take once
/// built (the run builds them after this check): an f32 job counts both copies, since its
/// frames that f32 cannot resolve or whose things move, and its compositing passes, are
/// traced in f64.
pub(crate) fn hierarchies(seq: &crate::sequence::Sequence) -> u64 {
    let f32_job = seq.settings.precision == crate::settings::Precision::F32;
    seq.scene
        .meshes
        .iter()
        .map(|m| budget::hierarchy_bytes(m.triangles.len() as u64, f32_job))
        .sum()
}

/// `Ok` when the meshes' hierarchies (`hierarchies`) fit in what the process may take now,
/// otherwise the figures: `check` and `render --dry-run` build them for their probe, which
/// runs on `threads` new workers (and a watchdog).
pub(crate) fn admit_hierarchies(
    seq: &crate::sequence::Sequence,
    threads: usize,
) -> Result<(), String> {
    let need = hierarchies(seq);
    // Only the probe's threads: no stream, signal or progress thread, no rows in flight.
    let arenas = arenas_to_come(threads as u64 + 1);
    match budget::free(arenas.bytes) {
        Some(free) if need > free.bytes => {
            let triangles: usize = seq.scene.meshes.iter().map(|m| m.triangles.len()).sum();
            Err(format!(
                "not enough memory for the meshes' hierarchies and triangle copies ({triangles} triangles): they need about {}, and only {} is free under {} of {}{}",
                size(need),
                size(free.bytes),
                free.limit,
                size(free.of),
                kept(&free, arenas)
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
        let two = Arenas {
            count: 2,
            bytes: 3 * ARENA,
        };
        assert_eq!(fit(4, 1 << 30, 0, two, free(10)), Ok(4));
        assert_eq!(fit(4, 1 << 30, 0, two, free(2)), Ok(2));
        assert_eq!(fit(4, 1 << 30, 1 << 30, two, free(2)), Ok(1));
        assert_eq!(fit(4, 1 << 30, 0, two, None), Ok(4));
        let refused = fit(4, 3 << 30, 0, two, free(2)).unwrap_err();
        assert!(
            refused.contains("3.22 GB") && refused.contains("under a limit of 17.18 GB"),
            "{refused}"
        );
        let tiny = fit(4, 12_288, 0, two, free(0)).unwrap_err();
        assert!(
            tiny.contains("about 12.3 kB") && tiny.contains("only 0 bytes"),
            "{tiny}"
        );
    }

    #[test]
    fn arenas_present_are_not_counted_again() {
        // This process has the main thread's arena at least, and the test harness's threads'.
        assert!(arenas_now().is_none_or(|n| n >= 1));
        let none = arenas_to_come(0);
        assert_eq!(none, Arenas { count: 0, bytes: 0 });
        let one = arenas_to_come(1);
        assert!(one.count <= 1 && one.bytes == ARENA * (one.count + one.count.min(1)));
        // However many threads, no more than glibc's cap of 8 a core in all.
        // SAFETY: as in `arenas_to_come`.
        let online = unsafe { libc::sysconf(libc::_SC_NPROCESSORS_ONLN) }.max(1) as u64;
        let many = arenas_to_come(10_000);
        assert!(many.count < 8 * online);
        assert_eq!(many.bytes, ARENA * (many.count + u64::from(many.count > 0)));
    }
}
