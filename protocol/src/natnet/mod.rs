//! NatNet, OptiTrack Motive's streaming protocol: packet framing, frames of mocap data, model
//! definitions, command messages, a sans-IO client session ([`Client`]), and the server's
//! side of the command channel ([`decode_command`], the replies).
//!
//! Like the rest of this crate: no sockets, no clock, no threads. Decoders take a whole UDP
//! datagram (header included); encoders write a whole datagram into a caller `Vec<u8>`.
//!
//! # Wire format
//!
//! Every datagram is `u16 message id, u16 payload size` (little-endian) and the payload;
//! [`check_packet`] checks the size against the datagram. Everything else is little-endian and
//! unaligned: `i32` counts, `f32` positions in metres (y up by default), NUL-terminated
//! UTF-8 names, `u64` high-resolution clock ticks of the server. Motive's command port is
//! 1510, its data port 1511, its default multicast group 239.255.42.99.
//!
//! # Version rules
//!
//! The layout of frames and model definitions depends on the NatNet (bitstream) version the
//! server announces in [`ServerInfo::natnet_version`] (or switches to after a `Bitstream`
//! request, see [`parse_bitstream_reply`]). This module decodes and encodes 3.x and 4.x and
//! refuses anything else with [`NatNetError::UnsupportedVersion`] rather than guess.
//!
//! | Version | Frame of data | Model definitions |
//! |---|---|---|
//! | 2.x (refused) | rigid bodies carry marker positions (2.0+: ids and sizes); skeletons 2.1+; labelled markers 2.3+; flags 2.6+; f64 timestamp 2.7+; force plates 2.9+; devices 2.11+; a software latency `f32` before the timecode | rigid body name 2.0+ |
//! | 3.0 | rigid bodies lose their marker lists; labelled markers gain the residual and param bits 3–5 (has model, unlabelled, active); software latency replaced by three `u64` stamps: camera mid-exposure, data received, transmit | rigid bodies gain marker offsets and required active labels; force plate and device descriptions |
//! | 3.1 | as 3.0 | as 3.0 |
//! | 4.0 | as 3.x; frame params bits 2 (live) and 3 (bitstream changed); precision timestamp disputed (below) | rigid bodies gain a name per marker |
//! | 4.1+ | every section is `count, i32 byte size, items`; an asset (trained markerset) section between skeletons and labelled markers; `u32` precision timestamp seconds and fraction before the params | every description is `type, i32 byte size, body`; asset descriptions (type 6) |
//!
//! Frame section order: frame number; markersets (name, positions); other (unlabelled)
//! markers; rigid bodies (id, position, quaternion, mean error, `i16` params); skeletons (id,
//! bones as rigid bodies); assets (4.1+); labelled markers (`id = model << 16 | marker`,
//! position, size, `i16` params, residual); force plates and devices (id, channels, samples
//! per channel); timecode and subframe; `f64` timestamp; the three stamps; precision
//! timestamp; `i16` params (bit 0 recording, bit 1 tracked models changed); a 4-byte
//! end-of-data tag.
//!
//! Quirks and where the sources disagree, with what this module does:
//! - The precision timestamp: the C++ PacketClient reads it from 4.1, the Python client from
//!   4.0. The frame tail has a fixed length, so a 4.0 frame is decoded either way, by length.
//! - Skeleton bone descriptions: the 3.0 PacketClient reads them without marker lists, the
//!   4.x PacketClient and Python client with them (3.0+ rule). This follows 4.x, the newest.
//! - NAT_UNRECOGNIZED_REQUEST is 100 (`NatNetTypes.h` and the capture); python_natnet's
//!   0x100 is wrong.
//! - The labelled-marker presence test reads `minor >= 3` in the C++ samples and `minor > 3`
//!   in the 4.x Python client: only 2.3 differs, and 2.x is refused.
//! - Motive's server-info name field carries uninitialised bytes after the NUL, and
//!   NatNetLib's requests carry garbage after the command's NUL: both are ignored.
//!
//! # Sources
//!
//! - NaturalPoint NatNet SDK `NatNetTypes.h` 3.0 (message ids, `sSender_Server`,
//!   `sConnectionOptions`, marker param bits), PacketClient.cpp 3.x and 4.x (section
//!   layouts, version tests, `UnpackDataSize`, end-of-data tag, frame param bits),
//!   NatNetClient.py 4.1 (connect packet with bitstream version, asset layouts, `Bitstream`
//!   reply), SampleClient.cpp 3.0 (latency formulas, timecode string). Read via mirrors such
//!   as whoenig/NatNetSDKCrossplatform and Vortex5Root/NatNetSDK_4.1.0.
//! - docs.optitrack.com, "NatNet 4.0"/"NatNet 4.1" SDK overview (ports, multicast group).
//! - mje-nz/python_natnet (BSD-3): an independent NatNet 3 reader, used as a test peer
//!   (`scripts/natnet_python_check.py`), and its Motive 2.1 capture, our test fixtures.
//!
//! # Example
//!
//! ```
//! use protocol::natnet::{decode_frame_into, encode_frame_into, FrameOfData, NatNetVersion};
//!
//! let mut frame = FrameOfData::default();
//! frame.frame_number = 7;
//! frame.push_markerset("face", &[[0.01, 1.5, 0.2], [f32::NAN; 3]]);
//! let mut datagram = Vec::new();
//! encode_frame_into(&frame, NatNetVersion::V4_1, &mut datagram).expect("encodable");
//!
//! let mut received = FrameOfData::with_capacity(200, 4);
//! decode_frame_into(&datagram, NatNetVersion::V4_1, &mut received).expect("valid frame");
//! let face = received.markerset_named("face").expect("sent");
//! assert_eq!(face.positions[0], [0.01, 1.5, 0.2]);
//! assert!(face.positions[1][0].is_nan());
//! ```

mod client;
mod client_types;
mod command;
mod error;
mod frame;
mod frame_decode;
mod frame_encode;
mod frame_parts;
mod message;
mod modeldef;
mod modeldef_encode;
mod server;
mod version;
mod wire;

pub use client::{Channel, Client, ClientConfig, ClockEstimate, DisconnectReason, Event, Incoming};
pub use command::{
    decode_packet, encode_connect_into, encode_echo_request_into, encode_echo_response_into,
    encode_request_into, encode_server_info_into, encode_text_into, response_code, response_text,
    Connect, ConnectionInfo, ConnectionOptions, EchoResponse, Packet, ServerInfo, NAME_LEN,
};
pub use error::{ModelDefError, NatNetEncodeError, NatNetError, NatNetErrorKind};
pub use frame::{
    positions_mm_into, AnalogData, FrameOfData, FrameParams, LabeledMarker, MarkerParams,
    Markerset, PrecisionTimestamp, RigidBody, Skeleton, Timecode, MM_PER_M,
};
pub use frame_decode::decode_frame_into;
pub use frame_encode::encode_frame_into;
pub use message::{check_packet, encode_empty_into, MessageId, HEADER_LEN, MAX_PAYLOAD};
pub use modeldef::{
    decode_model_defs, AssetDef, CameraDef, DeviceDef, ForcePlateDef, MarkersetDef, ModelDefs,
    RigidBodyDef, RigidBodyMarkerDef, SkeletonDef,
};
pub use modeldef_encode::encode_model_defs_into;
pub use server::{
    decode_command, encode_response_code_into, encode_response_f32_into, encode_unrecognized_into,
    parse_request, Command, Hello, Request, MAX_COMMAND_LEN,
};
pub use version::{parse_bitstream_reply, NatNetVersion};

/// Motive's default command port.
pub const DEFAULT_COMMAND_PORT: u16 = 1510;
/// Motive's default data port.
pub const DEFAULT_DATA_PORT: u16 = 1511;
/// Motive's default multicast group.
pub const DEFAULT_MULTICAST_GROUP: [u8; 4] = [239, 255, 42, 99];
