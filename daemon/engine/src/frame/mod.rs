//! The per-frame path shared by the offline commands and the live daemon, so that `emoshift
//! edit` and `emoshift serve` produce the same markers for the same settings:
//!
//! 1. head stabilisation: the rigid pose from the model's reference markers is removed;
//! 2. glitch checks, in head coordinates: a sample outside its marker's plausible ball (the
//!    model's `bounds`: labels that swap or drift slowly) or one that moved faster than the
//!    model's `max_speed_mm_s` since that marker's last accepted sample (spikes) is treated as
//!    missing;
//! 3. projection, masked where markers are missing;
//! 4. (the caller edits the components);
//! 5. resynthesis, and the captured head pose put back.
//!
//! Every buffer is allocated in [`FrameProcessor::new`]; the frame calls do not allocate.

use ica_core::model::{CaptureSettings, IcaModel};
use ica_core::project::{FrameError, FrameStatus, Projector};
use ica_core::stabilise::{self, Pose, Stabiliser};
use protocol::all_finite;

/// A glitching marker is believed again after this long (seconds) of rejected samples in a
/// row, so a marker that really moved (or was relabelled for good) is not lost forever. Long
/// enough for the swaps seen in real captures (Facial-Sing: 23 frames at 100 Hz).
pub const GLITCH_RELEASE_S: f64 = 0.5;

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

/// Steps 1–2 alone (glitch check and head stabilisation): what training needs before a model
/// exists, and what [`FrameProcessor`] runs before projecting.
#[derive(Debug, Clone)]
pub struct FramePrep {
    stabiliser: Option<Stabiliser>,
    /// Largest accepted move per frame (mm), from the speed limit and rate.
    max_step_mm: Option<f32>,
    /// Frames a glitching marker stays rejected before it is believed again.
    release_frames: u32,
    last: Vec<f32>,
    last_known: Vec<bool>,
    rejected_run: Vec<u32>,
    /// Frames a marker was absent (not rejected) since its last accepted sample.
    unseen_run: Vec<u32>,
    /// Every marker's last sample was accepted: all known, every run 0.
    steady: bool,
    missing: Vec<bool>,
    head: Vec<f32>,
    /// Per-marker centre (x y z) and squared radius of the plausible region, head coordinates.
    bounds: Option<(Vec<f32>, Vec<f32>)>,
}

/// A prepared frame: positions (head coordinates when stabilised) and the missing mask
/// including glitches, borrowed from the [`FramePrep`].
#[derive(Debug)]
pub struct PreparedFrame<'a> {
    /// Positions, markers x 3 (mm).
    pub xyz: &'a [f32],
    /// Missing flags after the glitch check.
    pub missing: &'a [bool],
    /// What preparing found (pose, residual, glitches); `status` is left default.
    pub info: Prepared,
}

impl FramePrep {
    /// Preparation for `markers` markers at `rate_hz` with the given settings.
    pub fn new(markers: usize, rate_hz: f64, capture: &CaptureSettings) -> FramePrep {
        let stabiliser = capture
            .head
            .clone()
            .and_then(|head| Stabiliser::new(head).ok());
        FramePrep {
            stabiliser,
            max_step_mm: capture.max_speed_mm_s.map(|v| (v / rate_hz) as f32),
            release_frames: ((GLITCH_RELEASE_S * rate_hz).ceil() as u32).max(1),
            last: vec![0.0; markers * 3],
            last_known: vec![false; markers],
            rejected_run: vec![0; markers],
            unseen_run: vec![0; markers],
            steady: false,
            missing: vec![false; markers],
            head: vec![0.0; markers * 3],
            bounds: capture.bounds.as_ref().map(|b| {
                let centre = b.centre.iter().flatten().map(|&v| v as f32).collect();
                let r2 = b.radius_mm.iter().map(|&r| (r * r) as f32).collect();
                (centre, r2)
            }),
        }
    }

    /// Markers per frame.
    pub fn markers(&self) -> usize {
        self.missing.len()
    }

    /// The last prepared frame's missing mask: absent samples and rejected glitches.
    pub fn missing(&self) -> &[bool] {
        &self.missing
    }

    /// Forgets the stream's history (glitch reference, held pose).
    pub fn reset(&mut self) {
        self.last_known.fill(false);
        self.rejected_run.fill(0);
        self.unseen_run.fill(0);
        self.steady = false;
        if let Some(s) = &mut self.stabiliser {
            s.reset();
        }
    }

    /// Glitch check and stabilisation of one frame in model marker order.
    ///
    /// # Errors
    /// [`FrameError::Length`] when a buffer does not match the marker count.
    pub fn prepare<'a>(
        &'a mut self,
        xyz: &'a [f32],
        missing: &[bool],
    ) -> Result<PreparedFrame<'a>, FrameError> {
        let n = self.markers();
        if xyz.len() != n * 3 || missing.len() != n {
            return Err(FrameError::Length {
                what: "frame",
                expected: n * 3,
                got: xyz.len(),
            });
        }
        if all_finite(xyz) {
            self.missing.copy_from_slice(missing);
        } else {
            for (m, gone) in self.missing.iter_mut().enumerate() {
                *gone = missing[m] || !xyz[m * 3..m * 3 + 3].iter().all(|v| v.is_finite());
            }
        }
        let mut info = Prepared::default();
        let stabilised = match &mut self.stabiliser {
            Some(st) => {
                let est = st.estimate(xyz, &self.missing);
                stabilise::to_head_into(&est.pose, xyz, &self.missing, &mut self.head);
                info.pose = Some(est.pose);
                info.residual_mm = est.residual_mm;
                info.pose_held = est.held;
                true
            }
            None => false,
        };
        // The checks read the frame in place when it is not stabilised (no copy into `head`);
        // `head` is moved out meanwhile (no allocation) so they can borrow `self` mutably.
        let head = std::mem::take(&mut self.head);
        let pos = if stabilised { &head[..] } else { xyz };
        info.glitches = self.check_bounds(pos) + self.check_speed(pos);
        self.head = head;
        Ok(PreparedFrame {
            xyz: if stabilised { &self.head } else { xyz },
            missing: &self.missing,
            info,
        })
    }

    /// Marks samples outside their marker's plausible ball (head coordinates) as missing.
    fn check_bounds(&mut self, pos: &[f32]) -> usize {
        let Some((centre, r2)) = &self.bounds else {
            return 0;
        };
        // Zipped chunks, no indexing: no bounds checks, and the branch-free test lets the
        // accepted-sample path (nearly every sample) run without a mispredict.
        let mut glitches = 0;
        for (((p, c), &r2), gone) in pos
            .chunks_exact(3)
            .zip(centre.chunks_exact(3))
            .zip(r2)
            .zip(self.missing.iter_mut())
        {
            let d2 = sq(p[0] - c[0]) + sq(p[1] - c[1]) + sq(p[2] - c[2]);
            let outside = !*gone && d2 > r2;
            *gone |= outside;
            glitches += usize::from(outside);
        }
        glitches
    }

    /// Marks samples that moved faster than the speed limit since their marker's last accepted
    /// sample (head coordinates, so head motion does not count) as missing.
    fn check_speed(&mut self, pos: &[f32]) -> usize {
        // Without a limit nothing reads the history below (`last`, the runs): skip the pass.
        let Some(step) = self.max_step_mm else {
            return 0;
        };
        if self.steady_frame_within(pos, step) {
            self.last.copy_from_slice(pos);
            return 0;
        }
        let release = self.release_frames;
        let mut glitches = 0;
        // Every per-marker array zipped: no bounds checks in the loop (it was indexed by m).
        let markers = pos
            .chunks_exact(3)
            .zip(self.last.chunks_exact_mut(3))
            .zip(self.missing.iter_mut())
            .zip(self.last_known.iter_mut())
            .zip(self.rejected_run.iter_mut())
            .zip(self.unseen_run.iter_mut());
        for (((((p, q), gone), known), rejected), unseen) in markers {
            if *gone {
                *unseen = unseen.saturating_add(1);
                continue;
            }
            if *known {
                let d2 = sq(p[0] - q[0]) + sq(p[1] - q[1]) + sq(p[2] - q[2]);
                // The allowance grows with the frames the marker was unseen, not with rejected
                // frames: a swapped marker stays far from its last good position, and must not
                // be believed just because time passed.
                let allowed = step * (1 + *unseen) as f32;
                if d2 > allowed * allowed && *rejected < release {
                    *gone = true;
                    *rejected += 1;
                    glitches += 1;
                    continue;
                }
            }
            q.copy_from_slice(p);
            *known = true;
            *rejected = 0;
            *unseen = 0;
        }
        self.steady = glitches == 0 && !any(&self.missing);
        glitches
    }

    /// The whole frame passes the speed check, decided in two vectorised passes: after a
    /// frame whose samples were all accepted (so every allowance is one `step`), with no
    /// sample missing now, and no coordinate moved more than `0.57 step` (then no marker moved
    /// more than `√3 · 0.57 < 0.99` steps, clear of the exact test's rounding). Otherwise
    /// the per-marker loop decides, so the outcome is the same either way.
    fn steady_frame_within(&self, pos: &[f32], step: f32) -> bool {
        if !self.steady || any(&self.missing) {
            return false;
        }
        let limit = 0.57 * step;
        let mut moved = [0.0_f32; 8];
        let (p, q) = (pos.chunks_exact(8), self.last.chunks_exact(8));
        let tail = p.remainder().iter().zip(q.remainder());
        let tail_ok = tail.fold(true, |ok, (a, b)| ok & ((a - b).abs() <= limit));
        for (p, q) in p.zip(q) {
            for i in 0..8 {
                let d = (p[i] - q[i]).abs();
                moved[i] = if d > moved[i] { d } else { moved[i] };
            }
        }
        // No NaN reaches here: with no sample missing every coordinate is finite.
        tail_ok && moved.iter().all(|&d| d <= limit)
    }
}

/// Any flag set, without an early exit (so it vectorises).
fn any(flags: &[bool]) -> bool {
    flags.iter().fold(false, |a, &b| a | b)
}

fn sq(v: f32) -> f32 {
    v * v
}

/// Per-frame processor for one stream or take. See the module docs for the steps.
#[derive(Debug, Clone)]
pub struct FrameProcessor {
    prep: FramePrep,
    projector: Projector,
    scratch: Vec<f32>,
}

impl FrameProcessor {
    /// Builds the processor and all its buffers from a model.
    pub fn new(model: &IcaModel) -> FrameProcessor {
        FrameProcessor {
            prep: FramePrep::new(model.markers(), model.rate_hz(), model.capture()),
            projector: Projector::new(model),
            scratch: vec![0.0; model.channels()],
        }
    }

    /// Markers per frame.
    pub fn markers(&self) -> usize {
        self.prep.markers()
    }

    /// Components per frame.
    pub fn components(&self) -> usize {
        self.projector.components()
    }

    /// The markers the model filled in the last frame (absent or rejected as glitches).
    pub fn filled(&self) -> &[bool] {
        self.prep.missing()
    }

    /// Forgets the stream's history (glitch reference, held pose, held components).
    pub fn reset(&mut self) {
        self.prep.reset();
        self.projector.reset();
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
        let frame = self.prep.prepare(xyz, missing)?;
        let mut info = frame.info;
        info.status = self
            .projector
            .project_masked_into(frame.xyz, Some(frame.missing), u)?;
        Ok(info)
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
}

#[cfg(test)]
mod tests;
