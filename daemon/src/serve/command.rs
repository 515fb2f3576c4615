//! The one message between the control task and the processing thread: a [`Command`] with the
//! channel its [`Reply`] goes back on. Applied between frames, so a frame never sees a half
//! applied setting.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::Control;
use tokio::sync::oneshot;

/// What the control task asks of the processing thread.
#[derive(Debug)]
pub(crate) enum Command {
    /// An edit setting, for every stream.
    Edit(Control),
    /// `/subscribe` or `/unsubscribe` from a peer.
    Client {
        /// Who asked.
        peer: SocketAddr,
        /// The control message.
        control: Control,
    },
    /// Swap in a validated model.
    SetModel(Arc<IcaModel>),
    /// Start recording the edited stream to `path`, and the raw input to `raw`.
    RecordStart {
        /// The edited stream's file.
        path: PathBuf,
        /// The raw input's file.
        raw: Option<PathBuf>,
        /// Replace files that exist.
        overwrite: bool,
        /// The OSC peer that asked, told by `/emoshift/error` if the recording stops by
        /// itself (a full disk); `None` from the monitor page, which reads `/status`.
        controller: Option<SocketAddr>,
    },
    /// Stop recording.
    RecordStop,
}

/// Why a command was refused: the text `/emoshift/error` carries.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum Refusal {
    /// Not a control message emoshift accepts (malformed, unknown address, bad argument).
    #[error("{0}")]
    Invalid(String),
    /// The engine refused an edit (unknown emotion, component out of range, ...).
    #[error("{0}")]
    Edit(String),
    /// A subscription change was refused.
    #[error("{0}")]
    Client(String),
    /// A recording could not start or stop.
    #[error("{0}")]
    Record(String),
    /// A model file could not be loaded.
    #[error("{0}")]
    Model(String),
    /// The peer is not in `control_allow`.
    #[error("control from {0} is not allowed: add its network to control_allow (--control-allow) on the daemon")]
    NotAllowed(std::net::IpAddr),
    /// A mutating control without the shared secret.
    #[error("this control needs the shared secret as its last argument: append control_secret as a string")]
    Secret,
    /// The processing thread did not take the command (queue full or stopped).
    #[error("the processing thread is busy or stopped: try again in a moment")]
    Busy,
    /// The processing thread did not answer in time.
    #[error("no answer from the processing thread")]
    Timeout,
    /// The daemon is shutting down.
    #[error("shutting down")]
    ShuttingDown,
}

impl Refusal {
    /// A refusal whose text is an error and all its causes, each once.
    pub(crate) fn from_error(
        make: fn(String) -> Refusal,
        e: &(dyn std::error::Error + 'static),
    ) -> Refusal {
        let mut text = e.to_string();
        let mut cause = e.source();
        while let Some(c) = cause {
            text.push_str(": ");
            text.push_str(&c.to_string());
            cause = c.source();
        }
        make(text)
    }
}

/// The processing thread's answer to a [`Command`].
pub(crate) type Reply = Result<(), Refusal>;

/// A [`Command`] and where its [`Reply`] goes.
#[derive(Debug)]
pub(crate) struct Request {
    /// What to do.
    pub(crate) command: Command,
    /// Where the answer goes.
    pub(crate) reply: oneshot::Sender<Reply>,
}
