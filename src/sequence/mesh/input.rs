//! A mesh file as a stream: lines (OBJ, PLY headers and ASCII bodies) or fixed-size values
//! (binary PLY), the FNV-1a digest of every byte taken on the way, and the line buffer grown
//! only as the memory budget admits. A NUL byte ends a text line's read at once, so a file of
//! zeros (a sparse file) is refused after its first block, not after being read whole.

use super::{Fail, fnv1a_on};
use crate::budget;
use std::io::BufRead;

pub(crate) struct Input<R> {
    inner: R,
    hash: u64,
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
            hash: FNV_START,
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
            self.hash = fnv1a_on(self.hash, part);
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
        self.hash = fnv1a_on(self.hash, &out);
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
        self.hash = fnv1a_on(self.hash, &chunk[..n]);
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
            self.hash = fnv1a_on(self.hash, chunk);
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
            self.hash = fnv1a_on(self.hash, chunk);
            self.taken += n as u64;
            self.inner.consume(n);
        }
        if self.taken > super::MAX_MESH_BYTES {
            return Err(Fail::whole(format!(
                "the file grew past {} GiB while it was read; meshes are limited to that",
                super::MAX_MESH_BYTES >> 30
            )));
        }
        Ok((self.hash, self.taken))
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

    #[test]
    fn a_nul_byte_is_refused_where_it_is() {
        let mut input = Input::new(&b"v 1 2 3\n\0\0\0"[..], 11);
        input.line().unwrap();
        let e = input.line().err().unwrap();
        assert_eq!(e.where_.as_deref(), Some("line 2"));
    }
}
