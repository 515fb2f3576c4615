//! A daemon on loopback with a client subscribed to its output ([`Subscribed`]), a take
//! replayed into it at its rate while a control script runs ([`Subscribed::replay`], with
//! [`Cue`]s such as an emotion [`sweep`]), or looping until the caller says stop
//! ([`Subscribed::loop_until`]); [`Subscribed::run`] stops the daemon whatever the run gave.
//! The demo's live part is these calls; a test or a script that edits a stream over time makes
//! the same ones and asserts on what the client's sink kept.

use std::collections::HashMap;
use std::future::Future;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use ica_core::model::IcaModel;
use protocol::{Control, Profile};
use replay::Take;

use super::source::{play_take, play_take_timed};
use super::{ControlClient, Daemon, Receiver};
use crate::serve::Config;

/// How long a replay waits after its last frame for the last outputs to arrive.
pub const SETTLE: Duration = Duration::from_millis(300);

/// How long [`Subscribed::stop`] waits for the daemon to finish.
pub const STOP_WITHIN: Duration = Duration::from_secs(2);

/// A control sent `at` after a replay starts (zero: confirmed before its first frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Cue {
    /// When, after the replay's start.
    pub at: Duration,
    /// What.
    pub control: Control,
}

/// The cues of an emotion sweep: the emotion ramps over one `share` to each of `targets` in
/// turn, at full amount, one `share` each (no cue without targets).
pub fn sweep(targets: &[String], share: Duration) -> Vec<Cue> {
    let Some(first) = targets.first() else {
        return Vec::new();
    };
    let start = [
        Control::Ramp(share.as_secs_f32()),
        Control::Target(first.clone()),
        Control::Amount(1.0),
    ];
    let cue = |at, control| Cue { at, control };
    let later = (1u32..).zip(&targets[1..]);
    start
        .into_iter()
        .map(|c| cue(Duration::ZERO, c))
        .chain(later.map(|(i, t)| cue(share * i, Control::Target(t.clone()))))
        .collect()
}

/// What a replay sent.
#[derive(Debug)]
pub struct Replayed {
    /// When each frame number went.
    pub sent: HashMap<i64, Instant>,
    /// How many frames the pacer sent late.
    pub late_sends: u64,
    /// The take's rate, Hz.
    pub rate_hz: f64,
}

/// A daemon on loopback, a control client, and a client subscribed to the daemon's output
/// (renewing its lease while it lives). Start the client's
/// [`collect`](Receiver::collect) before a replay, stop it after.
#[derive(Debug)]
pub struct Subscribed {
    /// The daemon.
    pub daemon: Daemon,
    /// Its control client (the script's cues go through it).
    pub control: ControlClient,
    /// The subscribed client.
    pub client: Receiver,
}

impl Subscribed {
    /// Starts a daemon from `config` serving `model`, and subscribes a client with `profile`.
    ///
    /// # Errors
    /// As [`Daemon::start_with`], or the daemon did not confirm the subscription.
    pub async fn start(config: Config, model: IcaModel, profile: Profile) -> Result<Subscribed> {
        let daemon = Daemon::start_with(config, model).await?;
        let control = ControlClient::new(daemon.control).await?;
        let client = Receiver::subscribe(&control, profile).await?;
        Ok(Subscribed {
            daemon,
            control,
            client,
        })
    }

    /// [`Subscribed::start`], then `work` on it, then [`Subscribed::stop`] whatever `work` gave.
    ///
    /// # Errors
    /// As [`Subscribed::start`], what `work` gave, or as [`Subscribed::stop`].
    pub async fn run<T>(
        config: Config,
        model: IcaModel,
        profile: Profile,
        work: impl AsyncFnOnce(&Subscribed) -> Result<T>,
    ) -> Result<T> {
        let live = Subscribed::start(config, model, profile).await?;
        let result = work(&live).await;
        live.stop().await?;
        result
    }

    /// Stops the daemon, waiting up to [`STOP_WITHIN`]. Call it whatever the run gave, so a
    /// failed run leaves no daemon behind (dropping it only asks it to stop).
    ///
    /// # Errors
    /// As [`Daemon::stop`].
    pub async fn stop(self) -> Result<()> {
        self.daemon.stop(STOP_WITHIN).await
    }

    /// Replays `frames` frames of `take` (looping) at its rate, confirming each cue of `script`
    /// (in order of time) when it is due, then waits [`SETTLE`].
    ///
    /// # Errors
    /// The daemon refused a cue or did not answer, or the replay failed.
    pub async fn replay(&self, take: Arc<Take>, frames: usize, script: &[Cue]) -> Result<Replayed> {
        let (first, later): (Vec<&Cue>, Vec<&Cue>) = script.iter().partition(|c| c.at.is_zero());
        for cue in first {
            self.control.confirm(&cue.control).await?;
        }
        let (to, rate_hz, start) = (
            self.daemon.frames,
            take.rate_hz,
            tokio::time::Instant::now(),
        );
        let sender = tokio::task::spawn_blocking(move || play_take_timed(&take, to, frames));
        for cue in later {
            tokio::time::sleep_until(start + cue.at).await;
            self.control.confirm(&cue.control).await?;
        }
        let (sent, late_sends) = sender.await.context("the sender panicked")??;
        tokio::time::sleep(SETTLE).await;
        Ok(Replayed {
            sent,
            late_sends,
            rate_hz,
        })
    }

    /// Replays `take` at its rate in a loop until `until` ends.
    ///
    /// # Errors
    /// The replay failed.
    pub async fn loop_until(&self, take: Arc<Take>, until: impl Future<Output = ()>) -> Result<()> {
        let stop = Arc::new(AtomicBool::new(false));
        let (to, stopped) = (self.daemon.frames, Arc::clone(&stop));
        let sender =
            tokio::task::spawn_blocking(move || play_take(&take, to, None, &stopped, |_| {}));
        let ended = tokio::select! {
            () = until => Ok(()),
            r = sender => r.context("the sender panicked").and_then(|r| r.map(drop)),
        };
        stop.store(true, Ordering::Relaxed);
        ended
    }
}
#[cfg(test)]
mod tests;
