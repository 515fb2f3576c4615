//! Per-frame types shared by projection and editing: the edit applied to a frame's components
//! ([`FrameEdit`]) and the errors of the frame calls ([`FrameError`], [`EditError`]). A leaf:
//! [`crate::project`] and [`crate::edit`] both read it.

/// A frame buffer of the wrong length. Small and `Copy`: returned per frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    /// A slice's length does not match the model.
    #[error("{what} has {got} values, the model needs {expected}")]
    Length {
        /// Which argument (`frame`, `components`, `output`, `missing mask`, `edit`).
        what: &'static str,
        /// Length the model needs.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A component index is outside the model.
    #[error("component {index} is out of range: the model has {components} components")]
    ComponentOutOfRange {
        /// The index.
        index: usize,
        /// Components in the model.
        components: usize,
    },
}

/// Why an edit could not be set up. Small and `Copy`, like [`FrameError`].
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EditError {
    /// A component index is outside the model.
    #[error("component {index} is out of range: the edit has {components} components")]
    ComponentOutOfRange {
        /// The index.
        index: usize,
        /// Components.
        components: usize,
    },
    /// An offset, gain or value is NaN or infinite.
    #[error("{what} for component {index} is not finite: {value}")]
    NonFinite {
        /// `offset`, `gain`, `override` or `value`.
        what: &'static str,
        /// Component.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A value series does not have one value per frame.
    #[error("value series has {got} values for a take of {expected} frames")]
    SeriesLength {
        /// Frames in the take.
        expected: usize,
        /// Values given.
        got: usize,
    },
}

/// A per-frame edit: `u'_k = override_k` if set, else `g_k u_k + offset_k`. Sized once for a
/// model's components; [`FrameEdit::apply`] does not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameEdit {
    offsets: Vec<f32>,
    gains: Vec<f32>,
    overrides: Vec<Option<f32>>,
}

impl FrameEdit {
    /// The identity edit for `components` components.
    pub fn identity(components: usize) -> FrameEdit {
        FrameEdit {
            offsets: vec![0.0; components],
            gains: vec![1.0; components],
            overrides: vec![None; components],
        }
    }

    /// Components this edit is sized for.
    pub fn components(&self) -> usize {
        self.offsets.len()
    }

    /// Whether the edit changes nothing.
    pub fn is_identity(&self) -> bool {
        self.offsets.iter().all(|&o| o == 0.0)
            && self.gains.iter().all(|&g| g == 1.0)
            && self.overrides.iter().all(Option::is_none)
    }

    /// Back to the identity, keeping the buffers.
    pub fn reset(&mut self) {
        self.offsets.fill(0.0);
        self.gains.fill(1.0);
        self.overrides.fill(None);
    }

    /// *Translate*: add `alpha` to component `k` (replaces a previous offset).
    ///
    /// # Errors
    /// [`EditError`] for a bad index or a non-finite value.
    pub fn set_offset(&mut self, k: usize, alpha: f32) -> Result<(), EditError> {
        self.check(k, "offset", alpha)?;
        self.offsets[k] = alpha;
        Ok(())
    }

    /// Multiply component `k` by `gain` (before the offset).
    ///
    /// # Errors
    /// [`EditError`] for a bad index or a non-finite value.
    pub fn set_gain(&mut self, k: usize, gain: f32) -> Result<(), EditError> {
        self.check(k, "gain", gain)?;
        self.gains[k] = gain;
        Ok(())
    }

    /// Force component `k` to `value` (per-frame *Copy and Replace*), or clear the override.
    ///
    /// # Errors
    /// [`EditError`] for a bad index or a non-finite value.
    pub fn set_override(&mut self, k: usize, value: Option<f32>) -> Result<(), EditError> {
        self.check(k, "override", value.unwrap_or(0.0))?;
        self.overrides[k] = value;
        Ok(())
    }

    /// Offset of component `k` (0 when out of range).
    pub fn offset(&self, k: usize) -> f32 {
        self.offsets.get(k).copied().unwrap_or(0.0)
    }

    /// Gain of component `k` (1 when out of range).
    pub fn gain(&self, k: usize) -> f32 {
        self.gains.get(k).copied().unwrap_or(1.0)
    }

    /// Applies the edit to one frame's components in place.
    ///
    /// # Errors
    /// [`FrameError::Length`] when `u` does not have [`FrameEdit::components`] values.
    pub fn apply(&self, u: &mut [f32]) -> Result<(), FrameError> {
        if u.len() != self.offsets.len() {
            return Err(FrameError::Length {
                what: "components",
                expected: self.offsets.len(),
                got: u.len(),
            });
        }
        self.apply_sized(u);
        Ok(())
    }

    /// [`FrameEdit::apply`] on `u` of the edit's length (shorter or longer: the common part).
    #[inline(always)]
    pub(crate) fn apply_sized(&self, u: &mut [f32]) {
        for ((ui, g), o) in u.iter_mut().zip(&self.gains).zip(&self.offsets) {
            *ui = *ui * g + o;
        }
        for (ui, ov) in u.iter_mut().zip(&self.overrides) {
            if let Some(v) = ov {
                *ui = *v;
            }
        }
    }

    fn check(&self, k: usize, what: &'static str, value: f32) -> Result<(), EditError> {
        if k >= self.offsets.len() {
            return Err(EditError::ComponentOutOfRange {
                index: k,
                components: self.offsets.len(),
            });
        }
        if !value.is_finite() {
            return Err(EditError::NonFinite {
                what,
                index: k,
                value: f64::from(value),
            });
        }
        Ok(())
    }
}
