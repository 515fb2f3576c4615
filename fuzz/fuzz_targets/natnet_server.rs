//! The NatNet server's command decoder on arbitrary datagrams: never panics, a request string
//! ends at its NUL and parses the same again, and one re-encoded decodes the same.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::natnet::{decode_command, encode_request_into, parse_request, Command, Request};

fuzz_target!(|data: &[u8]| {
    let Ok(command) = decode_command(data) else {
        return;
    };
    if let Command::Request(r) = command {
        let text = match r {
            Request::Other(t) => t,
            _ => return,
        };
        assert!(!text.contains(&0), "a request string stops at its NUL");
        assert_eq!(parse_request(text), r);
        if let Ok(s) = std::str::from_utf8(text) {
            let mut out = Vec::new();
            if encode_request_into(s, &mut out).is_ok() {
                assert_eq!(decode_command(&out).ok(), Some(Command::Request(r)));
            }
        }
    }
});
