//! The session's controls from the network: the OSC control socket and the performer page
//! both hand the OSC message they got to [`admit`], which holds it to serve's rules (its
//! `Guard`: the allow-list by the sender's address, the secret as the last argument), passes
//! `/session/*` controls to the session and refuses anything else.

use std::net::SocketAddr;
use std::sync::Arc;

use protocol::Control;
use tokio::net::UdpSocket;
use tokio::sync::{mpsc, oneshot};
use tokio_util::sync::CancellationToken;

use super::{Answer, Request};
use crate::serve::guard::Guard;

/// One control message from `peer`, admitted or refused, and the session's answer; `None`
/// when the session is gone.
pub(super) async fn admit(
    guard: &Guard,
    tx: &mpsc::Sender<Request>,
    peer: SocketAddr,
    bytes: &[u8],
) -> Option<Answer> {
    let refused = |address: &str, why: String| {
        let mut osc = Vec::with_capacity(256);
        protocol::encode_error_into(address, &why, &mut osc);
        Answer {
            osc,
            refused: Some(why),
        }
    };
    match guard.admit(peer).and_then(|()| guard.decode(bytes)) {
        Ok(Control::Session(control)) => {
            let (reply, answer) = oneshot::channel();
            let request = Request {
                control,
                reply: Some(reply),
            };
            tx.send(request).await.ok()?;
            answer.await.ok()
        }
        Ok(other) => Some(refused(
            other.address(),
            "a calibration session takes /session/* controls only".into(),
        )),
        Err(refusal) => {
            guard.warn_refused(peer, "", &refusal);
            Some(refused("", refusal.to_string()))
        }
    }
}

/// The OSC control socket: each datagram through [`admit`], answered to its sender.
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
        let Some(answer) = admit(guard, &tx, peer, &buf[..len]).await else {
            return;
        };
        let _ = socket.send_to(&answer.osc, peer).await;
    }
}
