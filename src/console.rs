//! Text for people: stdout where a reader that has gone is a normal end, stderr where a
//! failing write is a lost line and never a reason to stop, and strings from files and
//! command lines made safe to show on a terminal.

use std::borrow::Cow;
use std::io::{ErrorKind, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by `--progress json`: every line on stderr is then one JSON object.
static JSON: AtomicBool = AtomicBool::new(false);

pub(crate) fn set_json(on: bool) {
    JSON.store(on, Ordering::Relaxed);
}

/// The line `main` prints for an error that ends the run: `rayreel: MESSAGE`, or with
/// `--progress json` `{"event": "error", "text": "MESSAGE", "exit_code": N}`.
pub fn error_line(message: &str, exit_code: u8) -> String {
    match JSON.load(Ordering::Relaxed) {
        true => format!(
            "{{\"event\": \"error\", \"text\": {}, \"exit_code\": {exit_code}}}",
            quote(message)
        ),
        false => format!("rayreel: {}", printable(message)),
    }
}

/// A line on stderr that is not about one frame: as it is, or as a JSON `note` event.
pub(crate) fn note(text: &str) {
    line("note", text);
}

/// A warning on stderr: as it is, or as a JSON `warning` event.
pub(crate) fn warning(text: &str) {
    line("warning", text);
}

fn line(event: &str, text: &str) {
    match JSON.load(Ordering::Relaxed) {
        true => eprintln!("{{\"event\": \"{event}\", \"text\": {}}}", quote(text)),
        false => eprintln!("{}", printable(text)),
    }
}

/// One line on stderr (what `eprintln!` does in this crate). A stderr that cannot be written
/// (full, closed, a terminal gone) loses the line and nothing else: rendering goes on.
pub fn stderr_line(args: std::fmt::Arguments) {
    let mut line = args.to_string();
    line.push('\n');
    stderr_write(&line);
}

/// `text` on stderr, as it is, in one write; a failure is ignored (see `stderr_line`).
pub fn stderr_write(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// Writes `text` to stdout. A reader that has gone (`rayreel status FILE | head -1`) ends the
/// output normally, as in ripgrep; any other failure is an error.
pub(crate) fn print(text: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != ErrorKind::BrokenPipe => Err(format!("stdout: cannot write: {e}")),
        _ => Ok(()),
    }
}

/// `s` with control characters, and the bidirectional overrides that reorder what a terminal
/// shows, written as escapes (`\u{1b}`, `\n`): a name from a sequence file cannot move the
/// cursor, recolour the terminal or forge a line of output.
pub(crate) fn printable(s: &str) -> Cow<'_, str> {
    if !s.chars().any(hostile) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match hostile(c) {
            true => out.extend(c.escape_debug()),
            false => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// `printable` line by line: the line breaks stay.
pub fn printable_lines(s: &str) -> String {
    let lines: Vec<Cow<str>> = s.split('\n').map(printable).collect();
    lines.join("\n")
}

fn hostile(c: char) -> bool {
    c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// A JSON string literal.
pub(crate) fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A number as messages show it: its shortest decimal that reads back as the same f64, so a
/// value just past a limit never shows as the limit (`360.0001`, not `360`); plain from 1e-5
/// up to 1e16, in exponent form beyond (`1e-300`, `1.7976931348623157e308`), so at most 17
/// significant digits and never hundreds of characters.
pub(crate) fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-5..1e16).contains(&v.abs()) {
        return format!("{v}");
    }
    format!("{v:e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("frames/a.png"), "frames/a.png");
        assert_eq!(printable("é\u{1b}[2J\n\u{202e}"), "é\\u{1b}[2J\\n\\u{202e}");
    }
}
