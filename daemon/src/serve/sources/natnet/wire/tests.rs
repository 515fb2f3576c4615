use protocol::natnet::{encode_frame_into, FrameOfData, FrameParams, NatNetVersion};

use super::*;

#[test]
fn the_models_changed_flag_is_read_in_place_in_3_x_and_4_x_frames() {
    let mut f = FrameOfData::default();
    f.push_markerset("Face", &[[1.0, 2.0, 3.0]]);
    let mut bytes = Vec::new();
    for v in [
        NatNetVersion::V3_0,
        NatNetVersion::V4_0,
        NatNetVersion::V4_1,
    ] {
        for (params, changed) in [(0, false), (2, true), (1, false), (3, true)] {
            f.params = FrameParams(params);
            encode_frame_into(&f, v, &mut bytes).expect("encodable");
            assert_eq!(models_changed(&bytes), changed, "{v} params {params}");
        }
    }
}
