//! One loopback harness for the demo, `emoshift bench` and the end-to-end tests: the daemon
//! in this process ([`Daemon`]), paced sources ([`source`]), receivers ([`Receiver`]), a
//! control client ([`ControlClient`]), a NatNet server standing in for Motive ([`motive`]),
//! what a client sees of the emotion edit ([`probe`]), a take replayed while a control script
//! runs and a subscribed client collects ([`scripted`]), and synthetic models and frames
//! ([`synthetic`]).
//! Everything binds 127.0.0.1 only. `emoshift replay` sends through the same [`Source`] and
//! [`source::drive`], so a replay and a test source send alike.

pub mod control;
pub mod daemon;
pub mod motive;
pub mod probe;
pub mod receiver;
pub mod scripted;
pub mod source;

pub use control::{counter, text, ControlClient};
pub use daemon::Daemon;
pub use engine::synthetic;
pub use receiver::{Collecting, Received, Receiver};
pub use scripted::{Cue, Subscribed};
pub use source::Source;

/// Runs `work` on a current-thread runtime of its own: the client side of a harness run (the
/// daemon has its own runtime).
///
/// # Errors
/// The runtime cannot start, or `work` fails.
pub fn block_on<T>(
    work: impl std::future::Future<Output = anyhow::Result<T>>,
) -> anyhow::Result<T> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build();
    anyhow::Context::context(runtime, "cannot start the runtime")?.block_on(work)
}
