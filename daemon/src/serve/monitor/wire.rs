//! What the page receives: one binary message per snapshot (little-endian, laid out below),
//! and JSON texts for the rest (`hello`, `model`, `emotions`, `status`, `reply`).
//!
//! Snapshot (`EMF1`), offsets in bytes:
//!
//! | at | what |
//! |---|---|
//! | 0 | `EMF1` |
//! | 4 | i32 stream id |
//! | 8 | i32 frame number |
//! | 12 | u32 markers n |
//! | 16 | u32 components m |
//! | 20 | f32 amount, f32 amount goal, f32 ramp (s) |
//! | 32 | u32 bits: 1 = bypass |
//! | 36 | f64 frames, f64 duplicates dropped, f64 stale dropped |
//! | 60 | u32 target length t, then t bytes UTF-8, padded to 4 |
//! | then | f32 × 3n input, f32 × 3n output, f32 × m components in, f32 × m components out |
//! | then | u8 × n marker flags (1 missing as received, 2 filled by the model) |

use ica_core::model::IcaModel;
use serde_json::{json, Value};

use engine::monitor::Snapshot;

/// The first four bytes of a snapshot message.
pub(crate) const MAGIC: &[u8; 4] = b"EMF1";

/// Encodes a snapshot as the page reads it.
pub(crate) fn encode_snapshot(s: &Snapshot) -> Vec<u8> {
    let n = s.flags.len();
    let m = s.u_out.len();
    let target = s.target.as_bytes();
    let padded = target.len().div_ceil(4) * 4;
    let mut out = Vec::with_capacity(64 + padded + 4 * (6 * n + 2 * m) + n);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&s.stream_id.to_le_bytes());
    out.extend_from_slice(&s.frame_number.to_le_bytes());
    out.extend_from_slice(&(n as u32).to_le_bytes());
    out.extend_from_slice(&(m as u32).to_le_bytes());
    for v in [s.amount, s.amount_goal, s.ramp_s] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&u32::from(s.bypass).to_le_bytes());
    for v in [s.frames, s.duplicates, s.stale] {
        out.extend_from_slice(&(v as f64).to_le_bytes());
    }
    out.extend_from_slice(&(target.len() as u32).to_le_bytes());
    out.extend_from_slice(target);
    out.resize(out.len() + padded - target.len(), 0);
    // Buffers of another length than n or m (never, from the tap) are cut or padded with 0,
    // so the page's offsets always hold.
    for (values, len) in [
        (&s.input, 3 * n),
        (&s.output, 3 * n),
        (&s.u_in, m),
        (&s.u_out, m),
    ] {
        for k in 0..len {
            out.extend_from_slice(&values.get(k).copied().unwrap_or(0.0).to_le_bytes());
        }
    }
    out.extend_from_slice(&s.flags);
    out
}

/// A model's emotion space: components, and each emotion's point and spread.
pub(crate) fn emotion_json(model: &IcaModel) -> Value {
    let e = model.emotion();
    let points: Vec<Value> = e
        .names()
        .into_iter()
        .filter_map(|name| {
            let level = e.point(&name)?;
            let spread = e
                .points
                .get(&name)
                .map(|p| p.spread.clone())
                .unwrap_or_default();
            Some(json!({ "name": name, "level": level, "spread": spread }))
        })
        .collect();
    json!({ "components": e.space_components(), "points": points })
}

/// `model`: what the page needs to draw stream `stream_id` on `model` (labels, roles, the
/// emotion space, the quality warnings). `file`: the model file, when known.
pub(crate) fn model_json(stream_id: i32, model: &IcaModel, file: Option<&str>) -> String {
    let roles: Vec<String> = model
        .roles()
        .iter()
        .map(|r| format!("{r:?}").to_lowercase())
        .collect();
    let warnings: Vec<&str> = model
        .quality()
        .warnings
        .iter()
        .map(|w| w.message.as_str())
        .collect();
    json!({
        "type": "model",
        "stream": stream_id,
        "file": file,
        "labels": model.labels(),
        "roles": roles,
        "rate_hz": model.rate_hz(),
        "markers": model.markers(),
        "components": model.components(),
        "emotion": emotion_json(model),
        "warnings": warnings,
    })
    .to_string()
}

#[cfg(test)]
mod tests {
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
}
