//! Decoding control messages: the shape each address takes and the documented limits of
//! every value ([`super::MAX_RAMP_S`] and its neighbours).

use rosc::{OscMessage, OscPacket, OscType};

use super::{
    Control, ControlError, Profile, SessionControl, MAX_ALPHA, MAX_GAIN, MAX_MIX_WEIGHT,
    MAX_NAME_BYTES, MAX_PATH_BYTES, MAX_RAMP_S,
};
use crate::address as a;
use crate::error::DecodeError;
use crate::scan::{check_datagram, Limits};

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

/// Decodes a control message and checks its values against the documented limits.
///
/// # Errors
/// [`ControlError`] naming the address and the bad argument; the daemon sends its text back
/// with [`crate::encode_error_into`].
pub fn decode_control(msg: &[u8]) -> Result<Control, ControlError> {
    let m = decode_osc(msg)?;
    parse_control(&m.addr, m.args)
}

/// Decodes a control message that may carry `secret` as its last string argument; returns
/// the control and whether it carried the secret. The caller refuses a mutating control
/// ([`Control::is_mutating`]) that did not.
///
/// # Errors
/// As [`decode_control`].
pub fn decode_control_with_secret(
    msg: &[u8],
    secret: &str,
) -> Result<(Control, bool), ControlError> {
    let mut m = decode_osc(msg)?;
    let signed = matches!(m.args.last(), Some(OscType::String(s)) if same_secret(s, secret));
    if signed {
        m.args.pop();
    }
    Ok((parse_control(&m.addr, m.args)?, signed))
}

/// Compares in time independent of where the strings differ, so a guess learns nothing from
/// how long the refusal took.
fn same_secret(given: &str, secret: &str) -> bool {
    let (g, s) = (given.as_bytes(), secret.as_bytes());
    let diff = g
        .iter()
        .zip(s)
        .fold(u8::from(g.len() != s.len()), |d, (x, y)| d | (x ^ y));
    diff == 0 && !secret.is_empty()
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

/// `v` when finite and within `lo..=hi`.
fn within(
    address: &'static str,
    what: &'static str,
    v: f32,
    (lo, hi): (f32, f32),
    range: &'static str,
) -> Result<f32, ControlError> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(ControlError::OutOfRange {
            address,
            what,
            value: v.to_string(),
            range,
        })
    }
}

/// `s` when at most `max` bytes long.
fn bounded(
    address: &'static str,
    what: &'static str,
    s: &str,
    max: usize,
    range: &'static str,
) -> Result<String, ControlError> {
    if s.len() <= max {
        Ok(s.to_string())
    } else {
        Err(ControlError::OutOfRange {
            address,
            what,
            value: format!("of {} bytes", s.len()),
            range,
        })
    }
}

fn name(address: &'static str, what: &'static str, s: &str) -> Result<String, ControlError> {
    bounded(address, what, s, MAX_NAME_BYTES, "at most 256 bytes")
}

fn path(address: &'static str, s: &str) -> Result<String, ControlError> {
    bounded(address, "path", s, MAX_PATH_BYTES, "at most 4096 bytes")
}

fn component(address: &'static str, i: i32) -> Result<u32, ControlError> {
    u32::try_from(i).map_err(|_| ControlError::OutOfRange {
        address,
        what: "component",
        value: i.to_string(),
        range: ">= 0",
    })
}

fn port(address: &'static str, p: i32) -> Result<u16, ControlError> {
    match u16::try_from(p) {
        Ok(p) if p != 0 => Ok(p),
        _ => Err(ControlError::OutOfRange {
            address,
            what: "port",
            value: p.to_string(),
            range: "1..=65535",
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
        let OscType::String(n) = &pair[0] else {
            return None;
        };
        let weight = float(&pair[1])?;
        let checked = name(address, "emotion", n).and_then(|n| {
            let range = (0.0, MAX_MIX_WEIGHT);
            Ok((n, within(address, "weight", weight, range, "0..=1000")?))
        });
        match checked {
            Ok(pair) => out.push(pair),
            Err(e) => return Some(Err(e)),
        }
    }
    if out.iter().all(|(_, w)| *w == 0.0) {
        return Some(Err(ControlError::OutOfRange {
            address,
            what: "weights",
            value: "all 0".into(),
            range: "at least one > 0",
        }));
    }
    Some(Ok(out))
}

fn subscribe(addr: &'static str, args: &[OscType]) -> Option<Result<Control, ControlError>> {
    let (p, profile, rest) = match args {
        [OscType::Int(p), OscType::String(profile), rest @ ..] => (*p, profile, rest),
        _ => return None,
    };
    let (performer, cookie) = match rest {
        [] => (None, None),
        [OscType::String(s)] => (Some(s), None),
        [OscType::Int(c)] => (None, Some(*c)),
        [OscType::String(s), OscType::Int(c)] => (Some(s), Some(*c)),
        _ => return None,
    };
    let parsed = (|| {
        Ok(Control::Subscribe {
            port: port(addr, p)?,
            profile: Profile::parse(profile).ok_or_else(|| ControlError::UnknownProfile {
                name: profile.clone(),
            })?,
            performer: performer.map(|s| name(addr, "performer", s)).transpose()?,
            cookie,
        })
    })();
    Some(parsed)
}

fn record_start(addr: &'static str, args: &[OscType]) -> Option<Result<Control, ControlError>> {
    let (p, raw, overwrite) = match args {
        [OscType::String(p)] => (p, None, false),
        [OscType::String(p), OscType::String(r)] => (p, Some(r), false),
        [OscType::String(p), OscType::Int(o)] => (p, None, *o != 0),
        [OscType::String(p), OscType::String(r), OscType::Int(o)] => (p, Some(r), *o != 0),
        _ => return None,
    };
    let parsed = (|| {
        Ok(Control::RecordStart {
            path: path(addr, p)?,
            raw: raw.map(|r| path(addr, r)).transpose()?,
            overwrite,
        })
    })();
    Some(parsed)
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
    let value = |v: &OscType| float(v).ok_or_else(wrong);
    let c = match (*addr, args.as_slice()) {
        (a::EMOTION_TARGET, [OscType::String(s)]) => Control::Target(name(addr, "emotion", s)?),
        (a::EMOTION_AMOUNT, [v]) => {
            Control::Amount(within(addr, "amount", value(v)?, (0.0, 1.0), "0..=1")?)
        }
        (a::EMOTION_RAMP, [v]) => Control::Ramp(within(
            addr,
            "seconds",
            value(v)?,
            (0.0, MAX_RAMP_S),
            "0..=60",
        )?),
        (a::EMOTION_ALPHA, [OscType::Int(i), v]) => Control::Alpha {
            component: component(addr, *i)?,
            value: within(
                addr,
                "value",
                value(v)?,
                (-MAX_ALPHA, MAX_ALPHA),
                "-100..=100",
            )?,
        },
        (a::COMPONENT_GAIN, [OscType::Int(i), v]) => Control::Gain {
            component: component(addr, *i)?,
            gain: within(addr, "gain", value(v)?, (-MAX_GAIN, MAX_GAIN), "-10..=10")?,
        },
        (a::EMOTION_MIX, pairs) if !pairs.is_empty() && pairs.len() % 2 == 0 => {
            Control::Mix(mix(addr, pairs).ok_or_else(wrong)??)
        }
        (a::EMOTION_LIST, []) => Control::EmotionList,
        (a::BYPASS, [OscType::Int(i)]) => Control::Bypass(*i != 0),
        (a::BYPASS, [OscType::Bool(b)]) => Control::Bypass(*b),
        (a::SUBSCRIBE, args) => subscribe(addr, args).ok_or_else(wrong)??,
        (a::UNSUBSCRIBE, [OscType::Int(p)]) => Control::Unsubscribe {
            port: port(addr, *p)?,
        },
        (a::MODEL_LOAD, [OscType::String(s)]) => Control::ModelLoad(path(addr, s)?),
        (a::RECORD_START, args) => record_start(addr, args).ok_or_else(wrong)??,
        (a::RECORD_STOP, []) => Control::RecordStop,
        (a::STATUS, []) => Control::Status,
        (addr, []) => match SessionControl::parse(addr) {
            Some(c) => Control::Session(c),
            None => return Err(wrong()),
        },
        _ => return Err(wrong()),
    };
    Ok(c)
}

/// Control addresses and the type tags each takes (for error messages).
const CONTROL_SHAPES: [(&str, &str); 22] = [
    (a::EMOTION_TARGET, ",s"),
    (a::EMOTION_AMOUNT, ",f"),
    (a::EMOTION_RAMP, ",f"),
    (a::EMOTION_MIX, ",sf or ,sfsf..."),
    (a::EMOTION_LIST, ","),
    (a::EMOTION_ALPHA, ",if"),
    (a::COMPONENT_GAIN, ",if"),
    (a::BYPASS, ",i"),
    (a::SUBSCRIBE, ",is, ,iss, ,isi or ,issi"),
    (a::UNSUBSCRIBE, ",i"),
    (a::MODEL_LOAD, ",s"),
    (a::RECORD_START, ",s, ,ss, ,si or ,ssi"),
    (a::RECORD_STOP, ","),
    (a::STATUS, ","),
    (a::SESSION_START, ","),
    (a::SESSION_STOP, ","),
    (a::SESSION_RETAKE, ","),
    (a::SESSION_SKIP, ","),
    (a::SESSION_BACK, ","),
    (a::SESSION_FINISH, ","),
    (a::SESSION_REDO, ","),
    (a::SESSION_STATUS, ","),
];
