//! Property tests: round trips, the borrowed frame parser agreeing with rosc, and no panics
//! on arbitrary or mutated input.

use proptest::prelude::*;
use protocol::*;
use rosc::{OscMessage, OscPacket, OscType};

fn frame_strategy() -> impl Strategy<Value = FrameBuf> {
    (0usize..=130, any::<i32>(), any::<i64>())
        .prop_flat_map(|(n, fnum, t)| {
            (
                prop::collection::vec(-5.0e3f32..5.0e3, n * 3),
                prop::collection::vec(prop::bool::weighted(0.1), n),
                Just((fnum, t)),
            )
        })
        .prop_map(|(pos, missing, (fnum, t))| {
            let mut f = FrameBuf::new();
            f.set_frame(fnum, t, &pos).expect("finite positions");
            for (i, m) in missing.into_iter().enumerate() {
                f.set_missing(i, m);
            }
            f
        })
}

/// Same numbers, NaN == NaN (missing markers).
fn same_positions(a: &[f32], b: &[f32]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
}

/// What rosc makes of a frame message: (frame, time, mask, positions with NaN for missing).
fn rosc_frame(bytes: &[u8]) -> Option<(i32, i64, Vec<u8>, Vec<f32>)> {
    let (rest, OscPacket::Message(m)) = rosc::decoder::decode_udp(bytes).ok()? else {
        return None;
    };
    if !rest.is_empty() || m.addr != "/mocap/frame" {
        return None;
    }
    match m.args.as_slice() {
        [OscType::Int(f), OscType::Long(t), OscType::Blob(mask), OscType::Blob(pos)] => {
            let mut out: Vec<f32> = pos
                .chunks_exact(4)
                .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            for (i, xyz) in out.chunks_exact_mut(3).enumerate() {
                if mask[i / 8] >> (i % 8) & 1 == 1 {
                    xyz.fill(f32::NAN);
                }
            }
            Some((*f, *t, mask.clone(), out))
        }
        [OscType::Int(f), OscType::Long(t), floats @ ..] => {
            let out: Vec<f32> = floats
                .iter()
                .map(|a| a.clone().float())
                .collect::<Option<_>>()?;
            let n = out.len() / 3;
            let mut mask = vec![0u8; n.div_ceil(8)];
            for (i, xyz) in out.chunks_exact(3).enumerate() {
                if xyz.iter().all(|v| v.is_nan()) {
                    mask[i / 8] |= 1 << (i % 8);
                }
            }
            Some((*f, *t, mask, out))
        }
        _ => None,
    }
}

/// Applies byte edits: (position, new byte) pairs, then a cut and an extension.
fn mutate(mut bytes: Vec<u8>, edits: &[(usize, u8)], cut: usize, extra: &[u8]) -> Vec<u8> {
    for &(at, b) in edits {
        if !bytes.is_empty() {
            let i = at % bytes.len();
            bytes[i] = b;
        }
    }
    bytes.truncate(bytes.len().saturating_sub(cut));
    bytes.extend_from_slice(extra);
    bytes
}

proptest! {
    #[test]
    fn frames_round_trip_and_agree_with_rosc(f in frame_strategy(), flat in any::<bool>()) {
        let mut bytes = Vec::new();
        if flat {
            encode_frame_flat_into(&f, &mut bytes).expect("finite");
        } else {
            encode_frame_into(&f, &mut bytes).expect("finite");
        }
        let mut g = FrameBuf::new();
        let h = decode_frame_into(&bytes, &mut g).expect("own encoding decodes");
        prop_assert_eq!(h.frame_number, f.header().frame_number);
        prop_assert_eq!(h.capture_time_us, f.header().capture_time_us);
        prop_assert_eq!(h.missing_count, f.header().missing_count);
        prop_assert_eq!(g.missing_mask(), f.missing_mask());
        prop_assert!(same_positions(g.positions(), f.positions()));
        let (rf, rt, rmask, rpos) = rosc_frame(&bytes).expect("rosc decodes our frame");
        prop_assert_eq!((rf, rt), (h.frame_number, h.capture_time_us));
        prop_assert_eq!(rmask.as_slice(), g.missing_mask());
        prop_assert!(same_positions(&rpos, g.positions()));
    }

    /// Whenever the borrowed parser accepts mutated bytes, rosc reads the same numbers.
    #[test]
    fn accepted_mutants_agree_with_rosc(
        f in frame_strategy(),
        flat in any::<bool>(),
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 0..4),
        cut in prop_oneof![Just(0usize), 0usize..16],
        extra in prop::collection::vec(any::<u8>(), 0..3),
    ) {
        let mut bytes = Vec::new();
        if flat {
            encode_frame_flat_into(&f, &mut bytes).expect("finite");
        } else {
            encode_frame_into(&f, &mut bytes).expect("finite");
        }
        let bytes = mutate(bytes, &edits, cut, &extra);
        let mut g = FrameBuf::new();
        if let Ok(h) = decode_frame_into(&bytes, &mut g) {
            let (rf, rt, rmask, rpos) = rosc_frame(&bytes).expect("rosc accepts what we accept");
            prop_assert_eq!((rf, rt), (h.frame_number, h.capture_time_us));
            prop_assert_eq!(rmask.as_slice(), g.missing_mask());
            prop_assert!(same_positions(&rpos, g.positions()));
        }
        // and the pre-scan's promise: what it passes, rosc decodes whole
        if check_datagram(&bytes, &Limits::default()).is_ok() {
            let (rest, _) = rosc::decoder::decode_udp(&bytes).expect("rosc decodes pre-scanned");
            prop_assert!(rest.is_empty());
        }
    }

    #[test]
    fn nothing_panics_on_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let mut g = FrameBuf::with_max_markers(50);
        let mut u = [0f32; 64];
        let mut pos = [0f32; 300];
        let _ = decode_frame_into(&bytes, &mut g);
        let _ = decode_labels(&bytes);
        let _ = decode_control(&bytes);
        let _ = decode_reply(&bytes);
        let _ = decode_part_into(&bytes, &mut pos);
        let _ = decode_components_into(&bytes, &mut u);
        let _ = decode_timecode(&bytes);
        if let Ok(msgs) = messages(&bytes, &Limits::default()) {
            for m in msgs {
                let _ = decode_frame_into(m.bytes, &mut g);
                let _ = decode_control(m.bytes);
                let _ = decode_timecode(m.bytes);
            }
        }
    }

    /// Issue 16: the timecode message round-trips (drop-frame included) and rosc reads the
    /// same five ints.
    #[test]
    fn timecodes_round_trip_and_agree_with_rosc(
        count in 0u64..5_000_000,
        sub in 0u32..16,
        rate in prop::sample::select(vec!["24", "25", "29.97df", "30", "59.94df", "23.976"]),
        utc in any::<bool>(),
        has in any::<bool>(),
    ) {
        let rate = TimecodeRate::parse(rate).expect("listed rates parse");
        let mut t = Smpte::from_frame_count(count, rate);
        t.subframe = sub;
        let time = FrameTime {
            timecode: has.then_some(t),
            irig: None,
            clock: if utc { CaptureClock::Utc } else { CaptureClock::Source },
        };
        let mut out = Vec::new();
        encode_timecode_into(&time, &mut out);
        prop_assert_eq!(decode_timecode(&out), Ok(time));
        let m = decode_osc(&out).map_err(TestCaseError::fail)?;
        prop_assert_eq!(m.addr.as_str(), "/mocap/timecode");
        let ints: Vec<i32> = m.args.iter().filter_map(|a| match a {
            OscType::Int(v) => Some(*v),
            _ => None,
        }).collect();
        prop_assert_eq!(ints.len(), 5);
        if has {
            prop_assert_eq!(ints[0] as u32, t.packed());
            prop_assert_eq!(ints[1] as u32, sub);
            prop_assert_eq!(ints[2] as u32, rate.numerator());
        }
    }

    #[test]
    fn labels_round_trip(
        id in any::<i32>(),
        names in prop::collection::hash_set("[A-Za-z0-9_.]{1,12}", 1..60),
    ) {
        let labels = Labels { layout_id: id, names: names.into_iter().collect() };
        let mut out = Vec::new();
        encode_labels_into(&labels, &mut out).expect("no nul");
        prop_assert_eq!(decode_labels(&out), Ok(labels));
    }

    #[test]
    fn control_and_replies_round_trip(c in control_strategy()) {
        let mut out = Vec::new();
        encode_control_into(&c, &mut out);
        prop_assert_eq!(decode_control(&out), Ok(c.clone()));
        if c != Control::Status {
            encode_confirm_into(&c, &mut out);
            prop_assert_eq!(decode_reply(&out), Ok(Reply::Confirm(c.clone())));
        }
        encode_error_into(c.address(), "bad value 3", &mut out);
        let want = Reply::Error { address: c.address().to_string(), message: "bad value 3".into() };
        prop_assert_eq!(decode_reply(&out), Ok(want));
    }

    #[test]
    fn status_round_trips(counters in prop::collection::vec(("[a-z_]{1,20}", any::<i64>()), 0..20)) {
        let mut out = Vec::new();
        let pairs: Vec<(String, StatusValue)> =
            counters.into_iter().map(|(k, v)| (k, StatusValue::Int(v))).collect();
        encode_status_into(&pairs, &mut out);
        prop_assert_eq!(decode_reply(&out), Ok(Reply::Status(pairs)));
    }

    #[test]
    fn compact_bundles_carry_frame_and_state(
        f in frame_strategy(),
        target in "[a-z]{0,20}",
        amount in -2.0f32..2.0,
        (id, name) in (any::<i32>(), "[a-z0-9.:/]{0,64}"),
    ) {
        let mut out = Vec::new();
        let tag = StreamTag { id, name: &name };
        let n = encode_compact_into(&tag, &f, &target, amount, &mut out).expect("valid");
        prop_assert_eq!(n, out.len());
        let msgs: Vec<_> = messages(&out, &Limits::default()).expect("valid bundle").collect();
        prop_assert_eq!(msgs.len(), 3);
        prop_assert_eq!(decode_stream(msgs[0].bytes), Ok((id, name.as_str())));
        let mut g = FrameBuf::new();
        decode_frame_into(msgs[1].bytes, &mut g).expect("frame");
        prop_assert!(same_positions(g.positions(), f.positions()));
        let ours = decode_state(msgs[2].bytes).expect("state");
        prop_assert_eq!((ours.target, ours.amount), (target.as_str(), amount));
        let state = decode_osc(msgs[2].bytes).expect("state");
        prop_assert_eq!(state.addr.as_str(), "/emoshift/state");
        prop_assert_eq!(state.args, vec![OscType::String(target), OscType::Float(amount)]);
    }

    #[test]
    fn flat_split_parts_fit_and_reassemble(f in frame_strategy(), max in 40usize..4096) {
        let Ok(split) = FlatSplit::new(max) else {
            prop_assert!(max < 200, "a part of {} bytes fits one marker", max);
            return Ok(());
        };
        let name = "n".repeat(MAX_STREAM_NAME_BYTES);
        let tag = StreamTag { id: 7, name: &name };
        let n = f.marker_count();
        let mut pos = vec![0f32; 3 * n];
        let mut out = Vec::new();
        let mut covered = 0;
        for part in 0..split.part_count(n) {
            let len = split.encode_part_into(&tag, &f, part, &mut out).expect("valid");
            prop_assert!(len > 0 && len <= max, "part {} is {} bytes, max {}", part, len, max);
            let msgs: Vec<_> = messages(&out, &Limits::default()).expect("a bundle").collect();
            prop_assert_eq!(msgs.len(), 2);
            prop_assert_eq!(decode_stream(msgs[0].bytes), Ok((7, name.as_str())));
            let h = decode_part_into(msgs[1].bytes, &mut pos).expect("own part decodes");
            prop_assert_eq!((h.first_marker, h.total_markers), (covered, n));
            prop_assert_eq!(h.frame_number, f.header().frame_number);
            covered += h.marker_count;
        }
        prop_assert_eq!(covered, n);
        prop_assert_eq!(split.encode_part_into(&tag, &f, split.part_count(n), &mut out), Ok(0));
        prop_assert!(same_positions(&pos, f.positions()));
    }

    #[test]
    fn components_round_trip_with_vmc(
        u in prop::collection::vec(-3.0f32..3.0, 0..40),
        names in prop::collection::vec(("[A-Za-z]{1,10}", 0usize..45), 0..6),
    ) {
        let mut out = Vec::new();
        let tag = StreamTag { id: 2, name: "bob" };
        encode_components_into(&tag, &u, &names, &mut out).expect("no nul");
        let msgs: Vec<_> = messages(&out, &Limits::default()).expect("valid").collect();
        prop_assert_eq!(decode_stream(msgs[0].bytes), Ok((2, "bob")));
        let msgs = &msgs[1..];
        let mut got = [0f32; 64];
        let n = decode_components_into(msgs[0].bytes, &mut got).expect("components");
        prop_assert_eq!(&got[..n], u.as_slice());
        let kept: Vec<_> = names.iter().filter(|(_, i)| *i < u.len()).collect();
        if names.is_empty() {
            prop_assert_eq!(msgs.len(), 1);
        } else {
            prop_assert_eq!(msgs.len(), kept.len() + 2);
            for ((name, i), m) in kept.iter().zip(&msgs[1..]) {
                prop_assert_eq!(decode_blend_val(m.bytes), Ok((name.as_str(), u[*i])));
                let v = decode_osc(m.bytes).expect("val");
                prop_assert_eq!(v.addr.as_str(), "/VMC/Ext/Blend/Val");
                prop_assert_eq!(v.args, vec![OscType::String(name.clone()), OscType::Float(u[*i])]);
            }
            prop_assert_eq!(msgs[msgs.len() - 1].address, "/VMC/Ext/Blend/Apply");
        }
    }
}

/// Every control within its documented limits.
fn control_strategy() -> impl Strategy<Value = Control> {
    let text = "[ -~]{0,30}";
    prop_oneof![
        text.prop_map(Control::Target),
        (0.0f32..=1.0).prop_map(Control::Amount),
        (0.0f32..=MAX_RAMP_S).prop_map(Control::Ramp),
        (0..=i32::MAX as u32, -MAX_ALPHA..=MAX_ALPHA)
            .prop_map(|(component, value)| Control::Alpha { component, value }),
        (0..=i32::MAX as u32, -MAX_GAIN..=MAX_GAIN)
            .prop_map(|(component, gain)| Control::Gain { component, gain }),
        any::<bool>().prop_map(Control::Bypass),
        (
            1..=u16::MAX,
            prop::sample::select(Profile::ALL.to_vec()),
            prop::option::of(text),
            prop::option::of(any::<i32>()),
        )
            .prop_map(|(port, profile, performer, cookie)| Control::Subscribe {
                port,
                profile,
                performer,
                cookie,
            }),
        (1..=u16::MAX).prop_map(|port| Control::Unsubscribe { port }),
        text.prop_map(Control::ModelLoad),
        (text, prop::option::of(text), any::<bool>()).prop_map(|(path, raw, overwrite)| {
            Control::RecordStart {
                path,
                raw,
                overwrite,
            }
        }),
        Just(Control::RecordStop),
        Just(Control::Status),
    ]
}

/// One message decoded by rosc, the independent reader the properties check against.
fn decode_osc(bytes: &[u8]) -> Result<OscMessage, String> {
    match rosc::decoder::decode_udp(bytes) {
        Ok((_, OscPacket::Message(m))) => Ok(m),
        other => Err(format!("not one message: {other:?}")),
    }
}
