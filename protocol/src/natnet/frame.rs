//! [`FrameOfData`]: one NAT_FRAMEOFDATA, decoded into caller-owned, reusable storage.

use std::ops::Range;

pub use super::frame_parts::{AnalogData, FrameParams, MarkerParams, PrecisionTimestamp, Timecode};

/// Millimetres per metre: NatNet positions are metres, emoshift works in millimetres.
pub const MM_PER_M: f32 = 1000.0;

/// A decoded frame of mocap data, reused from frame to frame.
///
/// [`decode_frame_into`](super::decode_frame_into) clears every list and refills it, so once
/// the lists have grown to the largest frame seen (or were sized by
/// [`FrameOfData::with_capacity`]) decoding allocates nothing. Positions are metres, y up
/// (Motive's default), exactly as sent; NaN is passed through as "no value".
///
/// Why owned storage rather than a borrowed view: the daemon reuses its receive buffer for
/// the next datagram while a frame is being edited, needs random access (marker `i` of
/// markerset `k`), and wants counts and strings validated once, at decode time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameOfData {
    /// Server frame number.
    pub frame_number: i32,
    names: String,
    markersets: Vec<Span>,
    markerset_positions: Vec<[f32; 3]>,
    /// Legacy "other" (unlabelled) marker positions.
    pub other_markers: Vec<[f32; 3]>,
    /// Rigid bodies.
    pub rigid_bodies: Vec<RigidBody>,
    skeletons: Vec<(i32, Range<usize>)>,
    skeleton_bones: Vec<RigidBody>,
    /// Assets (NatNet 4.1 trained markersets) in the frame: skipped, only counted.
    pub asset_count: usize,
    /// Labelled markers: every marker Motive reconstructed, labelled or not (see
    /// [`MarkerParams::unlabeled`]).
    pub labeled_markers: Vec<LabeledMarker>,
    /// Force plate samples.
    pub force_plates: AnalogData,
    /// Peripheral device (e.g. NI-DAQ) samples.
    pub devices: AnalogData,
    /// SMPTE timecode, packed as `hh mm ss ff` bytes (see [`FrameOfData::timecode`]).
    pub timecode: u32,
    /// Timecode subframe.
    pub timecode_subframe: u32,
    /// Server timestamp, seconds since Motive started.
    pub timestamp: f64,
    /// Server high-resolution clock at mid-exposure (0: unknown, e.g. USB cameras).
    pub camera_mid_exposure: u64,
    /// Server high-resolution clock when the camera data arrived.
    pub camera_data_received: u64,
    /// Server high-resolution clock just before the frame was sent.
    pub transmit: u64,
    /// Precision (PTP) timestamp, NatNet 4.1+ (and 4.0 frames that carry it).
    pub precision_timestamp: Option<PrecisionTimestamp>,
    /// Frame flags.
    pub params: FrameParams,
}

#[derive(Debug, Clone, PartialEq, Eq, Default)]
struct Span {
    name: Range<usize>,
    markers: Range<usize>,
}

/// One markerset of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Markerset<'a> {
    /// Its name, as in the model definitions (`all` lists every labelled marker).
    pub name: &'a str,
    /// Positions in metres, in the order of the markerset description's marker names.
    pub positions: &'a [[f32; 3]],
}

/// One skeleton of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Skeleton<'a> {
    /// Skeleton id.
    pub id: i32,
    /// Bones, as rigid bodies whose id is `skeleton id << 16 | bone id`.
    pub bones: &'a [RigidBody],
}

/// A rigid body (or skeleton bone) pose.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RigidBody {
    /// Streaming id.
    pub id: i32,
    /// Position, metres.
    pub position: [f32; 3],
    /// Orientation quaternion `qx, qy, qz, qw`.
    pub orientation: [f32; 4],
    /// Mean marker error, metres.
    pub mean_error: f32,
    /// Flags; bit 0: tracked in this frame.
    pub params: u16,
}

impl RigidBody {
    /// Whether the rigid body was tracked in this frame.
    pub fn tracking_valid(&self) -> bool {
        self.params & 0x01 != 0
    }
}

/// A labelled marker.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LabeledMarker {
    /// Marker id: `model id << 16 | marker index` for passive markers of an asset, the
    /// point-cloud id for unlabelled ones (model id 0), the active id for active markers.
    pub id: u32,
    /// Position, metres.
    pub position: [f32; 3],
    /// Estimated marker diameter, metres.
    pub size: f32,
    /// Flags.
    pub params: MarkerParams,
    /// Residual as on the wire (the SDK samples multiply it by 1000 to print mm per ray).
    pub residual: f32,
}

impl LabeledMarker {
    /// The owning model's id (rigid body streaming id), 0 for none.
    pub fn model_id(&self) -> u16 {
        (self.id >> 16) as u16
    }

    /// The marker's index in its model (1-based in Motive), or its point-cloud id.
    pub fn marker_index(&self) -> u16 {
        (self.id & 0xffff) as u16
    }

    /// Residual in millimetres per ray, as the SDK samples print it.
    pub fn residual_mm(&self) -> f32 {
        self.residual * MM_PER_M
    }
}

impl FrameOfData {
    /// An empty frame whose lists can hold `markers` positions (markersets and labelled
    /// markers each) and `rigid_bodies` rigid bodies without growing.
    pub fn with_capacity(markers: usize, rigid_bodies: usize) -> Self {
        FrameOfData {
            names: String::with_capacity(256),
            markersets: Vec::with_capacity(8),
            markerset_positions: Vec::with_capacity(markers * 2),
            other_markers: Vec::with_capacity(markers),
            rigid_bodies: Vec::with_capacity(rigid_bodies),
            labeled_markers: Vec::with_capacity(markers),
            ..FrameOfData::default()
        }
    }

    /// Empties every list (keeping their capacity) and zeroes every field.
    pub fn clear(&mut self) {
        self.frame_number = 0;
        self.names.clear();
        self.markersets.clear();
        self.markerset_positions.clear();
        self.other_markers.clear();
        self.rigid_bodies.clear();
        self.skeletons.clear();
        self.skeleton_bones.clear();
        self.asset_count = 0;
        self.labeled_markers.clear();
        self.force_plates.clear();
        self.devices.clear();
        self.timecode = 0;
        self.timecode_subframe = 0;
        self.timestamp = 0.0;
        self.camera_mid_exposure = 0;
        self.camera_data_received = 0;
        self.transmit = 0;
        self.precision_timestamp = None;
        self.params = FrameParams(0);
    }

    /// Number of markersets.
    pub fn markerset_count(&self) -> usize {
        self.markersets.len()
    }

    /// Markerset `i`.
    pub fn markerset(&self, i: usize) -> Option<Markerset<'_>> {
        let s = self.markersets.get(i)?;
        Some(Markerset {
            name: self.names.get(s.name.clone())?,
            positions: self.markerset_positions.get(s.markers.clone())?,
        })
    }

    /// Markersets in frame order.
    pub fn markersets(&self) -> impl Iterator<Item = Markerset<'_>> + '_ {
        (0..self.markersets.len()).filter_map(|i| self.markerset(i))
    }

    /// The first markerset called `name`.
    pub fn markerset_named(&self, name: &str) -> Option<Markerset<'_>> {
        self.markersets().find(|m| m.name == name)
    }

    /// Appends a markerset.
    pub fn push_markerset(&mut self, name: &str, positions: &[[f32; 3]]) {
        let n0 = self.names.len();
        self.names.push_str(name);
        let p0 = self.markerset_positions.len();
        self.markerset_positions.extend_from_slice(positions);
        self.markersets.push(Span {
            name: n0..self.names.len(),
            markers: p0..self.markerset_positions.len(),
        });
    }

    /// Starts a markerset whose positions follow with [`Self::push_markerset_position`].
    pub(crate) fn begin_markerset(&mut self, name: &str) {
        self.push_markerset(name, &[]);
    }

    pub(crate) fn push_markerset_position(&mut self, p: [f32; 3]) {
        self.markerset_positions.push(p);
        if let Some(s) = self.markersets.last_mut() {
            s.markers.end = self.markerset_positions.len();
        }
    }

    /// Number of skeletons.
    pub fn skeleton_count(&self) -> usize {
        self.skeletons.len()
    }

    /// Skeletons in frame order.
    pub fn skeletons(&self) -> impl Iterator<Item = Skeleton<'_>> + '_ {
        self.skeletons.iter().filter_map(|(id, r)| {
            Some(Skeleton {
                id: *id,
                bones: self.skeleton_bones.get(r.clone())?,
            })
        })
    }

    /// Appends a skeleton.
    pub fn push_skeleton(&mut self, id: i32, bones: &[RigidBody]) {
        let b0 = self.skeleton_bones.len();
        self.skeleton_bones.extend_from_slice(bones);
        self.skeletons.push((id, b0..self.skeleton_bones.len()));
    }

    pub(crate) fn push_skeleton_bone(&mut self, bone: RigidBody) {
        self.skeleton_bones.push(bone);
        if let Some(s) = self.skeletons.last_mut() {
            s.1.end = self.skeleton_bones.len();
        }
    }

    /// The unpacked timecode.
    pub fn timecode(&self) -> Timecode {
        Timecode::from_packed(self.timecode, self.timecode_subframe)
    }

    /// Software latency in ms as SampleClient computes it: (transmit − camera data received)
    /// × 1000 / clock frequency. `None` without a clock frequency or with stamps out of order.
    pub fn software_latency_ms(&self, clock_frequency_hz: u64) -> Option<f64> {
        ticks_ms(self.camera_data_received, self.transmit, clock_frequency_hz)
    }

    /// System latency in ms as SampleClient computes it: (transmit − mid-exposure) × 1000 /
    /// clock frequency. `None` when the mid-exposure stamp is 0 (not measured).
    pub fn system_latency_ms(&self, clock_frequency_hz: u64) -> Option<f64> {
        if self.camera_mid_exposure == 0 {
            return None;
        }
        ticks_ms(self.camera_mid_exposure, self.transmit, clock_frequency_hz)
    }
}

fn ticks_ms(from: u64, to: u64, hz: u64) -> Option<f64> {
    let ticks = to.checked_sub(from)?;
    (hz != 0).then(|| (ticks as f64 * 1000.0) / hz as f64)
}

/// Writes `positions` (metres) into `out` as flat `x y z` millimetres, emoshift's layout.
/// `out` is cleared first; it allocates only if its capacity is short.
pub fn positions_mm_into(positions: &[[f32; 3]], out: &mut Vec<f32>) {
    out.clear();
    out.extend(positions.iter().flatten().map(|v| v * MM_PER_M));
}

#[cfg(test)]
mod tests;
