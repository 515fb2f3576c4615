//! Edit controls applied to one stream's [`EditState`], checked against its model: a target
//! emotion or a blend of several (their point in the model's emotion space), the amount, the
//! ramp, a component's alpha or gain, bypass.

use ica_core::model::IcaModel;
use protocol::Control;

use super::{EditRefused, EditState};

/// A blend's name as the state reports it: `sad:0.50,angry:0.50` (weights normalised).
pub fn mix_name(pairs: &[(String, f32)]) -> String {
    let total: f32 = pairs.iter().map(|p| p.1).sum();
    pairs
        .iter()
        .map(|(n, w)| format!("{n}:{:.2}", w / total.max(f32::MIN_POSITIVE)))
        .collect::<Vec<_>>()
        .join(",")
}

fn set_blend(
    edit: &mut EditState,
    model: &IcaModel,
    name: &str,
    weights: &[(&str, f64)],
) -> Result<(), EditRefused> {
    let point = model.emotion().blend(weights).map_err(|e| match e {
        ica_core::model::BlendError::NoEmotion => EditRefused::NoEmotion,
        ica_core::model::BlendError::UnknownEmotion { name, known } => {
            EditRefused::UnknownEmotion { name, known }
        }
        ica_core::model::BlendError::BadWeight { name, weight } => {
            EditRefused::BadWeight { name, weight }
        }
    })?;
    let point: Vec<f32> = point.iter().map(|&v| v as f32).collect();
    edit.set_target(name, &point)
}

/// Applies one edit control to one stream's state, validated against its model.
pub fn apply_edit(
    edit: &mut EditState,
    model: &IcaModel,
    control: &Control,
) -> Result<(), EditRefused> {
    match control {
        Control::Target(name) => {
            let weights = [(name.as_str(), 1.0)];
            set_blend(edit, model, name, &weights)
        }
        Control::Mix(pairs) => {
            let weights: Vec<(&str, f64)> = pairs
                .iter()
                .map(|(n, w)| (n.as_str(), f64::from(*w)))
                .collect();
            set_blend(edit, model, &mix_name(pairs), &weights)
        }
        Control::Amount(a) => edit.set_amount(*a),
        Control::Ramp(r) => {
            edit.set_ramp(*r);
            Ok(())
        }
        Control::Alpha { component, value } => edit.set_alpha(*component, *value),
        Control::Gain { component, gain } => edit.set_gain(*component, *gain),
        Control::Bypass(b) => {
            edit.set_bypass(*b);
            Ok(())
        }
        _ => Ok(()),
    }
}
