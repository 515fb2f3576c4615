//! Qualisys QTM's real-time protocol (RT protocol 1.x), sans-IO: emoshift reads QTM as a
//! source and serves its edited frames as QTM does, so Qualisys clients (QTM Connect for
//! Unreal, Unity and MotionBuilder, the official SDKs) take them unchanged.
//!
//! - [`packet`]: the 8-byte header (size including the header, type; little-endian, QTM's
//!   port 22223), text/XML/event packets, and the [`Framer`] that cuts a TCP stream into
//!   packets with a size limit (a larger one is an error: the connection is dropped).
//! - [`command`]: the commands a client sends (`Version`, `GetParameters`, `StreamFrames`, ...)
//!   as a server reads them, refusals included.
//! - [`data`]: data packets with the `3D`, `3DRes`, `3DNoLabels` and `Timecode` components,
//!   both ways ([`encode_data_into`], [`decode_data_into`], no allocation when decoding).
//! - [`params`], [`params_read`]: the XML parameters (`General`'s frequency, `The_3D`'s
//!   labels), written as a server, read as a client (quick-xml).
//! - [`event`]: QTM's events.
//! - discovery on UDP [`DISCOVERY_PORT`]: [`decode_discover`], [`encode_discover_reply_into`].
//!
//! Only the little-endian port is spoken: `ByteOrder` answers "little endian", as QTM does on
//! 22223 (its big-endian port 22222 is legacy).
//!
//! ```
//! use protocol::qtm::{decode_data_into, decode_packet, encode_data_into, Components, DataFrame,
//!     FrameIn, PacketType};
//!
//! let nan = f32::NAN;
//! let frame = DataFrame { timestamp_us: 8_333, frame_number: 7,
//!     positions: &[1.0, 2.0, 3.0, nan, nan, nan], timecode: None };
//! let mut bytes = Vec::new();
//! encode_data_into(&frame, Components { d3: true, ..Components::default() }, &mut bytes);
//! let packet = decode_packet(&bytes).expect("one whole packet");
//! assert_eq!(packet.kind, PacketType::Data);
//! let mut got = FrameIn::with_max_markers(100);
//! decode_data_into(packet.payload, &mut got).expect("valid frame");
//! assert_eq!((got.frame_number, got.marker_count()), (7, 2));
//! assert!(got.positions()[3].is_nan());
//! ```

pub mod command;
pub mod data;
pub mod error;
pub mod event;
pub mod packet;
pub mod params;
pub mod params_read;
mod timecode;

pub use command::{parse_command, Command, Components, ParameterSet, Rate, Transport};
pub use data::{decode_data_into, encode_data_into, DataFrame, FrameIn, Timecode};
pub use error::QtmError;
pub use event::Event;
pub use packet::{
    decode_packet, encode_empty_into, encode_event_into, encode_text_into, Framer, Packet,
    PacketType, HEADER_BYTES,
};
pub use params::{encode_parameters_into, Parameters};
pub use params_read::{decode_parameters, ParametersError, QtmParameters};

/// QTM's little-endian RT port (TCP).
pub const DEFAULT_PORT: u16 = 22223;
/// QTM's discovery port (UDP).
pub const DISCOVERY_PORT: u16 = 22226;
/// The text QTM sends first on every connection.
pub const WELCOME: &str = "QTM RT Interface connected";
/// The newest protocol version emoshift speaks (as a server and as a client).
pub const VERSION: (u32, u32) = (1, 25);
/// The command that agrees [`VERSION`] (as a client).
pub const MAX_VERSION_TEXT: &str = "Version 1.25";
/// The oldest it accepts from a client (qtm-rt needs 1.8 or later).
pub const MIN_VERSION: (u32, u32) = (1, 8);

/// The reply port of a discovery request (10 bytes: header, then the port big-endian).
///
/// # Errors
/// Anything but a 10-byte discover packet.
pub fn decode_discover(bytes: &[u8]) -> Result<u16, QtmError> {
    let p = decode_packet(bytes)?;
    match (p.kind, p.payload) {
        (PacketType::Discover, [hi, lo]) => Ok(u16::from_be_bytes([*hi, *lo])),
        _ => Err(QtmError::BadSize {
            size: u32::try_from(bytes.len()).unwrap_or(u32::MAX),
            max: 10,
        }),
    }
}

/// The answer to a discovery request: a command packet with `info`, a NUL, then the RT base
/// port big-endian (as QTM and the SDKs read it).
pub fn encode_discover_reply_into(info: &str, base_port: u16, out: &mut Vec<u8>) {
    packet::start_packet(PacketType::Command, out);
    out.extend_from_slice(info.as_bytes());
    out.push(0);
    out.extend_from_slice(&base_port.to_be_bytes());
    packet::finish_packet(out);
}

#[cfg(test)]
mod tests;
