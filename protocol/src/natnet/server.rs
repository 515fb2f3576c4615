//! The server's side of the command channel: what clients send a NatNet server
//! ([`decode_command`]: connect, requests, keep-alive, echo, disconnect) and the replies a
//! server writes besides server info, frames and model definitions (`NAT_RESPONSE` codes,
//! floats and text; `NAT_UNRECOGNIZED_REQUEST`).
//!
//! Lenient where real clients differ, strict where nothing could be meant:
//! - NAT_CONNECT is the 264-byte sender block (NatNetLib, python_natnet), plus NatNet 4's
//!   5-byte connection options, or just a text (the `natnet` Python package sends `"Ping"`);
//!   the client name's bytes are not read (NatNetLib leaves garbage in them).
//! - Payloads of NAT_KEEPALIVE, NAT_REQUEST_MODELDEF (NatNet 4's type mask),
//!   NAT_REQUEST_FRAMEOFDATA and NAT_DISCONNECT are ignored (Python clients send a NUL).
//! - A request string is read up to its NUL; the rest (NatNetLib's garbage) is ignored.
//! - Messages only a server sends come back as [`Command::NotACommand`] for the caller to
//!   count; malformed headers and truncated payloads are errors.

use super::error::NatNetError;
use super::message::{begin_packet, check_packet, finish_packet, MessageId, HEADER_LEN};
use super::version::NatNetVersion;
use super::wire::{put_f32, put_fixed_str, put_i32, Reader};
use super::{NatNetEncodeError, ServerInfo, NAME_LEN};

/// Commands larger than this are refused before decoding: no client command is near it (the
/// largest, a NatNet 4 connect, is 270 bytes).
pub const MAX_COMMAND_LEN: usize = 1024;

/// What a client sends a server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command<'a> {
    /// NAT_CONNECT: answer with server info; a unicast client is remembered.
    Connect(Hello),
    /// NAT_DISCOVERY: answer with server info.
    Discovery(Hello),
    /// NAT_REQUEST: a command string.
    Request(Request<'a>),
    /// NAT_REQUEST_MODELDEF.
    RequestModelDef,
    /// NAT_REQUEST_FRAMEOFDATA.
    RequestFrameOfData,
    /// NAT_KEEPALIVE: a unicast client renews its session.
    KeepAlive,
    /// NAT_ECHOREQUEST: the client's stamp, to be returned with the server's clock.
    EchoRequest(u64),
    /// NAT_DISCONNECT.
    Disconnect,
    /// A message only a server sends (server info, frames, responses...).
    NotACommand(MessageId),
}

/// What a connecting client says about itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Hello {
    /// The NatNet version the client speaks (`None`: a connect without the sender block).
    pub natnet_version: Option<NatNetVersion>,
    /// The bitstream a NatNet 4 client asks for in its connection options (`None`: none
    /// sent, or all zero, meaning the server's own).
    pub bitstream: Option<NatNetVersion>,
}

/// A NAT_REQUEST string, as Motive knows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request<'a> {
    /// `Bitstream,M.m[.b.r]`: stream this version to the client (`None`: not a version).
    Bitstream(Option<NatNetVersion>),
    /// `FrameRate`: the capture rate, answered as an `f32`.
    FrameRate,
    /// `UnitsToMillimeters`: millimetres per unit of the stream, answered as an `f32`.
    UnitsToMillimeters,
    /// `TimelinePlay`.
    TimelinePlay,
    /// `TimelineStop`.
    TimelineStop,
    /// Anything else, up to its NUL.
    Other(&'a [u8]),
}

/// Decodes one datagram a client sent to a server's command port.
///
/// # Errors
///
/// A bad header (unknown id, size not the datagram's), a truncated echo request or sender
/// block.
pub fn decode_command(datagram: &[u8]) -> Result<Command<'_>, NatNetError> {
    use MessageId as M;
    let id = check_packet(datagram)?;
    let mut r = Reader::at(datagram, HEADER_LEN);
    Ok(match id {
        M::Connect => Command::Connect(read_hello(&mut r)?),
        M::Discovery => Command::Discovery(read_hello(&mut r)?),
        M::Request => {
            let all = r.take(r.remaining())?;
            let end = all.iter().position(|&b| b == 0).unwrap_or(all.len());
            Command::Request(parse_request(&all[..end]))
        }
        M::RequestModelDef => Command::RequestModelDef,
        M::RequestFrameOfData => Command::RequestFrameOfData,
        M::KeepAlive => Command::KeepAlive,
        M::Disconnect => Command::Disconnect,
        M::EchoRequest => {
            let stamp = r.u64()?;
            r.finish()?;
            Command::EchoRequest(stamp)
        }
        other => Command::NotACommand(other),
    })
}

/// A request string (without its NUL) as a [`Request`]. Names are matched as Motive matches
/// them, case-insensitively.
pub fn parse_request(text: &[u8]) -> Request<'_> {
    let (name, arg) = match text.iter().position(|&b| b == b',') {
        Some(i) => (&text[..i], Some(&text[i + 1..])),
        None => (text, None),
    };
    let is = |known: &str| name.eq_ignore_ascii_case(known.as_bytes());
    if is("Bitstream") {
        return Request::Bitstream(arg.and_then(parse_version));
    }
    if arg.is_some() {
        return Request::Other(text);
    }
    if is("FrameRate") {
        Request::FrameRate
    } else if is("UnitsToMillimeters") {
        Request::UnitsToMillimeters
    } else if is("TimelinePlay") {
        Request::TimelinePlay
    } else if is("TimelineStop") {
        Request::TimelineStop
    } else {
        Request::Other(text)
    }
}

/// `M.m[.b[.r]]`, each part a byte.
fn parse_version(text: &[u8]) -> Option<NatNetVersion> {
    let text = std::str::from_utf8(text).ok()?;
    let mut parts = [0u8; 4];
    let mut n = 0;
    for p in text.trim().split('.') {
        *parts.get_mut(n)? = p.parse().ok()?;
        n += 1;
    }
    (n >= 2).then_some(NatNetVersion::from_bytes(parts))
}

fn read_hello(r: &mut Reader<'_>) -> Result<Hello, NatNetError> {
    if r.remaining() < NAME_LEN + 8 {
        // A bare text ("Ping"): nothing to learn.
        r.skip(r.remaining())?;
        return Ok(Hello::default());
    }
    r.skip(NAME_LEN + 4)?;
    let natnet = r.take(4)?;
    let natnet_version = NatNetVersion::from_bytes([natnet[0], natnet[1], natnet[2], natnet[3]]);
    let mut bitstream = None;
    if r.remaining() >= 5 {
        r.skip(1)?;
        let b = r.take(4)?;
        let v = NatNetVersion::from_bytes([b[0], b[1], b[2], b[3]]);
        bitstream = (v != NatNetVersion::default()).then_some(v);
    }
    // Anything after (the Python SDK's extra NUL) is ignored.
    r.skip(r.remaining())?;
    Ok(Hello {
        natnet_version: Some(natnet_version),
        bitstream,
    })
}

/// Encodes a NAT_RESPONSE carrying a 4-byte result code (0: done).
pub fn encode_response_code_into(code: i32, out: &mut Vec<u8>) {
    begin_packet(out, MessageId::Response);
    put_i32(out, code);
    out[2] = 4;
}

/// Encodes a NAT_RESPONSE carrying a 4-byte float (`FrameRate`, `UnitsToMillimeters`).
pub fn encode_response_f32_into(value: f32, out: &mut Vec<u8>) {
    begin_packet(out, MessageId::Response);
    put_f32(out, value);
    out[2] = 4;
}

/// Encodes NAT_UNRECOGNIZED_REQUEST as Motive sends it: its sender block (name, app version,
/// NatNet version).
///
/// # Errors
///
/// The application name has a NUL or is 256 bytes or longer.
pub fn encode_unrecognized_into(
    server: &ServerInfo,
    out: &mut Vec<u8>,
) -> Result<(), NatNetEncodeError> {
    begin_packet(out, MessageId::UnrecognizedRequest);
    put_fixed_str(out, &server.app_name, NAME_LEN)?;
    out.extend_from_slice(&server.app_version);
    out.extend_from_slice(&server.natnet_version.to_bytes());
    finish_packet(out)
}

#[cfg(test)]
mod tests;
