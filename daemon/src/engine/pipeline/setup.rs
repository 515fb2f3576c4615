//! Streams made on their first frame, and edit controls applied to a stream's edit state.

use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::Control;

use crate::engine::edit_state::EditRefused;
use crate::engine::stream::{Identity, Stream};
use crate::engine::streams::{Performer, StreamKey};

/// What a new stream is made from besides its source: the performers, the default model and
/// the settings its streams start with.
pub(super) struct Defaults<'a> {
    pub(super) performers: &'a [Performer],
    pub(super) model: &'a Arc<IcaModel>,
    pub(super) template: &'a crate::engine::edit_state::EditState,
    pub(super) lowpass_s: f32,
}

/// A new stream `id` for `key` on its performer's model (or the default one, with the
/// template's edit settings), named after its performer, else `name` (a NatNet markerset),
/// else its source; `None` when its labels share none with the model.
pub(super) fn new_stream(
    id: i32,
    key: &StreamKey,
    source_labels: &[String],
    name: Option<&str>,
    d: &Defaults<'_>,
) -> Option<Stream> {
    let performer = d.performers.iter().position(|p| p.owns_stream(key, name));
    let p = performer.map(|i| &d.performers[i]);
    let model = p
        .and_then(|p| p.model.clone())
        .unwrap_or_else(|| Arc::clone(d.model));
    let identity = match (p, name) {
        (Some(p), _) => Identity::new(id, &p.name),
        (None, Some(name)) => Identity::new(id, name),
        (None, None) => Identity::new(id, &format!("{}/{}", key.source, key.layout_id)),
    };
    let mut stream = Stream::new(
        identity,
        Arc::clone(&model),
        performer,
        source_labels,
        d.lowpass_s,
    )
    .ok()?;
    if Arc::ptr_eq(&model, d.model) {
        stream.edit.copy_settings(d.template);
    }
    if let Some(p) = p {
        defaults_of(p, &mut stream);
    }
    Some(stream)
}

/// A performer's default emotion, set at once (no ramp) on a new stream.
fn defaults_of(p: &Performer, stream: &mut Stream) {
    stream.edit.set_ramp(0.0);
    if let Some(target) = &p.target {
        let _ = apply_edit(
            &mut stream.edit,
            &stream.model,
            &Control::Target(target.clone()),
        );
    }
    if let Some(amount) = p.amount {
        let _ = stream.edit.set_amount(amount);
    }
    stream
        .edit
        .set_ramp(crate::engine::edit_state::DEFAULT_RAMP_S);
}

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
    edit: &mut crate::engine::edit_state::EditState,
    model: &IcaModel,
    name: &str,
    weights: &[(&str, f64)],
) -> Result<(), EditRefused> {
    let point = model.emotion().blend(weights).map_err(|e| match e {
        ica_core::model::BlendError::NoEmotion => EditRefused::NoEmotion,
        ica_core::model::BlendError::UnknownEmotion { name, .. } => {
            EditRefused::UnknownEmotion { name }
        }
        ica_core::model::BlendError::BadWeight { name, .. } => EditRefused::UnknownEmotion { name },
    })?;
    let point: Vec<f32> = point.iter().map(|&v| v as f32).collect();
    edit.set_target(name, &point)
}

/// Applies one edit control to one stream's state, validated against its model.
pub fn apply_edit(
    edit: &mut crate::engine::edit_state::EditState,
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
