//! Atomic frame files: bytes go to a temporary in the same directory, are flushed to disk, and
//! only then renamed to the final name, so a file with a final name is always complete.
//!
//! A temporary is `.NAME.rayreel-tmp-HOST-PID-RANDOM`. It is created exclusively and never
//! through a symbolic link (O_EXCL, O_NOFOLLOW), so nothing planted in a shared directory can
//! redirect the write; RANDOM (64 bits) makes the name unpredictable; HOST and PID tell a later
//! run whose leftover it is. When NAME is so long that this would pass the 255 bytes a file
//! name may have, a hash of NAME stands in for it, so every legal frame name has a temporary
//! (claims, `.NAME.rayreel-claim`, do the same).

use super::fingerprint::Hasher;
use crate::frameset::FrameSet;
use crate::pattern::{NAME_MAX, Pattern};
use std::collections::HashSet;
use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, SystemTime};

/// Marker in our temporary names.
pub(crate) const TEMP_MARKER: &str = ".rayreel-tmp-";

/// The longest a temporary's name adds to NAME: `.`, the marker, a host name of at most 64
/// bytes, `-`, a pid of at most 10 digits, `-` and 16 hex digits.
const TEMP_EXTRA: usize = 1 + TEMP_MARKER.len() + 64 + 1 + 10 + 1 + 16;

/// Leftovers from another host are only removed once this old (its process may be alive).
const FOREIGN_HOST_GRACE: Duration = Duration::from_secs(24 * 3600);

/// This machine's name (cached), reduced to at most 64 characters safe in a file name.
pub(crate) fn hostname() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(read_hostname)
}

fn read_hostname() -> String {
    let name = gethostname::gethostname().to_string_lossy().into_owned();
    let clean: String = name
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '.')
        .take(64)
        .collect();
    if clean.is_empty() {
        "host".into()
    } else {
        clean
    }
}

/// `.NAME{suffix}` beside `path`, with a hash for NAME when the name would pass NAME_MAX
/// with a suffix of up to `extra` bytes (the leading dot included).
pub(crate) fn sidecar(path: &Path, suffix: &str, extra: usize) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(".{}{suffix}", stem(&name, extra)))
}

/// NAME itself, or its hash when NAME plus `extra` bytes would not fit in a file name.
fn stem(name: &str, extra: usize) -> String {
    match name.len() + extra <= NAME_MAX {
        true => name.to_string(),
        false => Hasher::new().write(name.as_bytes()).hex(),
    }
}

/// A fresh `.NAME.rayreel-tmp-HOST-PID-RANDOM` for `path`.
pub(crate) fn temp_path(path: &Path) -> PathBuf {
    let suffix = format!(
        "{TEMP_MARKER}{}-{}-{:016x}",
        hostname(),
        std::process::id(),
        random()
    );
    sidecar(path, &suffix, TEMP_EXTRA)
}

/// 64 unpredictable bits: std's hash keys come from the operating system's random source,
/// mixed here with time, pid and a counter.
fn random() -> u64 {
    use std::hash::{BuildHasher, Hasher as _};
    let mut keyed = std::collections::hash_map::RandomState::new().build_hasher();
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let now = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .unwrap_or_default();
    let seed = format!(
        "{now:?} {} {}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    keyed.write(seed.as_bytes());
    keyed.finish()
}

pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let (tmp, mut file) = create_temp(path)?;
    let result = (|| {
        file.write_all(bytes)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// A new temporary for `path`, created exclusively and never through a symbolic link.
fn create_temp(path: &Path) -> std::io::Result<(PathBuf, File)> {
    let mut attempt = 0;
    loop {
        let tmp = temp_path(path);
        // Whatever stands under the name drawn goes first (unlinking never follows a link);
        // should something appear there again, a new name is drawn.
        let _ = fs::remove_file(&tmp);
        let opened = OpenOptions::new()
            .write(true)
            .create_new(true)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
            .open(&tmp);
        match opened {
            Ok(file) => return Ok((tmp, file)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempt < 8 => attempt += 1,
            Err(e) => return Err(e),
        }
    }
}

/// Checks that files can be made in `dir` by creating and removing a temporary there, so a
/// directory that is read-only, write-protected or not a real one (under `/proc`) is
/// reported before any frame renders rather than after the first one.
pub(crate) fn probe_writable(dir: &Path) -> std::io::Result<()> {
    let (tmp, file) = create_temp(&dir.join("probe"))?;
    drop(file);
    fs::remove_file(&tmp)
}

/// A fresh temporary for `path`, created empty (exclusively, not through a link) for another
/// program to write: ffmpeg encodes a video there.
pub(crate) fn reserve_temp(path: &Path) -> std::io::Result<PathBuf> {
    create_temp(path).map(|(tmp, _)| tmp)
}

/// A temporary's name split into NAME (or its hash), host and pid; `None` for any other
/// name. Temporaries of earlier versions (`…-HOST-PID`, no random part) count too.
fn parse_temp(file_name: &str) -> Option<(&str, &str, i32)> {
    let (stem, owner) = file_name.strip_prefix('.')?.rsplit_once(TEMP_MARKER)?;
    let mut parts = owner.split('-');
    let (host, pid) = (parts.next()?, parts.next()?.parse().ok()?);
    let random = parts.next();
    let well_formed =
        random.is_none_or(|r| r.len() == 16 && r.bytes().all(|b| b.is_ascii_hexdigit()));
    (well_formed && parts.next().is_none()).then_some((stem, host, pid))
}

/// Removes the temporaries in `dir` of the frames `frames` (named by `pattern`) that processes
/// which no longer run left behind (same host, dead pid; other hosts' after a day). Nothing
/// else is touched, whatever its name. Returns how many were removed.
pub(crate) fn clean_leftovers(dir: &Path, pattern: &Pattern, frames: &FrameSet) -> usize {
    let stale = stale_temporaries(dir);
    if stale.is_empty() {
        return 0;
    }
    let name = |n: u64| {
        let path = pattern.frame_path(n);
        path.file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let hashed = frames
        .iter()
        .next()
        .is_some_and(|n| name(n).len() + TEMP_EXTRA > NAME_MAX);
    let ours: HashSet<String> = match hashed {
        false => stale
            .iter()
            .filter(|(stem, _)| {
                pattern
                    .frame_number(stem)
                    .is_some_and(|n| frames.contains(n))
            })
            .map(|(stem, _)| stem.clone())
            .collect(),
        // A hash cannot be read back: hash our names until every leftover is accounted for.
        true => {
            let mut wanted: HashSet<&str> = stale.iter().map(|(s, _)| s.as_str()).collect();
            let mut found = HashSet::new();
            for n in frames.iter() {
                if wanted.is_empty() {
                    break;
                }
                let h = stem(&name(n), TEMP_EXTRA);
                if wanted.remove(h.as_str()) {
                    found.insert(h);
                }
            }
            found
        }
    };
    stale
        .iter()
        .filter(|(stem, path)| ours.contains(stem) && fs::remove_file(path).is_ok())
        .count()
}

/// Temporaries in `dir` whose owner is gone: (NAME or its hash, path).
fn stale_temporaries(dir: &Path) -> Vec<(String, PathBuf)> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut stale = Vec::new();
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some((stem, host, pid)) = file_name.to_str().and_then(parse_temp) else {
            continue;
        };
        let gone = if host == hostname() {
            !alive(pid)
        } else {
            entry.metadata().and_then(|m| m.modified()).is_ok_and(|t| {
                SystemTime::now().duration_since(t).unwrap_or_default() > FOREIGN_HOST_GRACE
            })
        };
        if gone {
            stale.push((stem.to_string(), entry.path()));
        }
    }
    stale
}

/// Whether a process with this pid exists on this host.
#[cfg(unix)]
pub(crate) fn alive(pid: i32) -> bool {
    // SAFETY: signal 0 only checks that the process exists.
    pid > 0
        && (unsafe { libc::kill(pid, 0) } == 0
            || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM))
}

/// Elsewhere a claim's owner counts as alive: its claim ends by its heartbeat's silence.
#[cfg(not(unix))]
pub(crate) fn alive(pid: i32) -> bool {
    pid > 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporaries_fit_and_parse_back() {
        let long = "f".repeat(250) + "_0001.png";
        for name in ["frame_0001.png".to_string(), long.clone()] {
            let tmp = temp_path(Path::new(&format!("dir/{name}")));
            let file = tmp.file_name().unwrap().to_str().unwrap();
            assert!(file.len() <= NAME_MAX, "{file}");
            let (stem_part, host, pid) = parse_temp(file).unwrap();
            assert_eq!((host, pid), (hostname(), std::process::id() as i32));
            assert_eq!(stem_part, stem(&name, TEMP_EXTRA));
        }
        assert_ne!(temp_path(Path::new("a.png")), temp_path(Path::new("a.png")));
        for other in [
            "notes.rayreel-tmp-vm-3999998",
            ".a.png.rayreel-tmp-vm-x",
            ".a.png.rayreel-tmp-vm-1-2-3",
        ] {
            assert_eq!(parse_temp(other), None, "{other}");
        }
        assert_eq!(
            parse_temp(".a.png.rayreel-tmp-vm-12"),
            Some(("a.png", "vm", 12))
        );
    }
}
