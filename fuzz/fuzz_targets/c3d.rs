//! The C3D reader on arbitrary bytes, by both decoders and the timecode reader: never panics,
//! and a take it accepts is one `Take::validate` accepts and the writer can write back.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The reader runs the c3dio cross-check inside `catch_unwind` and turns its panics into
    // errors; libfuzzer-sys's panic hook would abort on those caught panics too. A silent hook
    // instead: a panic that escapes the reader still aborts the run (fuzz_target catches it
    // and aborts), so our own panics are still found; rerun the artifact to see its message.
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let _ = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
    });
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
