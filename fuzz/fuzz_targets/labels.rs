//! decode_labels on arbitrary bytes: never panics; accepted labels round-trip.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{decode_labels, encode_labels_into};

fuzz_target!(|data: &[u8]| {
    if let Ok(l) = decode_labels(data) {
        let mut out = Vec::new();
        encode_labels_into(&l, &mut out).expect("decoded names hold no nul");
        assert_eq!(decode_labels(&out).expect("round trip"), l);
    }
});
