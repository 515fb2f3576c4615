//! NatNet as a source for `serve` and `record`: OptiTrack Motive's stream taken directly, no
//! bridge. [`link`] runs protocol's sans-IO NatNet client with sockets; each markerset of each
//! frame ([`frames`]) goes to the owner's sink as one stream's [`engine::SourceFrame`], beside
//! the OSC sources. What only NatNet knows stays here: the model definitions (markerset names
//! and labels, occlusion from labelled markers), the server's clock offset, its frame rate.
//!
//! - [`config`]: the `natnet*` keys;
//! - [`frames`]: a NAT_FRAMEOFDATA as source frames, sans-IO;
//! - [`link`]: sockets, connect, model definitions, keep-alive, echo, reconnects;
//! - [`status`]: what `/status` and the log say about it.

pub mod config;
pub mod frames;
pub mod link;
pub mod status;
mod wire;

pub use config::{NatNetConfig, RawNatNet};
pub use link::{Link, Session};
pub use status::NatNetStatus;
