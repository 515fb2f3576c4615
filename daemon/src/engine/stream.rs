//! One stream: a source's frames of one layout, with its own frame order, edit state,
//! low-pass state and per-frame buffers, processed by [`Stream::process`].

use std::sync::Arc;

use ica_core::model::IcaModel;
use protocol::{FrameBuf, FrameHeader};

use super::edit_state::EditState;
use super::frame::FrameProcessor;
use super::layout::{LabelMap, LayoutError};
use super::Counters;

/// A backwards jump of more than this many frames is a restarted source (a looping replay, a
/// restarted capture), not a late frame: the stream starts over instead of dropping it.
pub const RESTART_FRAMES: i64 = 240;

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
    /// The live edit.
    pub edit: EditState,
    /// VMC blend names of the labelled components (`/VMC/Ext/Blend/Val` of the components
    /// profile), from the model's roles.
    pub vmc: Vec<(String, usize)>,
    /// The source's labels, to build the stream again on another model.
    source_labels: Vec<String>,
    processor: FrameProcessor,
    map: LabelMap,
    /// Missing flags in source order.
    source_missing: Vec<bool>,
    /// Frame in model order.
    xyz: Vec<f32>,
    /// Missing flags in model order.
    missing: Vec<bool>,
    /// Components.
    u: Vec<f32>,
    /// Edited frame in model order.
    out: Vec<f32>,
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
            source_labels: source_labels.to_vec(),
            source_missing: vec![false; source_labels.len()],
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

    /// This stream on `model` (a model swap): same source, performer, edit settings and frame
    /// order, so the next frame is neither dropped nor taken for a restart.
    ///
    /// # Errors
    /// As [`Stream::new`].
    pub fn rebuilt_on(&self, model: Arc<IcaModel>, lowpass_s: f32) -> Result<Stream, LayoutError> {
        let mut fresh = Stream::new(model, self.performer, &self.source_labels, lowpass_s)?;
        fresh.edit.copy_settings(&self.edit);
        fresh.last_frame = self.last_frame;
        fresh.frames = self.frames;
        fresh.duplicates = self.duplicates;
        fresh.stale = self.stale;
        Ok(fresh)
    }

    /// The components of the last processed frame, after the edit.
    pub fn components(&self) -> &[f32] {
        &self.u
    }

    /// The edited frame in model order (gaps filled by the model).
    pub fn edited(&self) -> &[f32] {
        &self.out
    }

    /// Takes one received frame through the stream into `output`: order check, markers into
    /// model order, projection (masked where markers are missing), the live edit, resynthesis
    /// with the head pose put back. Returns the frame numbers since the previous processed
    /// frame, or `None` when the frame is dropped (counted in `counters`).
    pub fn process(
        &mut self,
        header: &FrameHeader,
        input: &FrameBuf,
        output: &mut FrameBuf,
        counters: &mut Counters,
    ) -> Option<u32> {
        let frames = match self.check_order(header.frame_number) {
            Order::Next { frames } => frames,
            Order::Restart => {
                counters.restarts += 1;
                1
            }
            Order::Duplicate => {
                counters.dropped_duplicate += 1;
                return None;
            }
            Order::Stale => {
                counters.dropped_stale += 1;
                return None;
            }
        };
        self.gather(header, input);
        counters.missing_markers += self.missing.iter().filter(|&&m| m).count() as u64;
        let Ok(prepared) = self
            .processor
            .project(&self.xyz, &self.missing, &mut self.u)
        else {
            counters.frame_errors += 1;
            return None;
        };
        counters.glitches += prepared.glitches as u64;
        let rate = self.model.rate_hz();
        // A gap of many frames moves the glides by at most a second.
        let dt = (f64::from(frames.min(rate.max(1.0) as u32)) / rate) as f32;
        self.edit.apply(dt, &mut self.u);
        let resynthesised =
            self.processor
                .resynthesise(prepared.pose.as_ref(), &self.u, &mut self.out);
        if resynthesised.is_err()
            || output
                .set_frame(header.frame_number, header.capture_time_us, &self.out)
                .is_err()
        {
            counters.frame_errors += 1;
            return None;
        }
        Some(frames)
    }

    /// The input's markers into model order, with their missing flags.
    fn gather(&mut self, header: &FrameHeader, input: &FrameBuf) {
        if header.missing_count == 0 {
            self.map
                .gather_present_into(input.positions(), &mut self.xyz, &mut self.missing);
        } else {
            for (i, m) in self.source_missing.iter_mut().enumerate() {
                *m = input.is_missing(i);
            }
            let (xyz, missing) = (&mut self.xyz, &mut self.missing);
            self.map
                .gather_into(input.positions(), &self.source_missing, xyz, missing);
        }
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

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use ica_core::model::Role;

    use super::*;
    use crate::loopback::synthetic::random_model;

    #[test]
    fn order_counts_duplicates_and_stale_and_restarts_far_jumps() {
        let model = Arc::new(random_model(4, 2, 1));
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
