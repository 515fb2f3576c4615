//! NatNet as a source for `serve` (and `record`): OptiTrack Motive's stream taken directly,
//! no bridge. A small shell over the engine: [`link`] runs protocol's sans-IO NatNet client
//! with sockets and hands each NAT_FRAMEOFDATA, with the [`Session`] that decodes it, to the
//! processing queue; the engine turns each markerset into a stream
//! ([`crate::engine::Pipeline::handle_natnet`]), beside the OSC sources.
//!
//! - [`config`]: the `natnet*` keys;
//! - [`link`]: sockets, connect, model definitions, keep-alive, echo, reconnects;
//! - [`status`]: what `/status` and the log say about it.

pub mod config;
pub mod link;
pub(super) mod source;
pub mod status;
mod wire;

pub use config::{NatNetConfig, RawNatNet};
pub use link::{Link, Session};
pub use status::NatNetStatus;
