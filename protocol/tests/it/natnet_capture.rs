//! The real Motive 2.1 capture against what NaturalPoint's SampleClient printed for it, and
//! the single command packets against their known contents.

use std::collections::HashMap;

use crate::natnet_fixtures::*;
use protocol::natnet::*;

/// `%.2f` as SampleClient (built with MSVC) prints it. That CRT first converts to 17
/// significant digits, then rounds the decimal string half away from zero: frame 162735's
/// timestamp 1356.125 prints "1356.13" and frame 162741's 1356.17499999999995 prints
/// "1356.18", where Rust and glibc, rounding the exact value, give "1356.12" and "1356.17".
fn printf2(x: f64) -> String {
    let sci = format!("{:.16e}", x.abs());
    let (mantissa, exp) = sci.split_once('e').expect("scientific notation");
    let exp: i32 = exp.parse().expect("exponent");
    let digits = mantissa.replace('.', "");
    let (int, frac) = if exp >= 0 {
        let cut = (exp + 1) as usize;
        let padded = format!("{digits:0<width$}", width = cut + 3);
        (padded[..cut].to_owned(), padded[cut..].to_owned())
    } else {
        (
            "0".to_owned(),
            format!("{}{digits}", "0".repeat((-exp - 1) as usize)),
        )
    };
    let mut d: Vec<u8> = format!("{int}{}", &frac[..2]).into_bytes();
    if frac.as_bytes()[2] >= b'5' {
        let mut i = d.len();
        loop {
            if i == 0 {
                d.insert(0, b'1');
                break;
            }
            i -= 1;
            if d[i] == b'9' {
                d[i] = b'0';
            } else {
                d[i] += 1;
                break;
            }
        }
    }
    let (a, b) = d.split_at(d.len() - 2);
    let body = format!(
        "{}.{}",
        String::from_utf8_lossy(a),
        String::from_utf8_lossy(b)
    );
    if x.is_sign_negative() {
        format!("-{body}")
    } else {
        body
    }
}

/// `%.2f` of a float (promoted to double, as in C).
fn c2(v: f32) -> String {
    printf2(f64::from(v))
}

#[test]
fn printf2_rounds_like_msvc() {
    assert_eq!(printf2(1356.125), "1356.13");
    assert_eq!(printf2(0.004), "0.00");
    assert_eq!(printf2(-0.004), "-0.00");
    assert_eq!(printf2(1356.175), "1356.18");
    assert_eq!(printf2(0.0123), "0.01");
    assert_eq!(printf2(99.999), "100.00");
}

fn flag(b: bool) -> &'static str {
    if b {
        "1"
    } else {
        "0"
    }
}

fn server_info() -> ServerInfo {
    let info = traffic()
        .iter()
        .find_map(|d| match decode_packet(&d.payload) {
            Ok(Packet::ServerInfo(s)) => Some(s),
            _ => None,
        })
        .expect("the capture has a server info");
    assert_eq!(info.app_name, "Motive");
    assert_eq!(info.app_version, [2, 1, 0, 0]);
    assert_eq!(info.natnet_version, NatNetVersion::V3_0);
    info
}

/// The fields of one frame, formatted the way SampleClient prints them.
fn printed(f: &FrameOfData, clock_hz: u64) -> String {
    let other: Vec<String> = f
        .other_markers
        .iter()
        .map(|p| format!("{},{},{}", c2(p[0]), c2(p[1]), c2(p[2])))
        .collect();
    let rigid: Vec<String> = f
        .rigid_bodies
        .iter()
        .map(|b| {
            let pose: Vec<String> = b
                .position
                .iter()
                .chain(&b.orientation)
                .map(|&v| c2(v))
                .collect();
            format!(
                "{},{},{},{}",
                b.id,
                c2(b.mean_error),
                flag(b.tracking_valid()),
                pose.join(",")
            )
        })
        .collect();
    let labeled: Vec<String> = f
        .labeled_markers
        .iter()
        .map(|m| {
            let p = m.params;
            format!(
                "{},{},{},{},{},{},{},{},{}",
                m.model_id(),
                m.marker_index(),
                flag(p.occluded()),
                flag(p.point_cloud_solved()),
                flag(p.model_solved()),
                c2(m.size),
                c2(m.position[0]),
                c2(m.position[1]),
                c2(m.position[2])
            )
        })
        .collect();
    let ms = |v: Option<f64>| printf2(v.expect("stamps present"));
    [
        f.frame_number.to_string(),
        printf2(f.timestamp),
        ms(f.software_latency_ms(clock_hz)),
        ms(f.system_latency_ms(clock_hz)),
        f.timecode().to_string(),
        other.join(";"),
        rigid.join(";"),
        labeled.join(";"),
    ]
    .join(" | ")
}

/// Transit time and total client latency need SampleClient's own clock and its echo-based
/// offset at that moment: they cannot be reproduced from the capture and are not compared.
#[test]
fn every_printed_frame_decodes_to_what_sampleclient_printed() {
    let info = server_info();
    let hz = info
        .connection
        .expect("NatNet 3 server info")
        .clock_frequency_hz;
    assert_eq!(hz, 3_312_787);
    let v = info.natnet_version;
    let mut decoded = HashMap::new();
    let mut frame = FrameOfData::default();
    for d in capture_frames() {
        decode_frame_into(&d, v, &mut frame).expect("every captured frame decodes");
        assert!(decoded
            .insert(frame.frame_number, printed(&frame, hz))
            .is_none());
    }
    assert_eq!(decoded.len(), 518);
    let lines = sampleclient_lines();
    assert_eq!(lines.len(), 251);
    for line in &lines {
        let id: i32 = line
            .split(' ')
            .next()
            .and_then(|s| s.parse().ok())
            .expect("frame id");
        assert_eq!(decoded.get(&id), Some(line), "frame {id}");
    }
    let printed_ids: Vec<i32> = lines
        .iter()
        .filter_map(|l| l.split(' ').next()?.parse().ok())
        .collect();
    assert_eq!(printed_ids.first(), Some(&162_734));
    assert_eq!(printed_ids.last(), Some(&162_984));
    // The capture goes on after SampleClient stopped printing; those frames decoded above.
    let unprinted = decoded
        .keys()
        .filter(|id| !printed_ids.contains(id))
        .count();
    assert_eq!(unprinted, 518 - 251);
    assert_eq!(decoded.keys().max(), Some(&163_251));
}

#[test]
fn every_captured_datagram_is_a_valid_packet() {
    let mut kinds = HashMap::new();
    let all = traffic();
    for d in &all {
        let p = decode_packet(&d.payload).unwrap_or_else(|e| panic!("{e}: {:?}", &d.payload[..4]));
        *kinds.entry(std::mem::discriminant(&p)).or_insert(0) += 1;
        match p {
            Packet::Request(cmd) if cmd.starts_with(b"FrameRate") => {}
            Packet::EchoResponse(e) => assert!(e.server_ticks > 0),
            _ => {}
        }
    }
    assert_eq!(
        kinds.len(),
        11,
        "connect, discovery, info, request, response, ..."
    );
}

#[test]
fn model_defs_name_the_rigid_body_and_markersets() {
    let from_capture = traffic()
        .into_iter()
        .find(|d| d.payload[0] == 5)
        .expect("a model def in the capture")
        .payload;
    for bytes in [fixture("modeldef_packet_v3.bin"), from_capture] {
        let defs = decode_model_defs(&bytes, NatNetVersion::V3_0).expect("valid");
        let rb = defs.rigid_body(2).expect("RaceQuad");
        assert_eq!(
            (rb.name.as_str(), rb.parent_id, rb.offset),
            ("RaceQuad", -1, [0.0; 3])
        );
        let offsets: Vec<String> = rb
            .markers
            .iter()
            .map(|m| {
                format!(
                    "{}, {}, {}",
                    c2(m.offset[0]),
                    c2(m.offset[1]),
                    c2(m.offset[2])
                )
            })
            .collect();
        // What SampleClient printed for the same description.
        assert_eq!(
            offsets,
            [
                "0.16, 0.04, -0.03",
                "-0.03, 0.04, -0.02",
                "0.19, -0.03, 0.15",
                "-0.07, 0.00, 0.03",
                "-0.06, -0.03, -0.14"
            ]
        );
        assert!(rb
            .markers
            .iter()
            .all(|m| m.required_label == 0 && m.name.is_empty()));
        let names = |n: &str| defs.markerset(n).map(|m| m.marker_names.clone());
        let quad: Vec<String> = (1..=5).map(|i| format!("Marker{i}")).collect();
        let all: Vec<String> = (1..=5).map(|i| format!("RaceQuad_{i}")).collect();
        assert_eq!(names("RaceQuad"), Some(quad));
        assert_eq!(names("all"), Some(all));
        assert_eq!(defs.markersets.len(), 2);
    }
}

#[test]
fn single_packets_decode_to_their_known_contents() {
    let info = match decode_packet(&fixture("serverinfo_packet_v3.bin")) {
        Ok(Packet::ServerInfo(s)) => s,
        other => panic!("{other:?}"),
    };
    let c = info.connection.expect("NatNet 3");
    assert_eq!(
        (c.data_port, c.multicast, c.multicast_group),
        (1511, true, DEFAULT_MULTICAST_GROUP)
    );
    for (name, discovery) in [
        ("connect_packet_v3.bin", false),
        ("discovery_packet_v3.bin", true),
    ] {
        let c = match decode_packet(&fixture(name)) {
            Ok(Packet::Connect(c)) if !discovery => c,
            Ok(Packet::Discovery(c)) if discovery => c,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            (c.client_name.as_str(), c.natnet_version, c.options),
            ("NatNetLib", NatNetVersion::V3_0, None)
        );
        let mut again = Vec::new();
        encode_connect_into(&c, discovery, &mut again).expect("encodable");
        assert_eq!(again, fixture(name), "re-encodes byte for byte");
    }
    let (req, resp) = (
        fixture("echorequest_packet_v3.bin"),
        fixture("echoresponse_packet_v3.bin"),
    );
    let (req, resp) = (decode_packet(&req), decode_packet(&resp));
    let (Ok(Packet::EchoRequest(stamp)), Ok(Packet::EchoResponse(e))) = (req, resp) else {
        panic!("echo packets")
    };
    assert_eq!(e.request_stamp, stamp);
    assert_eq!(
        decode_packet(&fixture("requestmodeldef_packet_v3.bin")),
        Ok(Packet::RequestModelDef)
    );
}

#[test]
fn the_occluded_frame_has_an_occluded_marker() {
    let mut f = FrameOfData::default();
    decode_frame_into(
        &fixture("mocapframe_packet_v3.bin"),
        NatNetVersion::V3_0,
        &mut f,
    )
    .expect("valid");
    assert!(f.labeled_markers.iter().all(|m| !m.params.occluded()));
    decode_frame_into(
        &fixture("mocapframe_packet_occluded_v3.bin"),
        NatNetVersion::V3_0,
        &mut f,
    )
    .expect("valid");
    assert!(f.labeled_markers.iter().any(|m| m.params.occluded()));
    let names: Vec<&str> = f.markersets().map(|m| m.name).collect();
    assert_eq!(names, ["FakeTree", "all"]);
}

#[test]
fn captured_frames_re_encode_byte_for_byte() {
    let mut f = FrameOfData::default();
    let mut out = Vec::new();
    for d in capture_frames() {
        decode_frame_into(&d, NatNetVersion::V3_0, &mut f).expect("valid");
        encode_frame_into(&f, NatNetVersion::V3_0, &mut out).expect("encodable");
        assert_eq!(out, d);
    }
}
