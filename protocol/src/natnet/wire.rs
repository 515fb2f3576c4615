//! Little-endian, unaligned NatNet primitives: a bounds-checked reader and append-only writers.

use super::error::{NatNetEncodeError, NatNetError};

/// A cursor over a datagram that never reads out of bounds. Offsets in errors are absolute
/// datagram offsets: the reader covers `buf[start..end]` of the whole datagram.
#[derive(Debug, Clone)]
pub(crate) struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// A reader over the whole datagram, starting at `pos`.
    pub(crate) fn at(buf: &'a [u8], pos: usize) -> Self {
        Reader { buf, pos }
    }

    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    pub(crate) fn remaining(&self) -> usize {
        self.buf.len().saturating_sub(self.pos)
    }

    pub(crate) fn take(&mut self, n: usize) -> Result<&'a [u8], NatNetError> {
        if n > self.remaining() {
            return Err(NatNetError::Truncated { offset: self.pos });
        }
        let out = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    pub(crate) fn skip(&mut self, n: usize) -> Result<(), NatNetError> {
        self.take(n).map(|_| ())
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], NatNetError> {
        let bytes = self.take(N)?;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        Ok(out)
    }

    pub(crate) fn u8(&mut self) -> Result<u8, NatNetError> {
        self.array::<1>().map(|b| b[0])
    }

    pub(crate) fn u16(&mut self) -> Result<u16, NatNetError> {
        self.array().map(u16::from_le_bytes)
    }

    pub(crate) fn u32(&mut self) -> Result<u32, NatNetError> {
        self.array().map(u32::from_le_bytes)
    }

    pub(crate) fn i32(&mut self) -> Result<i32, NatNetError> {
        self.array().map(i32::from_le_bytes)
    }

    pub(crate) fn u64(&mut self) -> Result<u64, NatNetError> {
        self.array().map(u64::from_le_bytes)
    }

    /// A raw `f64` (finiteness is the caller's business).
    pub(crate) fn f64(&mut self) -> Result<f64, NatNetError> {
        self.array().map(f64::from_le_bytes)
    }

    /// A float that may be NaN (NatNet's "no value") but not infinite.
    pub(crate) fn f32(&mut self) -> Result<f32, NatNetError> {
        let offset = self.pos;
        let v = self.array().map(f32::from_le_bytes)?;
        if v.is_infinite() {
            return Err(NatNetError::NonFinite { offset });
        }
        Ok(v)
    }

    pub(crate) fn vec3(&mut self) -> Result<[f32; 3], NatNetError> {
        Ok([self.f32()?, self.f32()?, self.f32()?])
    }

    pub(crate) fn quat(&mut self) -> Result<[f32; 4], NatNetError> {
        Ok([self.f32()?, self.f32()?, self.f32()?, self.f32()?])
    }

    /// A count (`i32` on the wire) whose items take at least `min_item` bytes each: negative
    /// counts and counts the remaining bytes cannot hold fail here, before anything is
    /// reserved, so a forged count of 2^31 costs nothing.
    pub(crate) fn count(&mut self, min_item: usize) -> Result<usize, NatNetError> {
        let offset = self.pos;
        let raw = self.i32()?;
        let n = usize::try_from(raw).map_err(|_| NatNetError::BadCount {
            count: i64::from(raw),
            offset,
        })?;
        if n.saturating_mul(min_item.max(1)) > self.remaining() {
            return Err(NatNetError::BadCount {
                count: i64::from(raw),
                offset,
            });
        }
        Ok(n)
    }

    /// A NUL-terminated UTF-8 string; the terminator is consumed.
    pub(crate) fn cstr(&mut self) -> Result<&'a str, NatNetError> {
        let start = self.pos;
        let rest = self.buf.get(start..).unwrap_or(&[]);
        let Some(nul) = rest.iter().position(|&b| b == 0) else {
            return Err(NatNetError::BadString { offset: start });
        };
        let s = std::str::from_utf8(&rest[..nul])
            .map_err(|_| NatNetError::BadString { offset: start })?;
        self.pos += nul + 1;
        Ok(s)
    }

    /// A fixed-size field holding a NUL-terminated string; bytes after the NUL are ignored
    /// (Motive leaves uninitialised memory there).
    pub(crate) fn fixed_str(&mut self, size: usize) -> Result<&'a str, NatNetError> {
        let start = self.pos;
        let field = self.take(size)?;
        let end = field.iter().position(|&b| b == 0).unwrap_or(field.len());
        std::str::from_utf8(&field[..end]).map_err(|_| NatNetError::BadString { offset: start })
    }

    /// Fails unless every byte was consumed.
    pub(crate) fn finish(&self) -> Result<(), NatNetError> {
        match self.remaining() {
            0 => Ok(()),
            extra => Err(NatNetError::TrailingBytes {
                offset: self.pos,
                extra,
            }),
        }
    }
}

pub(crate) fn put_u16(out: &mut Vec<u8>, v: u16) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_i32(out: &mut Vec<u8>, v: i32) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_f32(out: &mut Vec<u8>, v: f32) {
    out.extend_from_slice(&v.to_le_bytes());
}

pub(crate) fn put_f32s(out: &mut Vec<u8>, v: &[f32]) {
    for &x in v {
        put_f32(out, x);
    }
}

pub(crate) fn put_count(out: &mut Vec<u8>, n: usize) -> Result<(), NatNetEncodeError> {
    let v = i32::try_from(n).map_err(|_| NatNetEncodeError::CountOverflow { count: n })?;
    put_i32(out, v);
    Ok(())
}

/// A NUL-terminated string.
pub(crate) fn put_cstr(out: &mut Vec<u8>, s: &str) -> Result<(), NatNetEncodeError> {
    if s.as_bytes().contains(&0) {
        return Err(NatNetEncodeError::NulInString);
    }
    out.extend_from_slice(s.as_bytes());
    out.push(0);
    Ok(())
}

/// A string in a zero-padded field of `size` bytes (terminator included).
pub(crate) fn put_fixed_str(
    out: &mut Vec<u8>,
    s: &str,
    size: usize,
) -> Result<(), NatNetEncodeError> {
    if s.as_bytes().contains(&0) {
        return Err(NatNetEncodeError::NulInString);
    }
    if s.len() >= size {
        return Err(NatNetEncodeError::StringTooLong {
            len: s.len(),
            max: size,
        });
    }
    out.extend_from_slice(s.as_bytes());
    out.resize(out.len() + size - s.len(), 0);
    Ok(())
}

/// Reserves a 4-byte size field; [`end_size`] fills it with the bytes written since.
pub(crate) fn begin_size(out: &mut Vec<u8>) -> usize {
    out.extend_from_slice(&[0; 4]);
    out.len()
}

pub(crate) fn end_size(out: &mut [u8], start: usize) -> Result<(), NatNetEncodeError> {
    let n = out.len() - start;
    let v = i32::try_from(n).map_err(|_| NatNetEncodeError::CountOverflow { count: n })?;
    out[start - 4..start].copy_from_slice(&v.to_le_bytes());
    Ok(())
}

#[cfg(test)]
mod tests;
