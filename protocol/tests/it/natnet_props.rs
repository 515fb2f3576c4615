//! NatNet property tests: encode → decode round trips for every message emoshift encodes,
//! and no panic on arbitrary bytes, truncations and bit flips of real packets.

use crate::natnet_fixtures::*;
use proptest::prelude::*;
use protocol::natnet::*;

const VERSIONS: [NatNetVersion; 5] = [
    NatNetVersion::V3_0,
    NatNetVersion::V3_1,
    NatNetVersion::V4_0,
    NatNetVersion::V4_1,
    NatNetVersion::new(4, 2, 0, 0),
];

fn version() -> impl Strategy<Value = NatNetVersion> {
    prop::sample::select(&VERSIONS[..])
}

fn v3() -> impl Strategy<Value = [f32; 3]> {
    prop::array::uniform3(-10.0f32..10.0)
}

fn name() -> impl Strategy<Value = String> {
    "[A-Za-z0-9_ ]{0,16}"
}

fn rigid_body() -> impl Strategy<Value = RigidBody> {
    (
        any::<i32>(),
        v3(),
        prop::array::uniform4(-1.0f32..1.0),
        0.0f32..0.01,
        any::<u16>(),
    )
        .prop_map(
            |(id, position, orientation, mean_error, params)| RigidBody {
                id,
                position,
                orientation,
                mean_error,
                params,
            },
        )
}

fn labeled_marker() -> impl Strategy<Value = LabeledMarker> {
    (any::<u32>(), v3(), 0.0f32..0.05, any::<u16>(), 0.0f32..0.01).prop_map(
        |(id, position, size, p, residual)| LabeledMarker {
            id,
            position,
            size,
            params: MarkerParams(p),
            residual,
        },
    )
}

type Analog = Vec<(i32, Vec<Vec<f32>>)>;

fn analog() -> impl Strategy<Value = Analog> {
    prop::collection::vec(
        (
            any::<i32>(),
            prop::collection::vec(prop::collection::vec(-1e3f32..1e3, 0..4), 0..3),
        ),
        0..3,
    )
}

fn push_analog(a: &mut AnalogData, devices: &Analog) {
    for (id, channels) in devices {
        let ch: Vec<&[f32]> = channels.iter().map(Vec::as_slice).collect();
        a.push(*id, &ch);
    }
}

prop_compose! {
    fn frame(v: NatNetVersion)(
        number in any::<i32>(),
        sets in prop::collection::vec((name(), prop::collection::vec(v3(), 0..20)), 0..4),
        other in prop::collection::vec(v3(), 0..10),
        bodies in prop::collection::vec(rigid_body(), 0..4),
        skeletons in prop::collection::vec((any::<i32>(), prop::collection::vec(rigid_body(), 0..4)), 0..3),
        labeled in prop::collection::vec(labeled_marker(), 0..30),
        plates in analog(),
        devices in analog(),
        stamps in (any::<u32>(), any::<u32>(), 0.0f64..1e6, any::<u64>(), any::<u64>(), any::<u64>()),
        precision in (any::<bool>(), any::<u32>(), any::<u32>()),
        params in any::<u16>(),
    ) -> FrameOfData {
        let mut f = FrameOfData::default();
        f.frame_number = number;
        for (n, p) in &sets {
            f.push_markerset(n, p);
        }
        f.other_markers = other;
        f.rigid_bodies = bodies;
        for (id, bones) in &skeletons {
            f.push_skeleton(*id, bones);
        }
        f.labeled_markers = labeled;
        push_analog(&mut f.force_plates, &plates);
        push_analog(&mut f.devices, &devices);
        (f.timecode, f.timecode_subframe, f.timestamp) = (stamps.0, stamps.1, stamps.2);
        (f.camera_mid_exposure, f.camera_data_received, f.transmit) = (stamps.3, stamps.4, stamps.5);
        let with = v.has_precision_timestamp() || (v.major == 4 && precision.0);
        f.precision_timestamp = with.then_some(PrecisionTimestamp { seconds: precision.1, fraction: precision.2 });
        f.params = FrameParams(params);
        f
    }
}

fn rb_def(with_names: bool) -> impl Strategy<Value = RigidBodyDef> {
    (
        name(),
        any::<i32>(),
        any::<i32>(),
        v3(),
        prop::collection::vec((v3(), any::<i32>(), name()), 0..6),
    )
        .prop_map(move |(name, id, parent_id, offset, markers)| RigidBodyDef {
            name,
            id,
            parent_id,
            offset,
            markers: markers
                .into_iter()
                .map(|(offset, required_label, n)| RigidBodyMarkerDef {
                    offset,
                    required_label,
                    name: if with_names { n } else { String::new() },
                })
                .collect(),
        })
}

fn model_defs(v: NatNetVersion) -> impl Strategy<Value = ModelDefs> {
    let names4 = v.has_rigid_body_marker_names();
    (
        prop::collection::vec((name(), prop::collection::vec(name(), 0..6)), 0..4),
        prop::collection::vec(rb_def(names4), 0..3),
        prop::collection::vec(
            (
                name(),
                any::<i32>(),
                prop::collection::vec(rb_def(names4), 0..3),
            ),
            0..2,
        ),
        prop::collection::vec(
            (
                any::<i32>(),
                name(),
                prop::collection::vec(-1.0f32..1.0, 144),
                prop::collection::vec(name(), 0..3),
            ),
            0..2,
        ),
        prop::collection::vec(
            (
                any::<i32>(),
                name(),
                name(),
                any::<i32>(),
                prop::collection::vec(name(), 0..3),
            ),
            0..2,
        ),
        prop::collection::vec((name(), v3(), prop::array::uniform4(-1.0f32..1.0)), 0..3),
        prop::collection::vec(
            (
                name(),
                any::<i32>(),
                prop::collection::vec(rb_def(names4), 0..2),
                prop::collection::vec(
                    (name(), any::<i32>(), v3(), 0.0f32..0.1, any::<u16>()),
                    0..3,
                ),
            ),
            0..2,
        ),
    )
        .prop_map(move |(ms, rbs, sks, fps, devs, cams, assets)| ModelDefs {
            markersets: ms
                .into_iter()
                .map(|(name, marker_names)| MarkersetDef { name, marker_names })
                .collect(),
            rigid_bodies: rbs,
            skeletons: sks
                .into_iter()
                .map(|(name, id, bones)| SkeletonDef { name, id, bones })
                .collect(),
            force_plates: fps
                .into_iter()
                .map(|(id, serial, calibration, channel_names)| ForcePlateDef {
                    id,
                    serial,
                    size: [0.5, 0.6],
                    origin: [0.0, 0.01, 0.0],
                    calibration,
                    corners: [[1.0, 0.0, 0.0]; 4],
                    plate_type: 2,
                    channel_data_type: 0,
                    channel_names,
                })
                .collect(),
            devices: devs
                .into_iter()
                .map(|(id, name, serial, device_type, channel_names)| DeviceDef {
                    id,
                    name,
                    serial,
                    device_type,
                    channel_data_type: 1,
                    channel_names,
                })
                .collect(),
            cameras: cams
                .into_iter()
                .map(|(name, position, orientation)| CameraDef {
                    name,
                    position,
                    orientation,
                })
                .collect(),
            assets: if v.has_section_sizes() {
                assets
                    .into_iter()
                    .map(|(name, id, rigid_bodies, markers)| AssetDef {
                        name,
                        asset_type: 1,
                        id,
                        rigid_bodies,
                        markers,
                    })
                    .collect()
            } else {
                Vec::new()
            },
            skipped_types: Vec::new(),
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn frames_round_trip((v, f) in version().prop_flat_map(|v| (Just(v), frame(v)))) {
        let mut bytes = Vec::new();
        encode_frame_into(&f, v, &mut bytes).expect("encodable");
        let mut back = FrameOfData::with_capacity(10, 2);
        decode_frame_into(&bytes, v, &mut back).expect("decodes");
        prop_assert_eq!(back, f);
    }

    #[test]
    fn model_defs_round_trip((v, d) in version().prop_flat_map(|v| (Just(v), model_defs(v)))) {
        let mut bytes = Vec::new();
        encode_model_defs_into(&d, v, &mut bytes).expect("encodable");
        prop_assert_eq!(decode_model_defs(&bytes, v).expect("decodes"), d);
    }

    #[test]
    fn command_messages_round_trip(
        app in name(), ver in any::<[u8; 4]>(), nn in version(), hz in any::<u64>(), port in any::<u16>(),
        multicast in any::<bool>(), group in any::<[u8; 4]>(), with_conn in any::<bool>(),
        stamps in any::<(u64, u64)>(), text in "[ -~]{0,40}", options in any::<Option<(bool, [u8; 4])>>(),
    ) {
        let mut out = Vec::new();
        let info = ServerInfo {
            app_name: app.clone(),
            app_version: ver,
            natnet_version: nn,
            connection: with_conn.then_some(ConnectionInfo { clock_frequency_hz: hz, data_port: port, multicast, multicast_group: group }),
        };
        encode_server_info_into(&info, &mut out).expect("encodable");
        prop_assert_eq!(decode_packet(&out), Ok(Packet::ServerInfo(info)));
        let c = Connect {
            client_name: app,
            app_version: ver,
            natnet_version: nn,
            options: options.map(|(s, b)| ConnectionOptions { subscribed_data_only: s, bitstream_version: NatNetVersion::from_bytes(b) }),
        };
        for discovery in [false, true] {
            encode_connect_into(&c, discovery, &mut out).expect("encodable");
            let expected = if discovery { Packet::Discovery(c.clone()) } else { Packet::Connect(c.clone()) };
            prop_assert_eq!(decode_packet(&out), Ok(expected));
        }
        encode_echo_request_into(stamps.0, &mut out);
        prop_assert_eq!(decode_packet(&out), Ok(Packet::EchoRequest(stamps.0)));
        let e = EchoResponse { request_stamp: stamps.0, server_ticks: stamps.1 };
        encode_echo_response_into(&e, &mut out);
        prop_assert_eq!(decode_packet(&out), Ok(Packet::EchoResponse(e)));
        encode_request_into(&text, &mut out).expect("encodable");
        prop_assert_eq!(decode_packet(&out), Ok(Packet::Request(text.as_bytes())));
        encode_text_into(MessageId::MessageString, &text, &mut out).expect("encodable");
        prop_assert_eq!(decode_packet(&out), Ok(Packet::MessageString(text.as_bytes())));
        for (id, p) in [(MessageId::KeepAlive, Packet::KeepAlive), (MessageId::RequestModelDef, Packet::RequestModelDef),
                        (MessageId::Disconnect, Packet::Disconnect), (MessageId::RequestFrameOfData, Packet::RequestFrameOfData)] {
            encode_empty_into(id, &mut out);
            prop_assert_eq!(decode_packet(&out), Ok(p));
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600), id in prop::sample::select(vec![1u16, 5, 7, 13])) {
        let mut f = FrameOfData::default();
        decode_all(&bytes, &mut f);
        // the same bytes behind a valid header, to reach the payload decoders
        let mut framed = id.to_le_bytes().to_vec();
        framed.extend_from_slice(&(bytes.len() as u16).to_le_bytes());
        framed.extend_from_slice(&bytes);
        decode_all(&framed, &mut f);
    }
}

/// Every decoder, every version, plus a client session: none may panic.
fn decode_all(bytes: &[u8], f: &mut FrameOfData) {
    let _ = decode_packet(bytes);
    for v in VERSIONS
        .into_iter()
        .chain([NatNetVersion::new(2, 9, 0, 0), NatNetVersion::default()])
    {
        let _ = decode_frame_into(bytes, v, f);
        let _ = decode_model_defs(bytes, v);
    }
}

fn real_packets() -> Vec<Vec<u8>> {
    let mut all: Vec<Vec<u8>> = SINGLE_PACKETS.iter().map(|n| fixture(n)).collect();
    all.extend(capture_frames().into_iter().step_by(50));
    all
}

/// Every prefix of every real packet is rejected, both as is (the header size no longer
/// matches) and with the header size patched to the prefix (the payload decoders must see
/// the truncation).
#[test]
fn truncations_of_real_packets_are_errors() {
    let mut f = FrameOfData::default();
    for p in real_packets() {
        for cut in 0..p.len() {
            let mut t = p[..cut].to_vec();
            decode_all(&t, &mut f);
            if cut >= 4 {
                t[2..4].copy_from_slice(&((cut - 4) as u16).to_le_bytes());
                decode_all(&t, &mut f);
                if p[0] == 7 {
                    assert!(
                        decode_frame_into(&t, NatNetVersion::V3_0, &mut f).is_err(),
                        "cut {cut}"
                    );
                }
                if p[0] == 5 {
                    assert!(
                        decode_model_defs(&t, NatNetVersion::V3_0).is_err(),
                        "cut {cut}"
                    );
                }
            }
        }
    }
}

#[test]
fn bit_flips_of_real_packets_never_panic() {
    let mut f = FrameOfData::default();
    for p in real_packets() {
        for bit in 0..p.len() * 8 {
            let mut t = p.clone();
            t[bit / 8] ^= 1 << (bit % 8);
            decode_all(&t, &mut f);
        }
    }
}

#[test]
fn forged_counts_fail_fast() {
    let mut p = fixture("mocapframe_packet_v3.bin");
    // markerset count at payload offset 4 → 2^31 - 1
    p[8..12].copy_from_slice(&i32::MAX.to_le_bytes());
    let mut f = FrameOfData::default();
    assert_eq!(
        decode_frame_into(&p, NatNetVersion::V3_0, &mut f),
        Err(NatNetError::BadCount {
            count: i64::from(i32::MAX),
            offset: 8
        })
    );
    p[8..12].copy_from_slice(&(-1i32).to_le_bytes());
    assert_eq!(
        decode_frame_into(&p, NatNetVersion::V3_0, &mut f),
        Err(NatNetError::BadCount {
            count: -1,
            offset: 8
        })
    );
}
