//! OSC 1.0 wire formats of emoshift: marker frames, labels, output profiles and control;
//! [`qtm`], Qualisys QTM's RT protocol (packets, commands, 3D data, parameters, events);
//! [`natnet`], OptiTrack Motive's NatNet protocol (frames, model definitions, commands, a
//! sans-IO client session) so the daemon can take Motive streams as a source.
//!
//! Sans-IO: every function takes bytes and returns values, or writes into a caller
//! `Vec<u8>`. No sockets, no clock, no threads, no logging; the daemon owns all of those.
//!
//! # Address space
//!
//! Big-endian, 4-byte aligned OSC 1.0 over UDP. `i` int32, `h` int64, `f` float32, `s` string,
//! `b` blob. Every address is a constant in [`address`]; what each one carries, who sends it
//! and the control limits are in the workspace's one address table, `docs/osc.md` (a test,
//! `docs_osc`, fails when an address defined here is missing from it).
//!
//! # Decisions
//!
//! - **Layout binding.** Frames keep `,ihbb` exactly and name no layout: a frame's layout is
//!   the latest `/mocap/labels` from the same source address whose marker count equals the
//!   frame's ([`LayoutBook`]). A source may send layouts of different sizes; same-size layouts
//!   replace each other, so a source with two same-size layouts must use two ports. Frames with
//!   no matching layout are counted and dropped by the daemon until the labels arrive.
//! - **Compact profile.** One bundle, time tag "immediately": `/emoshift/stream ,is`, the
//!   `,ihbb` frame, `/emoshift/state ,sf` and the source's `/mocap/timecode`. Atomic in one
//!   datagram ([`encode_compact_into`]: 1,464 bytes for 109 markers without the timecode).
//! - **Components profile.** Without VMC labels, the bare `/emoshift/components` message;
//!   with labels, one bundle: components, the `Val`s, then `Apply`.
//! - **Flat-split.** Parts carry the frame's marker count so a receiver knows when it has all.
//! - **Status reply.** `/status/confirm` carries `(s name, h value)` pairs; names are the
//!   daemon's (e.g. `frames_in`, `frames_dropped`, one per [`DecodeErrorKind::as_str`]).
//!
//! # Decoding
//!
//! Every datagram first goes through [`messages`]: a pre-scan that allocates nothing, rejects
//! datagrams over [`Limits::max_datagram`] (65,507 by default), bundles nested deeper than
//! [`Limits::max_bundle_depth`] (8) — rosc recurses per bundle and aborts the process on
//! deep nesting — and any truncation, trailing byte, bad element size or unknown type tag;
//! then it yields the messages, bundles flattened. Frames are decoded by a borrowed parser
//! into a caller [`FrameBuf`] ([`decode_frame_into`], no allocation; cross-checked against
//! rosc by property tests). Labels and control go through rosc ([`decode_labels`],
//! [`decode_control`]). Every failure is a [`DecodeError`] (small, `Copy`, with a
//! [`DecodeErrorKind`] for counters) or a [`ControlError`] for control; nothing panics.
//!
//! ```
//! use protocol::{decode_frame_into, encode_frame_into, messages, Address, FrameBuf, Limits};
//!
//! let mut frame = FrameBuf::with_max_markers(200);
//! let nan = f32::NAN;
//! frame.set_frame(7, 1_000, &[1.0, 2.0, 3.0, nan, nan, nan]).expect("valid frame");
//! let mut datagram = Vec::with_capacity(1_500);
//! encode_frame_into(&frame, &mut datagram).expect("finite positions");
//!
//! let mut received = FrameBuf::with_max_markers(200);
//! for msg in messages(&datagram, &Limits::default()).expect("well-formed") {
//!     if Address::parse(msg.address) == Some(Address::Frame) {
//!         let header = decode_frame_into(msg.bytes, &mut received).expect("valid frame");
//!         assert_eq!((header.frame_number, header.marker_count, header.missing_count), (7, 2, 1));
//!         assert!(received.is_missing(1));
//!     }
//! }
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod address;
mod control;
mod error;
mod frame;
mod labels;
pub mod natnet;
mod output;
pub mod qtm;
mod reply;
mod scan;
mod timecode;
mod wire;

pub use address::Address;
pub use control::{
    decode_control, decode_control_with_secret, Control, ControlError, Profile, SessionControl,
    MAX_ALPHA, MAX_GAIN, MAX_MIX_WEIGHT, MAX_NAME_BYTES, MAX_PATH_BYTES, MAX_RAMP_S,
};
pub use error::{DecodeError, DecodeErrorKind, EncodeError};
pub use frame::{
    all_finite, decode_frame_into, encode_frame_flat_into, encode_frame_into, frame_message_len,
    FrameBuf, FrameForm, FrameHeader, MAX_FRAME_MARKERS,
};
pub use labels::{
    decode_labels, encode_labels_into, Labels, LayoutBook, LayoutChange, MAX_LAYOUTS_PER_SOURCE,
};
pub use output::{
    decode_blend_val, decode_components_into, decode_part_into, decode_state, decode_stream,
    encode_compact_into, encode_components_into, FlatSplit, PartHeader, State, StreamTag,
    ETHERNET_PAYLOAD, MAX_STREAM_NAME_BYTES,
};
pub use reply::{
    decode_reply, encode_challenge_into, encode_confirm_into, encode_control_into,
    encode_control_signed_into, encode_emotion_list_into, encode_error_into,
    encode_session_status_into, encode_status_into, EmotionList, Reply, SessionStatus, StatusValue,
};
pub use scan::{
    check_datagram, messages, Limits, Message, Messages, TimeTag, BUNDLE_DEPTH_CAP,
    DEFAULT_MAX_BUNDLE_DEPTH, MAX_ARRAY_DEPTH, MAX_UDP_PAYLOAD,
};
pub use timecode::{
    append_timecode_element, decode_timecode, encode_frame_timed_into, encode_timecode_into,
    CaptureClock, FrameTime, Irig, Smpte, TimecodeError, TimecodeRate, TIMECODE_MESSAGE_LEN,
};
