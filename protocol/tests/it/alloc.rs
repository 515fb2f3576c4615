//! The frame path allocates nothing once buffers exist: allocation-counter's counting global
//! allocator (it counts per thread) decides.

use protocol::*;

#[test]
fn frame_decode_edit_encode_allocates_nothing() {
    let positions: Vec<f32> = (0..109 * 3).map(|i| i as f32).collect();
    let mut src = FrameBuf::with_max_markers(109);
    src.set_frame(0, 0, &positions).expect("valid");
    src.set_missing(5, true);
    let mut wire = Vec::with_capacity(1_500);
    encode_frame_into(&src, &mut wire).expect("finite");
    let tag = StreamTag {
        id: 3,
        name: "alice",
    };
    let mut compact = wire.clone();
    encode_compact_into(&tag, &src, "neutral", 0.5, &mut compact).expect("valid");
    let mut buf = FrameBuf::with_max_markers(109);
    let mut out = Vec::with_capacity(1_500);
    let split = FlatSplit::new(ETHERNET_PAYLOAD).expect("fits");
    let u = [0.25f32; 12];
    let vmc = [("joy", 0usize), ("anger", 3)];
    let limits = Limits::default();

    let info = allocation_counter::measure(|| {
        for i in 0..10_000 {
            for datagram in [&wire, &compact] {
                for m in messages(datagram, &limits).expect("valid") {
                    if m.address == "/mocap/frame" {
                        decode_frame_into(m.bytes, &mut buf).expect("valid frame");
                    }
                }
            }
            buf.positions_mut()[0] += 1.0;
            buf.set_header(i, i64::from(i) * 8_333);
            encode_frame_into(&buf, &mut out).expect("finite");
            encode_compact_into(&tag, &buf, "joy", 0.5, &mut out).expect("valid");
            for p in 0..split.part_count(buf.marker_count()) {
                split
                    .encode_part_into(&tag, &buf, p, &mut out)
                    .expect("valid");
            }
            encode_components_into(&tag, &u, &vmc, &mut out).expect("valid");
        }
    });
    assert_eq!(info.count_total, 0, "{info:?}");
}
