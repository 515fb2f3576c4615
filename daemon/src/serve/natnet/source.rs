//! `serve`'s end of the NatNet link: each frame into the processing queue (the same queue,
//! buffers and latest-frame-wins rule as the OSC frame socket), the session's status into
//! `/status`.

use std::sync::{Arc, Mutex};

use tokio_util::sync::CancellationToken;

use super::link::{Link, Session};
use crate::serve::processing::InFrame;
use crate::serve::server::Queue;
use crate::serve::stats::Stats;

/// Runs the link until `shutdown`, feeding `queue` and `stats`.
pub(in crate::serve) async fn run(
    link: Link,
    queue: Queue,
    stats: Arc<Mutex<Stats>>,
    shutdown: CancellationToken,
) {
    let mut on_frame = |bytes: &[u8], received, session: &Arc<Session>| {
        let mut buf = queue.buffer();
        buf.extend_from_slice(bytes);
        queue.push(InFrame {
            peer: session.server,
            bytes: buf,
            received,
            natnet: Some(Arc::clone(session)),
        });
    };
    let mut on_status = |status: &super::NatNetStatus| {
        if let Ok(mut s) = stats.lock() {
            s.natnet = Some(status.clone());
        }
    };
    if let Err(e) = link.run(shutdown, &mut on_frame, &mut on_status).await {
        tracing::error!(target: "emoshift", error = %format!("{e:#}"), "natnet: the source stopped");
    }
}
