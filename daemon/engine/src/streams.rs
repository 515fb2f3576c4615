//! The streams: each source (sender address + layout id) is its own [`Stream`]. A performer
//! in the config maps a source and/or layout to a named model and default emotion; other
//! streams use the loaded model.

use core::net::SocketAddr;
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use ica_core::model::IcaModel;

use super::stream::Stream;

/// Identity of a stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StreamKey {
    /// Sender address.
    pub source: SocketAddr,
    /// Layout id of the labels the frames are bound to.
    pub layout_id: i32,
}

/// One stream's state and counters for `/status` (frame order is per stream: a late frame of
/// one performer says nothing about another).
#[derive(Debug, Clone, PartialEq)]
pub struct StreamStatus {
    /// The stream.
    pub key: StreamKey,
    /// Its id and name.
    pub id: i32,
    /// Its name (the performer's, or `ip:port/layout`).
    pub name: String,
    /// The performer owning it, if named in the config.
    pub performer: Option<String>,
    /// Markers of its model.
    pub model_markers: usize,
    /// Of those, the ones its source does not name.
    pub unmatched_markers: usize,
    /// Target emotion (empty before one is set).
    pub target: String,
    /// Amount now.
    pub amount: f32,
    /// Frames taken in order.
    pub frames: u64,
    /// Duplicate frame numbers dropped.
    pub duplicates: u64,
    /// Out-of-order (older) frames dropped.
    pub stale: u64,
}

/// A named performer: which streams it owns, its model and default emotion. The config holds
/// its model as a path ([`Performer<PathBuf>`]), the engine as a loaded model.
#[derive(Debug, Clone, PartialEq)]
pub struct Performer<M = Arc<IcaModel>> {
    /// Name, for logs.
    pub name: String,
    /// Only frames from this address (any when `None`).
    pub source: Option<SocketAddr>,
    /// Only frames of this layout id (any when `None`).
    pub layout: Option<i32>,
    /// Only the NatNet markerset (Motive asset) of this name (any when `None`).
    pub markerset: Option<String>,
    /// Its model (the loaded model when `None`).
    pub model: Option<M>,
    /// Default target emotion.
    pub target: Option<String>,
    /// Default amount.
    pub amount: Option<f32>,
}

/// A performer as configured, its model a file.
pub type PerformerConfig = Performer<PathBuf>;

impl<M> Performer<M> {
    /// The same performer with `model` in place of its own (a loaded model for a path).
    pub fn with_model<N>(self, model: Option<N>) -> Performer<N> {
        Performer {
            model,
            name: self.name,
            source: self.source,
            layout: self.layout,
            markerset: self.markerset,
            target: self.target,
            amount: self.amount,
        }
    }

    /// Whether this performer owns a stream of a source that names no performer (OSC).
    pub fn owns(&self, key: &StreamKey) -> bool {
        self.owns_stream(key, None)
    }

    /// Whether this performer owns a stream, which its source calls `markerset` if it names
    /// one (a NatNet markerset).
    pub fn owns_stream(&self, key: &StreamKey, markerset: Option<&str>) -> bool {
        self.source.is_none_or(|s| s == key.source)
            && self.layout.is_none_or(|l| l == key.layout_id)
            && self
                .markerset
                .as_deref()
                .is_none_or(|m| Some(m) == markerset)
    }
}

/// All streams, bounded in number against spoofed senders, and the stream ids of the session.
#[derive(Debug)]
pub struct Streams {
    map: HashMap<StreamKey, Stream>,
    max_streams: usize,
    /// A source keeps its id when its stream is made again (new labels, a model swap).
    ids: HashMap<StreamKey, i32>,
    next_id: i32,
}

impl Streams {
    /// At most `max_streams` streams.
    pub fn new(max_streams: usize) -> Streams {
        Streams {
            map: HashMap::with_capacity(max_streams),
            max_streams,
            ids: HashMap::with_capacity(max_streams),
            next_id: 0,
        }
    }

    /// The session's id of `key`, given on its first stream. Ids of sources gone quiet are
    /// forgotten once there are many, so spoofed senders cannot grow the table.
    fn id_for(&mut self, key: StreamKey) -> i32 {
        if let Some(&id) = self.ids.get(&key) {
            return id;
        }
        if self.ids.len() >= 4 * self.max_streams {
            let live = &self.map;
            self.ids.retain(|k, _| live.contains_key(k));
        }
        let id = self.next_id;
        self.next_id = self.next_id.wrapping_add(1).max(0);
        self.ids.insert(key, id);
        id
    }

    /// The stream of `key`, made by `create` when it does not exist yet (one hash lookup per
    /// frame). `None` when `create` gives none or the cap is reached.
    pub fn get_or_create(
        &mut self,
        key: StreamKey,
        create: impl FnOnce(i32) -> Option<Stream>,
    ) -> Option<&mut Stream> {
        let full = self.map.len() >= self.max_streams;
        if !full && !self.map.contains_key(&key) {
            let id = self.id_for(key);
            let stream = create(id)?;
            return Some(self.map.entry(key).or_insert(stream));
        }
        match self.map.entry(key) {
            Entry::Occupied(e) => Some(e.into_mut()),
            Entry::Vacant(_) => None,
        }
    }

    /// The stream of `key`, if it exists.
    pub fn get(&self, key: &StreamKey) -> Option<&Stream> {
        self.map.get(key)
    }

    /// Drops the streams of one source and layout (its labels changed).
    pub fn forget(&mut self, source: SocketAddr, layout_id: i32) {
        self.map
            .retain(|k, _| !(k.source == source && k.layout_id == layout_id));
    }

    /// Drops every stream of one source (it went quiet).
    pub fn forget_source(&mut self, source: SocketAddr) {
        self.map.retain(|k, _| k.source != source);
    }

    /// Drops the streams no frame reached since sweep `since` (see
    /// [`crate::Pipeline::forget_quiet_streams`]); returns their keys.
    pub fn forget_quiet(&mut self, since: u64) -> Vec<StreamKey> {
        let quiet: Vec<StreamKey> = self
            .map
            .iter()
            .filter(|(_, s)| s.heard_sweep < since)
            .map(|(k, _)| *k)
            .collect();
        for key in &quiet {
            self.map.remove(key);
        }
        quiet
    }

    /// Every stream, to read.
    pub fn iter(&self) -> impl Iterator<Item = (&StreamKey, &Stream)> {
        self.map.iter()
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
                id: s.identity.id,
                name: s.identity.name.clone(),
                performer: s.performer.map(|i| performers[i].name.clone()),
                model_markers: s.labels().len(),
                unmatched_markers: s.unmatched_markers(),
                target: s.edit.target().to_string(),
                amount: s.edit.amount(),
                frames: s.frames,
                duplicates: s.duplicates,
                stale: s.stale,
            })
            .collect();
        out.sort_by_key(|s| s.id);
        out
    }
}

#[cfg(test)]
mod tests;
