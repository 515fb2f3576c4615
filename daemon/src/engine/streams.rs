//! Streams: each source (sender address + layout id) is its own stream, with its own frame
//! ordering, edit state, low-pass state and per-frame buffers. A performer in the config maps
//! a source and/or layout to a named model and default emotion; other streams use the loaded
//! model.

use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;

use ica_core::model::IcaModel;

use super::edit_state::EditState;
use crate::engine::frame::FrameProcessor;
use crate::engine::layout::{LabelMap, LayoutError};

/// A backwards jump of more than this many frames is a restarted source (a looping replay, a
/// restarted capture), not a late frame: the stream starts over instead of dropping it.
pub const RESTART_FRAMES: i64 = 240;

/// Identity of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StreamKey {
    /// Sender address.
    pub source: SocketAddr,
    /// Layout id of the labels the frames are bound to.
    pub layout_id: i32,
}

/// One stream's counters (frame order is per stream: a late frame of one performer says
/// nothing about another).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamStatus {
    /// The stream.
    pub key: StreamKey,
    /// The performer owning it, if named in the config.
    pub performer: Option<String>,
    /// Frames taken in order.
    pub frames: u64,
    /// Duplicate frame numbers dropped.
    pub duplicates: u64,
    /// Out-of-order (older) frames dropped.
    pub stale: u64,
}

/// A named performer: which streams it owns, its model and default emotion.
#[derive(Debug, Clone)]
pub struct Performer {
    /// Name, for logs.
    pub name: String,
    /// Only frames from this address (any when `None`).
    pub source: Option<SocketAddr>,
    /// Only frames of this layout id (any when `None`).
    pub layout: Option<i32>,
    /// Its model (the loaded model when `None`).
    pub model: Option<Arc<IcaModel>>,
    /// Default target emotion.
    pub target: Option<String>,
    /// Default amount.
    pub amount: Option<f32>,
}

impl Performer {
    /// Whether this performer owns a stream.
    pub fn owns(&self, key: &StreamKey) -> bool {
        self.source.is_none_or(|s| s == key.source)
            && self.layout.is_none_or(|l| l == key.layout_id)
    }
}

/// Where a frame number falls in a stream's order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// Newer than the last frame: process, `frames` after it (1 = the next one).
    Next {
        /// Frames since the last one sent (1 for the first frame).
        frames: u32,
    },
    /// The same number as the last frame: drop.
    Duplicate,
    /// Older than the last frame: drop.
    Stale,
    /// Far behind: the source restarted; process and start over.
    Restart,
}

/// One stream's state and buffers, all sized from its model at creation.
#[derive(Debug)]
pub struct Stream {
    /// The model used.
    pub model: Arc<IcaModel>,
    /// Performer index, if a performer owns the stream.
    pub performer: Option<usize>,
    /// Per-frame processor.
    pub processor: FrameProcessor,
    /// The live edit.
    pub edit: EditState,
    /// Labels of the source mapped to the model.
    pub map: LabelMap,
    /// Source frame, missing flags in source order.
    pub take_missing: Vec<bool>,
    /// Frame in model order.
    pub xyz: Vec<f32>,
    /// Missing flags in model order.
    pub missing: Vec<bool>,
    /// Components.
    pub u: Vec<f32>,
    /// Edited frame in model order.
    pub out: Vec<f32>,
    /// VMC blend names of the labelled components (`/VMC/Ext/Blend/Val` of the components
    /// profile), from the model's roles.
    pub vmc: Vec<(String, usize)>,
    last_frame: Option<i32>,
    /// Frames taken in order (processed).
    pub frames: u64,
    /// Duplicate frame numbers dropped.
    pub duplicates: u64,
    /// Out-of-order (older) frames dropped.
    pub stale: u64,
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

impl Stream {
    /// Builds a stream for `source_labels` on `model`.
    ///
    /// # Errors
    /// [`LayoutError::NoCommonMarkers`] when the source shares no label with the model.
    pub fn new(
        model: Arc<IcaModel>,
        performer: Option<usize>,
        source_labels: &[String],
        lowpass_s: f32,
    ) -> Result<Stream, LayoutError> {
        let map = LabelMap::new(model.labels(), source_labels)?;
        let n = model.markers();
        let m = model.components();
        Ok(Stream {
            processor: FrameProcessor::new(&model),
            edit: EditState::for_model(&model, lowpass_s),
            map,
            take_missing: vec![false; source_labels.len()],
            xyz: vec![0.0; n * 3],
            missing: vec![false; n],
            u: vec![0.0; m],
            out: vec![0.0; n * 3],
            vmc: vmc_names(&model),
            last_frame: None,
            frames: 0,
            duplicates: 0,
            stale: 0,
            model,
            performer,
        })
    }

    /// Carries the frame order over from the stream this one replaces (a model swap), so the
    /// next frame is neither dropped nor taken for a restart.
    pub fn take_last_frame_from(&mut self, old: &Stream) {
        self.last_frame = old.last_frame;
        self.frames = old.frames;
        self.duplicates = old.duplicates;
        self.stale = old.stale;
    }

    /// Classifies `frame_number` against the last frame and, unless it is dropped, makes it
    /// the last frame. Counts duplicates and stale frames.
    pub fn check_order(&mut self, frame_number: i32) -> Order {
        let Some(last) = self.last_frame else {
            self.last_frame = Some(frame_number);
            self.frames += 1;
            return Order::Next { frames: 1 };
        };
        let delta = i64::from(frame_number) - i64::from(last);
        let order = match delta {
            0 => Order::Duplicate,
            d if d < -RESTART_FRAMES => Order::Restart,
            d if d < 0 => Order::Stale,
            d => Order::Next {
                frames: u32::try_from(d).unwrap_or(u32::MAX),
            },
        };
        match order {
            Order::Duplicate => self.duplicates += 1,
            Order::Stale => self.stale += 1,
            Order::Restart => {
                self.processor.reset();
                self.edit.reset_lowpass();
                self.last_frame = Some(frame_number);
                self.frames += 1;
            }
            Order::Next { .. } => {
                self.last_frame = Some(frame_number);
                self.frames += 1;
            }
        }
        order
    }
}

/// All streams, bounded in number against spoofed senders.
#[derive(Debug)]
pub struct Streams {
    map: HashMap<StreamKey, Stream>,
    max_streams: usize,
}

impl Streams {
    /// At most `max_streams` streams.
    pub fn new(max_streams: usize) -> Streams {
        Streams {
            map: HashMap::with_capacity(max_streams),
            max_streams,
        }
    }

    /// The stream of `key`, if it exists.
    pub fn get_mut(&mut self, key: &StreamKey) -> Option<&mut Stream> {
        self.map.get_mut(key)
    }

    /// The stream of `key`, made by `create` when it does not exist yet: one hash lookup, where
    /// `get_mut` then `insert` took two or three per frame. `None` when `create` gives none or
    /// the cap is reached.
    pub fn get_or_create(
        &mut self,
        key: StreamKey,
        create: impl FnOnce() -> Option<Stream>,
    ) -> Option<&mut Stream> {
        let full = self.map.len() >= self.max_streams;
        match self.map.entry(key) {
            Entry::Occupied(e) => Some(e.into_mut()),
            Entry::Vacant(_) if full => None,
            Entry::Vacant(e) => Some(e.insert(create()?)),
        }
    }

    /// Adds a stream; `false` when the cap is reached.
    pub fn insert(&mut self, key: StreamKey, stream: Stream) -> bool {
        if self.map.len() >= self.max_streams && !self.map.contains_key(&key) {
            return false;
        }
        self.map.insert(key, stream);
        true
    }

    /// Drops the streams of one source and layout (its labels changed).
    pub fn forget(&mut self, source: SocketAddr, layout_id: i32) {
        self.map
            .retain(|k, _| !(k.source == source && k.layout_id == layout_id));
    }

    /// Every stream.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (&StreamKey, &mut Stream)> {
        self.map.iter_mut()
    }

    /// Streams held.
    pub fn len(&self) -> usize {
        self.map.len()
    }

    /// No stream yet.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }

    /// Each stream's counters, for `/status` and the log, in a stable order.
    pub fn status(&self, performers: &[Performer]) -> Vec<StreamStatus> {
        let mut out: Vec<StreamStatus> = self
            .map
            .iter()
            .map(|(key, s)| StreamStatus {
                key: *key,
                performer: s.performer.map(|i| performers[i].name.clone()),
                frames: s.frames,
                duplicates: s.duplicates,
                stale: s.stale,
            })
            .collect();
        out.sort_by_key(|s| (s.key.source, s.key.layout_id));
        out
    }

    /// Duplicates and stale frames over all streams.
    pub fn dropped(&self) -> (u64, u64) {
        self.map
            .values()
            .fold((0, 0), |(d, s), st| (d + st.duplicates, s + st.stale))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn tiny_model() -> IcaModel {
        crate::loopback::synthetic::random_model(4, 2, 1)
    }

    #[test]
    fn order_counts_duplicates_and_stale_and_restarts_far_jumps() {
        let model = Arc::new(tiny_model());
        let labels: Vec<String> = model.labels().to_vec();
        let mut s = Stream::new(model, None, &labels, 1.0).expect("same labels");
        assert_eq!(s.check_order(10), Order::Next { frames: 1 });
        assert_eq!(s.check_order(12), Order::Next { frames: 2 });
        assert_eq!(s.check_order(12), Order::Duplicate);
        assert_eq!(s.check_order(11), Order::Stale);
        assert_eq!(s.check_order(13), Order::Next { frames: 1 });
        assert_eq!(s.check_order(-1000), Order::Restart);
        assert_eq!(s.check_order(-999), Order::Next { frames: 1 });
        assert_eq!((s.duplicates, s.stale), (1, 1));
    }

    #[test]
    fn performers_match_on_source_and_layout() {
        let a: SocketAddr = "127.0.0.1:7000".parse().expect("addr");
        let b: SocketAddr = "127.0.0.1:7001".parse().expect("addr");
        let p = Performer {
            name: "alice".into(),
            source: Some(a),
            layout: None,
            model: None,
            target: None,
            amount: None,
        };
        assert!(p.owns(&StreamKey {
            source: a,
            layout_id: 3
        }));
        assert!(!p.owns(&StreamKey {
            source: b,
            layout_id: 3
        }));
    }
}

#[cfg(test)]
mod vmc_tests {
    use ica_core::model::Role;

    use super::vmc_names;
    use crate::loopback::synthetic::random_model;

    #[test]
    fn labelled_components_get_blend_names() {
        let mut model = random_model(6, 5, 1);
        for (k, role) in [
            Role::Emotion,
            Role::Speech,
            Role::Other,
            Role::Speech,
            Role::Eyelids,
        ]
        .into_iter()
        .enumerate()
        {
            model.set_role(k, role).expect("in range");
        }
        let names = vmc_names(&model);
        let expected = [
            ("emotion", 0),
            ("speech1", 1),
            ("speech2", 3),
            ("eyelids", 4),
        ];
        let got: Vec<(&str, usize)> = names.iter().map(|(n, k)| (n.as_str(), *k)).collect();
        assert_eq!(got, expected);
    }
}
