//! The pre-scan: every datagram is checked here before any decoder, rosc included, sees it.
//!
//! rosc decodes nested bundles by recursion and aborts the process on a stack overflow when a
//! datagram nests a few thousand `#bundle` headers; it also builds nested `Vec`s for `[` arrays
//! in type tags. [`messages`] walks the whole datagram once without allocating, bounds bundle and
//! array nesting, checks every element size and every argument against the type tags, and only
//! then hands out the messages. Whatever passes is well-formed OSC 1.0 that rosc decodes.

use crate::error::DecodeError;
use crate::wire::Reader;

/// Largest UDP payload over IPv4: 65,535 - 8 (UDP header) - 20 (IP header).
pub const MAX_UDP_PAYLOAD: usize = 65_507;
/// Default limit on bundle nesting (a plain message is depth 0, a bundle of messages depth 1).
pub const DEFAULT_MAX_BUNDLE_DEPTH: usize = 8;
/// Hard cap on [`Limits::max_bundle_depth`]; larger settings are clamped to it.
pub const BUNDLE_DEPTH_CAP: usize = 16;
/// Limit on `[` array nesting inside one message's type tags.
pub const MAX_ARRAY_DEPTH: usize = 8;

/// Size and nesting limits applied to every datagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Datagrams longer than this are rejected with [`DecodeError::Oversize`].
    pub max_datagram: usize,
    /// Deepest bundle nesting accepted (clamped to [`BUNDLE_DEPTH_CAP`]).
    pub max_bundle_depth: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_datagram: MAX_UDP_PAYLOAD,
            max_bundle_depth: DEFAULT_MAX_BUNDLE_DEPTH,
        }
    }
}

impl Limits {
    fn depth(&self) -> usize {
        self.max_bundle_depth.min(BUNDLE_DEPTH_CAP)
    }
}

/// An OSC time tag (NTP format: seconds since 1900 and a 2^-32 fraction).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TimeTag {
    /// Seconds since 1900-01-01.
    pub seconds: u32,
    /// Fractional seconds in units of 2^-32 s.
    pub fraction: u32,
}

impl TimeTag {
    /// The special value 1: "immediately".
    pub const IMMEDIATE: TimeTag = TimeTag {
        seconds: 0,
        fraction: 1,
    };
}

/// One OSC message of a datagram, already structurally validated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Message<'a> {
    /// The address pattern, e.g. `/mocap/frame`.
    pub address: &'a str,
    /// The whole encoded message (address, type tags, arguments), 4-byte aligned.
    pub bytes: &'a [u8],
    /// Time tag of the innermost enclosing bundle, `None` for a bare message.
    pub timetag: Option<TimeTag>,
}

/// Checks a datagram and returns an iterator over its messages, bundles flattened in order.
///
/// # Errors
/// Any structural problem anywhere in the datagram rejects the whole datagram: oversize,
/// truncation, trailing bytes, bad element sizes, bundles deeper than the limit, bad addresses,
/// missing or unknown type tags, non-UTF-8 strings, arrays nested deeper than
/// [`MAX_ARRAY_DEPTH`].
pub fn messages<'a>(datagram: &'a [u8], limits: &Limits) -> Result<Messages<'a>, DecodeError> {
    check_datagram(datagram, limits)?;
    Ok(Messages {
        top: Some(datagram),
        stack: [(&[], TimeTag::IMMEDIATE); BUNDLE_DEPTH_CAP],
        depth: 0,
    })
}

/// Validates a datagram without handing out its messages. See [`messages`].
///
/// # Errors
/// As [`messages`].
pub fn check_datagram(datagram: &[u8], limits: &Limits) -> Result<(), DecodeError> {
    if datagram.is_empty() {
        return Err(DecodeError::Empty);
    }
    if datagram.len() > limits.max_datagram {
        return Err(DecodeError::Oversize {
            len: datagram.len(),
            max: limits.max_datagram,
        });
    }
    check_packet(datagram, 0, 0, limits.depth())
}

fn is_bundle(packet: &[u8]) -> bool {
    packet.starts_with(b"#bundle\0")
}

/// `base` is the packet's offset in the datagram (for error offsets); `depth` the number of
/// bundles around it. Recursion is bounded by `max_depth` <= [`BUNDLE_DEPTH_CAP`].
fn check_packet(
    packet: &[u8],
    base: usize,
    depth: usize,
    max_depth: usize,
) -> Result<(), DecodeError> {
    if !is_bundle(packet) {
        return check_message(packet).map_err(|e| shift(e, base));
    }
    if depth + 1 > max_depth {
        return Err(DecodeError::BundleTooDeep { max: max_depth });
    }
    let mut r = Reader::new(packet);
    r.take(16).map_err(|e| shift(e, base))?;
    while r.remaining() > 0 {
        let at = r.pos();
        let size = r.u32().map_err(|e| shift(e, base))?;
        let len = size as usize;
        if len == 0 || len % 4 != 0 || len > r.remaining() {
            return Err(DecodeError::BadElementSize {
                size,
                offset: base + at,
            });
        }
        let start = r.pos();
        let element = r.take(len).map_err(|e| shift(e, base))?;
        check_packet(element, base + start, depth + 1, max_depth)?;
    }
    Ok(())
}

/// Moves an error's offset from element-relative to datagram-relative.
fn shift(e: DecodeError, base: usize) -> DecodeError {
    use DecodeError as E;
    match e {
        E::Truncated { offset } => E::Truncated {
            offset: offset + base,
        },
        E::TrailingBytes { offset, extra } => E::TrailingBytes {
            offset: offset + base,
            extra,
        },
        E::BadAddress { offset } => E::BadAddress {
            offset: offset + base,
        },
        E::MissingTypeTags { offset } => E::MissingTypeTags {
            offset: offset + base,
        },
        E::BadTypeTag { tag, offset } => E::BadTypeTag {
            tag,
            offset: offset + base,
        },
        E::BadString { offset } => E::BadString {
            offset: offset + base,
        },
        other => other,
    }
}

/// Reads the address and type tags of a message: `(address, tags without the comma, reader at
/// the first argument)`.
pub(crate) fn read_head(msg: &[u8]) -> Result<(&str, &[u8], Reader<'_>), DecodeError> {
    let mut r = Reader::new(msg);
    let addr = r.str_bytes()?;
    let address = match std::str::from_utf8(addr) {
        Ok(a) if a.starts_with('/') => a,
        _ => return Err(DecodeError::BadAddress { offset: 0 }),
    };
    let at = r.pos();
    if r.remaining() == 0 {
        return Err(DecodeError::MissingTypeTags { offset: at });
    }
    let tags = r.str_bytes()?;
    match tags.split_first() {
        Some((b',', rest)) => Ok((address, rest, r)),
        _ => Err(DecodeError::MissingTypeTags { offset: at }),
    }
}

/// Checks one message: every argument present for its tag, nothing left over.
fn check_message(msg: &[u8]) -> Result<(), DecodeError> {
    let (_, tags, mut r) = read_head(msg)?;
    // offset of the first tag byte: after the address and the comma
    let tags_at = r.pos() - crate::wire::pad4(tags.len() + 2);
    let mut arrays = 0usize;
    for (i, &tag) in tags.iter().enumerate() {
        let bad = DecodeError::BadTypeTag {
            tag,
            offset: tags_at + 1 + i,
        };
        match tag {
            b'i' | b'f' | b'r' | b'm' => drop(r.take(4)?),
            b'h' | b'd' | b't' => drop(r.take(8)?),
            b'c' => {
                let at = r.pos();
                if char::from_u32(r.u32()?).is_none() {
                    return Err(DecodeError::BadString { offset: at });
                }
            }
            b's' => {
                let at = r.pos();
                if std::str::from_utf8(r.str_bytes()?).is_err() {
                    return Err(DecodeError::BadString { offset: at });
                }
            }
            b'b' => drop(r.blob()?),
            b'T' | b'F' | b'N' | b'I' => {}
            b'[' => {
                arrays += 1;
                if arrays > MAX_ARRAY_DEPTH {
                    return Err(DecodeError::ArrayTooDeep {
                        max: MAX_ARRAY_DEPTH,
                    });
                }
            }
            b']' => arrays = arrays.checked_sub(1).ok_or(bad)?,
            _ => return Err(bad),
        }
    }
    if arrays != 0 {
        return Err(DecodeError::BadTypeTag {
            tag: b'[',
            offset: tags_at,
        });
    }
    if r.remaining() != 0 {
        return Err(DecodeError::TrailingBytes {
            offset: r.pos(),
            extra: r.remaining(),
        });
    }
    Ok(())
}

/// Iterator over the messages of a checked datagram; see [`messages`]. Never allocates.
#[derive(Debug, Clone)]
pub struct Messages<'a> {
    top: Option<&'a [u8]>,
    /// Unread elements and time tag of each open bundle, outermost first.
    stack: [(&'a [u8], TimeTag); BUNDLE_DEPTH_CAP],
    depth: usize,
}

impl<'a> Messages<'a> {
    /// Opens a bundle (known valid) or returns the message it is.
    fn enter(&mut self, packet: &'a [u8], timetag: Option<TimeTag>) -> Option<Message<'a>> {
        if is_bundle(packet) {
            let tt = packet.get(8..16)?;
            let timetag = TimeTag {
                seconds: u32::from_be_bytes(tt[..4].try_into().ok()?),
                fraction: u32::from_be_bytes(tt[4..].try_into().ok()?),
            };
            // the pre-scan bounded the depth, so this slot exists
            *self.stack.get_mut(self.depth)? = (packet.get(16..)?, timetag);
            self.depth += 1;
            return None;
        }
        let (address, _, _) = read_head(packet).ok()?;
        Some(Message {
            address,
            bytes: packet,
            timetag,
        })
    }
}

impl<'a> Iterator for Messages<'a> {
    type Item = Message<'a>;

    fn next(&mut self) -> Option<Message<'a>> {
        if let Some(top) = self.top.take() {
            if let Some(m) = self.enter(top, None) {
                return Some(m);
            }
        }
        while self.depth > 0 {
            let (rest, timetag) = self.stack[self.depth - 1];
            if rest.len() < 4 {
                self.depth -= 1;
                continue;
            }
            let size = u32::from_be_bytes(rest[..4].try_into().ok()?) as usize;
            let element = rest.get(4..4 + size)?;
            self.stack[self.depth - 1].0 = &rest[4 + size..];
            if let Some(m) = self.enter(element, Some(timetag)) {
                return Some(m);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests;
