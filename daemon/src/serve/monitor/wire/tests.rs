use super::*;
use engine::synthetic::random_space_model;

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

#[test]
fn a_snapshot_lays_out_as_the_page_reads_it() {
    let s = Snapshot {
        stream_id: 3,
        frame_number: 77,
        input: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        output: vec![-1.0; 6],
        flags: vec![0, 3],
        u_in: vec![0.5],
        u_out: vec![0.25],
        target: "happy".into(),
        amount: 0.5,
        amount_goal: 1.0,
        ramp_s: 0.25,
        bypass: true,
        frames: 10,
        duplicates: 2,
        stale: 1,
        ..Snapshot::default()
    };
    let b = encode_snapshot(&s);
    assert_eq!(&b[..4], MAGIC);
    assert_eq!(i32::from_le_bytes(b[4..8].try_into().expect("4")), 3);
    assert_eq!(u32::from_le_bytes(b[12..16].try_into().expect("4")), 2);
    assert_eq!((f32_at(&b, 20), f32_at(&b, 24)), (0.5, 1.0));
    assert_eq!(b[32], 1, "bypass");
    assert_eq!(f64::from_le_bytes(b[44..52].try_into().expect("8")), 2.0);
    assert_eq!(u32::from_le_bytes(b[60..64].try_into().expect("4")), 5);
    assert_eq!(&b[64..69], b"happy");
    let floats = 72;
    assert_eq!(f32_at(&b, floats + 4 * 5), 6.0, "last input coordinate");
    assert_eq!(f32_at(&b, floats + 4 * 12), 0.5, "component in");
    assert_eq!(f32_at(&b, floats + 4 * 13), 0.25, "component out");
    assert_eq!(&b[floats + 4 * 14..], &[0, 3], "flags close it");
}

#[test]
fn the_model_message_names_labels_roles_and_emotion_points() {
    let model = random_space_model(5, 3, 1);
    let v: Value = serde_json::from_str(&model_json(2, &model, Some("m.json"))).expect("json");
    assert_eq!(v["labels"][4], "m4");
    assert_eq!(v["emotion"]["components"], json!([0, 2]));
    let happy = v["emotion"]["points"]
        .as_array()
        .expect("points")
        .iter()
        .find(|p| p["name"] == "happy")
        .expect("happy");
    assert_eq!(happy["level"], json!([2.0, 0.0]));
    assert_eq!(v["file"], "m.json");
}
