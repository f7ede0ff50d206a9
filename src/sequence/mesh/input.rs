//! A mesh file as a stream: lines (OBJ, PLY headers and ASCII bodies) or fixed-size values
//! (binary PLY), the FNV-1a digest of every byte taken on the way (on a thread of its own for
//! a large file: `Digest`), and the line buffer grown
//! only as the memory budget admits. A NUL byte ends a text line's read at once, so a file of
//! zeros (a sparse file) is refused after its first block, not after being read whole.

use super::{Fail, fnv1a_on};
use crate::budget;
use std::io::BufRead;
use std::sync::mpsc::SyncSender;
use std::thread::JoinHandle;

pub(crate) struct Input<R> {
    inner: R,
    digest: Digest,
    /// Bytes taken so far.
    taken: u64,
    /// The file's size as its metadata says (for checks of what a header declares).
    size: u64,
    /// Lines taken so far: the number of the line in `line`.
    pub(crate) line_number: usize,
    line: Vec<u8>,
}

/// FNV-1a's offset basis: the digest of no bytes.
const FNV_START: u64 = 0xcbf2_9ce4_8422_2325;

impl<R: BufRead> Input<R> {
    pub(crate) fn new(inner: R, size: u64) -> Input<R> {
        Input {
            inner,
            digest: Digest::new(size),
            taken: 0,
            size,
            line_number: 0,
            line: Vec::new(),
        }
    }

    /// Bytes left after what was taken, by the file's size (0 once past it).
    pub(crate) fn left(&self) -> u64 {
        self.size.saturating_sub(self.taken)
    }

    /// The next line without its `\n` (or `\r\n`), or `None` at the end of the file. `what`
    /// names the line in a refusal (`line 12`, `header line 3`).
    pub(crate) fn line(&mut self) -> Result<Option<&[u8]>, Fail> {
        self.line.clear();
        let mut any = false;
        loop {
            let chunk = self.inner.fill_buf().map_err(read_error)?;
            if chunk.is_empty() {
                break;
            }
            any = true;
            let (take, ends) = match chunk.iter().position(|&b| b == b'\n') {
                Some(i) => (i + 1, true),
                None => (chunk.len(), false),
            };
            let part = &chunk[..take];
            if part.contains(&0) {
                return Err(Fail::at(
                    format!("line {}", self.line_number + 1),
                    "a NUL byte: this is not a text file",
                ));
            }
            let number = self.line_number + 1;
            budget::grow(&mut self.line, take, || {
                format!("line {number} of the file")
            })?;
            self.line.extend_from_slice(part);
            self.digest.feed(part);
            self.taken += take as u64;
            self.inner.consume(take);
            if ends {
                break;
            }
        }
        if !any {
            return Ok(None);
        }
        self.line_number += 1;
        if self.line.last() == Some(&b'\n') {
            self.line.pop();
        }
        if self.line.last() == Some(&b'\r') {
            self.line.pop();
        }
        Ok(Some(&self.line))
    }

    /// The next `N` bytes, or `None` when the file ends first.
    pub(crate) fn bytes<const N: usize>(&mut self) -> Result<Option<[u8; N]>, Fail> {
        let mut out = [0u8; N];
        let mut have = 0;
        while have < N {
            let chunk = self.inner.fill_buf().map_err(read_error)?;
            if chunk.is_empty() {
                return Ok(None);
            }
            let take = chunk.len().min(N - have);
            out[have..have + take].copy_from_slice(&chunk[..take]);
            self.inner.consume(take);
            have += take;
        }
        self.digest.feed(&out);
        self.taken += N as u64;
        Ok(Some(out))
    }

    /// The bytes read ahead and not yet taken (empty at the end of the file): a binary reader
    /// decodes whole rows where they lie, then takes them with `consume`.
    pub(crate) fn buffered(&mut self) -> Result<&[u8], Fail> {
        self.inner.fill_buf().map_err(read_error)
    }

    /// Takes the first `n` bytes of `buffered` (which must hold them).
    pub(crate) fn consume(&mut self, n: usize) -> Result<(), Fail> {
        let chunk = self.inner.fill_buf().map_err(read_error)?;
        self.digest.feed(&chunk[..n]);
        self.taken += n as u64;
        self.inner.consume(n);
        Ok(())
    }

    /// The first bytes still to be read (as many as the buffer holds, at most `n`).
    pub(crate) fn peek(&mut self, n: usize) -> Result<Vec<u8>, Fail> {
        let chunk = self.inner.fill_buf().map_err(read_error)?;
        Ok(chunk[..chunk.len().min(n)].to_vec())
    }

    /// Everything still to be read, as the budget admits it.
    pub(crate) fn rest(&mut self) -> Result<Vec<u8>, Fail> {
        let mut out = Vec::new();
        loop {
            let chunk = self.inner.fill_buf().map_err(read_error)?;
            if chunk.is_empty() {
                return Ok(out);
            }
            let n = chunk.len();
            budget::grow(&mut out, n, || "the file's text".into())?;
            out.extend_from_slice(chunk);
            self.digest.feed(chunk);
            self.taken += n as u64;
            self.inner.consume(n);
        }
    }

    /// The rest of the file read (it counts in the digest), then the digest and the size.
    pub(crate) fn finish(&mut self) -> Result<(u64, u64), Fail> {
        loop {
            let chunk = self.inner.fill_buf().map_err(read_error)?;
            if chunk.is_empty() {
                break;
            }
            let n = chunk.len();
            self.digest.feed(chunk);
            self.taken += n as u64;
            self.inner.consume(n);
        }
        if self.taken > super::MAX_MESH_BYTES {
            return Err(Fail::whole(format!(
                "the file grew past {} GiB while it was read; meshes are limited to that",
                super::MAX_MESH_BYTES >> 30
            )));
        }
        let digest = std::mem::replace(&mut self.digest, Digest::Here(FNV_START));
        Ok((digest.value()?, self.taken))
    }
}

/// The FNV-1a digest of the bytes taken so far. FNV-1a is serial (a multiplication a byte,
/// about 1.5 ns): for a file of `BESIDE_FROM` bytes or more it is taken on a thread of its own,
/// fed batches of the bytes as they are taken, beside the parsing (65 ms of a 2M-triangle
/// terrain's load were the digest alone); a smaller file is hashed in place. Either way the
/// bytes are hashed once each, in file order: the same digest.
enum Digest {
    Here(u64),
    Beside {
        pending: Vec<u8>,
        to: SyncSender<Vec<u8>>,
        hash: JoinHandle<u64>,
    },
}

/// Files from 1 MiB have their digest taken beside their parsing.
const BESIDE_FROM: u64 = 1 << 20;
/// Bytes handed to the digest's thread at a time (at most `QUEUED` batches wait: with the
/// one being hashed and the one filling, under 2 MiB, left to the budget's reserve).
const BATCH: usize = 1 << 18;
const QUEUED: usize = 4;

impl Digest {
    fn new(size: u64) -> Digest {
        if size < BESIDE_FROM {
            return Digest::Here(FNV_START);
        }
        let (to, batches) = std::sync::mpsc::sync_channel::<Vec<u8>>(QUEUED);
        let spawned = std::thread::Builder::new()
            .name("mesh digest".into())
            .spawn(move || batches.iter().fold(FNV_START, |h, b| fnv1a_on(h, &b)));
        match spawned {
            Ok(hash) => Digest::Beside {
                pending: Vec::with_capacity(BATCH),
                to,
                hash,
            },
            // No thread to be had: the digest is taken here.
            Err(_) => Digest::Here(FNV_START),
        }
    }

    fn feed(&mut self, bytes: &[u8]) {
        match self {
            Digest::Here(h) => *h = fnv1a_on(*h, bytes),
            Digest::Beside { pending, to, .. } => {
                pending.extend_from_slice(bytes);
                if pending.len() >= BATCH {
                    // A thread that is gone shows when its hash is asked for.
                    let _ = to.send(std::mem::replace(pending, Vec::with_capacity(BATCH)));
                }
            }
        }
    }

    /// The digest of every byte fed.
    fn value(self) -> Result<u64, Fail> {
        match self {
            Digest::Here(h) => Ok(h),
            Digest::Beside { pending, to, hash } => {
                let sent = to.send(pending);
                drop(to);
                match (sent, hash.join()) {
                    (Ok(()), Ok(h)) => Ok(h),
                    _ => Err(Fail::whole("the thread taking the file's digest failed")),
                }
            }
        }
    }
}

fn read_error(e: std::io::Error) -> Fail {
    Fail::whole(format!("cannot read: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_drop_their_ends_and_the_digest_covers_every_byte() {
        let text = b"v 1 2 3\r\nf 1 2 3\nlast";
        let mut input = Input::new(&text[..], text.len() as u64);
        assert_eq!(input.line().unwrap(), Some(&b"v 1 2 3"[..]));
        assert_eq!(input.line().unwrap(), Some(&b"f 1 2 3"[..]));
        assert_eq!(input.line().unwrap(), Some(&b"last"[..]));
        assert_eq!(input.line().unwrap(), None);
        assert_eq!(input.line_number, 3);
        assert_eq!(
            input.finish().unwrap(),
            (super::super::fnv1a(text), text.len() as u64)
        );
    }

    /// A file large enough to be hashed on a thread of its own, taken in every way a reader
    /// takes bytes, has the digest of its bytes.
    #[test]
    fn a_large_file_has_the_same_digest_beside_its_parsing() {
        let n = 3 * BESIDE_FROM as usize + 12_345;
        let bytes: Vec<u8> = (0..n).map(|i| (i * 7 + i / 251) as u8 | 1).collect();
        let mut input = Input::new(&bytes[..], n as u64);
        assert!(matches!(input.digest, Digest::Beside { .. }));
        input.bytes::<3>().unwrap();
        let first = input.buffered().unwrap().len().min(100_000);
        input.consume(first).unwrap();
        input.peek(10).unwrap();
        assert_eq!(
            input.finish().unwrap(),
            (super::super::fnv1a(&bytes), n as u64)
        );
    }

    #[test]
    fn a_nul_byte_is_refused_where_it_is() {
        let mut input = Input::new(&b"v 1 2 3\n\0\0\0"[..], 11);
        input.line().unwrap();
        let e = input.line().err().unwrap();
        assert_eq!(e.where_.as_deref(), Some("line 2"));
    }
}
