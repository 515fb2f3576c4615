//! Control messages to the daemon: the [`Control`] values, their documented limits, and
//! their decoding ([`decode_control`], with a shared secret [`decode_control_with_secret`]).
//! rosc decodes and encodes; its types stay inside the crate.

mod parse;

use rosc::OscType;

use crate::address as a;
use crate::error::DecodeError;

pub use parse::{decode_control, decode_control_with_secret};
pub(crate) use parse::{decode_osc, parse_control};

/// Largest ramp, seconds: a longer glide would look like a frozen setting.
pub const MAX_RAMP_S: f32 = 60.0;
/// Largest |gain| of `/component/gain`.
pub const MAX_GAIN: f32 = 10.0;
/// Largest |value| of `/emotion/alpha`, in component units (unit variance): far past any face.
pub const MAX_ALPHA: f32 = 100.0;
/// Largest weight of one emotion in `/emotion/mix` (weights are normalised to sum 1).
pub const MAX_MIX_WEIGHT: f32 = 1_000.0;
/// Longest emotion, performer or secret name, bytes.
pub const MAX_NAME_BYTES: usize = 256;
/// Longest path of `/model/load` and `/record/start`, bytes.
pub const MAX_PATH_BYTES: usize = 4_096;

/// Output profile a client subscribes to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Profile {
    /// `,ihbb` frame + `/emoshift/state ,sf` in one bundle.
    Compact,
    /// `/mocap/part` messages of plain floats, each within the part size.
    FlatSplit,
    /// `/emoshift/components` and the VMC blend messages.
    Components,
}

impl Profile {
    /// Every profile.
    pub const ALL: [Profile; 3] = [Profile::Compact, Profile::FlatSplit, Profile::Components];

    /// The wire name: `compact`, `flat-split` or `components`.
    pub fn as_str(self) -> &'static str {
        match self {
            Profile::Compact => "compact",
            Profile::FlatSplit => "flat-split",
            Profile::Components => "components",
        }
    }

    /// Parses a wire name.
    pub fn parse(name: &str) -> Option<Profile> {
        Profile::ALL.into_iter().find(|p| p.as_str() == name)
    }
}

/// A decoded control message.
#[derive(Debug, Clone, PartialEq)]
pub enum Control {
    /// `/emotion/target ,s`: the emotion to move towards.
    Target(String),
    /// `/emotion/amount ,f`: how far to move, finite.
    Amount(f32),
    /// `/emotion/ramp ,f`: seconds to reach a new amount, finite and >= 0.
    Ramp(f32),
    /// `/emotion/mix ,sfsf...`: move towards a blend of named emotions, each with a weight
    /// (finite, >= 0, not all 0; the daemon normalises them to sum 1).
    Mix(Vec<(String, f32)>),
    /// `/emotion/list ,`: answered with `/emotion/list/confirm` (see
    /// [`crate::encode_emotion_list_into`]).
    EmotionList,
    /// `/emotion/alpha ,if`: raw translate of one component.
    Alpha {
        /// Component index.
        component: u32,
        /// Translation, finite.
        value: f32,
    },
    /// `/component/gain ,if`: gain of one component.
    Gain {
        /// Component index.
        component: u32,
        /// Gain, finite.
        gain: f32,
    },
    /// `/bypass ,i`: non-zero turns the edit off (frames pass through).
    Bypass(bool),
    /// `/subscribe ,is`, `,iss`, `,isi` or `,issi`: send `profile` to the sender's host at
    /// `port`, every stream or only `performer`'s. Sent again within the lease, it renews the
    /// subscription. From beyond loopback the daemon first answers `/subscribe/challenge ,i`
    /// and subscribes when the same address sends the request again with that `cookie`.
    Subscribe {
        /// UDP port on the sender's host, 1..=65535.
        port: u16,
        /// Output profile.
        profile: Profile,
        /// Only this performer's stream (by its name, as `/emoshift/stream` carries it).
        performer: Option<String>,
        /// The cookie of `/subscribe/challenge`, echoed.
        cookie: Option<i32>,
    },
    /// `/unsubscribe ,i`: stop sending to the sender's host at `port`.
    Unsubscribe {
        /// UDP port on the sender's host.
        port: u16,
    },
    /// `/model/load ,s`: path of a model file.
    ModelLoad(String),
    /// `/record/start ,s`, `,ss`, `,si` or `,ssi`: path to record the edited stream to,
    /// optionally a second path for the raw input beside it, and a non-zero `i` to overwrite
    /// files that exist.
    RecordStart {
        /// The edited stream's file.
        path: String,
        /// The raw input's file, if wanted.
        raw: Option<String>,
        /// Replace files that exist (refused otherwise).
        overwrite: bool,
    },
    /// `/record/stop`.
    RecordStop,
    /// `/status`: answered with `/status/confirm` and the counters.
    Status,
    /// `/session/...`: a calibration session's control (`emoshift session`; `serve` refuses
    /// it).
    Session(SessionControl),
}

/// The controls of a calibration session (`emoshift session`), none with arguments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SessionControl {
    /// `/session/start`: record the prompted take.
    Start,
    /// `/session/stop`: stop recording and check the take.
    Stop,
    /// `/session/retake`: record the refused take again, or the last accepted one.
    Retake,
    /// `/session/skip`: leave the prompted take out.
    Skip,
    /// `/session/back`: go back one take.
    Back,
    /// `/session/finish`: train and analyse (after a finish that offered a redo: end the
    /// session with the model as it is).
    Finish,
    /// `/session/redo`: record again, now, the takes the last finish said to redo.
    Redo,
    /// `/session/status`: answered with `/session/status/confirm ,iiisss` (see
    /// [`crate::encode_session_status_into`]).
    Status,
}

impl SessionControl {
    /// Every session control.
    pub const ALL: [SessionControl; 8] = [
        SessionControl::Start,
        SessionControl::Stop,
        SessionControl::Retake,
        SessionControl::Skip,
        SessionControl::Back,
        SessionControl::Finish,
        SessionControl::Redo,
        SessionControl::Status,
    ];

    /// Its OSC address.
    pub fn address(self) -> &'static str {
        match self {
            SessionControl::Start => a::SESSION_START,
            SessionControl::Stop => a::SESSION_STOP,
            SessionControl::Retake => a::SESSION_RETAKE,
            SessionControl::Skip => a::SESSION_SKIP,
            SessionControl::Back => a::SESSION_BACK,
            SessionControl::Finish => a::SESSION_FINISH,
            SessionControl::Redo => a::SESSION_REDO,
            SessionControl::Status => a::SESSION_STATUS,
        }
    }

    /// The control at `address`, if it is one.
    pub fn parse(address: &str) -> Option<SessionControl> {
        SessionControl::ALL
            .into_iter()
            .find(|c| c.address() == address)
    }
}

/// Why a control message was refused; its `Display` text is what `/emoshift/error` carries.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControlError {
    /// Not a well-formed single OSC message.
    #[error("malformed message: {0}")]
    Packet(#[from] DecodeError),
    /// Well-formed, but not a control address.
    #[error("unknown control address {address}")]
    UnknownAddress {
        /// The address received.
        address: String,
    },
    /// The arguments do not have the shape the address takes.
    #[error("{address} takes {expected}, got ,{got}")]
    WrongArgs {
        /// The control address.
        address: &'static str,
        /// Accepted type tags, e.g. `,if`.
        expected: &'static str,
        /// Type tags received.
        got: String,
    },
    /// An argument has the right type but a bad value.
    #[error("{address}: {what} {value} is out of range ({range})")]
    OutOfRange {
        /// The control address.
        address: &'static str,
        /// Which argument.
        what: &'static str,
        /// The value received, printed.
        value: String,
        /// The accepted range, printed.
        range: &'static str,
    },
    /// `/subscribe` named an unknown profile.
    #[error("unknown profile {name:?}, expected compact, flat-split or components")]
    UnknownProfile {
        /// The name received.
        name: String,
    },
}

impl Control {
    /// The control's OSC address.
    pub fn address(&self) -> &'static str {
        match self {
            Control::Target(_) => a::EMOTION_TARGET,
            Control::Amount(_) => a::EMOTION_AMOUNT,
            Control::Ramp(_) => a::EMOTION_RAMP,
            Control::Mix(_) => a::EMOTION_MIX,
            Control::EmotionList => a::EMOTION_LIST,
            Control::Alpha { .. } => a::EMOTION_ALPHA,
            Control::Gain { .. } => a::COMPONENT_GAIN,
            Control::Bypass(_) => a::BYPASS,
            Control::Subscribe { .. } => a::SUBSCRIBE,
            Control::Unsubscribe { .. } => a::UNSUBSCRIBE,
            Control::ModelLoad(_) => a::MODEL_LOAD,
            Control::RecordStart { .. } => a::RECORD_START,
            Control::RecordStop => a::RECORD_STOP,
            Control::Status => a::STATUS,
            Control::Session(c) => c.address(),
        }
    }

    /// Whether it changes what the daemon does for everyone (the edit, the model, the
    /// recording): these carry the shared secret when one is configured. Reading the state and
    /// one's own subscription do not.
    pub fn is_mutating(&self) -> bool {
        !matches!(
            self,
            Control::Status
                | Control::Session(SessionControl::Status)
                | Control::EmotionList
                | Control::Subscribe { .. }
                | Control::Unsubscribe { .. }
        )
    }

    /// The arguments in canonical wire types (as sent, and as echoed by the confirm).
    pub(crate) fn args(&self) -> Vec<OscType> {
        use OscType as T;
        match self {
            Control::Target(s) | Control::ModelLoad(s) => vec![T::String(s.clone())],
            Control::RecordStart {
                path,
                raw,
                overwrite,
            } => {
                let mut args: Vec<OscType> = std::iter::once(path)
                    .chain(raw)
                    .map(|s| T::String(s.clone()))
                    .collect();
                if *overwrite {
                    args.push(T::Int(1));
                }
                args
            }
            Control::Amount(v) | Control::Ramp(v) => vec![T::Float(*v)],
            Control::Alpha {
                component,
                value: v,
            }
            | Control::Gain { component, gain: v } => {
                vec![T::Int(*component as i32), T::Float(*v)]
            }
            Control::Bypass(b) => vec![T::Int(i32::from(*b))],
            Control::Subscribe {
                port,
                profile,
                performer,
                cookie,
            } => {
                let mut args = vec![
                    T::Int(i32::from(*port)),
                    T::String(profile.as_str().to_string()),
                ];
                args.extend(performer.iter().map(|p| T::String(p.clone())));
                args.extend(cookie.iter().map(|&c| T::Int(c)));
                args
            }
            Control::Unsubscribe { port } => vec![T::Int(i32::from(*port))],
            Control::Mix(pairs) => pairs
                .iter()
                .flat_map(|(n, w)| [T::String(n.clone()), T::Float(*w)])
                .collect(),
            Control::RecordStop | Control::Status | Control::EmotionList | Control::Session(_) => {
                vec![]
            }
        }
    }
}
