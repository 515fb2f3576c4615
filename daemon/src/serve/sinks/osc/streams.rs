//! What the OSC output sends about each stream besides its frames: its `/mocap/labels` (model
//! order, layout id = stream id) and the VMC blend names of its labelled components, made
//! once per stream and model (a model swap makes them again). A stream without a model has
//! its source's labels and no blend names.

use std::collections::HashMap;
use std::sync::Arc;

use engine::pipeline::MAX_SOURCES;
use engine::Processed;
use ica_core::model::IcaModel;
use protocol::{encode_labels_into, Labels};

/// One stream's labels message and blend names.
#[derive(Debug)]
pub struct StreamNames {
    id: i32,
    /// `None`: the stream passes its frames through without a model.
    model: Option<Arc<IcaModel>>,
    /// `/mocap/labels` of the stream (empty when a label cannot be sent).
    pub labels_msg: Vec<u8>,
    /// VMC blend names of the labelled components (`/VMC/Ext/Blend/Val`).
    pub vmc: Vec<(String, usize)>,
}

/// The names of the streams seen lately, at most [`MAX_SOURCES`].
#[derive(Debug, Default)]
pub struct Names {
    streams: Vec<StreamNames>,
    /// When each was last used (a count of frames), to evict the longest unused.
    used: Vec<u64>,
    frames: u64,
    /// Blend names sent instead of the defaults (`vmc_names`).
    rename: HashMap<String, String>,
}

impl Names {
    /// Names whose default blend names `rename` maps to others.
    pub fn renamed(rename: HashMap<String, String>) -> Names {
        Names {
            rename,
            ..Names::default()
        }
    }

    /// The names of `frame`'s stream, made on its first frame or after a model swap.
    pub fn of(&mut self, frame: &Processed<'_>) -> &StreamNames {
        self.frames += 1;
        let id = frame.identity().id;
        let at = match self.streams.iter().position(|s| s.id == id) {
            Some(i) if frame.stream.runs_on(self.streams[i].model.as_ref()) => i,
            Some(i) => {
                self.streams[i] = StreamNames::of(id, frame, &self.rename);
                i
            }
            None if self.streams.len() < MAX_SOURCES => {
                self.streams.push(StreamNames::of(id, frame, &self.rename));
                self.used.push(0);
                self.streams.len() - 1
            }
            None => {
                let oldest = (0..self.used.len())
                    .min_by_key(|&i| self.used[i])
                    .unwrap_or(0);
                self.streams[oldest] = StreamNames::of(id, frame, &self.rename);
                oldest
            }
        };
        self.used[at] = self.frames;
        &self.streams[at]
    }
}

impl StreamNames {
    fn of(id: i32, frame: &Processed<'_>, rename: &HashMap<String, String>) -> StreamNames {
        StreamNames::new(id, frame.stream.model.as_ref(), frame.labels(), rename)
    }

    /// The names of stream `id` on `model` (none: its source's `labels`, no blend names).
    fn new(
        id: i32,
        model: Option<&Arc<IcaModel>>,
        labels: &[String],
        rename: &HashMap<String, String>,
    ) -> StreamNames {
        let labels = Labels {
            layout_id: id,
            names: labels.to_vec(),
        };
        let mut labels_msg = Vec::new();
        if encode_labels_into(&labels, &mut labels_msg).is_err() {
            labels_msg.clear();
        }
        StreamNames {
            id,
            model: model.cloned(),
            labels_msg,
            vmc: model
                .map(|m| vmc_names(m))
                .unwrap_or_default()
                .into_iter()
                .map(|(name, k)| (rename.get(&name).cloned().unwrap_or(name), k))
                .collect(),
        }
    }
}

/// Blend names for the components with a known role: `emotion`, `speech1`, `speech2`, ...,
/// `eyebrows1`, `eyelids1` (a role held by one component has no number). Unknown and other
/// components are not named.
pub fn vmc_names(model: &IcaModel) -> Vec<(String, usize)> {
    use ica_core::model::Role;
    let name = |role: Role| match role {
        Role::Emotion => Some("emotion"),
        Role::Speech => Some("speech"),
        Role::Eyebrows => Some("eyebrows"),
        Role::Eyelids => Some("eyelids"),
        Role::Unknown | Role::Other => None,
    };
    let roles = model.roles();
    let mut out = Vec::new();
    for (k, &role) in roles.iter().enumerate() {
        let Some(base) = name(role) else { continue };
        let same = roles.iter().filter(|&&r| r == role).count();
        if same == 1 {
            out.push((base.to_string(), k));
        } else {
            let nth = roles[..=k].iter().filter(|&&r| r == role).count();
            out.push((format!("{base}{nth}"), k));
        }
    }
    out
}

#[cfg(test)]
mod tests;
