//! Replies to control messages, and control messages as a client sends them; rosc encodes.
//!
//! Every control message is answered to its sender: `<address>/confirm` echoing the accepted
//! arguments in canonical types, or `/emoshift/error ,ss` (address, message). `/status` is
//! answered by `/status/confirm` with name/value pairs, each an OSC string (its name) followed
//! by an `h` (int64, counters) or an `s` (text: stream names, models, addresses), in the order
//! the daemon lists them. A `/subscribe` from beyond loopback is answered by
//! `/subscribe/challenge ,i` (a cookie to echo).

use rosc::{OscMessage, OscPacket, OscType};

use crate::address as a;
use crate::control::{decode_osc, parse_control, Control, ControlError};
use crate::error::DecodeError;

/// The emotion space a daemon's model holds, as `/emotion/list/confirm` carries it.
#[derive(Debug, Clone, PartialEq)]
pub struct EmotionList {
    /// The emotion components (the space's axes).
    pub components: Vec<u32>,
    /// Each emotion's name and level vector over `components`.
    pub emotions: Vec<(String, Vec<f32>)>,
}

/// A decoded reply from the daemon.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// `/emotion/list/confirm`: the emotion names and their level vectors.
    EmotionList(EmotionList),
    /// `<address>/confirm` of an accepted control, with its echoed arguments.
    Confirm(Control),
    /// `/status/confirm`: (name, value) pairs, in the daemon's order.
    Status(Vec<(String, StatusValue)>),
    /// `/subscribe/challenge ,i`: echo this cookie in the `/subscribe` to be subscribed.
    Challenge(i32),
    /// `/session/status/confirm ,iiisss`: where a calibration session is.
    SessionStatus(SessionStatus),
    /// `/emoshift/error ,ss`.
    Error {
        /// Address of the refused message.
        address: String,
        /// Why it was refused.
        message: String,
    },
}

/// Where a calibration session (`emoshift session`) is, as `/session/status/confirm ,iiisss`
/// carries it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionStatus {
    /// The prompted take, from 0 (equal to `takes` when every take is done).
    pub take: i32,
    /// Takes in the script.
    pub takes: i32,
    /// The prompted sentence's number in the script, from 1.
    pub sentence: i32,
    /// The prompted emotion.
    pub emotion: String,
    /// `waiting`, `recording`, `review` or `done`.
    pub state: String,
    /// The sentence's text.
    pub text: String,
}

/// One value of `/status/confirm`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StatusValue {
    /// A counter or a measure (`h`).
    Int(i64),
    /// A name, a path, an address (`s`).
    Text(String),
}

impl StatusValue {
    /// The number, if it is one.
    pub fn as_int(&self) -> Option<i64> {
        match self {
            StatusValue::Int(v) => Some(*v),
            StatusValue::Text(_) => None,
        }
    }

    /// The text, if it is one.
    pub fn as_text(&self) -> Option<&str> {
        match self {
            StatusValue::Int(_) => None,
            StatusValue::Text(s) => Some(s),
        }
    }
}

impl From<i64> for StatusValue {
    fn from(v: i64) -> StatusValue {
        StatusValue::Int(v)
    }
}

impl From<String> for StatusValue {
    fn from(v: String) -> StatusValue {
        StatusValue::Text(v)
    }
}

/// rosc cannot fail writing into a `Vec`; clear and encode.
fn encode_message(addr: String, args: Vec<OscType>, out: &mut Vec<u8>) -> usize {
    out.clear();
    let packet = OscPacket::Message(OscMessage { addr, args });
    match rosc::encoder::encode_into(&packet, out) {
        Ok(n) => n,
        Err(never) => match never {},
    }
}

/// OSC strings end at the first NUL: replace NULs so a reply stays parseable.
fn osc_string(s: &str) -> String {
    s.replace('\0', "?")
}

/// Encodes a control message as a client sends it. Returns the encoded length.
pub fn encode_control_into(control: &Control, out: &mut Vec<u8>) -> usize {
    let args = sanitize(control.args());
    encode_message(control.address().to_string(), args, out)
}

/// Encodes a control message carrying the daemon's shared `secret` as its last argument.
/// Returns the encoded length.
pub fn encode_control_signed_into(control: &Control, secret: &str, out: &mut Vec<u8>) -> usize {
    let mut args = control.args();
    args.push(OscType::String(secret.to_string()));
    encode_message(control.address().to_string(), sanitize(args), out)
}

/// Encodes `/subscribe/challenge ,i`. Returns the encoded length.
pub fn encode_challenge_into(cookie: i32, out: &mut Vec<u8>) -> usize {
    encode_message(
        a::SUBSCRIBE_CHALLENGE.to_string(),
        vec![OscType::Int(cookie)],
        out,
    )
}

fn sanitize(mut args: Vec<OscType>) -> Vec<OscType> {
    for arg in &mut args {
        if let OscType::String(s) = arg {
            if s.contains('\0') {
                *s = osc_string(s);
            }
        }
    }
    args
}

/// Encodes the `<address>/confirm` reply of an accepted control, echoing its arguments. For
/// [`Control::Status`] use [`encode_status_into`]. Returns the encoded length.
pub fn encode_confirm_into(control: &Control, out: &mut Vec<u8>) -> usize {
    let addr = format!("{}{}", control.address(), a::CONFIRM_SUFFIX);
    encode_message(addr, sanitize(control.args()), out)
}

/// Encodes `/status/confirm` from (name, value) pairs. Returns the length.
pub fn encode_status_into<S: AsRef<str>>(pairs: &[(S, StatusValue)], out: &mut Vec<u8>) -> usize {
    let mut args = Vec::with_capacity(pairs.len() * 2);
    for (name, value) in pairs {
        args.push(OscType::String(osc_string(name.as_ref())));
        args.push(match value {
            StatusValue::Int(v) => OscType::Long(*v),
            StatusValue::Text(s) => OscType::String(osc_string(s)),
        });
    }
    encode_message(format!("{}{}", a::STATUS, a::CONFIRM_SUFFIX), args, out)
}

/// Encodes `/session/status/confirm ,iiisss`. Returns the length.
pub fn encode_session_status_into(status: &SessionStatus, out: &mut Vec<u8>) -> usize {
    let args = vec![
        OscType::Int(status.take),
        OscType::Int(status.takes),
        OscType::Int(status.sentence),
        OscType::String(osc_string(&status.emotion)),
        OscType::String(osc_string(&status.state)),
        OscType::String(osc_string(&status.text)),
    ];
    encode_message(
        format!("{}{}", a::SESSION_STATUS, a::CONFIRM_SUFFIX),
        args,
        out,
    )
}

/// Encodes `/emotion/list/confirm`: `i` the number of emotion components `k`, `k` × `i` their
/// indices, then for each emotion its name (`s`) and `k` × `f` levels. Returns the length.
pub fn encode_emotion_list_into(list: &EmotionList, out: &mut Vec<u8>) -> usize {
    let k = list.components.len();
    let mut args = Vec::with_capacity(1 + k + list.emotions.len() * (k + 1));
    args.push(OscType::Int(k as i32));
    args.extend(list.components.iter().map(|&c| OscType::Int(c as i32)));
    for (name, levels) in &list.emotions {
        args.push(OscType::String(osc_string(name)));
        args.extend(levels.iter().take(k).map(|&v| OscType::Float(v)));
        args.extend((levels.len()..k).map(|_| OscType::Float(0.0)));
    }
    encode_message(
        format!("{}{}", a::EMOTION_LIST, a::CONFIRM_SUFFIX),
        args,
        out,
    )
}

/// Encodes `/emoshift/error ,ss` (address of the refused message, why). Returns the length.
pub fn encode_error_into(address: &str, message: &str, out: &mut Vec<u8>) -> usize {
    let args = vec![
        OscType::String(osc_string(address)),
        OscType::String(osc_string(message)),
    ];
    encode_message(a::ERROR.to_string(), args, out)
}

/// Decodes a reply from the daemon (client side: the tests crate, tools).
///
/// # Errors
/// [`ControlError`] if it is not a well-formed reply.
pub fn decode_reply(msg: &[u8]) -> Result<Reply, ControlError> {
    let m = decode_osc(msg)?;
    if m.addr == a::SUBSCRIBE_CHALLENGE {
        return match m.args.as_slice() {
            [OscType::Int(c)] => Ok(Reply::Challenge(*c)),
            _ => Err(DecodeError::WrongTypeTags.into()),
        };
    }
    if m.addr == a::ERROR {
        return match <[OscType; 2]>::try_from(m.args) {
            Ok([OscType::String(address), OscType::String(message)]) => {
                Ok(Reply::Error { address, message })
            }
            _ => Err(DecodeError::WrongTypeTags.into()),
        };
    }
    let Some(base) = m.addr.strip_suffix(a::CONFIRM_SUFFIX) else {
        return Err(ControlError::UnknownAddress { address: m.addr });
    };
    if base == a::STATUS {
        return parse_status(m.args).map(Reply::Status);
    }
    if base == a::SESSION_STATUS {
        return match <[OscType; 6]>::try_from(m.args) {
            Ok(
                [OscType::Int(take), OscType::Int(takes), OscType::Int(sentence), OscType::String(emotion), OscType::String(state), OscType::String(text)],
            ) => Ok(Reply::SessionStatus(SessionStatus {
                take,
                takes,
                sentence,
                emotion,
                state,
                text,
            })),
            _ => Err(DecodeError::WrongTypeTags.into()),
        };
    }
    if base == a::EMOTION_LIST {
        return parse_emotion_list(m.args)
            .map(Reply::EmotionList)
            .ok_or_else(|| DecodeError::WrongTypeTags.into());
    }
    parse_control(base, m.args).map(Reply::Confirm)
}

fn parse_emotion_list(args: Vec<OscType>) -> Option<EmotionList> {
    let mut it = args.into_iter();
    let OscType::Int(k) = it.next()? else {
        return None;
    };
    let k = usize::try_from(k).ok()?;
    let mut components = Vec::with_capacity(k.min(64));
    for _ in 0..k {
        let OscType::Int(c) = it.next()? else {
            return None;
        };
        components.push(u32::try_from(c).ok()?);
    }
    let mut emotions = Vec::new();
    while let Some(name) = it.next() {
        let OscType::String(name) = name else {
            return None;
        };
        let mut levels = Vec::with_capacity(k);
        for _ in 0..k {
            let OscType::Float(v) = it.next()? else {
                return None;
            };
            levels.push(v);
        }
        emotions.push((name, levels));
    }
    Some(EmotionList {
        components,
        emotions,
    })
}

fn parse_status(args: Vec<OscType>) -> Result<Vec<(String, StatusValue)>, ControlError> {
    if args.len() % 2 != 0 {
        return Err(DecodeError::WrongTypeTags.into());
    }
    let mut out = Vec::with_capacity(args.len() / 2);
    let mut it = args.into_iter();
    while let (Some(name), Some(value)) = (it.next(), it.next()) {
        match (name, value) {
            (OscType::String(n), OscType::Long(v)) => out.push((n, StatusValue::Int(v))),
            (OscType::String(n), OscType::String(v)) => out.push((n, StatusValue::Text(v))),
            _ => return Err(DecodeError::WrongTypeTags.into()),
        }
    }
    Ok(out)
}
