//! NatNet frames as emoshift frames, sans-IO: each markerset (Motive asset) of a
//! NAT_FRAMEOFDATA is one [`SourceFrame`], its markers named as Motive names them in exported
//! takes, in millimetres, occluded markers missing, with the frame's timecode and capture time.
//!
//! - **Names.** Motive's C3D, TRC and CSV exports name a marker `Asset:Marker` by default
//!   (its "Marker Name Syntax" export option switches the separator to `_`), so a model
//!   trained on exports matches the live stream with no mapping. [`Naming`] picks the
//!   separator (or bare marker names) and a rename table covers the rest.
//! - **Occlusion.** A markerset's positions do not say which markers were seen: Motive fills
//!   occluded markers of a rigid body with their solved positions. When the frame's labelled
//!   markers include markers of the markerset's model (the rigid body, skeleton or asset of the
//!   same name, ids `model << 16 | index`), a marker absent from them or flagged occluded is
//!   missing; otherwise a marker at exactly (0, 0, 0), or NaN, is.
//! - **Asset markers off.** A frame without the markerset (Motive's *Asset Markers* streaming
//!   off) takes the asset's markers from its labelled markers (model id, 1-based index), in
//!   the order of the markerset description.
//! - **Motive's `all` markerset** repeats every labelled marker of the other assets: skipped.
//! - **Time.** The capture time is the mid-exposure stamp in µs of the server's clock (its
//!   timestamp when the cameras give none); the timecode is the frame's, at the configured
//!   rate (NatNet does not carry the rate).

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;

use engine::{SourceFrame, StreamKey};
use protocol::natnet::{
    decode_frame_into, FrameOfData, ModelDefs, NatNetError, NatNetVersion, MM_PER_M,
};
use protocol::{CaptureClock, FrameBuf, FrameHeader, FrameTime, Smpte, TimecodeRate};

/// The markerset Motive sends with every labelled marker again.
pub const ALL_MARKERSET: &str = "all";
/// Markersets given a layout id at most (bounds memory against a server that renames assets
/// forever).
pub const MAX_MARKERSETS: usize = 64;

/// How live markers are named.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Naming {
    /// Between asset and marker name: `:` (Motive's default), `_`, or `None` for the bare
    /// marker name.
    pub separator: Option<String>,
    /// Names as built (`Asset:Marker`) to the model's labels.
    pub rename: HashMap<String, String>,
}

impl Default for Naming {
    fn default() -> Self {
        Naming {
            separator: Some(":".into()),
            rename: HashMap::new(),
        }
    }
}

impl Naming {
    /// The label of marker `marker` of asset `asset`.
    pub fn label(&self, asset: &str, marker: &str) -> String {
        let built = match &self.separator {
            Some(sep) => format!("{asset}{sep}{marker}"),
            None => marker.to_string(),
        };
        self.rename.get(&built).cloned().unwrap_or(built)
    }
}

/// One markerset as a source layout.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MarkersetLayout {
    /// Markerset (asset) name (shared with its frames).
    pub name: Arc<str>,
    /// Its markers' labels, in frame order (shared with its frames).
    pub labels: Arc<[String]>,
    /// Layout id, stable for the daemon's life ([`LayoutIds`]).
    pub layout_id: i32,
    /// The rigid body, skeleton or asset of the same name, whose labelled markers tell
    /// occlusion.
    pub model_id: Option<u16>,
}

/// Stable layout ids for markerset names, kept across model definitions and reconnects.
#[derive(Debug, Clone, Default)]
pub struct LayoutIds {
    names: Vec<String>,
}

impl LayoutIds {
    /// The id of `name`, given on first sight; `None` past [`MAX_MARKERSETS`] names.
    pub fn id(&mut self, name: &str) -> Option<i32> {
        if let Some(i) = self.names.iter().position(|n| n == name) {
            return i32::try_from(i).ok();
        }
        if self.names.len() >= MAX_MARKERSETS {
            return None;
        }
        self.names.push(name.to_string());
        i32::try_from(self.names.len() - 1).ok()
    }
}

/// What a NatNet session knows about the server's frames: their version, the server clock,
/// the timecode rate and each markerset's layout. Made when model definitions arrive.
#[derive(Debug, Clone, PartialEq)]
pub struct NatNetLayout {
    /// Version frames are decoded with.
    pub version: NatNetVersion,
    /// Ticks per second of the server clock (0: unknown).
    pub clock_hz: u64,
    /// Timecode rate (NatNet does not send it).
    pub timecode_rate: Option<TimecodeRate>,
    /// The markersets that become streams, in definition order.
    pub markersets: Vec<MarkersetLayout>,
}

impl NatNetLayout {
    /// The layout of `defs`: every markerset but [`ALL_MARKERSET`], named by `naming`, ids
    /// from `ids`. A markerset whose labels repeat (after renaming) is left out, as a
    /// `/mocap/labels` naming a marker twice would be.
    pub fn new(
        version: NatNetVersion,
        clock_hz: u64,
        timecode_rate: Option<TimecodeRate>,
        defs: &ModelDefs,
        naming: &Naming,
        ids: &mut LayoutIds,
    ) -> NatNetLayout {
        let model_id = |name: &str| {
            let rigid = defs
                .rigid_bodies
                .iter()
                .find(|b| b.name == name)
                .map(|b| b.id);
            let skeleton = || defs.skeletons.iter().find(|s| s.name == name).map(|s| s.id);
            let asset = || defs.assets.iter().find(|a| a.name == name).map(|a| a.id);
            rigid
                .or_else(skeleton)
                .or_else(asset)
                .and_then(|id| u16::try_from(id).ok())
        };
        let mut markersets = Vec::new();
        for m in defs.markersets.iter().filter(|m| m.name != ALL_MARKERSET) {
            let labels: Vec<String> = m
                .marker_names
                .iter()
                .map(|marker| naming.label(&m.name, marker))
                .collect();
            let distinct = labels
                .iter()
                .enumerate()
                .all(|(i, l)| !l.is_empty() && !labels[..i].contains(l));
            let Some(layout_id) = ids.id(&m.name) else {
                continue;
            };
            if distinct && !labels.is_empty() {
                markersets.push(MarkersetLayout {
                    name: m.name.as_str().into(),
                    labels: labels.into(),
                    layout_id,
                    model_id: model_id(&m.name),
                });
            }
        }
        NatNetLayout {
            version,
            clock_hz,
            timecode_rate,
            markersets,
        }
    }

    /// The layout of the markerset called `name`.
    pub fn markerset(&self, name: &str) -> Option<&MarkersetLayout> {
        self.markersets.iter().find(|m| &*m.name == name)
    }
}

/// A decoded NatNet frame and the buffers that turn its markersets into frames; reused, so
/// that once warm nothing allocates.
#[derive(Debug)]
pub struct NatNetFrames {
    frame: FrameOfData,
    xyz: Vec<f32>,
    seen: Vec<bool>,
}

impl NatNetFrames {
    /// Buffers for frames of up to `max_markers` markers per markerset.
    pub fn new(max_markers: usize) -> NatNetFrames {
        NatNetFrames {
            frame: FrameOfData::with_capacity(max_markers, 16),
            xyz: Vec::with_capacity(max_markers * 3),
            seen: Vec::with_capacity(max_markers),
        }
    }

    /// Decodes one NAT_FRAMEOFDATA datagram from the server at `server` and gives each of its
    /// markersets to `out` as the frame of one stream (key: the server and the markerset's
    /// layout id; named after the markerset).
    ///
    /// # Errors
    /// What [`decode_frame_into`] finds wrong; nothing is given then.
    pub fn handle_datagram(
        &mut self,
        server: SocketAddr,
        datagram: &[u8],
        layout: &NatNetLayout,
        buf: &mut FrameBuf,
        out: &mut dyn FnMut(&SourceFrame<'_>),
    ) -> Result<(), NatNetError> {
        self.decode(datagram, layout)?;
        let time = self.time(layout);
        for set in &layout.markersets {
            if self.markerset_into(set, layout, buf).is_none() {
                continue;
            }
            out(&SourceFrame {
                key: StreamKey {
                    source: server,
                    layout_id: set.layout_id,
                },
                performer: Some(&set.name),
                labels: &set.labels,
                frame: buf,
                time,
            });
        }
        Ok(())
    }

    /// Decodes one NAT_FRAMEOFDATA datagram.
    ///
    /// # Errors
    /// What [`decode_frame_into`] finds wrong.
    pub fn decode(&mut self, datagram: &[u8], layout: &NatNetLayout) -> Result<(), NatNetError> {
        decode_frame_into(datagram, layout.version, &mut self.frame)
    }

    /// The decoded frame.
    pub fn frame(&self) -> &FrameOfData {
        &self.frame
    }

    /// The source's time of the decoded frame: its timecode (when it has one, or always with
    /// a configured rate) on the Source clock.
    pub fn time(&self, layout: &NatNetLayout) -> FrameTime {
        let f = &self.frame;
        let present = layout.timecode_rate.is_some() || f.timecode != 0 || f.timecode_subframe != 0;
        let timecode = present
            .then(|| Smpte::from_packed(f.timecode, f.timecode_subframe, layout.timecode_rate))
            .filter(Smpte::is_valid);
        FrameTime {
            timecode,
            irig: None,
            clock: CaptureClock::Source,
        }
    }

    /// Capture time in µs of the server's clock: mid-exposure, else the frame's timestamp.
    pub fn capture_time_us(&self, layout: &NatNetLayout) -> i64 {
        let f = &self.frame;
        if f.camera_mid_exposure != 0 && layout.clock_hz != 0 {
            let us = u128::from(f.camera_mid_exposure) * 1_000_000 / u128::from(layout.clock_hz);
            return i64::try_from(us).unwrap_or(i64::MAX);
        }
        (f.timestamp * 1e6) as i64
    }

    /// Markerset `set` of the layout, from the decoded frame, into `out` (mm, missing markers
    /// NaN). When the frame carries no such markerset (Motive's *Asset Markers* streaming off)
    /// its markers come from the asset's labelled markers instead. `None` when the frame has
    /// neither, or carries another number of markers than the description.
    pub fn markerset_into(
        &mut self,
        set: &MarkersetLayout,
        layout: &NatNetLayout,
        out: &mut FrameBuf,
    ) -> Option<FrameHeader> {
        let n = set.labels.len();
        self.xyz.clear();
        let carried = match self.frame.markerset_named(&set.name) {
            Some(ms) if ms.positions.len() == n => {
                self.seen.clear();
                self.seen.resize(n, false);
                let judged = set
                    .model_id
                    .is_some_and(|model| mark_seen(&self.frame, model, &mut self.seen));
                for (p, &seen) in ms.positions.iter().zip(&self.seen) {
                    let gone = if judged {
                        !seen
                    } else {
                        *p == [0.0; 3] || p.iter().any(|v| v.is_nan())
                    };
                    push_mm(&mut self.xyz, (!gone).then_some(p));
                }
                true
            }
            Some(_) => false,
            None => set
                .model_id
                .is_some_and(|model| labelled_into(&self.frame, model, n, &mut self.xyz)),
        };
        if !carried {
            return None;
        }
        let capture = self.capture_time_us(layout);
        out.set_frame(self.frame.frame_number, capture, &self.xyz)
            .ok()?;
        Some(out.header())
    }
}

/// Marks the markers of `model` seen in `frame`'s labelled markers (present, not occluded);
/// `true` when any of its labelled markers is there at all.
fn mark_seen(frame: &FrameOfData, model: u16, seen: &mut [bool]) -> bool {
    let mut any = false;
    for m in &frame.labeled_markers {
        let i = usize::from(m.marker_index());
        if m.model_id() == model && (1..=seen.len()).contains(&i) {
            any = true;
            seen[i - 1] = !m.params.occluded();
        }
    }
    any
}

/// The `n` markers of `model` from `frame`'s labelled markers (1-based index order), in mm
/// into `xyz` (missing: absent or occluded); `false` when none of them is there.
fn labelled_into(frame: &FrameOfData, model: u16, n: usize, xyz: &mut Vec<f32>) -> bool {
    xyz.clear();
    xyz.resize(n * 3, f32::NAN);
    let mut any = false;
    for m in &frame.labeled_markers {
        let i = usize::from(m.marker_index());
        if m.model_id() == model && (1..=n).contains(&i) {
            any = true;
            if !m.params.occluded() && m.position.iter().all(|v| v.is_finite()) {
                for (d, v) in xyz[3 * (i - 1)..3 * i].iter_mut().zip(m.position) {
                    *d = v * MM_PER_M;
                }
            }
        }
    }
    any
}

/// Appends one marker in mm, or NaN for a missing one.
fn push_mm(xyz: &mut Vec<f32>, p: Option<&[f32; 3]>) {
    match p {
        Some(p) => xyz.extend(p.iter().map(|v| v * MM_PER_M)),
        None => xyz.extend_from_slice(&[f32::NAN; 3]),
    }
}

#[cfg(test)]
mod tests;
