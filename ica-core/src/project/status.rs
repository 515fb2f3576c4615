//! What happened to one frame's projection.

/// What happened to one frame's projection.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrameStatus {
    /// Some markers were missing (masked or non-finite) and were solved around.
    pub masked: bool,
    /// Markers missing in this frame.
    pub missing_markers: usize,
    /// The observed markers barely determine some component (observability below
    /// [`MIN_OBSERVABILITY`](super::MIN_OBSERVABILITY)): the solve was regularised toward the last good components.
    pub ill_conditioned: bool,
    /// Fewer observed channels than components: `u` was held at the last good value (or 0,
    /// the mean pose, before any).
    pub held: bool,
    /// Smallest share of a component's footprint still observed, in `[0, 1]`: 1 for a full
    /// frame, 0 for a held one.
    pub observability: f32,
}
