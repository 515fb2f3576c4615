//! Packet framing: `u16 message id, u16 payload size` (little-endian), then the payload.

use super::error::{NatNetEncodeError, NatNetError};
use super::wire::put_u16;

/// Bytes of the packet header.
pub const HEADER_LEN: usize = 4;

/// Largest payload the 16-bit size field can announce.
pub const MAX_PAYLOAD: usize = u16::MAX as usize;

/// NatNet message ids (`NatNetTypes.h`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u16)]
pub enum MessageId {
    /// Client → server: connect (sender info, and from NatNet 4 connection options).
    Connect = 0,
    /// Server → client: server info (reply to connect and discovery).
    ServerInfo = 1,
    /// Client → server: a command string.
    Request = 2,
    /// Server → client: reply to a request (4-byte code or string).
    Response = 3,
    /// Client → server: send the model definitions.
    RequestModelDef = 4,
    /// Server → client: model (data) definitions.
    ModelDef = 5,
    /// Client → server: send the current frame.
    RequestFrameOfData = 6,
    /// Server → client: a frame of mocap data.
    FrameOfData = 7,
    /// Server → client: a message string.
    MessageString = 8,
    /// Client → server or server → client: disconnect.
    Disconnect = 9,
    /// Client → server: keep-alive (unicast).
    KeepAlive = 10,
    /// Server → client: the server dropped the client after a timeout.
    DisconnectByTimeout = 11,
    /// Client → server: echo request carrying the client's timestamp.
    EchoRequest = 12,
    /// Server → client: the client's timestamp and the server's.
    EchoResponse = 13,
    /// Client → broadcast: who is there (same payload as connect).
    Discovery = 14,
    /// Server → client: the request was not understood.
    UnrecognizedRequest = 100,
}

impl MessageId {
    /// The id for a wire value, if it is one.
    pub fn from_u16(id: u16) -> Option<MessageId> {
        use MessageId as M;
        Some(match id {
            0 => M::Connect,
            1 => M::ServerInfo,
            2 => M::Request,
            3 => M::Response,
            4 => M::RequestModelDef,
            5 => M::ModelDef,
            6 => M::RequestFrameOfData,
            7 => M::FrameOfData,
            8 => M::MessageString,
            9 => M::Disconnect,
            10 => M::KeepAlive,
            11 => M::DisconnectByTimeout,
            12 => M::EchoRequest,
            13 => M::EchoResponse,
            14 => M::Discovery,
            100 => M::UnrecognizedRequest,
            _ => return None,
        })
    }

    /// The wire value.
    pub fn as_u16(self) -> u16 {
        self as u16
    }
}

/// Checks a datagram's header against its length and returns the message id.
/// The payload is `datagram[HEADER_LEN..]`.
///
/// # Errors
///
/// [`NatNetError::Truncated`] for less than a header, [`NatNetError::UnknownMessage`],
/// [`NatNetError::PayloadSize`] when the announced size is not the datagram's.
pub fn check_packet(datagram: &[u8]) -> Result<MessageId, NatNetError> {
    let Some(header) = datagram.get(..HEADER_LEN) else {
        return Err(NatNetError::Truncated {
            offset: datagram.len(),
        });
    };
    let raw = u16::from_le_bytes([header[0], header[1]]);
    let declared = usize::from(u16::from_le_bytes([header[2], header[3]]));
    let id = MessageId::from_u16(raw).ok_or(NatNetError::UnknownMessage { id: raw })?;
    let actual = datagram.len() - HEADER_LEN;
    if declared != actual {
        return Err(NatNetError::PayloadSize { declared, actual });
    }
    Ok(id)
}

/// [`check_packet`], then that the id is `expected`.
pub(crate) fn expect_packet(datagram: &[u8], expected: MessageId) -> Result<(), NatNetError> {
    let got = check_packet(datagram)?;
    if got != expected {
        return Err(NatNetError::WrongMessage {
            expected: expected.as_u16(),
            got: got.as_u16(),
        });
    }
    Ok(())
}

/// Clears `out` and writes a header with a zero size; [`finish_packet`] fills the size.
pub(crate) fn begin_packet(out: &mut Vec<u8>, id: MessageId) {
    out.clear();
    put_u16(out, id.as_u16());
    put_u16(out, 0);
}

/// Fills the header's size from the bytes written after it.
pub(crate) fn finish_packet(out: &mut [u8]) -> Result<(), NatNetEncodeError> {
    let len = out.len() - HEADER_LEN;
    let size = u16::try_from(len).map_err(|_| NatNetEncodeError::Oversize {
        len,
        max: MAX_PAYLOAD,
    })?;
    out[2..4].copy_from_slice(&size.to_le_bytes());
    Ok(())
}

/// Encodes a message with an empty payload (keep-alive, request model def, request frame,
/// disconnect, unrecognized request).
pub fn encode_empty_into(id: MessageId, out: &mut Vec<u8>) {
    begin_packet(out, id);
}

#[cfg(test)]
mod tests;
