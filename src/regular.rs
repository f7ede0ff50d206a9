//! Reading files someone else may have put in place (frames and claims in a shared output
//! directory, mesh files): nothing that stands at a name can make a read block or run without
//! end. The name is looked at first, so a device or FIFO is never even opened; the open
//! itself never blocks (O_NONBLOCK: a FIFO put there in between opens at once) and, where
//! asked, never follows a link (O_NOFOLLOW); the opened descriptor is checked again (fstat)
//! to be a regular file, and reads stop at a bound the caller sizes from what the file can be.

use std::fs::{File, FileType, Metadata, OpenOptions};
use std::io::{self, Read};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// Why a name could not be opened as a regular file.
#[derive(Debug)]
pub(crate) enum Refused {
    /// Nothing is there.
    Missing,
    /// Something that is not a regular file: what it is (`a FIFO`, `a symbolic link`).
    NotRegular(&'static str),
    /// It could not be looked at or opened.
    Io(io::Error),
}

/// Whether a symbolic link at the name is followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Links {
    Follow,
    /// A link at the name is refused as `a symbolic link` (O_NOFOLLOW).
    Refuse,
}

/// Opens the regular file at `path` for reading, without blocking, with its metadata as the
/// opened descriptor has it.
pub(crate) fn open(path: &Path, links: Links) -> Result<(File, Metadata), Refused> {
    let looked = match links {
        Links::Follow => std::fs::metadata(path),
        Links::Refuse => std::fs::symlink_metadata(path),
    };
    match looked {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Err(Refused::Missing),
        Err(e) => return Err(Refused::Io(e)),
        Ok(m) if !m.is_file() => return Err(Refused::NotRegular(kind(&m.file_type()))),
        Ok(_) => {}
    }
    let flags = libc::O_NONBLOCK
        | libc::O_CLOEXEC
        | match links {
            Links::Follow => 0,
            Links::Refuse => libc::O_NOFOLLOW,
        };
    let file = match OpenOptions::new().read(true).custom_flags(flags).open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Err(Refused::Missing),
        Err(e) if e.raw_os_error() == Some(libc::ELOOP) && links == Links::Refuse => {
            return Err(Refused::NotRegular("a symbolic link"));
        }
        Err(e) => return Err(Refused::Io(e)),
    };
    let meta = file.metadata().map_err(Refused::Io)?;
    if !meta.is_file() {
        return Err(Refused::NotRegular(kind(&meta.file_type())));
    }
    Ok((file, meta))
}

/// What a file that is not a regular one is, for messages.
pub(crate) fn kind(t: &FileType) -> &'static str {
    if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else {
        "not a regular file"
    }
}

/// At most `limit` bytes from the start of `file` (a file growing meanwhile is cut there).
pub(crate) fn read_at_most(file: &File, size_hint: u64, limit: u64) -> io::Result<Vec<u8>> {
    let mut bytes = Vec::with_capacity(size_hint.min(limit) as usize);
    file.take(limit).read_to_end(&mut bytes)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_open_and_reads_stop_at_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let (file, fifo, link) = (
            dir.path().join("f"),
            dir.path().join("p"),
            dir.path().join("l"),
        );
        std::fs::write(&file, b"0123456789").unwrap();
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let (f, meta) = open(&file, Links::Refuse).unwrap();
        assert_eq!(read_at_most(&f, meta.len(), 4).unwrap(), b"0123");
        for links in [Links::Follow, Links::Refuse] {
            assert!(matches!(
                open(&fifo, links),
                Err(Refused::NotRegular("a FIFO"))
            ));
            assert!(matches!(
                open(dir.path(), links),
                Err(Refused::NotRegular("a directory"))
            ));
            assert!(matches!(
                open(&dir.path().join("none"), links),
                Err(Refused::Missing)
            ));
        }
        assert!(matches!(
            open(&link, Links::Follow),
            Err(Refused::NotRegular("a character device"))
        ));
        assert!(matches!(
            open(&link, Links::Refuse),
            Err(Refused::NotRegular("a symbolic link"))
        ));
    }
}
