//! The per-frame path shared by the offline commands and the live daemon, so that `emoshift
//! edit` and `emoshift serve` produce the same markers for the same settings:
//!
//! 1. glitch check: a sample that moved faster than the model's `max_speed_mm_s` since the last
//!    accepted sample of that marker (a marker swap or spike) is treated as missing;
//! 2. head stabilisation: the rigid pose from the model's reference markers is removed;
//! 3. projection, masked where markers are missing;
//! 4. (the caller edits the components);
//! 5. resynthesis, and the captured head pose put back.
//!
//! Every buffer is allocated in [`FrameProcessor::new`]; the frame calls do not allocate.

use ica_core::model::IcaModel;
use ica_core::project::{FrameError, FrameStatus, Projector};
use ica_core::stabilise::{self, Pose, Stabiliser};

/// A glitching marker is re-accepted after this many rejected frames in a row, so a marker
/// that really moved (or was relabelled for good) is not lost forever.
pub const GLITCH_RELEASE_FRAMES: u32 = 12;

/// What preparing and projecting one frame found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Prepared {
    /// Projection status (masked, held, ill-conditioned).
    pub status: FrameStatus,
    /// Head pose removed from the frame (`None` without stabilisation).
    pub pose: Option<Pose>,
    /// Stabilisation residual (mm RMS over the reference markers; NaN when the pose was held).
    pub residual_mm: f64,
    /// The pose was held because fewer than three reference markers were visible.
    pub pose_held: bool,
    /// Samples dropped as glitches in this frame.
    pub glitches: usize,
}

/// Per-frame processor for one stream or take. See the module docs for the steps.
#[derive(Debug, Clone)]
pub struct FrameProcessor {
    projector: Projector,
    stabiliser: Option<Stabiliser>,
    /// Largest accepted move per frame (mm), from the model's speed limit and rate.
    max_step_mm: Option<f32>,
    last: Vec<f32>,
    last_known: Vec<bool>,
    rejected_run: Vec<u32>,
    missing: Vec<bool>,
    head: Vec<f32>,
    scratch: Vec<f32>,
}

impl FrameProcessor {
    /// Builds the processor and all its buffers from a model.
    pub fn new(model: &IcaModel) -> FrameProcessor {
        let markers = model.markers();
        let capture = model.capture();
        let stabiliser = capture
            .head
            .clone()
            .and_then(|head| Stabiliser::new(head).ok());
        FrameProcessor {
            projector: Projector::new(model),
            stabiliser,
            max_step_mm: capture.max_speed_mm_s.map(|v| (v / model.rate_hz()) as f32),
            last: vec![0.0; markers * 3],
            last_known: vec![false; markers],
            rejected_run: vec![0; markers],
            missing: vec![false; markers],
            head: vec![0.0; markers * 3],
            scratch: vec![0.0; markers * 3],
        }
    }

    /// Markers per frame.
    pub fn markers(&self) -> usize {
        self.missing.len()
    }

    /// Components per frame.
    pub fn components(&self) -> usize {
        self.projector.components()
    }

    /// Forgets the stream's history (glitch reference, held pose, held components).
    pub fn reset(&mut self) {
        self.last_known.fill(false);
        self.rejected_run.fill(0);
        self.projector.reset();
        if let Some(s) = &mut self.stabiliser {
            s.reset();
        }
    }

    /// Steps 1–3: glitch check, stabilisation and projection of a frame in model marker order.
    /// `u` receives the components.
    ///
    /// # Errors
    /// [`FrameError::Length`] when a buffer does not match the model.
    pub fn project(
        &mut self,
        xyz: &[f32],
        missing: &[bool],
        u: &mut [f32],
    ) -> Result<Prepared, FrameError> {
        let n = self.markers();
        if xyz.len() != n * 3 || missing.len() != n {
            return Err(FrameError::Length {
                what: "frame",
                expected: n * 3,
                got: xyz.len(),
            });
        }
        let glitches = self.check_glitches(xyz, missing);
        let mut prepared = Prepared {
            glitches,
            ..Prepared::default()
        };
        let input: &[f32] = match &mut self.stabiliser {
            Some(st) => {
                let est = st.estimate(xyz, &self.missing);
                stabilise::to_head_into(&est.pose, xyz, &self.missing, &mut self.head);
                prepared.pose = Some(est.pose);
                prepared.residual_mm = est.residual_mm;
                prepared.pose_held = est.held;
                &self.head
            }
            None => xyz,
        };
        prepared.status = self
            .projector
            .project_masked_into(input, Some(&self.missing), u)?;
        Ok(prepared)
    }

    /// Step 5: resynthesise (edited) components and put the head pose back into `out`.
    ///
    /// # Errors
    /// [`FrameError::Length`] when a buffer does not match the model.
    pub fn resynthesise(
        &mut self,
        pose: Option<&Pose>,
        u: &[f32],
        out: &mut [f32],
    ) -> Result<(), FrameError> {
        match pose {
            Some(pose) => {
                self.projector.resynth_into(u, &mut self.scratch)?;
                stabilise::to_world_into(pose, &self.scratch, out);
                Ok(())
            }
            None => self.projector.resynth_into(u, out),
        }
    }

    /// Marks missing samples and glitches in `self.missing`; returns the glitch count.
    fn check_glitches(&mut self, xyz: &[f32], missing: &[bool]) -> usize {
        let mut glitches = 0;
        for m in 0..missing.len() {
            let p = &xyz[m * 3..m * 3 + 3];
            let gone = missing[m] || !p.iter().all(|v| v.is_finite());
            self.missing[m] = gone;
            if gone {
                continue;
            }
            if let (Some(step), true) = (self.max_step_mm, self.last_known[m]) {
                let q = &self.last[m * 3..m * 3 + 3];
                let d2: f32 = (0..3).map(|a| (p[a] - q[a]) * (p[a] - q[a])).sum();
                // The allowance grows with the frames since the last accepted sample.
                let allowed = step * (1 + self.rejected_run[m]) as f32;
                if d2 > allowed * allowed && self.rejected_run[m] < GLITCH_RELEASE_FRAMES {
                    self.missing[m] = true;
                    self.rejected_run[m] += 1;
                    glitches += 1;
                    continue;
                }
            }
            self.last[m * 3..m * 3 + 3].copy_from_slice(p);
            self.last_known[m] = true;
            self.rejected_run[m] = 0;
        }
        glitches
    }
}
