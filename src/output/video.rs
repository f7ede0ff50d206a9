//! `--video out.mp4`: the ordered raw stream piped into the system's ffmpeg, which writes a
//! temporary beside the video; only a complete encode is renamed to the final name, and an
//! existing file there is replaced only with `--force`. Complete means more than ffmpeg's
//! exit status (ffmpeg 5.1 exits 0 after "Error writing trailer … No space left on device"):
//! its stderr reports no error, the container is whole (MP4 and MOV boxes that end where the
//! file ends with a `moov` among them; a Matroska segment closed with its size), and, when
//! ffprobe is installed, the file holds one video packet for every frame sent (`verify`).
//!
//! `.mp4` and `.mkv` get H.264 in yuv420p (odd sizes padded by one pixel), `.mov` the same,
//! or ProRes 4444 with its alpha when the frames have alpha (`.mkv` too; `.mp4` refuses
//! alpha). `--video-args` words go after these options, so they replace them.

use super::atomic;
use super::stream::{Source, StreamFormat, codec_words, input_words, shell_quote};
use std::io::{Read, Seek, SeekFrom, Write};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

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
            sent: Arc::new(AtomicU64::new(0)),
            frame_bytes: self.frame_bytes(),
            container: self.container,
            extra: !self.extra.is_empty(),
        })
    }

    /// Bytes of one raw frame in the stream: 3 or 4 samples a pixel, of 1 or 2 bytes.
    fn frame_bytes(&self) -> u64 {
        let p = &self.picture;
        let (w, h) = (u64::from(p.size.0), u64::from(p.size.1));
        w * h * (3 + u64::from(p.alpha)) * (1 + u64::from(p.sixteen_bit))
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
    /// Bytes the run wrote into ffmpeg, and a frame's bytes: the frames the video must hold.
    sent: Arc<AtomicU64>,
    frame_bytes: u64,
    /// ffmpeg's `-f`: how the written file is checked.
    container: &'static str,
    /// `--video-args` were given: ffmpeg may rightly keep fewer frames than it was sent.
    extra: bool,
}

/// The pipe into ffmpeg, counting what passes.
pub(crate) struct Counted {
    pipe: ChildStdin,
    sent: Arc<AtomicU64>,
}

impl Write for Counted {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.pipe.write(buf)?;
        self.sent.fetch_add(n as u64, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.pipe.flush()
    }
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
    pub(crate) fn take_input(&mut self) -> Option<Counted> {
        let sent = Arc::clone(&self.sent);
        self.stdin.take().map(|pipe| Counted { pipe, sent })
    }

    /// Waits for ffmpeg (the stream must have been closed), then puts the video under its
    /// name once `verify` finds it whole; on any failure the temporary goes and the message
    /// ends with ffmpeg's stderr. `whole_stream`: ffmpeg read every frame sent (it did not
    /// end the stream itself).
    pub(crate) fn finish(mut self, whole_stream: bool) -> Result<(), String> {
        self.stdin = None;
        self.done = true;
        let status = self.child.wait();
        let (said, errors) = self.stderr_tail();
        let result = match status {
            Ok(s) if s.success() => self
                .verify(errors, whole_stream, &said)
                .and_then(|()| self.publish()),
            Ok(s) => Err(format!("ffmpeg failed ({s}){said}")),
            Err(e) => Err(format!("ffmpeg: {e}{said}")),
        };
        if result.is_err() {
            let _ = std::fs::remove_file(&self.temp);
        }
        result.map_err(|e| format!("{}: {e}; nothing was written there", self.path.display()))
    }

    /// `: LAST LINES` of ffmpeg's stderr, or nothing when it said nothing; and whether it
    /// reported an error.
    fn stderr_tail(&mut self) -> (String, bool) {
        let text = self
            .stderr
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default();
        let text = String::from_utf8_lossy(&text);
        let text = text.trim();
        let errors = text.lines().any(reports_an_error);
        let start = text.len().saturating_sub(STDERR_TAIL);
        let start = (start..=text.len())
            .find(|&i| text.is_char_boundary(i))
            .unwrap_or(0);
        let tail = match &text[start..] {
            "" => String::new(),
            tail => format!("; ffmpeg said: {tail}"),
        };
        (tail, errors)
    }

    /// Whether the temporary is a whole video, though ffmpeg exited 0: no error on its
    /// stderr, a whole container, and with ffprobe, a file it reads without error that holds
    /// a packet for every frame sent (when ffmpeg read them all under rayreel's own options:
    /// `--video-args` such as `-t` or `-frames:v` may rightly keep fewer, but not none).
    fn verify(&self, errors: bool, whole_stream: bool, said: &str) -> Result<(), String> {
        if errors {
            return Err(format!("ffmpeg exited 0 but reported an error{said}"));
        }
        whole_container(&self.temp, self.container).map_err(|why| {
            format!("ffmpeg exited 0 but the file it wrote is not whole: {why}{said}")
        })?;
        let sent = self.sent.load(Ordering::Relaxed);
        let counted = whole_stream && !self.extra && self.frame_bytes > 0;
        let frames =
            (counted && sent.is_multiple_of(self.frame_bytes)).then(|| sent / self.frame_bytes);
        match (probe_packets(&self.temp), frames) {
            (Some(Ok(n)), Some(frames)) if n != frames => Err(format!(
                "ffmpeg exited 0 but the file holds {n} video frames of the {frames} sent{said}"
            )),
            (Some(Ok(0)), None) => Err(format!(
                "ffmpeg exited 0 but the file holds no video frame{said}"
            )),
            (Some(Err(why)), _) => Err(format!(
                "ffprobe cannot read the file ffmpeg wrote: {why}{said}"
            )),
            _ => Ok(()),
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

/// A line of ffmpeg's stderr that says something failed: ffmpeg runs at `-loglevel error`, but
/// `--video-args` may raise it, so the words decide, not the line's presence.
fn reports_an_error(line: &str) -> bool {
    let lower = line.to_ascii_lowercase();
    lower.contains("error") || lower.contains("no space left") || lower.contains("failed")
}

/// The container's own structure, from the file's bytes: MP4 and MOV top-level boxes that
/// follow each other to the file's end exactly, a `moov` (written last, by the trailer) and an
/// `mdat` among them; Matroska's EBML header, then a segment whose size is known (written by
/// the trailer) and ends where the file ends.
pub(crate) fn whole_container(path: &Path, container: &str) -> Result<(), String> {
    let mut f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let len = f.metadata().map_err(|e| e.to_string())?.len();
    match container {
        "matroska" => whole_matroska(&mut f, len),
        _ => whole_boxes(&mut f, len),
    }
}

fn whole_boxes(f: &mut std::fs::File, len: u64) -> Result<(), String> {
    let (mut at, mut moov, mut mdat) = (0u64, false, false);
    while at < len {
        let mut head = [0u8; 16];
        f.seek(SeekFrom::Start(at)).map_err(|e| e.to_string())?;
        let got = f.read(&mut head).map_err(|e| e.to_string())?;
        if got < 8 {
            return Err(format!("a box header is cut off at byte {at}"));
        }
        let small = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        let size = match small {
            1 if got >= 16 => u64::from_be_bytes(head[8..16].try_into().expect("8 bytes")),
            0 => return Err(format!("the box at byte {at} was never closed (size 0)")),
            s => s,
        };
        if size < 8 || at.checked_add(size).is_none_or(|end| end > len) {
            return Err(format!(
                "the box at byte {at} claims {size} bytes; the file ends at {len}"
            ));
        }
        moov |= &head[4..8] == b"moov";
        mdat |= &head[4..8] == b"mdat";
        at += size;
    }
    match (moov, mdat) {
        (true, true) => Ok(()),
        (false, _) => Err("no `moov` box (the index a player needs, written last)".into()),
        (true, false) => Err("no `mdat` box (the frames)".into()),
    }
}

fn whole_matroska(f: &mut std::fs::File, len: u64) -> Result<(), String> {
    let mut head = vec![0u8; 4096];
    let got = f.read(&mut head).map_err(|e| e.to_string())?;
    let head = &head[..got];
    let Some((ebml_size, at)) = element(head, 0, 0x1A45_DFA3) else {
        return Err("no EBML header".into());
    };
    let segment_at = at as u64 + ebml_size.ok_or("the EBML header has no size")?;
    let Some((size, data)) = usize::try_from(segment_at)
        .ok()
        .and_then(|s| element(head, s, 0x1853_8067))
    else {
        return Err("no segment after the EBML header".into());
    };
    match size {
        None => Err("the segment's size was never written (the trailer is missing)".into()),
        Some(size) if data as u64 + size != len => Err(format!(
            "the segment claims {size} bytes from byte {data}; the file ends at {len}"
        )),
        Some(_) => Ok(()),
    }
}

/// The element `id` (4 bytes) at `at` in `b`: its size (`None` when unknown, all ones) and
/// where its data starts.
fn element(b: &[u8], at: usize, id: u32) -> Option<(Option<u64>, usize)> {
    if b.get(at..at + 4)? != id.to_be_bytes() {
        return None;
    }
    let first = *b.get(at + 4)?;
    let n = first.leading_zeros() as usize + 1;
    if n > 8 {
        return None;
    }
    let bytes = b.get(at + 4..at + 4 + n)?;
    let mut v = u64::from(first) & (0xff >> n);
    for &x in &bytes[1..] {
        v = v << 8 | u64::from(x);
    }
    let unknown = v == (1u64 << (7 * n)) - 1;
    Some(((!unknown).then_some(v), at + 4 + n))
}

/// The number of video packets ffprobe counts in `path`, `None` without ffprobe.
fn probe_packets(path: &Path) -> Option<Result<u64, String>> {
    find_on_path("ffprobe")?;
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-count_packets"])
        .args(["-show_entries", "stream=nb_read_packets", "-of", "csv=p=0"])
        .arg(path)
        .stdin(Stdio::null())
        .output();
    let out = match out {
        Ok(out) => out,
        Err(e) => return Some(Err(e.to_string())),
    };
    let text = String::from_utf8_lossy(&out.stdout);
    let said = String::from_utf8_lossy(&out.stderr);
    Some(match (out.status.success(), text.trim().parse::<u64>()) {
        (true, Ok(n)) if said.trim().is_empty() => Ok(n),
        _ => Err(format!("{} {}", text.trim(), said.trim())
            .trim()
            .to_string()),
    })
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
    fn containers_are_whole_only_to_their_end() {
        let dir = tempfile::tempdir().unwrap();
        let at = |name: &str, bytes: &[u8]| {
            let p = dir.path().join(name);
            std::fs::write(&p, bytes).unwrap();
            p
        };
        let boxes = |list: &[(&[u8; 4], u32)]| {
            let mut b = Vec::new();
            for (kind, size) in list {
                b.extend(size.to_be_bytes());
                b.extend(*kind);
                b.resize(b.len() + *size as usize - 8, 0);
            }
            b
        };
        let good = boxes(&[(b"ftyp", 16), (b"mdat", 40), (b"moov", 24)]);
        assert_eq!(whole_container(&at("a.mp4", &good), "mp4"), Ok(()));
        let no_moov = boxes(&[(b"ftyp", 16), (b"mdat", 40)]);
        assert!(whole_container(&at("b.mp4", &no_moov), "mp4").is_err());
        assert!(whole_container(&at("c.mp4", &good[..good.len() - 1]), "mp4").is_err());
        // EBML header of 2 bytes, then a segment of 3 bytes: known, then unknown size.
        let mkv = [
            0x1A, 0x45, 0xDF, 0xA3, 0x82, 0, 0, 0x18, 0x53, 0x80, 0x67, 0x83, 1, 2, 3,
        ];
        assert_eq!(whole_container(&at("d.mkv", &mkv), "matroska"), Ok(()));
        let mut open = mkv;
        open[11] = 0xFF;
        assert!(whole_container(&at("e.mkv", &open), "matroska").is_err());
    }

    #[test]
    fn containers_follow_the_extension() {
        assert_eq!(container(Path::new("a.MP4"), false), Ok("mp4"));
        assert_eq!(container(Path::new("a.mkv"), true), Ok("matroska"));
        assert!(container(Path::new("a.mp4"), true).is_err());
        assert!(container(Path::new("a.avi"), false).is_err());
    }
}
