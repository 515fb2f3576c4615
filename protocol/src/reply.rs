//! Replies to control messages, and control messages as a client sends them; rosc encodes.
//!
//! Every control message is answered to its sender: `<address>/confirm` echoing the accepted
//! arguments in canonical types, or `/emoshift/error ,ss` (address, message). `/status` is
//! answered by `/status/confirm` with name/value pairs: `,shsh...`, each counter an OSC string
//! (its name) followed by an `h` (int64) value, in the order the daemon lists them.

use rosc::{OscMessage, OscPacket, OscType};

use crate::address as a;
use crate::control::{decode_osc, parse_control, Control, ControlError};
use crate::error::DecodeError;

/// A decoded reply from the daemon.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// `<address>/confirm` of an accepted control, with its echoed arguments.
    Confirm(Control),
    /// `/status/confirm`: counters as (name, value) pairs, in the daemon's order.
    Status(Vec<(String, i64)>),
    /// `/emoshift/error ,ss`.
    Error {
        /// Address of the refused message.
        address: String,
        /// Why it was refused.
        message: String,
    },
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

/// Encodes `/status/confirm ,shsh...` from (name, value) counter pairs. Returns the length.
pub fn encode_status_into<S: AsRef<str>>(counters: &[(S, i64)], out: &mut Vec<u8>) -> usize {
    let mut args = Vec::with_capacity(counters.len() * 2);
    for (name, value) in counters {
        args.push(OscType::String(osc_string(name.as_ref())));
        args.push(OscType::Long(*value));
    }
    encode_message(format!("{}{}", a::STATUS, a::CONFIRM_SUFFIX), args, out)
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
    parse_control(base, m.args).map(Reply::Confirm)
}

fn parse_status(args: Vec<OscType>) -> Result<Vec<(String, i64)>, ControlError> {
    if args.len() % 2 != 0 {
        return Err(DecodeError::WrongTypeTags.into());
    }
    let mut out = Vec::with_capacity(args.len() / 2);
    let mut it = args.into_iter();
    while let (Some(name), Some(value)) = (it.next(), it.next()) {
        match (name, value) {
            (OscType::String(n), OscType::Long(v)) => out.push((n, v)),
            _ => return Err(DecodeError::WrongTypeTags.into()),
        }
    }
    Ok(out)
}
