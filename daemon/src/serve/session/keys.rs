//! The operator's keyboard: one line per control (Enter alone starts or stops the take), read
//! on a thread of its own since stdin blocks.

use protocol::SessionControl;
use tokio::sync::mpsc;

use super::Request;

/// What a typed line asks for: Enter alone toggles recording (sent as start; the session
/// turns a start while recording into a stop).
fn control_of(line: &str) -> Option<SessionControl> {
    Some(match line.trim() {
        "" => SessionControl::Start,
        "x" | "stop" => SessionControl::Stop,
        "t" | "retake" => SessionControl::Retake,
        "s" | "skip" => SessionControl::Skip,
        "b" | "back" => SessionControl::Back,
        "f" | "finish" => SessionControl::Finish,
        "r" | "redo" => SessionControl::Redo,
        "?" | "status" => SessionControl::Status,
        _ => return None,
    })
}

/// Reads stdin until it closes, each line a control.
pub(super) fn spawn(tx: mpsc::Sender<Request>) {
    std::thread::spawn(move || {
        let mut line = String::new();
        while std::io::stdin().read_line(&mut line).is_ok_and(|n| n > 0) {
            match control_of(&line) {
                Some(control) => {
                    let request = Request {
                        control,
                        reply: None,
                    };
                    if tx.blocking_send(request).is_err() {
                        return;
                    }
                }
                None => eprintln!(
                    "keys: Enter starts/stops, x stop, t retake, s skip, b back, f finish, r redo what finish offers, ? status"
                ),
            }
            line.clear();
        }
    });
}
