//! Frame streams on stdout for ffmpeg: raw rgb24 / rgb48le bytes (rgba / rgba64le with
//! alpha), or a sequence of PNGs.
//! Nothing but frame bytes is ever written here.

use super::format::{Compression, EncodeError};
use super::png;
use crate::frame::Frame;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum StreamFormat {
    /// Raw rgb24 (rgb48le with --bit-depth 16), for `ffmpeg -f rawvideo`.
    Raw,
    /// Concatenated PNGs, for `ffmpeg -f image2pipe`.
    Png,
}

pub(crate) fn encode(
    frame: &mut Frame,
    format: StreamFormat,
    sixteen_bit: bool,
) -> Result<Vec<u8>, EncodeError> {
    match (format, sixteen_bit) {
        (StreamFormat::Raw, false) => Ok(frame.take_rgb8()),
        (StreamFormat::Raw, true) => Ok(frame
            .to_rgb16()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()),
        (StreamFormat::Png, _) => png::encode(frame, sixteen_bit, Compression::Fast, &[]),
    }
}

/// What ffmpeg reads: this stream on its stdin, or the frame files.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Source<'a> {
    Stream {
        format: StreamFormat,
        sixteen_bit: bool,
    },
    /// ffmpeg's image2 pattern (`frames/orbit/frame_%04d.png`) and the first frame number.
    Files { pattern: &'a str, first: u64 },
}

/// The ffmpeg command that reads `source` (frames of `width`×`height` at `fps`, written as
/// ffmpeg's `-r` takes it: `24`, `24000/1001`) and makes an H.264 video in yuv420p, which
/// every player takes; odd sizes get a pad filter, since yuv420p needs even ones. Frames
/// with `alpha` make ProRes 4444 instead (any size), which keeps the alpha H.264 cannot
/// carry. Every word is quoted for a POSIX shell where it needs it, so the line can be
/// pasted as it is.
pub(crate) fn ffmpeg_command(
    source: Source,
    alpha: bool,
    size: (u32, u32),
    fps: &str,
    out: &str,
) -> String {
    let mut words: Vec<String> = vec!["ffmpeg".into()];
    words.extend(input_words(source, alpha, size, fps));
    words.extend(codec_words(alpha, size));
    words.push(match alpha {
        true => format!("{}.mov", out.strip_suffix(".mp4").unwrap_or(out)),
        false => out.to_string(),
    });
    let quoted: Vec<String> = words.iter().map(|w| shell_quote(w)).collect();
    quoted.join(" ")
}

/// ffmpeg's options for reading `source`, up to and including `-i`.
pub(crate) fn input_words(
    source: Source,
    alpha: bool,
    (width, height): (u32, u32),
    fps: &str,
) -> Vec<String> {
    let mut words: Vec<String> = Vec::new();
    let mut add = |list: &[&str]| words.extend(list.iter().map(|w| w.to_string()));
    match source {
        Source::Stream {
            format: StreamFormat::Raw,
            sixteen_bit,
        } => {
            add(&["-f", "rawvideo", "-pix_fmt", pix_fmt(sixteen_bit, alpha)]);
            add(&["-s", &format!("{width}x{height}"), "-r", fps, "-i", "-"]);
        }
        Source::Stream {
            format: StreamFormat::Png,
            ..
        } => add(&["-f", "image2pipe", "-framerate", fps, "-i", "-"]),
        Source::Files { pattern, first } => {
            add(&["-framerate", fps]);
            if first != 0 {
                add(&["-start_number", &first.to_string()]);
            }
            add(&["-i", pattern]);
        }
    }
    words
}

/// The codec options: H.264 in yuv420p (padded to an even size), or ProRes 4444 with alpha.
pub(crate) fn codec_words(alpha: bool, (width, height): (u32, u32)) -> Vec<String> {
    let words: &[&str] = match alpha {
        true => &[
            "-c:v",
            "prores_ks",
            "-profile:v",
            "4444",
            "-pix_fmt",
            "yuva444p10le",
        ],
        false if width % 2 == 1 || height % 2 == 1 => {
            &["-vf", PAD, "-c:v", "libx264", "-pix_fmt", "yuv420p"]
        }
        false => &["-c:v", "libx264", "-pix_fmt", "yuv420p"],
    };
    words.iter().map(|w| w.to_string()).collect()
}

/// The stream's pixels as ffmpeg names them.
pub(crate) fn pix_fmt(sixteen_bit: bool, alpha: bool) -> &'static str {
    match (sixteen_bit, alpha) {
        (false, false) => "rgb24",
        (true, false) => "rgb48le",
        (false, true) => "rgba",
        (true, true) => "rgba64le",
    }
}

/// The filter that pads an odd size to the next even one.
pub(crate) const PAD: &str = "pad=ceil(iw/2)*2:ceil(ih/2)*2";

/// `w` as one word of a shell: as it is when it holds only characters no shell treats
/// specially, otherwise in single quotes (a quote inside becomes `'\''`). A word holding a
/// control character, or a character that reorders what a terminal shows, is written in
/// bash's `$'…'` instead, each such character as an escape (`\n`, `\t`, `\x01`, `\u202e`):
/// printed as it is, the line would be broken or garbled on the way to the terminal (rayreel
/// shows such characters as escapes), and a pasted line would name another file.
pub(crate) fn shell_quote(w: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./:=,+%@".contains(c);
    if !w.is_empty() && w.chars().all(plain) {
        return w.to_string();
    }
    if !w.chars().any(escaped) {
        return format!("'{}'", w.replace('\'', r"'\''"));
    }
    let mut out = String::from("$'");
    for c in w.chars() {
        match c {
            '\\' => out.push_str(r"\\"),
            '\'' => out.push_str(r"\'"),
            '\n' => out.push_str(r"\n"),
            '\t' => out.push_str(r"\t"),
            '\r' => out.push_str(r"\r"),
            c if escaped(c) && (c as u32) < 0x80 => out.push_str(&format!("\\x{:02x}", c as u32)),
            c if escaped(c) => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('\'');
    out
}

/// What `shell_quote` writes as an escape: what `console::printable` would not show as it is.
fn escaped(c: char) -> bool {
    c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_paste_into_a_shell() {
        let raw = Source::Stream {
            format: StreamFormat::Raw,
            sixteen_bit: false,
        };
        assert_eq!(
            ffmpeg_command(raw, false, (641, 361), "24", "out.mp4"),
            "ffmpeg -f rawvideo -pix_fmt rgb24 -s 641x361 -r 24 -i - -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -pix_fmt yuv420p out.mp4"
        );
        let files = Source::Files {
            pattern: "my frames/f_%04d.png",
            first: 1001,
        };
        assert_eq!(
            ffmpeg_command(files, false, (640, 360), "24000/1001", "it's.mp4"),
            "ffmpeg -framerate 24000/1001 -start_number 1001 -i 'my frames/f_%04d.png' -c:v libx264 -pix_fmt yuv420p 'it'\\''s.mp4'"
        );
        // Control characters and bidirectional overrides as escapes, in bash's $'…'.
        assert_eq!(
            shell_quote("a\nb\tc's\\\u{1}\u{202e}é"),
            r"$'a\nb\tc\'s\\\x01\u202eé'"
        );
        // RGBA files keep their alpha in ProRes 4444, at any size.
        assert_eq!(
            ffmpeg_command(files, true, (641, 361), "24", "a.mp4"),
            "ffmpeg -framerate 24 -start_number 1001 -i 'my frames/f_%04d.png' -c:v prores_ks -profile:v 4444 -pix_fmt yuva444p10le a.mov"
        );
    }
}
