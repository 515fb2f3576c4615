//! Small value types of a frame: flags, timestamps, timecode, analog samples.

use std::fmt;
use std::ops::Range;

/// Labelled marker flags (`sMarker::params`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct MarkerParams(pub u16);

impl MarkerParams {
    /// Bit 0: not visible in this frame.
    pub fn occluded(self) -> bool {
        self.0 & 0x01 != 0
    }
    /// Bit 1: position from the point-cloud solve.
    pub fn point_cloud_solved(self) -> bool {
        self.0 & 0x02 != 0
    }
    /// Bit 2: position from the model (asset) solve.
    pub fn model_solved(self) -> bool {
        self.0 & 0x04 != 0
    }
    /// Bit 3 (NatNet 3+): the marker has an associated asset in the stream.
    pub fn has_model(self) -> bool {
        self.0 & 0x08 != 0
    }
    /// Bit 4 (NatNet 3+): unlabelled, but with a point-cloud id.
    pub fn unlabeled(self) -> bool {
        self.0 & 0x10 != 0
    }
    /// Bit 5 (NatNet 3+): an actively labelled LED marker.
    pub fn active(self) -> bool {
        self.0 & 0x20 != 0
    }
}

/// Frame flags (`sFrameOfMocapData::params`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct FrameParams(pub u16);

impl FrameParams {
    /// Bit 0: Motive is recording.
    pub fn is_recording(self) -> bool {
        self.0 & 0x01 != 0
    }
    /// Bit 1: the tracked model list changed; model definitions should be requested again.
    pub fn tracked_models_changed(self) -> bool {
        self.0 & 0x02 != 0
    }
    /// Bit 2 (NatNet 4 PacketClient): live mode, as opposed to edit (playback).
    pub fn live_mode(self) -> bool {
        self.0 & 0x04 != 0
    }
    /// Bit 3 (NatNet 4 PacketClient): the bitstream version has just changed.
    pub fn bitstream_changed(self) -> bool {
        self.0 & 0x08 != 0
    }
}

/// NatNet 4.1 precision (typically PTP) timestamp.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct PrecisionTimestamp {
    /// Whole seconds.
    pub seconds: u32,
    /// Fractional seconds, as sent.
    pub fraction: u32,
}

/// An SMPTE timecode, unpacked the way the SDK's `NatNet_DecodeTimecode` does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Timecode {
    /// Hours (bits 24..32).
    pub hours: u8,
    /// Minutes (bits 16..24).
    pub minutes: u8,
    /// Seconds (bits 8..16).
    pub seconds: u8,
    /// Frames (bits 0..8).
    pub frames: u8,
    /// Subframe.
    pub subframe: u32,
}

impl Timecode {
    /// Unpacks `timecode` (`hh mm ss ff`, most significant byte first) and its subframe.
    pub fn from_packed(timecode: u32, subframe: u32) -> Self {
        let [hours, minutes, seconds, frames] = timecode.to_be_bytes();
        Timecode {
            hours,
            minutes,
            seconds,
            frames,
            subframe,
        }
    }
}

/// `hh:mm:ss:ff.s`, as SampleClient prints it (`NatNet_TimecodeStringify`).
impl fmt::Display for Timecode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:02}:{:02}:{:02}:{:02}.{}",
            self.hours, self.minutes, self.seconds, self.frames, self.subframe
        )
    }
}

/// Samples of force plates or devices: per device an id and channels, per channel the
/// samples of this mocap frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AnalogData {
    devices: Vec<(i32, Range<usize>)>,
    channels: Vec<Range<usize>>,
    samples: Vec<f32>,
}

impl AnalogData {
    /// Number of devices (or plates).
    pub fn len(&self) -> usize {
        self.devices.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.devices.is_empty()
    }

    /// Id of device `i`.
    pub fn id(&self, i: usize) -> Option<i32> {
        self.devices.get(i).map(|d| d.0)
    }

    /// Channel count of device `i`.
    pub fn channel_count(&self, i: usize) -> usize {
        self.devices.get(i).map_or(0, |d| d.1.len())
    }

    /// Samples of channel `c` of device `i`.
    pub fn samples(&self, i: usize, c: usize) -> Option<&[f32]> {
        let d = self.devices.get(i)?;
        let ch = self.channels.get(d.1.clone())?.get(c)?;
        self.samples.get(ch.clone())
    }

    /// Appends a device with its channels' samples.
    pub fn push(&mut self, id: i32, channels: &[&[f32]]) {
        let first = self.channels.len();
        for ch in channels {
            let start = self.samples.len();
            self.samples.extend_from_slice(ch);
            self.channels.push(start..self.samples.len());
        }
        self.devices.push((id, first..self.channels.len()));
    }

    pub(crate) fn begin_device(&mut self, id: i32) {
        let n = self.channels.len();
        self.devices.push((id, n..n));
    }

    pub(crate) fn begin_channel(&mut self) {
        let s = self.samples.len();
        self.channels.push(s..s);
        if let Some(d) = self.devices.last_mut() {
            d.1.end = self.channels.len();
        }
    }

    pub(crate) fn push_sample(&mut self, v: f32) {
        self.samples.push(v);
        if let Some(c) = self.channels.last_mut() {
            c.end = self.samples.len();
        }
    }

    pub(crate) fn clear(&mut self) {
        self.devices.clear();
        self.channels.clear();
        self.samples.clear();
    }
}
