use protocol::qtm::{encode_data_into, Components, DataFrame, Timecode, HEADER_BYTES};
use protocol::Irig;

use super::*;

fn params(labels: &[&str]) -> QtmParameters {
    QtmParameters {
        frequency_hz: Some(120.0),
        labels: Some(labels.iter().map(|s| s.to_string()).collect()),
    }
}

fn packet(frame_number: u32, positions: &[f32], tc: Option<Timecode>) -> Vec<u8> {
    let mut out = Vec::new();
    let frame = DataFrame {
        timestamp_us: 42,
        frame_number,
        positions,
        timecode: tc,
    };
    let c = Components {
        d3: true,
        timecode: true,
        ..Components::default()
    };
    encode_data_into(&frame, c, &mut out);
    out
}

#[test]
fn performers_come_from_label_prefixes_with_the_prefix_taken_off() {
    let server = "127.0.0.1:22223".parse().expect("addr");
    let mut frames = QtmFrames::new(server, 16);
    let performers = vec![
        ("alice".to_string(), "Alice_".to_string()),
        ("bob".to_string(), "Bob_".to_string()),
    ];
    frames.set_parameters(
        &params(&["Alice_Brow", "Bob_Jaw", "Alice_Lip"]),
        &performers,
    );
    let nan = f32::NAN;
    let tc = Timecode::Smpte {
        hours: 1,
        minutes: 2,
        seconds: 3,
        frames: 4,
        subframes: 0,
    };
    let bytes = packet(9, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, nan, nan, nan], Some(tc));
    let mut buf = FrameBuf::with_max_markers(16);
    let mut got = Vec::new();
    let outcome = frames
        .handle_data(&bytes[HEADER_BYTES..], &mut buf, &mut |f| {
            got.push((
                f.performer.map(|p| p.to_string()),
                f.labels.to_vec(),
                f.frame_number(),
                f.frame.header().capture_time_us,
                f.frame.positions().to_vec(),
                f.frame.is_missing(1),
                f.time.timecode.map(|t| (t.hours, t.frames)),
            ));
        })
        .expect("valid");
    assert_eq!(outcome, Outcome::Frames(2));
    assert_eq!(got[0].0.as_deref(), Some("alice"));
    assert_eq!(got[0].1, vec!["Brow".to_string(), "Lip".to_string()]);
    assert_eq!((got[0].2, got[0].3), (9, 42));
    assert_eq!(got[0].4[..3], [1.0, 2.0, 3.0]);
    assert!(got[0].5, "QTM's NaN is a missing marker");
    assert_eq!(got[0].6, Some((1, 4)));
    assert_eq!(got[1].1, vec!["Jaw".to_string()]);
    assert_eq!(got[1].4, vec![4.0, 5.0, 6.0]);

    let short = packet(10, &[1.0, 2.0, 3.0], None);
    let outcome = frames.handle_data(&short[HEADER_BYTES..], &mut buf, &mut |_| {});
    assert_eq!(outcome, Ok(Outcome::Mismatch));
}

#[test]
fn without_performers_one_stream_has_every_label() {
    let server = "127.0.0.1:22223".parse().expect("addr");
    let mut frames = QtmFrames::new(server, 16);
    frames.set_parameters(&params(&["a", "b"]), &[]);
    assert_eq!(frames.stream_names(), vec!["(all labels)".to_string()]);
    let bytes = packet(1, &[0.0; 6], None);
    let mut buf = FrameBuf::with_max_markers(16);
    let mut n = 0;
    frames
        .handle_data(&bytes[HEADER_BYTES..], &mut buf, &mut |f| {
            assert!(f.performer.is_none());
            assert_eq!(f.labels.len(), 2);
            n += 1;
        })
        .expect("valid");
    assert_eq!(n, 1);
}

/// Issue 32: QTM's IRIG timecode is the frame's IRIG time (and no SMPTE timecode).
#[test]
fn irig_timecode_is_the_frames_irig_time() {
    let server = "127.0.0.1:22223".parse().expect("addr");
    let mut frames = QtmFrames::new(server, 16);
    frames.set_parameters(&params(&["a"]), &[]);
    let tc = Timecode::Irig {
        years: 26,
        days: 332,
        hours: 8,
        minutes: 59,
        seconds: 30,
        tenths: 4,
    };
    let bytes = packet(5, &[1.0, 2.0, 3.0], Some(tc));
    let mut buf = FrameBuf::with_max_markers(16);
    let mut got = None;
    frames
        .handle_data(&bytes[HEADER_BYTES..], &mut buf, &mut |f| {
            got = Some(f.time)
        })
        .expect("valid");
    let time = got.expect("one frame");
    assert_eq!(time.timecode, None);
    let irig = time.irig.expect("IRIG");
    assert_eq!(irig.to_string(), "26:332:08:59:30.4");
    assert_eq!(
        irig,
        Irig {
            year: 26,
            day: 332,
            hours: 8,
            minutes: 59,
            seconds: 30,
            tenths: 4
        }
    );
}
