//! decode_control and decode_reply on arbitrary bytes: typed errors, never panics; an accepted
//! control re-encodes to a message that decodes to the same control.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{decode_control, decode_reply, encode_control_into};

fuzz_target!(|data: &[u8]| {
    let _ = decode_reply(data);
    if let Ok(c) = decode_control(data) {
        let mut out = Vec::new();
        encode_control_into(&c, &mut out);
        assert_eq!(decode_control(&out).expect("re-encoded control decodes"), c);
    }
});
