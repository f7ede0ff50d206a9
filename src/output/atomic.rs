//! Atomic frame files: bytes go to a temporary name in the same directory, are flushed to disk,
//! and only then renamed to the final name, so a file with a final name is always complete.
//! Temporary names carry the host and process id, so a later run can tell which leftovers
//! belong to a process that is gone.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// Marker in our temporary names; only files carrying it are ever cleaned up as ours.
pub const TEMP_MARKER: &str = ".rayreel-tmp-";

/// Leftovers from another host are only removed once this old (its process may be alive).
const FOREIGN_HOST_GRACE: Duration = Duration::from_secs(24 * 3600);

/// This machine's name (cached), reduced to characters safe in a file name.
pub fn hostname() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(read_hostname)
}

fn read_hostname() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: the buffer is valid for its length; gethostname NUL-terminates within it or fails.
    let ok = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } == 0;
    let name = if ok {
        let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
        String::from_utf8_lossy(&buf[..end]).into_owned()
    } else {
        String::new()
    };
    let clean: String = name
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '.')
        .collect();
    if clean.is_empty() {
        "host".into()
    } else {
        clean
    }
}

/// `dir/.name.rayreel-tmp-HOST-PID` for `dir/name`.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(
        ".{name}{TEMP_MARKER}{}-{}",
        hostname(),
        std::process::id()
    ))
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Removes temporary files in `dir` left by rayreel processes that no longer run (same host,
/// dead pid) or by other hosts long ago. Returns how many were removed.
pub fn clean_leftovers(dir: &Path) -> usize {
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    let host = hostname();
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some((_, owner)) = name.split_once(TEMP_MARKER) else {
            continue;
        };
        let Some((owner_host, pid)) = owner.rsplit_once('-') else {
            continue;
        };
        let stale = if owner_host == host {
            pid.parse::<i32>().is_ok_and(|pid| !alive(pid))
        } else {
            entry.metadata().and_then(|m| m.modified()).is_ok_and(|t| {
                SystemTime::now().duration_since(t).unwrap_or_default() > FOREIGN_HOST_GRACE
            })
        };
        if stale && fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// Whether a process with this pid exists on this host.
pub fn alive(pid: i32) -> bool {
    // SAFETY: signal 0 only checks that the process exists.
    pid > 0
        && (unsafe { libc::kill(pid, 0) } == 0
            || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM))
}
