//! Control messages to the daemon and its replies, decoded and encoded with rosc.

use rosc::{OscMessage, OscPacket, OscType};

use crate::address as a;
use crate::error::DecodeError;
use crate::scan::{check_datagram, Limits};

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
    /// `/subscribe ,is`: send `profile` to the sender's host at `port`.
    Subscribe {
        /// UDP port on the sender's host, 1..=65535.
        port: u16,
        /// Output profile.
        profile: Profile,
    },
    /// `/unsubscribe ,i`: stop sending to the sender's host at `port`.
    Unsubscribe {
        /// UDP port on the sender's host.
        port: u16,
    },
    /// `/model/load ,s`: path of a model file.
    ModelLoad(String),
    /// `/record/start ,s` or `,ss`: path to record the edited stream to, and optionally a
    /// second path for the raw input beside it.
    RecordStart {
        /// The edited stream's file.
        path: String,
        /// The raw input's file, if wanted.
        raw: Option<String>,
    },
    /// `/record/stop`.
    RecordStop,
    /// `/status`: answered with `/status/confirm` and the counters.
    Status,
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
    #[error("{address}: {what} {value} is out of range")]
    OutOfRange {
        /// The control address.
        address: &'static str,
        /// Which argument.
        what: &'static str,
        /// The value received, printed.
        value: String,
    },
    /// `/subscribe` named an unknown profile.
    #[error("unknown profile {name:?}, expected compact, flat-split or components")]
    UnknownProfile {
        /// The name received.
        name: String,
    },
}

/// Decodes one message (not a bundle) with rosc after the crate's own pre-scan: the generic
/// path for everything that is not a frame. Crate-private: rosc's types stay inside.
///
/// # Errors
/// Any structural [`DecodeError`]; [`DecodeError::BadAddress`] for a bundle.
pub(crate) fn decode_osc(msg: &[u8]) -> Result<OscMessage, DecodeError> {
    if msg.first() == Some(&b'#') {
        return Err(DecodeError::BadAddress { offset: 0 });
    }
    check_datagram(msg, &Limits::default())?;
    match rosc::decoder::decode_udp(msg) {
        Ok((&[], OscPacket::Message(m))) => Ok(m),
        // the pre-scan accepts only what rosc decodes whole; keep a typed error regardless
        _ => Err(DecodeError::WrongTypeTags),
    }
}

/// Decodes a control message.
///
/// # Errors
/// [`ControlError`] naming the address and the bad argument; the daemon sends its text back
/// with [`crate::encode_error_into`].
pub fn decode_control(msg: &[u8]) -> Result<Control, ControlError> {
    let m = decode_osc(msg)?;
    parse_control(&m.addr, m.args)
}

fn tags_of(args: &[OscType]) -> String {
    args.iter()
        .map(|t| match t {
            OscType::Int(_) => 'i',
            OscType::Float(_) => 'f',
            OscType::String(_) => 's',
            OscType::Blob(_) => 'b',
            OscType::Long(_) => 'h',
            OscType::Double(_) => 'd',
            OscType::Time(_) => 't',
            OscType::Bool(true) => 'T',
            OscType::Bool(false) => 'F',
            OscType::Nil => 'N',
            OscType::Inf => 'I',
            OscType::Char(_) => 'c',
            OscType::Color(_) => 'r',
            OscType::Midi(_) => 'm',
            OscType::Array(_) => '[',
        })
        .collect()
}

/// A float argument; ints and doubles are accepted too, as hand-typed senders use them.
fn float(t: &OscType) -> Option<f32> {
    match *t {
        OscType::Float(f) => Some(f),
        OscType::Double(d) => Some(d as f32),
        OscType::Int(i) => Some(i as f32),
        _ => None,
    }
}

fn finite(address: &'static str, what: &'static str, v: f32) -> Result<f32, ControlError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ControlError::OutOfRange {
            address,
            what,
            value: v.to_string(),
        })
    }
}

fn component(address: &'static str, i: i32) -> Result<u32, ControlError> {
    u32::try_from(i).map_err(|_| ControlError::OutOfRange {
        address,
        what: "component",
        value: i.to_string(),
    })
}

fn port(address: &'static str, p: i32) -> Result<u16, ControlError> {
    match u16::try_from(p) {
        Ok(p) if p != 0 => Ok(p),
        _ => Err(ControlError::OutOfRange {
            address,
            what: "port",
            value: p.to_string(),
        }),
    }
}

/// `(name, weight)` pairs of `/emotion/mix`: `None` for a wrong type, an error for a bad weight.
fn mix(
    address: &'static str,
    args: &[OscType],
) -> Option<Result<Vec<(String, f32)>, ControlError>> {
    let mut out = Vec::with_capacity(args.len() / 2);
    for pair in args.chunks_exact(2) {
        let OscType::String(name) = &pair[0] else {
            return None;
        };
        let weight = float(&pair[1])?;
        if !(weight.is_finite() && weight >= 0.0) {
            return Some(Err(ControlError::OutOfRange {
                address,
                what: "weight",
                value: weight.to_string(),
            }));
        }
        out.push((name.clone(), weight));
    }
    if out.iter().all(|(_, w)| *w == 0.0) {
        return Some(Err(ControlError::OutOfRange {
            address,
            what: "weights",
            value: "all 0".into(),
        }));
    }
    Some(Ok(out))
}

/// Parses the arguments of a control address (also used for `/confirm` echoes).
pub(crate) fn parse_control(address: &str, args: Vec<OscType>) -> Result<Control, ControlError> {
    let Some((addr, expected)) = CONTROL_SHAPES.iter().find(|(c, _)| *c == address) else {
        return Err(ControlError::UnknownAddress {
            address: address.to_string(),
        });
    };
    let wrong = || ControlError::WrongArgs {
        address: addr,
        expected,
        got: tags_of(&args),
    };
    let c = match (*addr, args.as_slice()) {
        (a::EMOTION_TARGET, [OscType::String(s)]) => Control::Target(s.clone()),
        (a::EMOTION_AMOUNT, [v]) => {
            Control::Amount(finite(addr, "amount", float(v).ok_or_else(wrong)?)?)
        }
        (a::EMOTION_RAMP, [v]) => {
            let s = finite(addr, "seconds", float(v).ok_or_else(wrong)?)?;
            if s < 0.0 {
                return Err(ControlError::OutOfRange {
                    address: addr,
                    what: "seconds",
                    value: s.to_string(),
                });
            }
            Control::Ramp(s)
        }
        (a::EMOTION_ALPHA, [OscType::Int(i), v]) => Control::Alpha {
            component: component(addr, *i)?,
            value: finite(addr, "value", float(v).ok_or_else(wrong)?)?,
        },
        (a::COMPONENT_GAIN, [OscType::Int(i), v]) => Control::Gain {
            component: component(addr, *i)?,
            gain: finite(addr, "gain", float(v).ok_or_else(wrong)?)?,
        },
        (a::EMOTION_MIX, pairs) if !pairs.is_empty() && pairs.len() % 2 == 0 => {
            Control::Mix(mix(addr, pairs).ok_or_else(wrong)??)
        }
        (a::EMOTION_LIST, []) => Control::EmotionList,
        (a::BYPASS, [OscType::Int(i)]) => Control::Bypass(*i != 0),
        (a::BYPASS, [OscType::Bool(b)]) => Control::Bypass(*b),
        (a::SUBSCRIBE, [OscType::Int(p), OscType::String(name)]) => Control::Subscribe {
            port: port(addr, *p)?,
            profile: Profile::parse(name)
                .ok_or_else(|| ControlError::UnknownProfile { name: name.clone() })?,
        },
        (a::UNSUBSCRIBE, [OscType::Int(p)]) => Control::Unsubscribe {
            port: port(addr, *p)?,
        },
        (a::MODEL_LOAD, [OscType::String(s)]) => Control::ModelLoad(s.clone()),
        (a::RECORD_START, [OscType::String(s)]) => Control::RecordStart {
            path: s.clone(),
            raw: None,
        },
        (a::RECORD_START, [OscType::String(s), OscType::String(raw)]) => Control::RecordStart {
            path: s.clone(),
            raw: Some(raw.clone()),
        },
        (a::RECORD_STOP, []) => Control::RecordStop,
        (a::STATUS, []) => Control::Status,
        _ => return Err(wrong()),
    };
    Ok(c)
}

/// Control addresses and the type tags each takes (for error messages).
const CONTROL_SHAPES: [(&str, &str); 14] = [
    (a::EMOTION_TARGET, ",s"),
    (a::EMOTION_AMOUNT, ",f"),
    (a::EMOTION_RAMP, ",f"),
    (a::EMOTION_MIX, ",sf or ,sfsf..."),
    (a::EMOTION_LIST, ","),
    (a::EMOTION_ALPHA, ",if"),
    (a::COMPONENT_GAIN, ",if"),
    (a::BYPASS, ",i"),
    (a::SUBSCRIBE, ",is"),
    (a::UNSUBSCRIBE, ",i"),
    (a::MODEL_LOAD, ",s"),
    (a::RECORD_START, ",s or ,ss"),
    (a::RECORD_STOP, ","),
    (a::STATUS, ","),
];

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
        }
    }

    /// The arguments in canonical wire types (as sent, and as echoed by the confirm).
    pub(crate) fn args(&self) -> Vec<OscType> {
        use OscType as T;
        match self {
            Control::Target(s) | Control::ModelLoad(s) => vec![T::String(s.clone())],
            Control::RecordStart { path, raw } => std::iter::once(path)
                .chain(raw)
                .map(|s| T::String(s.clone()))
                .collect(),
            Control::Amount(v) | Control::Ramp(v) => vec![T::Float(*v)],
            Control::Alpha {
                component,
                value: v,
            }
            | Control::Gain { component, gain: v } => {
                vec![T::Int(*component as i32), T::Float(*v)]
            }
            Control::Bypass(b) => vec![T::Int(i32::from(*b))],
            Control::Subscribe { port, profile } => {
                vec![
                    T::Int(i32::from(*port)),
                    T::String(profile.as_str().to_string()),
                ]
            }
            Control::Unsubscribe { port } => vec![T::Int(i32::from(*port))],
            Control::Mix(pairs) => pairs
                .iter()
                .flat_map(|(n, w)| [T::String(n.clone()), T::Float(*w)])
                .collect(),
            Control::RecordStop | Control::Status | Control::EmotionList => vec![],
        }
    }
}
