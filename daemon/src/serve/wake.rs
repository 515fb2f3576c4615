//! The processing thread's doorbell. The thread waits in one `poll` on the OSC frame socket,
//! which it reads itself (a frame is received, processed and sent on one thread, as a relay
//! would), and on this bell: every other producer (the NatNet and QTM sources' queue, control
//! commands, shutdown) rings it after handing something over.

use std::sync::Arc;

/// Wakes the processing thread from its `poll`. Ringing costs one write to an eventfd.
#[derive(Debug, Clone)]
pub struct Doorbell(Arc<mio::Waker>);

impl Doorbell {
    /// A bell on `waker`.
    pub fn new(waker: mio::Waker) -> Doorbell {
        Doorbell(Arc::new(waker))
    }

    /// Wakes the thread (a failure means it is gone, which its channel says too).
    pub fn ring(&self) {
        let _ = self.0.wake();
    }
}
