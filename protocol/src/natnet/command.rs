//! Command-channel messages: connect/discovery, server info, requests and responses, echo.
//! Model definitions and frames have their own modules; [`decode_packet`] only names them.

use super::error::{NatNetEncodeError, NatNetError};
use super::message::{begin_packet, check_packet, finish_packet, MessageId, HEADER_LEN};
use super::version::NatNetVersion;
use super::wire::{put_cstr, put_fixed_str, put_u16, put_u64, Reader};

/// Size of the fixed name fields (`MAX_NAMELENGTH`).
pub const NAME_LEN: usize = 256;
/// `sSender`: name, app version, NatNet version.
const SENDER_LEN: usize = NAME_LEN + 8;
/// `sSender_Server`: sender, clock frequency, data port, multicast flag, group.
const SERVER_INFO_LEN: usize = SENDER_LEN + 8 + 2 + 1 + 4;
/// `sConnectionOptions`: subscribed-data-only flag and bitstream version (NatNet 4).
const OPTIONS_LEN: usize = 5;

/// NAT_CONNECT and NAT_DISCOVERY payload: who the client is and, from NatNet 4, which
/// bitstream version it asks for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connect {
    /// Client application name (NaturalPoint's library sends `NatNetLib`), < 256 bytes.
    pub client_name: String,
    /// Client application version.
    pub app_version: [u8; 4],
    /// NatNet version the client speaks.
    pub natnet_version: NatNetVersion,
    /// `sConnectionOptions`, sent by NatNet 4 clients only.
    pub options: Option<ConnectionOptions>,
}

/// `sConnectionOptions` of a NatNet 4 connect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConnectionOptions {
    /// Ask for subscribed data only.
    pub subscribed_data_only: bool,
    /// Requested bitstream version (all zero: the server's own).
    pub bitstream_version: NatNetVersion,
}

impl Connect {
    /// What emoshift sends: its name, and connection options when `version` is 4 or later.
    pub fn emoshift(version: NatNetVersion) -> Self {
        Connect {
            client_name: "emoshift".to_owned(),
            app_version: [0, 1, 0, 0],
            natnet_version: version,
            options: (version.major >= 4).then_some(ConnectionOptions {
                subscribed_data_only: false,
                bitstream_version: version,
            }),
        }
    }
}

/// NAT_SERVERINFO payload (`sSender_Server`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServerInfo {
    /// Server application name (`Motive`).
    pub app_name: String,
    /// Server application version (Motive 2.1.0.0 sends `[2, 1, 0, 0]`).
    pub app_version: [u8; 4],
    /// NatNet version the server streams: it selects every frame and model def layout.
    pub natnet_version: NatNetVersion,
    /// Clock and connection info, sent by NatNet 3.0+ servers.
    pub connection: Option<ConnectionInfo>,
}

/// NatNet 3.0+ part of the server info.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ConnectionInfo {
    /// Ticks per second of the server's high-resolution clock (frame and echo stamps).
    pub clock_frequency_hz: u64,
    /// Data port the server streams frames to.
    pub data_port: u16,
    /// Whether frames are multicast (else unicast to each client).
    pub multicast: bool,
    /// Multicast group, e.g. `[239, 255, 42, 99]`.
    pub multicast_group: [u8; 4],
}

/// NAT_ECHORESPONSE payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EchoResponse {
    /// The client's timestamp from the request, unchanged.
    pub request_stamp: u64,
    /// The server's high-resolution clock when it received the request, in its ticks.
    pub server_ticks: u64,
}

/// One decoded NatNet packet. Frames and model definitions depend on the version and are
/// only named here: decode them with [`decode_frame_into`](super::decode_frame_into) and
/// [`decode_model_defs`](super::decode_model_defs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Packet<'a> {
    /// NAT_CONNECT.
    Connect(Connect),
    /// NAT_SERVERINFO.
    ServerInfo(ServerInfo),
    /// NAT_REQUEST: command bytes up to the NUL (Motive commands are ASCII, but NatNetLib
    /// sends binary ones too).
    Request(&'a [u8]),
    /// NAT_RESPONSE: the raw payload; see [`response_text`] and [`response_code`].
    Response(&'a [u8]),
    /// NAT_REQUEST_MODELDEF (any payload, e.g. NatNet 4's type mask, is ignored).
    RequestModelDef,
    /// NAT_MODELDEF.
    ModelDef,
    /// NAT_REQUEST_FRAMEOFDATA.
    RequestFrameOfData,
    /// NAT_FRAMEOFDATA.
    FrameOfData,
    /// NAT_MESSAGESTRING: text up to the NUL.
    MessageString(&'a [u8]),
    /// NAT_DISCONNECT.
    Disconnect,
    /// NAT_KEEPALIVE.
    KeepAlive,
    /// NAT_DISCONNECTBYTIMEOUT.
    DisconnectByTimeout,
    /// NAT_ECHOREQUEST: the client's timestamp.
    EchoRequest(u64),
    /// NAT_ECHORESPONSE.
    EchoResponse(EchoResponse),
    /// NAT_DISCOVERY.
    Discovery(Connect),
    /// NAT_UNRECOGNIZED_REQUEST (Motive echoes its sender block; ignored).
    UnrecognizedRequest,
}

/// Decodes any NatNet packet's header and, for command messages, its payload.
///
/// # Errors
///
/// Any [`NatNetError`]: framing, truncation, trailing bytes, bad strings.
pub fn decode_packet(datagram: &[u8]) -> Result<Packet<'_>, NatNetError> {
    use MessageId as M;
    let id = check_packet(datagram)?;
    let mut r = Reader::at(datagram, HEADER_LEN);
    let packet = match id {
        M::Connect => Packet::Connect(read_connect(&mut r)?),
        M::Discovery => Packet::Discovery(read_connect(&mut r)?),
        M::ServerInfo => Packet::ServerInfo(read_server_info(&mut r)?),
        M::Request => Packet::Request(until_nul(&mut r)),
        M::Response => Packet::Response(r.take(r.remaining())?),
        M::MessageString => Packet::MessageString(until_nul(&mut r)),
        M::EchoRequest => Packet::EchoRequest(r.u64()?),
        M::EchoResponse => Packet::EchoResponse(EchoResponse {
            request_stamp: r.u64()?,
            server_ticks: r.u64()?,
        }),
        M::RequestModelDef | M::ModelDef | M::FrameOfData | M::UnrecognizedRequest => {
            r.skip(r.remaining())?;
            match id {
                M::RequestModelDef => Packet::RequestModelDef,
                M::ModelDef => Packet::ModelDef,
                M::FrameOfData => Packet::FrameOfData,
                _ => Packet::UnrecognizedRequest,
            }
        }
        M::RequestFrameOfData => Packet::RequestFrameOfData,
        M::Disconnect => Packet::Disconnect,
        M::KeepAlive => Packet::KeepAlive,
        M::DisconnectByTimeout => Packet::DisconnectByTimeout,
    };
    r.finish()?;
    Ok(packet)
}

/// Bytes up to the first NUL; the rest of the payload (NatNetLib leaves garbage after it)
/// is consumed.
fn until_nul<'a>(r: &mut Reader<'a>) -> &'a [u8] {
    let all = r.take(r.remaining()).unwrap_or(&[]);
    let end = all.iter().position(|&b| b == 0).unwrap_or(all.len());
    &all[..end]
}

/// A NAT_RESPONSE as text: bytes up to the first NUL, if UTF-8 (`"Bitstream,4.0"`).
pub fn response_text(payload: &[u8]) -> Option<&str> {
    let end = payload
        .iter()
        .position(|&b| b == 0)
        .unwrap_or(payload.len());
    std::str::from_utf8(&payload[..end]).ok()
}

/// A 4-byte NAT_RESPONSE as the SDK's integer result code (0 = ok). Some commands answer
/// with a float in the same 4 bytes (`FrameRate`): reinterpret with `f32::from_bits`.
pub fn response_code(payload: &[u8]) -> Option<i32> {
    let b: [u8; 4] = payload.try_into().ok()?;
    Some(i32::from_le_bytes(b))
}

fn read_version(r: &mut Reader<'_>) -> Result<[u8; 4], NatNetError> {
    Ok([r.u8()?, r.u8()?, r.u8()?, r.u8()?])
}

fn read_connect(r: &mut Reader<'_>) -> Result<Connect, NatNetError> {
    let client_name = r.fixed_str(NAME_LEN)?.to_owned();
    let app_version = read_version(r)?;
    let natnet_version = NatNetVersion::from_bytes(read_version(r)?);
    let options = if r.remaining() >= OPTIONS_LEN {
        let subscribed_data_only = r.u8()? != 0;
        let bitstream_version = NatNetVersion::from_bytes(read_version(r)?);
        // NatNet 4's Python client appends one more NUL.
        if r.remaining() == 1 {
            r.skip(1)?;
        }
        Some(ConnectionOptions {
            subscribed_data_only,
            bitstream_version,
        })
    } else {
        None
    };
    Ok(Connect {
        client_name,
        app_version,
        natnet_version,
        options,
    })
}

fn read_server_info(r: &mut Reader<'_>) -> Result<ServerInfo, NatNetError> {
    let app_name = r.fixed_str(NAME_LEN)?.to_owned();
    let app_version = read_version(r)?;
    let natnet_version = NatNetVersion::from_bytes(read_version(r)?);
    // Servers before NatNet 3 send the bare sender block.
    let connection = if r.remaining() == 0 {
        None
    } else {
        Some(ConnectionInfo {
            clock_frequency_hz: r.u64()?,
            data_port: r.u16()?,
            multicast: r.u8()? != 0,
            multicast_group: read_version(r)?,
        })
    };
    Ok(ServerInfo {
        app_name,
        app_version,
        natnet_version,
        connection,
    })
}

fn put_sender(out: &mut Vec<u8>, name: &str, app: [u8; 4], natnet: NatNetVersion) -> Enc {
    put_fixed_str(out, name, NAME_LEN)?;
    out.extend_from_slice(&app);
    out.extend_from_slice(&natnet.to_bytes());
    Ok(())
}

type Enc = Result<(), NatNetEncodeError>;

/// Encodes NAT_CONNECT (`discovery == false`) or NAT_DISCOVERY into `out` (cleared first):
/// `sSender` (264 bytes), then `sConnectionOptions` (5 bytes) when present.
///
/// # Errors
///
/// The client name has a NUL or is 256 bytes or longer.
pub fn encode_connect_into(c: &Connect, discovery: bool, out: &mut Vec<u8>) -> Enc {
    let id = if discovery {
        MessageId::Discovery
    } else {
        MessageId::Connect
    };
    begin_packet(out, id);
    put_sender(out, &c.client_name, c.app_version, c.natnet_version)?;
    if let Some(o) = c.options {
        out.push(u8::from(o.subscribed_data_only));
        out.extend_from_slice(&o.bitstream_version.to_bytes());
    }
    finish_packet(out)
}

/// Encodes NAT_SERVERINFO into `out` (cleared first): 264 bytes, plus 15 with connection info.
///
/// # Errors
///
/// The application name has a NUL or is 256 bytes or longer.
pub fn encode_server_info_into(s: &ServerInfo, out: &mut Vec<u8>) -> Enc {
    begin_packet(out, MessageId::ServerInfo);
    put_sender(out, &s.app_name, s.app_version, s.natnet_version)?;
    if let Some(c) = s.connection {
        put_u64(out, c.clock_frequency_hz);
        put_u16(out, c.data_port);
        out.push(u8::from(c.multicast));
        out.extend_from_slice(&c.multicast_group);
    }
    debug_assert!(
        out.len() == HEADER_LEN + SENDER_LEN || out.len() == HEADER_LEN + SERVER_INFO_LEN
    );
    finish_packet(out)
}

/// Encodes NAT_REQUEST carrying `command` and its NUL (e.g. `"Bitstream,4.0"`).
///
/// # Errors
///
/// The command has a NUL or exceeds the packet size.
pub fn encode_request_into(command: &str, out: &mut Vec<u8>) -> Enc {
    encode_text_into(MessageId::Request, command, out)
}

/// Encodes a text message (NAT_REQUEST, NAT_RESPONSE, NAT_MESSAGESTRING) with its NUL.
///
/// # Errors
///
/// The text has a NUL or exceeds the packet size.
pub fn encode_text_into(id: MessageId, text: &str, out: &mut Vec<u8>) -> Enc {
    begin_packet(out, id);
    put_cstr(out, text)?;
    finish_packet(out)
}

/// Encodes NAT_ECHOREQUEST carrying the client's timestamp (any 64-bit value it can map back).
pub fn encode_echo_request_into(client_stamp: u64, out: &mut Vec<u8>) {
    begin_packet(out, MessageId::EchoRequest);
    put_u64(out, client_stamp);
    out[2] = 8;
}

/// Encodes NAT_ECHORESPONSE.
pub fn encode_echo_response_into(e: &EchoResponse, out: &mut Vec<u8>) {
    begin_packet(out, MessageId::EchoResponse);
    put_u64(out, e.request_stamp);
    put_u64(out, e.server_ticks);
    out[2] = 16;
}
