//! The live emotion edit of one stream, sans-IO: it advances on a frame clock (`dt_s` per frame,
//! from frame numbers and the model rate), never on the wall clock, so a test or an offline run
//! sees exactly what the daemon does.
//!
//! The edit, in the coordinates `y = A u` of the model's emotion space (its axes `A`, fitted
//! over every component, or its emotion components themselves in older models):
//! `u' = u + amount · M (target − lowpass(y))`, where `M` holds the components each axis moves,
//! `target` is the point of the target emotion (or of a blend) in that space, and the one-pole
//! low-pass has the window as time constant (default 1 s): the slow emotion level is moved, the
//! fast speech motion of the same components is kept. Raw alpha (`u_k + alpha_k`), gains (`g_k · u_k`) and bypass
//! complete it; with amount 0 and no bypass the result is bit-for-bit `FrameEdit::apply`
//! (`u · g + alpha`), so the live and offline edits agree.
//!
//! `target` keeps the part of each axis's level that belongs to what is said (see
//! [`SpaceTarget`]): an axis that carries emotion alone goes to the target's level, one whose
//! level also follows the sentence keeps its own offset from the source emotion.
//!
//! Every setting glides from its current value to the new one over the ramp (default 0.25 s)
//! on a smoothstep curve (`3t² − 2t³`): value and slope are continuous at both ends, so no
//! setting change makes a step (a "pop") in the markers. A change during a glide starts from
//! where the glide is.

use ica_core::model::SpaceTarget;

mod apply;
mod glide;
pub use apply::{apply_edit, mix_name};
pub use glide::Glide;

/// Default ramp of a new setting (seconds).
pub const DEFAULT_RAMP_S: f32 = 0.25;
/// Default low-pass window of the emotion component (seconds).
pub const DEFAULT_LOWPASS_S: f32 = 1.0;

/// Why an edit setting was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EditRefused {
    /// Component index past the model's.
    #[error("component {index} is out of range, the model has {components}")]
    Component {
        /// Index received.
        index: u32,
        /// Components of the model.
        components: usize,
    },
    /// The model has no emotion component (run `emoshift analyze --write-model`).
    #[error("the model has no emotion component")]
    NoEmotion,
    /// The model has no level for that emotion.
    #[error("unknown emotion {name:?} (the model knows {known})")]
    UnknownEmotion {
        /// Name received.
        name: String,
        /// The emotions the model knows, comma separated.
        known: String,
    },
    /// A blend weight that is negative or not finite, or weights that sum to zero.
    #[error(
        "blend weight {weight} for {name:?}: weights must be finite, at least 0, and not all 0"
    )]
    BadWeight {
        /// The emotion it was given for.
        name: String,
        /// The weight.
        weight: f64,
    },
    /// No model is loaded: frames pass through unedited until one is.
    #[error(
        "no model is loaded, frames pass through unedited: load one with /model/load PATH, or \
         record a calibration session with `emoshift session ... --load-into`"
    )]
    NoModel,
    /// A target point with a number of levels other than the emotion space's dimensions.
    #[error("a target of {got} levels for an emotion space of {expected}")]
    Dims {
        /// Dimensions of the space.
        expected: usize,
        /// Levels given.
        got: usize,
    },
}

/// The live edit of one stream. Call order per frame: [`EditState::apply`] with the frame's
/// `dt_s`; settings (`set_*`) between frames.
#[derive(Debug, Clone)]
pub struct EditState {
    /// Dimensions of the emotion space (0: the model has none).
    dims: usize,
    target: String,
    /// The target point, one glide per axis.
    level: Vec<Glide>,
    amount: Glide,
    alpha: Vec<Glide>,
    gains: Vec<Glide>,
    wet: Glide,
    ramp_s: f32,
    lowpass_s: f32,
    /// Low-pass of each coordinate in the emotion space; `None` before the first frame.
    lowpass: Option<Vec<f32>>,
    /// Preallocated storage for `lowpass` (moved in on the first frame, no allocation).
    lowpass_buf: Vec<f32>,
    /// Where a take goes to reach the target point (sentence share kept), and the maps between
    /// components and the space.
    space: SpaceTarget,
    /// The target point now (glide values), and the coordinates to move to; per axis.
    goal: Vec<f32>,
    to: Vec<f32>,
    /// This frame's coordinates, then the move along each axis.
    coords: Vec<f32>,
    raw: Vec<f32>,
}

impl EditState {
    /// An identity edit for `components` components; `emotion` are the emotion components, each
    /// an axis of the space (empty: the model has none). Components out of range are ignored.
    pub fn new(components: usize, emotion: &[usize], lowpass_s: f32) -> EditState {
        let emotion: Vec<usize> = emotion
            .iter()
            .copied()
            .filter(|&k| k < components)
            .collect();
        let levels = ica_core::model::EmotionLevels {
            components: emotion,
            ..Default::default()
        };
        EditState::with_space(components, SpaceTarget::new(&levels, components), lowpass_s)
    }

    fn with_space(components: usize, space: SpaceTarget, lowpass_s: f32) -> EditState {
        let dims = space.dims();
        EditState {
            space,
            goal: vec![0.0; dims],
            to: vec![0.0; dims],
            coords: vec![0.0; dims],
            target: String::with_capacity(64),
            level: vec![Glide::settled(0.0); dims],
            lowpass_buf: vec![0.0; dims],
            dims,
            amount: Glide::settled(0.0),
            alpha: vec![Glide::settled(0.0); components],
            gains: vec![Glide::settled(1.0); components],
            wet: Glide::settled(1.0),
            ramp_s: DEFAULT_RAMP_S,
            lowpass_s: lowpass_s.max(0.0),
            lowpass: None,
            raw: vec![0.0; components],
        }
    }

    /// The edit for a model: its components and emotion space (points, spreads and
    /// persistence included).
    pub fn for_model(model: &ica_core::IcaModel, lowpass_s: f32) -> EditState {
        let m = model.components();
        EditState::with_space(m, SpaceTarget::new(model.emotion(), m), lowpass_s)
    }

    /// The target emotion (empty before one is set).
    pub fn target(&self) -> &str {
        &self.target
    }

    /// The amount now (mid-glide values included).
    pub fn amount(&self) -> f32 {
        self.amount.value()
    }

    /// The amount being glided to.
    pub fn amount_goal(&self) -> f32 {
        self.amount.goal()
    }

    /// The ramp of new settings, seconds.
    pub fn ramp_s(&self) -> f32 {
        self.ramp_s
    }

    /// Bypass is set (the edit glides out, or is out).
    pub fn bypassed(&self) -> bool {
        self.wet.goal() == 0.0
    }

    /// Ramp used by the next settings.
    pub fn set_ramp(&mut self, ramp_s: f32) {
        self.ramp_s = ramp_s.max(0.0);
    }

    /// Sets the target: its name (an emotion, or a blend's description) and its point in the
    /// emotion space, which the caller looked up in the model.
    ///
    /// # Errors
    /// [`EditRefused::NoEmotion`] when the model has no emotion component,
    /// [`EditRefused::Dims`] for a point of the wrong length.
    pub fn set_target(&mut self, name: &str, point: &[f32]) -> Result<(), EditRefused> {
        if self.dims == 0 {
            return Err(EditRefused::NoEmotion);
        }
        if point.len() != self.level.len() {
            return Err(EditRefused::Dims {
                expected: self.level.len(),
                got: point.len(),
            });
        }
        self.target.clear();
        self.target.push_str(name);
        for (g, &p) in self.level.iter_mut().zip(point) {
            g.set(p, self.ramp_s);
        }
        Ok(())
    }

    /// Sets the amount.
    ///
    /// # Errors
    /// [`EditRefused::NoEmotion`] when the model has no emotion component.
    pub fn set_amount(&mut self, amount: f32) -> Result<(), EditRefused> {
        if self.dims == 0 {
            return Err(EditRefused::NoEmotion);
        }
        self.amount.set(amount, self.ramp_s);
        Ok(())
    }

    /// Sets the raw translate of component `k`.
    ///
    /// # Errors
    /// [`EditRefused::Component`] past the model's components.
    pub fn set_alpha(&mut self, k: u32, value: f32) -> Result<(), EditRefused> {
        let ramp = self.ramp_s;
        self.slot(k, |s| &mut s.alpha)?.set(value, ramp);
        Ok(())
    }

    /// Sets the gain of component `k`.
    ///
    /// # Errors
    /// [`EditRefused::Component`] past the model's components.
    pub fn set_gain(&mut self, k: u32, gain: f32) -> Result<(), EditRefused> {
        let ramp = self.ramp_s;
        self.slot(k, |s| &mut s.gains)?.set(gain, ramp);
        Ok(())
    }

    /// Turns the edit off (frames pass through unedited) or back on, gliding.
    pub fn set_bypass(&mut self, bypass: bool) {
        self.wet.set(if bypass { 0.0 } else { 1.0 }, self.ramp_s);
    }

    fn slot(
        &mut self,
        k: u32,
        pick: impl FnOnce(&mut EditState) -> &mut Vec<Glide>,
    ) -> Result<&mut Glide, EditRefused> {
        let components = self.raw.len();
        pick(self)
            .get_mut(k as usize)
            .ok_or(EditRefused::Component {
                index: k,
                components,
            })
    }

    /// Edits one frame's components in place and advances every glide and the low-pass by
    /// `dt_s`. Allocation-free. `u` must have the model's component count (shorter or longer
    /// slices are edited over the common length).
    pub fn apply(&mut self, dt_s: f32, u: &mut [f32]) {
        let wet = self.wet.value();
        if wet < 1.0 {
            let n = u.len().min(self.raw.len());
            self.raw[..n].copy_from_slice(&u[..n]);
        }
        for ((ui, g), a) in u.iter_mut().zip(&self.gains).zip(&self.alpha) {
            *ui = *ui * g.value() + a.value();
        }
        if self.dims > 0 && u.len() == self.raw.len() {
            self.edit_emotion(dt_s, wet, u);
        }
        if wet < 1.0 {
            for (ui, r) in u.iter_mut().zip(&self.raw) {
                *ui = r + wet * (*ui - r);
            }
        }
        self.advance(dt_s);
    }

    /// Moves the take towards the target from the low-pass of its coordinates (taken before
    /// the edit: of the raw values when bypass is gliding).
    fn edit_emotion(&mut self, dt_s: f32, wet: f32, u: &mut [f32]) {
        let first = self.lowpass.is_none();
        let mut lp = self
            .lowpass
            .take()
            .unwrap_or_else(|| std::mem::take(&mut self.lowpass_buf));
        let gain = if self.lowpass_s <= 0.0 {
            1.0
        } else {
            dt_s / (self.lowpass_s + dt_s)
        };
        let source: &[f32] = if wet < 1.0 { &self.raw } else { u };
        self.space.coordinates_into(source, &mut self.coords);
        for (&x, y) in self.coords.iter().zip(lp.iter_mut()) {
            // One-pole low-pass, started at the first value.
            *y = if first { x } else { *y + (x - *y) * gain };
        }
        let amount = self.amount.value();
        if amount != 0.0 {
            for (g, level) in self.goal.iter_mut().zip(&self.level) {
                *g = level.value();
            }
            self.space.target_into(&lp, &self.goal, &mut self.to);
            for ((delta, y), to) in self.coords.iter_mut().zip(&lp).zip(&self.to) {
                *delta = to - y;
            }
            self.space.move_into(&self.coords, amount, u);
        }
        self.lowpass = Some(lp);
    }

    fn advance(&mut self, dt_s: f32) {
        for g in &mut self.level {
            g.advance(dt_s);
        }
        self.amount.advance(dt_s);
        self.wet.advance(dt_s);
        for g in self.alpha.iter_mut().chain(self.gains.iter_mut()) {
            g.advance(dt_s);
        }
    }

    /// Forgets the low-pass history (a stream restarted).
    pub fn reset_lowpass(&mut self) {
        if let Some(lp) = self.lowpass.take() {
            self.lowpass_buf = lp;
        }
    }

    /// Copies every setting (goals, settled) of `other` into `self`, for a new stream or a
    /// reloaded model; components beyond the shorter of the two keep their identity values.
    pub fn copy_settings(&mut self, other: &EditState) {
        self.ramp_s = other.ramp_s;
        self.target.clear();
        self.target.push_str(&other.target);
        // The target point carries over to a space of the same shape; the amount to any
        // space (a new model's points differ, so the target is re-resolved by the caller).
        if self.dims > 0 && other.dims > 0 {
            self.amount = Glide::settled(other.amount.goal());
            if self.level.len() == other.level.len() {
                for (a, b) in self.level.iter_mut().zip(&other.level) {
                    *a = Glide::settled(b.goal());
                }
            }
        }
        self.wet = Glide::settled(other.wet.goal());
        for (a, b) in self.alpha.iter_mut().zip(&other.alpha) {
            *a = Glide::settled(b.goal());
        }
        for (a, b) in self.gains.iter_mut().zip(&other.gains) {
            *a = Glide::settled(b.goal());
        }
    }
}

#[cfg(test)]
mod tests;
