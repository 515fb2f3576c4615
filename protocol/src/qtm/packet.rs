//! QTM RT packets: the 8-byte header (size including the header, then type, both `u32`
//! little-endian on QTM's little-endian port), text, XML, event and error packets, and a
//! [`Framer`] that cuts a TCP byte stream into whole packets with a size limit.

use super::error::QtmError;
use super::event::Event;

/// The header's size: `u32` size (the whole packet), `u32` type.
pub const HEADER_BYTES: usize = 8;

/// A packet's type, as QTM numbers them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PacketType {
    /// An error answer, NUL-terminated text.
    Error,
    /// A command (client to server) or its answer, NUL-terminated text.
    Command,
    /// Parameters as XML, NUL-terminated.
    Xml,
    /// A data frame (timestamp, frame number, components).
    Data,
    /// No frame to give (no measurement running).
    NoMoreData,
    /// A C3D file.
    C3dFile,
    /// One event byte.
    Event,
    /// A discovery request or answer (UDP).
    Discover,
    /// A QTM file.
    QtmFile,
}

impl PacketType {
    /// The type from its number.
    ///
    /// # Errors
    /// [`QtmError::UnknownType`] above 8.
    pub fn from_u32(kind: u32) -> Result<PacketType, QtmError> {
        Ok(match kind {
            0 => PacketType::Error,
            1 => PacketType::Command,
            2 => PacketType::Xml,
            3 => PacketType::Data,
            4 => PacketType::NoMoreData,
            5 => PacketType::C3dFile,
            6 => PacketType::Event,
            7 => PacketType::Discover,
            8 => PacketType::QtmFile,
            _ => return Err(QtmError::UnknownType { kind }),
        })
    }

    /// The type's number.
    pub fn as_u32(self) -> u32 {
        self as u32
    }
}

/// One whole packet, borrowed: its type and the payload after the header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Packet<'a> {
    /// The type.
    pub kind: PacketType,
    /// The bytes after the header.
    pub payload: &'a [u8],
}

impl<'a> Packet<'a> {
    /// The payload of a text packet (command, error, XML) without its final NUL.
    ///
    /// # Errors
    /// [`QtmError::BadText`] when it is not UTF-8 (a missing NUL is tolerated).
    pub fn text(&self) -> Result<&'a str, QtmError> {
        let bytes = self.payload.strip_suffix(&[0]).unwrap_or(self.payload);
        std::str::from_utf8(bytes).map_err(|_| QtmError::BadText)
    }

    /// The event of an event packet.
    ///
    /// # Errors
    /// [`QtmError::BadEvent`] for an empty payload or an unknown event.
    pub fn event(&self) -> Result<Event, QtmError> {
        match self.payload {
            [b] => Event::from_u8(*b).ok_or(QtmError::BadEvent),
            _ => Err(QtmError::BadEvent),
        }
    }
}

/// Decodes one whole packet (exactly `bytes`: a UDP datagram, or what [`Framer`] cut).
///
/// # Errors
/// A short header, a size that disagrees with `bytes`, or an unknown type.
pub fn decode_packet(bytes: &[u8]) -> Result<Packet<'_>, QtmError> {
    let (size, kind) = read_header(bytes)?;
    if (size as usize) < HEADER_BYTES {
        return Err(QtmError::BadSize {
            size,
            max: bytes.len(),
        });
    }
    match (size as usize).cmp(&bytes.len()) {
        std::cmp::Ordering::Greater => {
            return Err(QtmError::Truncated {
                offset: bytes.len(),
            })
        }
        std::cmp::Ordering::Less => {
            return Err(QtmError::TrailingBytes {
                extra: bytes.len() - size as usize,
            })
        }
        std::cmp::Ordering::Equal => {}
    }
    Ok(Packet {
        kind: PacketType::from_u32(kind)?,
        payload: &bytes[HEADER_BYTES..],
    })
}

/// The header's size and type fields.
fn read_header(bytes: &[u8]) -> Result<(u32, u32), QtmError> {
    match bytes.get(..HEADER_BYTES) {
        Some(h) => Ok((
            u32::from_le_bytes([h[0], h[1], h[2], h[3]]),
            u32::from_le_bytes([h[4], h[5], h[6], h[7]]),
        )),
        None => Err(QtmError::Truncated {
            offset: bytes.len(),
        }),
    }
}

/// Starts a packet of type `kind` in `out` (cleared); [`finish_packet`] writes its size.
pub fn start_packet(kind: PacketType, out: &mut Vec<u8>) {
    out.clear();
    out.extend_from_slice(&[0; 4]);
    out.extend_from_slice(&kind.as_u32().to_le_bytes());
}

/// Writes the size of the packet in `out` into its header.
pub fn finish_packet(out: &mut [u8]) {
    let size = u32::try_from(out.len()).unwrap_or(u32::MAX);
    if let Some(h) = out.get_mut(..4) {
        h.copy_from_slice(&size.to_le_bytes());
    }
}

/// A text packet (command, answer, error or XML): `text`, then a NUL.
pub fn encode_text_into(kind: PacketType, text: &str, out: &mut Vec<u8>) {
    start_packet(kind, out);
    out.extend_from_slice(text.as_bytes());
    out.push(0);
    finish_packet(out);
}

/// An event packet.
pub fn encode_event_into(event: Event, out: &mut Vec<u8>) {
    start_packet(PacketType::Event, out);
    out.push(event.as_u8());
    finish_packet(out);
}

/// A packet with no payload (`NoMoreData`).
pub fn encode_empty_into(kind: PacketType, out: &mut Vec<u8>) {
    start_packet(kind, out);
    finish_packet(out);
}

/// Cuts a TCP byte stream into whole packets; a packet larger than its limit is an error
/// (the peer is broken or hostile: the caller drops the connection).
///
/// Call order: [`Framer::buffer`] to get room, write received bytes into it and call
/// [`Framer::filled`]; then [`Framer::next_packet`] until it gives `None`.
#[derive(Debug)]
pub struct Framer {
    buf: Vec<u8>,
    start: usize,
    end: usize,
    max_packet: usize,
}

impl Framer {
    /// A framer accepting packets of at most `max_packet` bytes (header included).
    pub fn new(max_packet: usize) -> Framer {
        let max_packet = max_packet.max(HEADER_BYTES);
        Framer {
            buf: vec![0; max_packet.max(4096)],
            start: 0,
            end: 0,
            max_packet,
        }
    }

    /// Room for received bytes (never empty).
    pub fn buffer(&mut self) -> &mut [u8] {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        &mut self.buf[self.end..]
    }

    /// `n` bytes were written at the start of [`Framer::buffer`].
    pub fn filled(&mut self, n: usize) {
        self.end = (self.end + n).min(self.buf.len());
    }

    /// Bytes received and not yet cut into a packet.
    pub fn pending(&self) -> usize {
        self.end - self.start
    }

    /// The next whole packet, `Ok(None)` when more bytes are needed.
    ///
    /// # Errors
    /// A size outside `8..=max_packet` or an unknown type; the stream cannot be resynchronised
    /// after it.
    pub fn next_packet(&mut self) -> Result<Option<Packet<'_>>, QtmError> {
        let bytes = &self.buf[self.start..self.end];
        let Ok((size, kind)) = read_header(bytes) else {
            return Ok(None);
        };
        if (size as usize) < HEADER_BYTES || size as usize > self.max_packet {
            return Err(QtmError::BadSize {
                size,
                max: self.max_packet,
            });
        }
        let kind = PacketType::from_u32(kind)?;
        if bytes.len() < size as usize {
            return Ok(None);
        }
        let at = self.start;
        self.start += size as usize;
        Ok(Some(Packet {
            kind,
            payload: &self.buf[at + HEADER_BYTES..at + size as usize],
        }))
    }
}
