//! One loopback harness for the demo, `emoshift bench` and the end-to-end tests: the daemon
//! in this process ([`Daemon`]), paced sources ([`source`]), receivers ([`Receiver`]), a
//! control client ([`ControlClient`]), a NatNet server standing in for Motive ([`motive`]), and
//! synthetic models and frames ([`synthetic`]).
//! Everything binds 127.0.0.1 only. `emoshift replay` sends through the same [`Source`] and
//! [`source::drive`], so a replay and a test source send alike.

pub mod control;
pub mod daemon;
pub mod motive;
pub mod receiver;
pub mod source;

pub use control::{counter, text, ControlClient};
pub use daemon::Daemon;
pub use engine::synthetic;
pub use receiver::{Collecting, Received, Receiver};
pub use source::Source;
