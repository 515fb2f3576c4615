//! The C3D reader on arbitrary bytes, by both decoders and the timecode reader: never panics,
//! and a take it accepts is one `Take::validate` accepts and the writer can write back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = replay::c3d::read_time(data);
    if let Ok((take, _info)) = replay::c3d::read_with_info(data) {
        take.validate().expect("an accepted take is valid");
        let mut out = Vec::new();
        // A take read may still not fit what emoshift writes (labels, limits): an error, not a panic.
        let _ = replay::c3d::write(&take, &mut out);
    }
    if let Ok(take) = replay::c3d::read_own(data) {
        take.validate().expect("an accepted take is valid");
    }
});
