use super::*;

#[test]
fn text_packets_round_trip_with_their_nul() {
    let mut out = Vec::new();
    encode_text_into(PacketType::Command, WELCOME, &mut out);
    assert_eq!(out.len(), 8 + WELCOME.len() + 1);
    assert_eq!(&out[..8], &[35, 0, 0, 0, 1, 0, 0, 0]);
    let p = decode_packet(&out).expect("whole packet");
    assert_eq!((p.kind, p.text()), (PacketType::Command, Ok(WELCOME)));
}

#[test]
fn framer_cuts_a_stream_at_any_split_and_refuses_oversized_packets() {
    let mut stream = Vec::new();
    let mut one = Vec::new();
    for text in [
        "Version 1.25",
        "GetParameters All",
        "StreamFrames AllFrames 3D",
    ] {
        encode_text_into(PacketType::Command, text, &mut one);
        stream.extend_from_slice(&one);
    }
    encode_event_into(Event::CaptureStarted, &mut one);
    stream.extend_from_slice(&one);
    for split in 1..stream.len() {
        let mut f = Framer::new(1024);
        let mut got = Vec::new();
        for part in [&stream[..split], &stream[split..]] {
            f.buffer()[..part.len()].copy_from_slice(part);
            f.filled(part.len());
            while let Some(p) = f.next_packet().expect("valid stream") {
                got.push((p.kind, p.payload.to_vec()));
            }
        }
        assert_eq!(got.len(), 4, "split at {split}");
        assert_eq!(got[3], (PacketType::Event, vec![3]));
    }
    let mut f = Framer::new(64);
    f.buffer()[..8].copy_from_slice(&[0, 1, 0, 0, 1, 0, 0, 0]);
    f.filled(8);
    assert!(matches!(
        f.next_packet(),
        Err(QtmError::BadSize { size: 256, .. })
    ));
    let mut f = Framer::new(64);
    f.buffer()[..8].copy_from_slice(&[8, 0, 0, 0, 99, 0, 0, 0]);
    f.filled(8);
    assert_eq!(f.next_packet(), Err(QtmError::UnknownType { kind: 99 }));
}

#[test]
fn commands_parse_as_qtm_reads_them() {
    assert_eq!(
        parse_command("Version 1.25"),
        Command::Version(Some((1, 25)))
    );
    assert_eq!(parse_command("version"), Command::Version(None));
    assert_eq!(parse_command("qtmversion"), Command::QtmVersion);
    let all = ParameterSet {
        general: true,
        d3: true,
    };
    assert_eq!(
        parse_command("getparameters all"),
        Command::GetParameters(Ok(all))
    );
    assert_eq!(
        parse_command("GetParameters General 6D"),
        Command::GetParameters(Err("6D"))
    );
    let c = Components {
        d3: true,
        timecode: true,
        ..Components::default()
    };
    assert_eq!(
        parse_command("StreamFrames FrequencyDivisor:2 UDP:4545 3D Timecode"),
        Command::StreamFrames {
            rate: Rate::Divisor(2),
            transport: Transport::Udp {
                ip: None,
                port: 4545
            },
            components: Ok(c)
        }
    );
    assert_eq!(
        parse_command("streamframes allframes udp:127.0.0.2:4545 3dres"),
        Command::StreamFrames {
            rate: Rate::AllFrames,
            transport: Transport::Udp {
                ip: Some([127, 0, 0, 2].into()),
                port: 4545
            },
            components: Ok(Components {
                d3_res: true,
                ..Components::default()
            })
        }
    );
    assert_eq!(parse_command("StreamFrames Stop"), Command::StreamStop);
    assert_eq!(
        parse_command("StreamFrames Frequency:0 3D"),
        Command::Unknown
    );
    assert_eq!(
        parse_command("TakeControl secret"),
        Command::Refused("TakeControl")
    );
    assert_eq!(parse_command("calibrate"), Command::Refused("calibrate"));
    assert_eq!(parse_command("dance"), Command::Unknown);
    assert_eq!(parse_command(""), Command::Unknown);
    // Found by fuzz/qtm_server: a multi-byte character where "UDP" would be.
    assert!(matches!(
        parse_command("StreamFrames AllFrames UD\u{62f}P:4545 3D"),
        Command::StreamFrames {
            components: Err(_),
            ..
        }
    ));
}

#[test]
fn data_round_trips_3d_3dres_and_timecode_and_skips_other_components() {
    let nan = f32::NAN;
    let positions = [1.5, -2.0, 3.25, nan, nan, nan, 7.0, 8.0, 9.0];
    let tc = Timecode::Smpte {
        hours: 23,
        minutes: 59,
        seconds: 58,
        frames: 29,
        subframes: 300,
    };
    let frame = DataFrame {
        timestamp_us: -5,
        frame_number: u32::MAX,
        positions: &positions,
        timecode: Some(tc),
    };
    let all = Components {
        d3: true,
        d3_res: true,
        d3_no_labels: true,
        timecode: true,
    };
    let mut out = Vec::new();
    encode_data_into(&frame, all, &mut out);
    // header 8 + 16 + 3D (16 + 36) + 3DRes (16 + 48) + 3DNoLabels (16 + 32) + Timecode (24)
    assert_eq!(out.len(), 8 + 16 + 52 + 64 + 48 + 24);
    let p = decode_packet(&out).expect("whole packet");
    let mut got = FrameIn::with_max_markers(3);
    decode_data_into(p.payload, &mut got).expect("valid");
    assert_eq!(
        (got.timestamp_us, got.frame_number, got.timecode),
        (-5, u32::MAX, Some(tc))
    );
    for (a, b) in got.positions().iter().zip(positions) {
        assert!(a == &b || (a.is_nan() && b.is_nan()));
    }
    let only_res = Components {
        d3_res: true,
        ..Components::default()
    };
    encode_data_into(&frame, only_res, &mut out);
    let p = decode_packet(&out).expect("whole packet");
    decode_data_into(p.payload, &mut got).expect("valid");
    assert_eq!(got.positions()[6..], [7.0, 8.0, 9.0]);
    assert_eq!(got.timecode, None);
    let mut small = FrameIn::with_max_markers(2);
    assert!(matches!(
        decode_data_into(p.payload, &mut small),
        Err(QtmError::TooManyMarkers { count: 3, max: 2 })
    ));
}

#[test]
fn timecodes_pack_as_the_sdks_unpack_them() {
    let smpte = Timecode::Smpte {
        hours: 1,
        minutes: 2,
        seconds: 3,
        frames: 4,
        subframes: 0,
    };
    assert_eq!(smpte.to_words(), (0, 0, 1 | 2 << 5 | 3 << 11 | 4 << 17));
    let irig = Timecode::Irig {
        years: 26,
        days: 331,
        hours: 5,
        minutes: 6,
        seconds: 7,
        tenths: 8,
    };
    let (k, hi, lo) = irig.to_words();
    assert_eq!(Timecode::from_words(k, hi, lo), Some(irig));
    assert_eq!(
        Timecode::from_words(2, 1, 2),
        Some(Timecode::CameraTime((1 << 32) | 2))
    );
    assert_eq!(Timecode::from_words(3, 0, 0), None);
}

#[test]
fn data_decoder_rejects_bad_sizes_without_panicking() {
    let mut got = FrameIn::with_max_markers(8);
    assert!(decode_data_into(&[0; 15], &mut got).is_err());
    let mut p = vec![0u8; 16];
    p[12] = 1; // one component
    p.extend_from_slice(&4u32.to_le_bytes()); // size 4 < 8
    p.extend_from_slice(&COMPONENT.to_le_bytes());
    assert!(matches!(
        decode_data_into(&p, &mut got),
        Err(QtmError::ComponentSize { .. })
    ));
    for n in 0..200 {
        let bytes: Vec<u8> = (0..n).map(|i| (i * 37 + n) as u8).collect();
        let _ = decode_data_into(&bytes, &mut got);
        let _ = decode_packet(&bytes);
    }
}
const COMPONENT: u32 = data::COMPONENT_3D;

#[test]
fn parameters_name_the_version_rate_and_escaped_labels() {
    let labels = vec!["Alice_Brow<L>".to_string(), "Jaw&Chin".to_string()];
    let p = Parameters {
        version: (1, 25),
        frequency_hz: 120,
        labels: &labels,
    };
    let mut out = Vec::new();
    encode_parameters_into(
        &p,
        ParameterSet {
            general: true,
            d3: true,
        },
        &mut out,
    );
    let pk = decode_packet(&out).expect("whole packet");
    let xml = pk.text().expect("utf-8");
    assert_eq!(pk.kind, PacketType::Xml);
    assert!(xml.starts_with("<QTM_Parameters_Ver_1.25>"));
    assert!(xml.contains("<Frequency>120</Frequency>"));
    assert!(xml.contains("<Labels>2</Labels>"));
    assert!(xml.contains("<Name>Alice_Brow&lt;L&gt;</Name>"));
    assert!(xml.contains("<Name>Jaw&amp;Chin</Name>"));
    encode_parameters_into(
        &p,
        ParameterSet {
            general: true,
            d3: false,
        },
        &mut out,
    );
    assert!(!decode_packet(&out)
        .expect("packet")
        .text()
        .expect("utf-8")
        .contains("The_3D"));
}

#[test]
fn discovery_reads_the_reply_port_and_answers_with_the_base_port() {
    let mut req = vec![10, 0, 0, 0, 7, 0, 0, 0];
    req.extend_from_slice(&5555u16.to_be_bytes());
    assert_eq!(decode_discover(&req), Ok(5555));
    assert!(decode_discover(&req[..9]).is_err());
    let mut out = Vec::new();
    encode_discover_reply_into("emoshift", 22223, &mut out);
    assert_eq!(out.len(), 8 + 9 + 2);
    assert_eq!(&out[out.len() - 2..], &22223u16.to_be_bytes());
}

#[test]
fn events_keep_their_numbers() {
    for b in 1..=16u8 {
        assert_eq!(Event::from_u8(b).map(Event::as_u8), Some(b));
    }
    assert_eq!(Event::from_u8(0), None);
    assert!(Event::CameraSettingsChanged.rereads_parameters());
    assert!(Event::QtmShuttingDown.ends_stream());
}
