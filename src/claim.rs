//! Claim files: plain processes sharing one output directory split the frames without a
//! scheduler. Before rendering a frame a process creates `.NAME.rayreel-claim` next to it
//! with O_EXCL, naming its host, pid, the process's start time and the machine's boot id; it
//! refreshes the file's mtime (the heartbeat) while the frame is in flight and removes it once
//! the frame is written.
//!
//! A claim is stale, and taken over, when its heartbeat is older than the timeout, or when it
//! comes from this host and its process is gone: the pid is dead, or names another process
//! than the one that wrote the claim (its start time or the boot id differ: pid reuse, a
//! container restarted with the same host name). So a crashed process or machine leaves no
//! hole and nothing waits forever.
//!
//! Claims are read without blocking and never through a link, only when they are regular
//! files, and only their first `CLAIM_BYTES`: a FIFO, a device or a link at a claim's name
//! makes `try_claim` fail with an error naming it (nothing is removed that rayreel did not
//! write), and a huge file is read no further than an owner line can reach.

use crate::output::atomic::{alive, hostname, sidecar};
use crate::regular::{self, Links, Refused};
use std::fs::{self, OpenOptions};
use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

/// The most of a claim file ever read: an owner line is under 200 bytes.
const CLAIM_BYTES: u64 = 4096;

/// The owner line of the claim at `path`: `Ok(None)` when the claim is gone, an error when
/// something other than a regular file stands at its name.
fn owner_line(path: &Path) -> std::io::Result<Option<String>> {
    let text = |bytes: Vec<u8>| String::from_utf8_lossy(&bytes).trim().to_string();
    match regular::open(path, Links::Refuse) {
        Ok((f, meta)) => Ok(Some(
            regular::read_at_most(&f, meta.len(), CLAIM_BYTES)
                .map(text)
                .unwrap_or_default(),
        )),
        Err(Refused::Missing) => Ok(None),
        Err(Refused::NotRegular(what)) => Err(std::io::Error::other(format!(
            "{what} stands at the claim's name, where rayreel only ever writes regular files; remove it"
        ))),
        // Unreadable (permissions): an owner unknown, judged by its heartbeat alone.
        Err(Refused::Io(_)) => Ok(Some(String::new())),
    }
}

/// The owner line of the claim at `path`, or `""` when it cannot be read as one.
fn read_owner(path: &Path) -> String {
    owner_line(path).ok().flatten().unwrap_or_default()
}

pub(crate) struct Claims {
    timeout: Duration,
    owner: String,
}

/// What happened when trying to claim a frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Attempt {
    Claimed,
    /// Another live process holds it (its owner line).
    Held(String),
}

/// Who wrote a claim, as its owner line records it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
struct Owner {
    host: String,
    pid: Option<i32>,
    start: Option<u64>,
    boot: Option<String>,
}

impl Owner {
    fn parse(line: &str) -> Owner {
        let field = |key: &str| {
            line.split_whitespace()
                .find_map(|kv| kv.strip_prefix(key)?.strip_prefix('='))
                .map(str::to_string)
        };
        Owner {
            host: field("host").unwrap_or_default(),
            pid: field("pid").and_then(|p| p.parse().ok()),
            start: field("start").and_then(|s| s.parse().ok()),
            boot: field("boot"),
        }
    }

    /// Whether the process that wrote the claim is gone, judged on this host.
    fn gone_from_here(&self) -> bool {
        let Some(pid) = self.pid else {
            return false;
        };
        !alive(pid) || differs(&self.boot, boot_id()) || differs(&self.start, start_time(pid))
    }
}

/// Whether the writer of an owner line, as a claim file holds it, is gone from this host: the
/// judgement a waiting process makes on whatever bytes stand in a claim (fuzzed in `fuzzing`).
pub(crate) fn judge_owner_line(line: &str) -> bool {
    Owner::parse(line).gone_from_here()
}

/// Both known, and not the same.
fn differs<T: PartialEq>(recorded: &Option<T>, now: Option<T>) -> bool {
    recorded.is_some() && now.is_some() && *recorded != now
}

/// When process `pid` started, in clock ticks since boot (field 22 of /proc/PID/stat).
pub(crate) fn start_time(pid: i32) -> Option<u64> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces and parentheses.
    let after_name = &stat[stat.rfind(')')? + 1..];
    after_name.split_whitespace().nth(19)?.parse().ok()
}

/// This boot of the kernel (containers share their host's).
pub(crate) fn boot_id() -> Option<String> {
    let id = fs::read_to_string("/proc/sys/kernel/random/boot_id").ok()?;
    Some(id.trim().to_string()).filter(|id| !id.is_empty())
}

impl Claims {
    pub(crate) fn new(timeout: Duration) -> Claims {
        let pid = std::process::id();
        let field = |name: &str, v: Option<String>| v.map(|v| format!(" {name}={v}"));
        Claims {
            timeout,
            owner: format!(
                "host={} pid={pid}{}{}",
                hostname(),
                field("start", start_time(pid as i32).map(|s| s.to_string())).unwrap_or_default(),
                field("boot", boot_id()).unwrap_or_default()
            ),
        }
    }

    /// `.NAME.rayreel-claim` beside the frame (a hash for NAME when the name is too long).
    pub(crate) fn path(frame: &Path) -> PathBuf {
        const SUFFIX: &str = ".rayreel-claim";
        sidecar(frame, SUFFIX, 1 + SUFFIX.len())
    }

    /// Claims the frame file `frame`, taking over a stale claim.
    pub(crate) fn try_claim(&self, frame: &Path) -> std::io::Result<Attempt> {
        let path = Claims::path(frame);
        for _ in 0..2 {
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(mut f) => {
                    writeln!(f, "{}", self.owner)?;
                    return Ok(Attempt::Claimed);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    // Gone since: race for it again.
                    let Some(holder) = owner_line(&path)? else {
                        continue;
                    };
                    if !self.is_stale(&path, &holder) {
                        return Ok(Attempt::Held(holder));
                    }
                    // Remove the stale claim and race for it like everyone else; at worst two
                    // processes render the same deterministic bytes.
                    let _ = fs::remove_file(&path);
                }
                Err(e) => return Err(e),
            }
        }
        Ok(Attempt::Held(
            "a process that just took over a stale claim".into(),
        ))
    }

    fn is_stale(&self, path: &Path, holder: &str) -> bool {
        let silent = heartbeat_age(path).is_none_or(|age| age > self.timeout);
        let owner = Owner::parse(holder);
        silent || (owner.host == hostname() && owner.gone_from_here())
    }

    /// Shows the owner is alive: refreshes the claim's modification time.
    pub(crate) fn heartbeat(&self, frame: &Path) {
        let path = Claims::path(frame);
        // Never through a link someone put in the claim's place, never waiting on a FIFO.
        let opened = OpenOptions::new()
            .append(true)
            .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
            .open(&path);
        if let Ok(f) = opened {
            let _ = f.set_modified(SystemTime::now());
        }
    }

    pub(crate) fn release(&self, frame: &Path) {
        let path = Claims::path(frame);
        if read_owner(&path) == self.owner {
            let _ = fs::remove_file(path);
        }
    }

    /// How often in-flight claims are refreshed.
    pub(crate) fn heartbeat_every(&self) -> Duration {
        self.timeout / 4
    }
}

/// How long ago the claim at `path` was last refreshed.
fn heartbeat_age(path: &Path) -> Option<Duration> {
    let modified = fs::symlink_metadata(path).and_then(|m| m.modified()).ok()?;
    Some(
        SystemTime::now()
            .duration_since(modified)
            .unwrap_or_default(),
    )
}

/// A claim another process holds, as a waiting process reports it.
#[derive(Debug, Clone)]
pub(crate) struct Held {
    pub(crate) path: PathBuf,
    /// Its owner line: host, pid, start time, boot id.
    pub(crate) owner: String,
    /// How long ago it was refreshed; `None` once it is gone.
    pub(crate) heartbeat: Option<Duration>,
}

/// The claim on `frame` as it is now.
pub(crate) fn held(frame: &Path) -> Held {
    let path = Claims::path(frame);
    Held {
        owner: read_owner(&path),
        heartbeat: heartbeat_age(&path),
        path,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owners_are_identified_by_start_time_and_boot() {
        let me = std::process::id() as i32;
        let line = Claims::new(Duration::from_secs(9)).owner;
        let owner = Owner::parse(&line);
        assert_eq!((owner.host.as_str(), owner.pid), (hostname(), Some(me)));
        assert!(owner.start.is_some() && owner.boot.is_some(), "{line}");
        assert!(!owner.gone_from_here());
        let reused = Owner {
            start: owner.start.map(|s| s + 1),
            ..owner.clone()
        };
        let rebooted = Owner {
            boot: Some("another boot".into()),
            ..owner.clone()
        };
        assert!(reused.gone_from_here() && rebooted.gone_from_here());
        // Without a start time or boot id to compare, a live pid holds.
        assert!(!Owner::parse(&format!("host=h pid={me}")).gone_from_here());
    }
}
