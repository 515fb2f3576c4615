//! The session's OSC control socket: `/session/*` controls admitted under serve's rules go to
//! the session and are answered with its reply; anything else is refused.

use std::sync::Arc;

use protocol::Control;
use tokio::net::UdpSocket;
use tokio::sync::{mpsc, oneshot};
use tokio_util::sync::CancellationToken;

use super::Request;
use crate::serve::guard::Guard;

/// The OSC control socket: admitted session controls to the session, answered with its reply;
/// anything else refused the way serve refuses it.
pub(super) async fn control_task(
    socket: Option<Arc<UdpSocket>>,
    guard: &Guard,
    tx: mpsc::Sender<Request>,
    stop: &CancellationToken,
) {
    let Some(socket) = socket else { return };
    let mut buf = vec![0u8; protocol::MAX_UDP_PAYLOAD + 1];
    loop {
        let (len, peer) = tokio::select! {
            () = stop.cancelled() => return,
            r = socket.recv_from(&mut buf) => match r {
                Ok(r) => r,
                Err(_) => continue,
            },
        };
        let admitted = guard.admit(peer).and_then(|()| guard.decode(&buf[..len]));
        let mut out = Vec::with_capacity(256);
        match admitted {
            Ok(Control::Session(control)) => {
                let (reply, answer) = oneshot::channel();
                let request = Request {
                    control,
                    reply: Some(reply),
                };
                if tx.send(request).await.is_err() {
                    return;
                }
                match answer.await {
                    Ok(bytes) => out = bytes,
                    Err(_) => return,
                }
            }
            Ok(other) => {
                let why = "a calibration session takes /session/* controls only";
                protocol::encode_error_into(other.address(), why, &mut out);
            }
            Err(refusal) => {
                guard.warn_refused(peer, "", &refusal);
                protocol::encode_error_into("", &refusal.to_string(), &mut out);
            }
        }
        let _ = socket.send_to(&out, peer).await;
    }
}
