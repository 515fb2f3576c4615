//! Streams made on their first frame.

use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::Control;

use crate::edit_state::{apply_edit, EditState, DEFAULT_RAMP_S};
use crate::stream::{Identity, Stream};
use crate::streams::{Performer, StreamKey};

/// What a new stream is made from besides its source: the performers, the default model and
/// the settings its streams start with.
pub(super) struct Defaults<'a> {
    pub(super) performers: &'a [Performer],
    pub(super) model: Option<&'a Arc<IcaModel>>,
    pub(super) template: &'a EditState,
    pub(super) lowpass_s: f32,
    pub(super) passthrough_rate_hz: f64,
}

/// A new stream `id` for `key` on its performer's model (or the default one, with the
/// template's edit settings), named after its performer, else `name` (the source's name for
/// it: a NatNet markerset), else its source; `None` when its labels share none with the model.
/// Without a model (no performer's, no default) the stream passes its frames through.
pub(super) fn new_stream(
    id: i32,
    key: &StreamKey,
    source_labels: &Arc<[String]>,
    name: Option<&str>,
    d: &Defaults<'_>,
) -> Option<Stream> {
    let performer = d.performers.iter().position(|p| p.owns_stream(key, name));
    let p = performer.map(|i| &d.performers[i]);
    let model = p.and_then(|p| p.model.as_ref()).or(d.model);
    let identity = match (p, name) {
        (Some(p), _) => Identity::new(id, &p.name),
        (None, Some(name)) => Identity::new(id, name),
        (None, None) => Identity::new(id, &format!("{}/{}", key.source, key.layout_id)),
    };
    let Some(model) = model else {
        return Stream::passthrough(identity, performer, source_labels, d.passthrough_rate_hz).ok();
    };
    let mut stream = Stream::new(
        identity,
        Arc::clone(model),
        performer,
        source_labels,
        d.lowpass_s,
    )
    .ok()?;
    if d.model.is_some_and(|d| Arc::ptr_eq(model, d)) {
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
    if let (Some(target), Some(model)) = (&p.target, &stream.model) {
        let _ = apply_edit(&mut stream.edit, model, &Control::Target(target.clone()));
    }
    if let Some(amount) = p.amount {
        let _ = stream.edit.set_amount(amount);
    }
    stream.edit.set_ramp(DEFAULT_RAMP_S);
}
