//! Writes NatNet 3.0 packets encoded by emoshift's Motive stand-in, for the python_natnet
//! interop check (`scripts/natnet_python_check.py`). The library does no I/O; this example
//! writes the file.
//!
//! ```text
//! natnet_packets <out.bin>
//! ```
//! The file holds length-prefixed packets (`u16` little-endian length, then the datagram):
//! server info, model definitions, echo response, then frames 1000..1004. Each frame has a
//! markerset "face" of 3 markers and "all", 2 other markers, rigid body 7, labelled markers
//! `7 << 16 | i` at the markerset's positions, and a skeleton with one bone.

use protocol::natnet::*;

fn packets() -> Result<Vec<Vec<u8>>, NatNetEncodeError> {
    let v = NatNetVersion::V3_0;
    let mut out = Vec::new();
    let mut buf = Vec::new();
    let info = ServerInfo {
        app_name: "emoshift-stand-in".into(),
        app_version: [0, 1, 0, 0],
        natnet_version: v,
        connection: Some(ConnectionInfo {
            clock_frequency_hz: 10_000_000,
            data_port: DEFAULT_DATA_PORT,
            multicast: true,
            multicast_group: DEFAULT_MULTICAST_GROUP,
        }),
    };
    encode_server_info_into(&info, &mut buf)?;
    out.push(buf.clone());
    let names = |p: &str| (1..=3).map(|i| format!("{p}{i}")).collect::<Vec<_>>();
    let defs = ModelDefs {
        markersets: vec![
            MarkersetDef {
                name: "face".into(),
                marker_names: names("M"),
            },
            MarkersetDef {
                name: "all".into(),
                marker_names: names("face_"),
            },
        ],
        rigid_bodies: vec![RigidBodyDef {
            name: "head".into(),
            id: 7,
            parent_id: -1,
            offset: [0.0; 3],
            markers: (0..3)
                .map(|i| RigidBodyMarkerDef {
                    offset: [i as f32 * 0.01, 0.0, 0.0],
                    ..Default::default()
                })
                .collect(),
        }],
        ..ModelDefs::default()
    };
    encode_model_defs_into(&defs, v, &mut buf)?;
    out.push(buf.clone());
    encode_echo_response_into(
        &EchoResponse {
            request_stamp: 42,
            server_ticks: 123_456_789,
        },
        &mut buf,
    );
    out.push(buf.clone());
    for n in 1000..1005 {
        let t = (n - 1000) as f32 * 0.001;
        let pos: Vec<[f32; 3]> = (0..3).map(|i| [0.1 * i as f32 + t, 1.5, -0.2]).collect();
        let mut f = FrameOfData::default();
        f.frame_number = n;
        f.push_markerset("face", &pos);
        f.push_markerset("all", &pos);
        f.other_markers = vec![[0.5, 0.5, 0.5], [0.6, 0.6, 0.6]];
        let body = RigidBody {
            id: 7,
            position: [0.1, 1.5, -0.2],
            orientation: [0.0, 0.0, 0.0, 1.0],
            mean_error: 0.0002,
            params: 1,
        };
        f.rigid_bodies = vec![body];
        f.push_skeleton(
            3,
            &[RigidBody {
                id: 3 << 16 | 1,
                ..body
            }],
        );
        f.labeled_markers = pos
            .iter()
            .enumerate()
            .map(|(i, &position)| LabeledMarker {
                id: 7 << 16 | (i as u32 + 1),
                position,
                size: 0.01,
                params: MarkerParams(0x0a),
                residual: 0.0001,
            })
            .collect();
        f.timestamp = f64::from(n) / 120.0;
        (f.camera_mid_exposure, f.camera_data_received, f.transmit) = (1_000, 2_000, 3_000);
        f.params = FrameParams(if n == 1004 { 0x02 } else { 0 });
        encode_frame_into(&f, v, &mut buf)?;
        out.push(buf.clone());
    }
    Ok(out)
}

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: natnet_packets <out.bin>");
        std::process::exit(2);
    };
    let packets = packets().unwrap_or_else(|e| {
        eprintln!("natnet_packets: {e}");
        std::process::exit(1);
    });
    let mut file = Vec::new();
    for p in &packets {
        let len = u16::try_from(p.len()).expect("packets are far below 64 KiB");
        file.extend_from_slice(&len.to_le_bytes());
        file.extend_from_slice(p);
    }
    if let Err(e) = std::fs::write(&path, file) {
        eprintln!("natnet_packets: cannot write {path}: {e}");
        std::process::exit(1);
    }
    println!("{} packets -> {path}", packets.len());
}
