//! Claim files: plain processes sharing one output directory split the frames without a
//! scheduler. Before rendering a frame a process creates `.NAME.rayreel-claim` next to it
//! with O_EXCL, naming its host, pid and start time; it refreshes the file's mtime while the
//! frame is in flight and removes it once the frame is written. A claim whose owner is gone
//! (same host, dead pid) or silent for longer than the timeout is taken over, so a crashed
//! machine leaves no holes.

use crate::output::atomic::{alive, hostname, sidecar};
use std::fs::{self, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

pub struct Claims {
    timeout: Duration,
    owner: String,
}

/// What happened when trying to claim a frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Attempt {
    Claimed,
    /// Another live process holds it (its owner line).
    Held(String),
}

impl Claims {
    pub fn new(timeout: Duration) -> Claims {
        let start = SystemTime::now()
            .duration_since(SystemTime::UNIX_EPOCH)
            .unwrap_or_default();
        Claims {
            timeout,
            owner: format!(
                "host={} pid={} start={}",
                hostname(),
                std::process::id(),
                start.as_secs()
            ),
        }
    }

    /// `.NAME.rayreel-claim` beside the frame (a hash for NAME when the name is too long).
    pub fn path(frame: &Path) -> PathBuf {
        const SUFFIX: &str = ".rayreel-claim";
        sidecar(frame, SUFFIX, 1 + SUFFIX.len())
    }

    /// Claims the frame file `frame`, taking over a stale claim.
    pub fn try_claim(&self, frame: &Path) -> std::io::Result<Attempt> {
        let path = Claims::path(frame);
        for _ in 0..2 {
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(mut f) => {
                    writeln!(f, "{}", self.owner)?;
                    return Ok(Attempt::Claimed);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = fs::read_to_string(&path)
                        .unwrap_or_default()
                        .trim()
                        .to_string();
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
        let field = |key: &str| {
            holder
                .split_whitespace()
                .find_map(|kv| kv.strip_prefix(key)?.strip_prefix('='))
                .map(str::to_string)
        };
        if field("host").as_deref() == Some(hostname())
            && let Some(pid) = field("pid").and_then(|p| p.parse::<i32>().ok())
        {
            return !alive(pid);
        }
        let age = fs::metadata(path)
            .and_then(|m| m.modified())
            .map(|t| SystemTime::now().duration_since(t).unwrap_or_default());
        age.map_or(true, |a| a > self.timeout)
    }

    /// Shows the owner is alive: refreshes the claim's modification time.
    pub fn heartbeat(&self, frame: &Path) {
        let path = Claims::path(frame);
        if let Ok(f) = OpenOptions::new().append(true).open(&path) {
            let _ = f.set_modified(SystemTime::now());
        }
    }

    pub fn release(&self, frame: &Path) {
        let path = Claims::path(frame);
        if fs::read_to_string(&path).is_ok_and(|h| h.trim() == self.owner) {
            let _ = fs::remove_file(path);
        }
    }

    /// How often in-flight claims are refreshed.
    pub fn heartbeat_every(&self) -> Duration {
        self.timeout / 4
    }
}
