//! Atomic frame files: bytes go to a temporary name in the same directory, are flushed to disk,
//! and only then renamed to the final name, so a file with a final name is always complete.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Marker in our temporary names; only files carrying it are ever cleaned up as ours.
pub const TEMP_MARKER: &str = ".rayreel-tmp-";

/// `dir/.name.rayreel-tmp-PID` for `dir/name`.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}{TEMP_MARKER}{}", std::process::id()))
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
