//! The CSV reader on arbitrary bytes: never panics; a take it accepts is valid, and one the
//! writer can write reads back with the same shape.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(take) = replay::csv::read(data) {
        take.validate().expect("an accepted take is valid");
        let mut out = Vec::new();
        if replay::csv::write(&take, &mut out).is_ok() {
            let again = replay::csv::read(out.as_slice()).expect("a written take reads back");
            assert_eq!(again.n_frames(), take.n_frames());
            assert_eq!(again.labels, take.labels);
        }
    }
});
