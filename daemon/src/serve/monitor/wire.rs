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
mod tests;
