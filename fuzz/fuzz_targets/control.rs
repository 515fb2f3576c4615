//! decode_control, decode_control_with_secret and decode_reply on arbitrary bytes: typed
//! errors, never panics; an accepted control is within its documented limits and re-encodes
//! (signed or not) to a message that decodes to the same control.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{
    decode_control, decode_control_with_secret, decode_reply, encode_control_into,
    encode_control_signed_into, Control,
};

const SECRET: &str = "s3cret";

fn within_limits(c: &Control) -> bool {
    match c {
        Control::Amount(a) => (0.0..=1.0).contains(a),
        Control::Ramp(r) => (0.0..=protocol::MAX_RAMP_S).contains(r),
        Control::Gain { gain, .. } => gain.abs() <= protocol::MAX_GAIN,
        Control::Alpha { value, .. } => value.abs() <= protocol::MAX_ALPHA,
        Control::Target(n) => n.len() <= protocol::MAX_NAME_BYTES,
        Control::Subscribe { port, performer, .. } => {
            *port != 0 && performer.as_ref().is_none_or(|p| p.len() <= protocol::MAX_NAME_BYTES)
        }
        _ => true,
    }
}

fuzz_target!(|data: &[u8]| {
    let _ = decode_reply(data);
    let _ = protocol::decode_stream(data);
    if let Ok(c) = decode_control(data) {
        assert!(within_limits(&c), "{c:?}");
        let mut out = Vec::new();
        encode_control_into(&c, &mut out);
        assert_eq!(decode_control(&out).expect("re-encoded control decodes"), c);
    }
    if let Ok((c, signed)) = decode_control_with_secret(data, SECRET) {
        assert!(within_limits(&c), "{c:?}");
        let mut out = Vec::new();
        encode_control_signed_into(&c, SECRET, &mut out);
        assert_eq!(
            decode_control_with_secret(&out, SECRET).expect("re-encoded control decodes"),
            (c.clone(), true)
        );
        if !signed {
            assert_eq!(decode_control(data).ok(), Some(c));
        }
    }
});
