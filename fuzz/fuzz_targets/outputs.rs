//! The output-profile decoders (/mocap/part, /emoshift/components) on arbitrary bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{decode_components_into, decode_part_into};

fuzz_target!(|data: &[u8]| {
    let mut positions = [0f32; 3 * 400];
    if let Ok(h) = decode_part_into(data, &mut positions) {
        assert!(h.first_marker + h.marker_count <= h.total_markers);
        assert!(3 * h.total_markers <= positions.len());
    }
    let mut u = [0f32; 256];
    if let Ok(n) = decode_components_into(data, &mut u) {
        assert!(n <= u.len());
    }
});
