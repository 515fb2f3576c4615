//! QTM data packets as emoshift frames, sans-IO. QTM's labelled markers have no marker sets,
//! so performers come from label prefixes (`qtm_performers = { alice = "Alice_*" }`): each
//! performer is one stream of the labels with its prefix, the prefix taken off (the model's
//! labels are the bare names); with no performers configured, one stream of every label. A
//! marker QTM did not see (NaN) is missing; the frame number, the timestamp (µs, as the capture
//! time on the source's clock) and the SMPTE or IRIG timecode are QTM's.

use std::net::SocketAddr;
use std::sync::Arc;

use engine::{SourceFrame, StreamKey};
use protocol::qtm::{decode_data_into, FrameIn, QtmError, QtmParameters};
use protocol::{FrameBuf, FrameTime};

/// One stream: a performer's labels (or all of them).
#[derive(Debug, Clone)]
struct Layout {
    name: Option<Arc<str>>,
    labels: Arc<[String]>,
    /// Marker indices in QTM's list, in `labels` order.
    indices: Vec<usize>,
    layout_id: i32,
}

/// What a data packet did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Its streams went to the sink.
    Frames(usize),
    /// It carried no labelled 3D markers (only other components).
    No3d,
    /// Its marker count is not the parameters' label count: read them again.
    Mismatch,
}

/// The streams of the current parameters, and the buffers frames are decoded into.
#[derive(Debug)]
pub struct QtmFrames {
    server: SocketAddr,
    layouts: Vec<Layout>,
    label_count: usize,
    frame_in: FrameIn,
    positions: Vec<f32>,
    /// The frequency from the parameters.
    pub rate_hz: Option<f64>,
}

impl QtmFrames {
    /// Buffers for up to `max_markers` labelled markers, from QTM at `server`.
    pub fn new(server: SocketAddr, max_markers: usize) -> QtmFrames {
        QtmFrames {
            server,
            layouts: Vec::new(),
            label_count: 0,
            frame_in: FrameIn::with_max_markers(max_markers),
            positions: Vec::with_capacity(max_markers * 3),
            rate_hz: None,
        }
    }

    /// Labels QTM announced.
    pub fn label_count(&self) -> usize {
        self.label_count
    }

    /// New parameters: the streams again (`performers`: name and label prefix).
    pub fn set_parameters(&mut self, p: &QtmParameters, performers: &[(String, String)]) {
        if let Some(hz) = p.frequency_hz.filter(|hz| *hz > 0.0) {
            self.rate_hz = Some(hz);
        }
        let Some(labels) = &p.labels else {
            return;
        };
        self.label_count = labels.len();
        self.layouts.clear();
        if performers.is_empty() {
            self.layouts.push(Layout {
                name: None,
                labels: labels.clone().into(),
                indices: (0..labels.len()).collect(),
                layout_id: 0,
            });
            return;
        }
        for (k, (name, prefix)) in performers.iter().enumerate() {
            let (indices, bare): (Vec<usize>, Vec<String>) = labels
                .iter()
                .enumerate()
                .filter_map(|(i, l)| l.strip_prefix(prefix.as_str()).map(|b| (i, b.to_string())))
                .unzip();
            if indices.is_empty() {
                continue;
            }
            self.layouts.push(Layout {
                name: Some(name.as_str().into()),
                labels: bare.into(),
                indices,
                layout_id: k as i32,
            });
        }
    }

    /// Names of the streams now (for the log and `/status`).
    pub fn stream_names(&self) -> Vec<String> {
        self.layouts
            .iter()
            .map(|l| l.name.as_deref().unwrap_or("(all labels)").to_string())
            .collect()
    }

    /// Decodes one data packet's payload and gives each stream's frame to `out`.
    ///
    /// # Errors
    /// What [`decode_data_into`] finds wrong; nothing is given then.
    pub fn handle_data(
        &mut self,
        payload: &[u8],
        buf: &mut FrameBuf,
        out: &mut dyn FnMut(&SourceFrame<'_>),
    ) -> Result<Outcome, QtmError> {
        decode_data_into(payload, &mut self.frame_in)?;
        let f = &self.frame_in;
        if !f.has_3d {
            return Ok(Outcome::No3d);
        }
        if f.marker_count() != self.label_count {
            return Ok(Outcome::Mismatch);
        }
        let mut time = FrameTime::default();
        if let Some(t) = f.timecode {
            t.set_frame_time(&mut time);
        }
        let all = f.positions();
        let frame_number = f.frame_number as i32;
        for l in &self.layouts {
            self.positions.clear();
            for &i in &l.indices {
                self.positions.extend_from_slice(&all[3 * i..3 * i + 3]);
            }
            if buf
                .set_frame(frame_number, f.timestamp_us, &self.positions)
                .is_err()
            {
                continue;
            }
            out(&SourceFrame {
                key: StreamKey {
                    source: self.server,
                    layout_id: l.layout_id,
                },
                performer: l.name.as_ref(),
                labels: &l.labels,
                frame: buf,
                time,
            });
        }
        Ok(Outcome::Frames(self.layouts.len()))
    }
}

#[cfg(test)]
mod tests;
