//! The per-frame edit: the plan's edits applied to one frame's components after another.

use anyhow::Result;
use engine::edit_state::EditState;
use ica_core::edit::FrameEdit;

use super::Series;

/// Edits one frame's components after another: the state that crosses frames (the live
/// edit's low-pass) lives here, so a take edited in blocks gets the whole take's edit.
pub(crate) struct FrameEditor {
    pub(super) edit: FrameEdit,
    pub(super) live: Option<EditState>,
    pub(super) dt: f32,
    pub(super) replace: Series,
}

impl FrameEditor {
    /// Edits the components `u` of frame index `f` (counted from the take's first frame).
    ///
    /// # Errors
    /// A replaced value the edit refuses.
    pub(crate) fn apply(&mut self, f: usize, u: &mut [f32]) -> Result<()> {
        for (k, values) in &self.replace {
            self.edit.set_override(*k, Some(values[f] as f32))?;
        }
        self.edit.apply(u)?;
        if let Some(state) = self.live.as_mut() {
            state.apply(self.dt, u);
        }
        Ok(())
    }
}
