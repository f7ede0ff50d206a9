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
//! samples and the file's bytes. What may be used is the smallest of the cgroup's memory.max
//! less its memory.current, RLIMIT_AS less the process's address space now (with the arena and
//! stack each worker thread reserves), and /proc/meminfo's MemAvailable.

use crate::output::{ExrPrecision, FileFormat};
use crate::settings::Settings;

/// Address space a thread may reserve beyond the frames: glibc's malloc arena (64 MiB on 64-bit,
/// mapped as 128 MiB while it is aligned) and its stack. Measured under `prlimit --as`: with
/// less kept for each worker and the 4 other threads a run has (main, stream, signals,
/// progress), a run whose frames fit still failed an allocation as it finished.
const PER_THREAD: u64 = 136 << 20;
const OTHER_THREADS: u64 = 4;
/// Room kept for everything else: the scene, meshes' hierarchies, buffers of rows in flight.
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

/// The smallest limit on this process's memory and which one it is.
pub(crate) fn available(threads: usize) -> Option<(u64, &'static str)> {
    let reserved = PER_THREAD * (threads as u64 + OTHER_THREADS) + SLACK;
    let limits = [
        (cgroup(), "the cgroup's memory.max"),
        (address_space(), "RLIMIT_AS (ulimit -v)"),
        (mem_available(), "MemAvailable in /proc/meminfo"),
    ];
    limits
        .into_iter()
        .filter_map(|(bytes, what)| Some((bytes?.saturating_sub(reserved), what)))
        .min_by_key(|(bytes, _)| *bytes)
}

/// How many of `window` frames fit in `available` bytes, `Err` with the figures when none does.
pub(crate) fn fit(
    window: usize,
    per_frame: u64,
    available: Option<(u64, &'static str)>,
) -> Result<usize, String> {
    let Some((bytes, what)) = available else {
        return Ok(window);
    };
    let fits = (bytes / per_frame.max(1)).min(window as u64) as usize;
    match fits {
        0 => Err(format!(
            "one frame needs about {} (rendered, then encoded) and only {} is free under {what}; render a smaller size (--size), fewer channels, or raise the limit",
            gb(per_frame),
            gb(bytes)
        )),
        n => Ok(n),
    }
}

/// `3.22 GB`.
pub(crate) fn gb(bytes: u64) -> String {
    format!("{:.2} GB", bytes as f64 / 1e9)
}

/// memory.max less memory.current of this process's cgroup (v2), when it has a limit.
fn cgroup() -> Option<u64> {
    let line = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = line.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = std::path::Path::new("/sys/fs/cgroup").join(path.trim_start_matches('/'));
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
    let max: u64 = read("memory.max")?.trim().parse().ok()?;
    let current: u64 = read("memory.current")?.trim().parse().unwrap_or(0);
    Some(max.saturating_sub(current))
}

/// RLIMIT_AS less the address space this process has mapped now (VmSize).
fn address_space() -> Option<u64> {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit only writes the struct it is given, which lives through the call.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } != 0
        || limit.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let used = kb_field(&status, "VmSize:").unwrap_or(0);
    Some(limit.rlim_cur.saturating_sub(used))
}

fn mem_available() -> Option<u64> {
    kb_field(
        &std::fs::read_to_string("/proc/meminfo").ok()?,
        "MemAvailable:",
    )
}

/// `Key:   1234 kB` as bytes.
fn kb_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find_map(|l| l.strip_prefix(key))?;
    let kb: u64 = line.trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_shrink_to_what_fits_and_none_is_refused() {
        let free = |gb: u64| Some((gb << 30, "a limit"));
        assert_eq!(fit(4, 1 << 30, free(10)), Ok(4));
        assert_eq!(fit(4, 1 << 30, free(2)), Ok(2));
        assert_eq!(fit(4, 1 << 30, None), Ok(4));
        let refused = fit(4, 3 << 30, free(2)).unwrap_err();
        assert!(
            refused.contains("3.22 GB") && refused.contains("under a limit"),
            "{refused}"
        );
    }
}
