//! `--video out.mp4`: the ordered raw stream piped into the system's ffmpeg, which writes a
//! temporary beside the video; only a complete encode (ffmpeg exits 0) is renamed to the
//! final name, and an existing file there is replaced only with `--force`.
//!
//! `.mp4` and `.mkv` get H.264 in yuv420p (odd sizes padded by one pixel), `.mov` the same,
//! or ProRes 4444 with its alpha when the frames have alpha (`.mkv` too; `.mp4` refuses
//! alpha). `--video-args` words go after these options, so they replace them.

use super::atomic;
use super::stream::{Source, StreamFormat, codec_words, input_words, shell_quote};
use std::io::Read;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};

/// What a video job asks for, checked against the command line before anything renders.
#[derive(Debug, Clone)]
pub(crate) struct VideoJob {
    pub(crate) path: PathBuf,
    /// ffmpeg's `-f` for the container: the temporary's name tells ffmpeg nothing.
    container: &'static str,
    picture: Picture,
    pub(crate) extra: Vec<String>,
    pub(crate) force: bool,
}

/// The frames a video is made of, as the job renders them.
#[derive(Debug, Clone)]
pub(crate) struct Picture {
    pub(crate) alpha: bool,
    pub(crate) sixteen_bit: bool,
    pub(crate) size: (u32, u32),
    /// The frame rate as an exact fraction, `24/1` or `24000/1001`.
    pub(crate) fps: String,
}

/// The container for a video's extension, or why there is none.
pub(crate) fn container(path: &Path, alpha: bool) -> Result<&'static str, String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    match (ext.to_ascii_lowercase().as_str(), alpha) {
        ("mp4", true) => Err(format!(
            "{}: H.264 in .mp4 cannot keep the alpha channel (--alpha, render.alpha); name a .mov (ProRes 4444) instead",
            path.display()
        )),
        ("mp4", false) => Ok("mp4"),
        ("mov", _) => Ok("mov"),
        ("mkv", _) => Ok("matroska"),
        _ => Err(format!(
            "{}: --video makes .mp4, .mov or .mkv files (got `.{ext}`)",
            path.display()
        )),
    }
}

impl VideoJob {
    pub(crate) fn new(
        path: PathBuf,
        picture: Picture,
        extra: Vec<String>,
        force: bool,
    ) -> Result<VideoJob, String> {
        Ok(VideoJob {
            container: container(&path, picture.alpha)?,
            path,
            picture,
            extra,
            force,
        })
    }

    /// The stream ffmpeg reads: raw frames, 16 bits when asked (ProRes keeps 10).
    pub(crate) fn stream(&self) -> (StreamFormat, bool) {
        (StreamFormat::Raw, self.picture.sixteen_bit)
    }

    /// ffmpeg's arguments, writing the video to `out`.
    pub(crate) fn args(&self, out: &Path) -> Vec<String> {
        let p = &self.picture;
        let source = Source::Stream {
            format: StreamFormat::Raw,
            sixteen_bit: p.sixteen_bit,
        };
        let mut words: Vec<String> = ["-hide_banner", "-loglevel", "error", "-nostats"]
            .map(String::from)
            .to_vec();
        words.extend(input_words(source, p.alpha, p.size, &p.fps));
        words.extend(codec_words(p.alpha, p.size));
        words.extend(self.extra.iter().cloned());
        words.extend(["-f".into(), self.container.into(), "-y".into()]);
        words.push(out.to_string_lossy().into_owned());
        words
    }

    /// The command as a shell line, for the progress output.
    pub(crate) fn command_line(&self) -> String {
        let mut words = vec!["ffmpeg".to_string()];
        words.extend(self.args(&self.path));
        let quoted: Vec<String> = words.iter().map(|w| shell_quote(w)).collect();
        quoted.join(" ")
    }

    /// What must hold before any frame renders: ffmpeg is there, the video's directory
    /// takes files, and no file is in the way unless `--force`.
    pub(crate) fn preflight(&self) -> Result<(), String> {
        if find_on_path("ffmpeg").is_none() {
            return Err(format!(
                "{}: --video encodes with ffmpeg, which is not on the PATH; install it (e.g. apt install ffmpeg), or render frames and encode them elsewhere",
                self.path.display()
            ));
        }
        let dir = match self.path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("{}: cannot create directory: {e}", dir.display()))?;
        atomic::probe_writable(dir).map_err(|e| {
            format!(
                "{}: cannot write files in this directory: {e}",
                dir.display()
            )
        })?;
        match std::fs::symlink_metadata(&self.path) {
            Ok(m) if m.is_dir() => Err(format!("{}: is a directory", self.path.display())),
            Ok(_) if !self.force => Err(format!(
                "{}: already exists; rayreel does not replace it without --force",
                self.path.display()
            )),
            _ => Ok(()),
        }
    }

    /// Starts ffmpeg on a fresh temporary beside the video.
    pub(crate) fn start(&self) -> Result<Encoder, String> {
        let temp = atomic::reserve_temp(&self.path)
            .map_err(|e| format!("{}: cannot create a temporary: {e}", self.path.display()))?;
        let child = Command::new("ffmpeg")
            .args(self.args(&temp))
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            // Its own process group: Ctrl-C reaches rayreel alone, which then stops ffmpeg
            // and removes the temporary, rather than racing ffmpeg to the pipe's end.
            .process_group(0)
            .spawn();
        let mut child = match child {
            Ok(child) => child,
            Err(e) => {
                let _ = std::fs::remove_file(&temp);
                return Err(format!("cannot start ffmpeg: {e}"));
            }
        };
        let stdin = child.stdin.take();
        let stderr = child.stderr.take().map(|mut s| {
            std::thread::spawn(move || {
                let mut text = Vec::new();
                let _ = s.read_to_end(&mut text);
                text
            })
        });
        Ok(Encoder {
            child,
            stdin,
            stderr,
            temp,
            path: self.path.clone(),
            force: self.force,
            done: false,
        })
    }
}

/// A running ffmpeg: its stdin takes the stream, its stderr is kept for a failure's message.
pub(crate) struct Encoder {
    child: Child,
    stdin: Option<ChildStdin>,
    stderr: Option<std::thread::JoinHandle<Vec<u8>>>,
    temp: PathBuf,
    path: PathBuf,
    force: bool,
    /// `finish` ran: dropping it no longer stops ffmpeg.
    done: bool,
}

/// An encoder dropped before `finish` (the run failed or was stopped) stops ffmpeg and
/// removes its temporary: a video is published only whole.
impl Drop for Encoder {
    fn drop(&mut self) {
        if self.done {
            return;
        }
        self.stdin = None;
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.temp);
    }
}

/// How much of ffmpeg's stderr a failure quotes: its last lines say why.
const STDERR_TAIL: usize = 2000;

impl Encoder {
    /// The pipe into ffmpeg, handed to the run as its stream (once).
    pub(crate) fn take_input(&mut self) -> Option<ChildStdin> {
        self.stdin.take()
    }

    /// Waits for ffmpeg (the stream must have been closed), then puts the video under its
    /// name; on any failure the temporary goes and the message ends with ffmpeg's stderr.
    pub(crate) fn finish(mut self) -> Result<(), String> {
        self.stdin = None;
        self.done = true;
        let status = self.child.wait();
        let said = self.stderr_tail();
        let result = match status {
            Ok(s) if s.success() => self.publish(),
            Ok(s) => Err(format!("ffmpeg failed ({s}){said}")),
            Err(e) => Err(format!("ffmpeg: {e}{said}")),
        };
        if result.is_err() {
            let _ = std::fs::remove_file(&self.temp);
        }
        result.map_err(|e| format!("{}: {e}; nothing was written there", self.path.display()))
    }

    /// `: LAST LINES` of ffmpeg's stderr, or nothing when it said nothing.
    fn stderr_tail(&mut self) -> String {
        let text = self
            .stderr
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default();
        let text = String::from_utf8_lossy(&text);
        let text = text.trim();
        let start = text.len().saturating_sub(STDERR_TAIL);
        let start = (start..=text.len())
            .find(|&i| text.is_char_boundary(i))
            .unwrap_or(0);
        match &text[start..] {
            "" => String::new(),
            tail => format!("; ffmpeg said: {tail}"),
        }
    }

    /// The temporary under the final name: with --force by rename, otherwise by a hard link
    /// that fails when something appeared there meanwhile (never replaced silently).
    fn publish(&self) -> Result<(), String> {
        if self.force {
            return std::fs::rename(&self.temp, &self.path).map_err(|e| e.to_string());
        }
        match std::fs::hard_link(&self.temp, &self.path) {
            Ok(()) => std::fs::remove_file(&self.temp).map_err(|e| e.to_string()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(
                "a file appeared there while rendering; rayreel does not replace it without --force"
                    .into(),
            ),
            // File systems without hard links: the name was free a moment ago.
            Err(_) if !self.path.exists() => {
                std::fs::rename(&self.temp, &self.path).map_err(|e| e.to_string())
            }
            Err(e) => Err(e.to_string()),
        }
    }
}

/// The first executable file `name` in the directories of PATH.
fn find_on_path(name: &str) -> Option<PathBuf> {
    use std::os::unix::fs::PermissionsExt;
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(name))
        .find(|p| {
            std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
        })
}

/// `fps` as an exact fraction for ffmpeg: the file's own fraction, or the shortest decimal
/// that reads back as the f64 (`29.97` → `2997/100`), so ffmpeg's rate is exactly the one the
/// frames' times were computed with.
pub(crate) fn exact_rate(fraction: Option<(u64, u64)>, fps: f64) -> String {
    if let Some((num, den)) = fraction {
        return format!("{num}/{den}");
    }
    let text = format!("{fps}");
    let (whole, decimals) = text.split_once('.').unwrap_or((&text, ""));
    let digits = format!("{whole}{decimals}");
    let num = digits.parse::<u64>().ok();
    let den = 10u64.checked_pow(decimals.len() as u32);
    match num.zip(den) {
        Some((num, den)) if num > 0 => {
            let g = gcd(num, den);
            format!("{}/{}", num / g, den / g)
        }
        _ => text,
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_are_exact_fractions() {
        assert_eq!(exact_rate(None, 24.0), "24/1");
        assert_eq!(exact_rate(None, 29.97), "2997/100");
        assert_eq!(exact_rate(None, 0.5), "1/2");
        assert_eq!(exact_rate(Some((24000, 1001)), 23.976), "24000/1001");
    }

    #[test]
    fn containers_follow_the_extension() {
        assert_eq!(container(Path::new("a.MP4"), false), Ok("mp4"));
        assert_eq!(container(Path::new("a.mkv"), true), Ok("matroska"));
        assert!(container(Path::new("a.mp4"), true).is_err());
        assert!(container(Path::new("a.avi"), false).is_err());
    }
}
