//! Loads the NatNet fixtures (see tests/fixtures/natnet/SOURCE.txt). A missing fixture fails
//! the test that needs it: these tests must never pass by skipping.

use std::io::Read;
use std::path::PathBuf;

/// One UDP datagram of the capture (every field of its record; the tests read some).
#[derive(Debug, Clone)]
pub struct Datagram {
    #[allow(dead_code)]
    pub ts_us: u64,
    pub src_port: u16,
    #[allow(dead_code)]
    pub dst_port: u16,
    pub payload: Vec<u8>,
}

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/natnet")
        .join(name)
}

/// The bytes of fixture `name`.
pub fn fixture(name: &str) -> Vec<u8> {
    let p = path(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("fixture {} is missing: {e}", p.display()))
}

fn gunzip(name: &str) -> Vec<u8> {
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(fixture(name).as_slice())
        .read_to_end(&mut out)
        .unwrap_or_else(|e| panic!("fixture {name} is not gzip: {e}"));
    out
}

/// Every UDP payload of the Motive 2.1 capture, in order.
pub fn traffic() -> Vec<Datagram> {
    let d = gunzip("traffic.udp.gz");
    let mut out = Vec::new();
    let mut i = 0;
    while i < d.len() {
        let ts_us = u64::from_le_bytes(d[i..i + 8].try_into().expect("8 bytes"));
        let src_port = u16::from_le_bytes([d[i + 8], d[i + 9]]);
        let dst_port = u16::from_le_bytes([d[i + 10], d[i + 11]]);
        let n = usize::from(u16::from_le_bytes([d[i + 12], d[i + 13]]));
        out.push(Datagram {
            ts_us,
            src_port,
            dst_port,
            payload: d[i + 14..i + 14 + n].to_vec(),
        });
        i += 14 + n;
    }
    assert_eq!(out.len(), 550, "the capture has 550 datagrams");
    out
}

/// The frames of data (data port 1511) of the capture.
pub fn capture_frames() -> Vec<Vec<u8>> {
    traffic()
        .into_iter()
        .filter(|d| d.src_port == 1511)
        .map(|d| d.payload)
        .collect()
}

/// SampleClient's printout, one line per frame (format in the file's first line).
pub fn sampleclient_lines() -> Vec<String> {
    let text = String::from_utf8(gunzip("sampleclient.txt.gz")).expect("utf-8");
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(str::to_owned)
        .collect()
}

/// The single real packets shipped beside the capture.
pub const SINGLE_PACKETS: [&str; 9] = [
    "connect_packet_v3.bin",
    "discovery_packet_v3.bin",
    "echorequest_packet_v3.bin",
    "echoresponse_packet_v3.bin",
    "mocapframe_packet_occluded_v3.bin",
    "mocapframe_packet_v3.bin",
    "modeldef_packet_v3.bin",
    "requestmodeldef_packet_v3.bin",
    "serverinfo_packet_v3.bin",
];
