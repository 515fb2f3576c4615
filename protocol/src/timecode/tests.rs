use super::*;
use crate::{messages, Address, DecodeError, FrameBuf, Limits};

fn df() -> TimecodeRate {
    TimecodeRate::DF_29_97
}

#[test]
fn rates_parse_from_the_ways_stages_write_them() {
    let r = |t: &str| TimecodeRate::parse(t).expect(t);
    assert_eq!(r("29.97df"), df());
    assert_eq!(r("30000/1001 DF"), df());
    assert_eq!(r("30"), TimecodeRate::FPS_30);
    assert_eq!(r("25"), TimecodeRate::FPS_25);
    assert_eq!(r("23.976").numerator(), 24_000);
    assert_eq!(r("59.94df").nominal_fps(), 60);
    assert!(!r("29.97ndf").drop_frame());
    assert_eq!(r("29.97df").to_string(), "29.97df");
    assert_eq!(r("23.976").to_string(), "23.976");
    assert_eq!(r("30").to_string(), "30");
    for bad in ["", "fast", "0", "30df", "25df", "-1", "1/0", "29.5"] {
        assert!(TimecodeRate::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn drop_frame_counts_skip_two_numbers_a_minute_except_every_tenth() {
    let at = |h, m, s, f| Smpte {
        hours: h,
        minutes: m,
        seconds: s,
        frames: f,
        subframe: 0,
        rate: Some(df()),
    };
    assert!(!at(0, 1, 0, 0).is_valid() && !at(0, 1, 0, 1).is_valid());
    assert!(at(0, 1, 0, 2).is_valid() && at(0, 10, 0, 0).is_valid());
    let before = at(0, 0, 59, 29).frame_count().expect("valid");
    assert_eq!(before, 1_799);
    assert_eq!(Smpte::from_frame_count(before + 1, df()), at(0, 1, 0, 2));
    let ten = at(0, 10, 0, 0).frame_count().expect("valid");
    assert_eq!(ten, 17_982, "29.97 DF: 17,982 frames per ten minutes");
    assert_eq!(Smpte::from_frame_count(ten - 1, df()), at(0, 9, 59, 29));
    // Every count round-trips, across hours.
    for n in (0..200_000u64).step_by(7).chain([2_589_407, 2_589_408]) {
        let t = Smpte::from_frame_count(n, df());
        assert!(t.is_valid(), "{t}");
        assert_eq!(t.frame_count(), Some(n % 2_589_408), "{t}");
    }
    assert_eq!(at(1, 2, 3, 4).to_string(), "01:02:03;04.0");
}

#[test]
fn non_drop_counts_are_plain() {
    let r = TimecodeRate::FPS_25;
    let t = Smpte::from_frame_count(25 * 3_600 + 26, r);
    assert_eq!((t.hours, t.minutes, t.seconds, t.frames), (1, 0, 1, 1));
    assert_eq!(t.frame_count(), Some(25 * 3_600 + 26));
    assert_eq!(
        Smpte::parse("01:00:01:01.3", Some(r)).map(|t| (t.frames, t.subframe)),
        Ok((1, 3))
    );
    assert!(Smpte::parse("01:00:01:25", Some(r)).is_err());
    assert_eq!(
        Smpte::from_packed(0x0102_0304, 2, None).packed(),
        0x0102_0304
    );
}

#[test]
fn the_message_round_trips_and_rides_in_the_frame_bundle() {
    let time = FrameTime {
        timecode: Some(Smpte {
            hours: 10,
            minutes: 1,
            seconds: 0,
            frames: 2,
            subframe: 3,
            rate: Some(df()),
        }),
        irig: None,
        clock: CaptureClock::Utc,
    };
    let mut out = Vec::new();
    assert_eq!(encode_timecode_into(&time, &mut out), TIMECODE_MESSAGE_LEN);
    assert_eq!(decode_timecode(&out), Ok(time));
    let mut frame = FrameBuf::with_max_markers(4);
    frame.set_frame(9, 1_234, &[1.0, 2.0, 3.0]).expect("valid");
    encode_frame_timed_into(&frame, &time, &mut out).expect("finite");
    let kinds: Vec<Option<Address>> = messages(&out, &Limits::default())
        .expect("well-formed")
        .map(|m| Address::parse(m.address))
        .collect();
    assert_eq!(kinds, [Some(Address::Timecode), Some(Address::Frame)]);
    // Nothing to say: the bare frame, as before.
    let n = encode_frame_timed_into(&frame, &FrameTime::default(), &mut out).expect("finite");
    assert_eq!(n, crate::frame_message_len(1));
}

#[test]
fn bad_messages_name_the_bad_argument() {
    let base = FrameTime {
        timecode: Some(Smpte::from_packed(0x0001_0002, 0, Some(df()))),
        irig: None,
        clock: CaptureClock::Source,
    };
    let mut good = Vec::new();
    encode_timecode_into(&base, &mut good);
    let arg = |i: usize| 24 + 4 * i;
    let with = |i: usize, v: u32| {
        let mut m = good.clone();
        m[arg(i)..arg(i) + 4].copy_from_slice(&v.to_be_bytes());
        decode_timecode(&m)
    };
    assert_eq!(
        with(0, 0x0001_0000),
        Err(DecodeError::OutOfRange { index: 0 })
    );
    assert_eq!(
        with(0, 0x1800_0000),
        Err(DecodeError::OutOfRange { index: 0 })
    );
    assert_eq!(with(3, 0), Err(DecodeError::OutOfRange { index: 3 }));
    assert_eq!(with(2, 25), Err(DecodeError::OutOfRange { index: 2 }));
    assert_eq!(with(4, 8 | 1), Err(DecodeError::OutOfRange { index: 4 }));
    assert_eq!(
        decode_timecode(&good[..good.len() - 4]).map(|_| ()),
        Err(DecodeError::Truncated { offset: 40 })
    );
    let mut frame = Vec::new();
    crate::encode_frame_into(&FrameBuf::with_max_markers(1), &mut frame).expect("empty frame");
    assert_eq!(decode_timecode(&frame), Err(DecodeError::UnknownAddress));
}
