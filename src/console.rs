//! Text for people: stdout where a reader that has gone is a normal end, and strings from
//! files and command lines made safe to show on a terminal.

use std::io::{ErrorKind, Write};

/// Writes `text` to stdout. A reader that has gone (`rayreel status FILE | head -1`) ends the
/// output normally, as in ripgrep; any other failure is an error.
pub fn print(text: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != ErrorKind::BrokenPipe => Err(format!("stdout: cannot write: {e}")),
        _ => Ok(()),
    }
}
