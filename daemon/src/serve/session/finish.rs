//! Finish inside the sitting: training and analysis run off the runtime while the source and
//! the page run on, and what they say to redo is offered to the operator there and then.

use std::sync::Mutex;

use anyhow::{Context, Result};
use protocol::SessionControl;
use tokio::sync::mpsc;

use super::view::View;
use super::{answer, lock, Finisher, Request};
use crate::offline::session::advice::Advice;
use crate::offline::session::Sitting;

/// Trains and analyses off the runtime; meanwhile the status is answered and every other
/// control refused with the reason.
pub(super) async fn finishing(
    sitting: &Sitting,
    finish: &Finisher,
    rx: &mut mpsc::Receiver<Request>,
    view: &Mutex<View>,
) -> Result<Advice> {
    lock(view).finishing = true;
    let finish = finish.clone();
    let mut job = tokio::task::spawn_blocking(move || finish());
    let done = loop {
        tokio::select! {
            r = &mut job => break r.context("the training task failed"),
            Some(request) = rx.recv() => {
                let busy = "training and analysing: wait for what to redo".to_string();
                let refused = (request.control != SessionControl::Status).then_some(&busy);
                if let Some(reply) = request.reply {
                    let _ = reply.send(answer(sitting, request.control, refused));
                }
            }
        }
    };
    lock(view).finishing = false;
    done?
}

/// Offers to record again, now, what the finish said to redo; `true` when nothing is to redo
/// (the session is over).
pub(super) fn offer(
    sitting: &mut Sitting,
    advice: &Advice,
    view: &Mutex<View>,
    say: &mut (dyn FnMut(&str) + Send),
) -> Result<bool> {
    if advice.redo.is_empty() {
        return Ok(true);
    }
    sitting
        .offer(&advice.redo)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut v = lock(view);
    v.advice = advice.lines.clone();
    v.update(sitting);
    drop(v);
    say(&format!(
        "re-record {} now: r (or /session/redo, or the page's button) prompts just those \
         takes, then finish again; f (or /session/finish) ends the session with this model",
        match advice.redo.len() {
            1 => "that take".to_string(),
            n => format!("those {n} takes"),
        }
    ));
    Ok(false)
}
