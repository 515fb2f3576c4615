//! Borrowed OSC 1.0 primitives: a bounds-checked reader and append-only writers.
//!
//! Everything is big-endian and 4-byte aligned. Offsets in errors are relative to the slice
//! the [`Reader`] was built on, which is always a whole message or datagram.

use crate::error::{DecodeError, EncodeError};

/// Rounds `n` up to the next multiple of 4.
pub(crate) const fn pad4(n: usize) -> usize {
    (n + 3) & !3
}

/// A cursor over one message or datagram that never reads out of bounds.
#[derive(Debug, Clone)]
pub(crate) struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(buf: &'a [u8]) -> Self {
        Reader { buf, pos: 0 }
    }

    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    pub(crate) fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Takes `n` raw bytes.
    pub(crate) fn take(&mut self, n: usize) -> Result<&'a [u8], DecodeError> {
        if n > self.remaining() {
            return Err(DecodeError::Truncated { offset: self.pos });
        }
        let out = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], DecodeError> {
        let bytes = self.take(N)?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    pub(crate) fn u32(&mut self) -> Result<u32, DecodeError> {
        self.array().map(u32::from_be_bytes)
    }

    pub(crate) fn i32(&mut self) -> Result<i32, DecodeError> {
        self.array().map(i32::from_be_bytes)
    }

    pub(crate) fn i64(&mut self) -> Result<i64, DecodeError> {
        self.array().map(i64::from_be_bytes)
    }

    pub(crate) fn f32(&mut self) -> Result<f32, DecodeError> {
        self.array().map(f32::from_be_bytes)
    }

    /// An OSC string: bytes up to the first NUL, then padding to 4 bytes. Padding content is
    /// not checked (rosc and liblo do not either), only its presence.
    pub(crate) fn str_bytes(&mut self) -> Result<&'a [u8], DecodeError> {
        let start = self.pos;
        let rest = &self.buf[start..];
        let Some(nul) = rest.iter().position(|&b| b == 0) else {
            return Err(DecodeError::Truncated { offset: start });
        };
        let padded = pad4(nul + 1);
        if padded > rest.len() {
            return Err(DecodeError::Truncated { offset: start });
        }
        self.pos += padded;
        Ok(&rest[..nul])
    }

    /// An OSC blob: u32 size, the bytes, padding to 4 bytes.
    pub(crate) fn blob(&mut self) -> Result<&'a [u8], DecodeError> {
        let start = self.pos;
        let size = self.u32()? as usize;
        if pad4(size) > self.remaining() || size > self.remaining() {
            return Err(DecodeError::Truncated { offset: start });
        }
        let data = &self.buf[self.pos..self.pos + size];
        self.pos += pad4(size);
        Ok(data)
    }
}

/// Appends an OSC string with its NUL and padding.
pub(crate) fn put_str(out: &mut Vec<u8>, s: &str) -> Result<(), EncodeError> {
    if s.as_bytes().contains(&0) {
        return Err(EncodeError::NulInString);
    }
    put_str_unchecked(out, s);
    Ok(())
}

/// Appends an OSC string known to hold no NUL (crate constants).
pub(crate) fn put_str_unchecked(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(s.as_bytes());
    let padded = pad4(s.len() + 1);
    out.resize(out.len() + padded - s.len(), 0);
}

pub(crate) fn put_i32(out: &mut Vec<u8>, v: i32) {
    out.extend_from_slice(&v.to_be_bytes());
}

pub(crate) fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_be_bytes());
}

pub(crate) fn put_i64(out: &mut Vec<u8>, v: i64) {
    out.extend_from_slice(&v.to_be_bytes());
}

pub(crate) fn put_f32(out: &mut Vec<u8>, v: f32) {
    out.extend_from_slice(&v.to_be_bytes());
}

/// Appends a blob header for `len` bytes; the caller appends the bytes, then [`pad_to4`].
/// Writes a message's address and its type tag string `,` + `fixed` + `count` × `repeated`,
/// NUL-terminated and padded to 4 bytes from `start` (the message's first byte): the prologue
/// of every message whose argument list is a fixed head and a run of one type.
pub(crate) fn put_prologue(
    out: &mut Vec<u8>,
    start: usize,
    address: &str,
    fixed: &[u8],
    repeated: u8,
    count: usize,
) {
    put_str_unchecked(out, address);
    out.push(b',');
    out.extend_from_slice(fixed);
    out.resize(out.len() + count, repeated);
    out.push(0);
    pad_to4(out, start);
}

pub(crate) fn put_blob_len(out: &mut Vec<u8>, len: usize) {
    put_u32(
        out,
        u32::try_from(len).expect("blob lengths are bounded by the datagram limit"),
    );
}

/// Pads `out` with NULs to a multiple of 4 bytes (its length is the packet offset).
pub(crate) fn pad_to4(out: &mut Vec<u8>, start: usize) {
    let len = out.len() - start;
    out.resize(start + pad4(len), 0);
}

/// Starts a bundle element: writes a placeholder size and returns where it is.
pub(crate) fn begin_element(out: &mut Vec<u8>) -> usize {
    let at = out.len();
    put_u32(out, 0);
    at
}

/// Ends a bundle element started with [`begin_element`] by filling in its size.
pub(crate) fn end_element(out: &mut [u8], at: usize) {
    let size = out.len() - at - 4;
    let size = u32::try_from(size).expect("element sizes are bounded by the datagram limit");
    out[at..at + 4].copy_from_slice(&size.to_be_bytes());
}

/// Bundle header with the "immediately" time tag (1).
pub(crate) fn put_bundle_header(out: &mut Vec<u8>) {
    out.extend_from_slice(b"#bundle\0");
    put_u32(out, 0);
    put_u32(out, 1);
}

#[cfg(test)]
mod tests;
