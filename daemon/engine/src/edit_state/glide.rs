//! One setting gliding from where it is to its new value over the ramp, on a smoothstep curve.

/// One value gliding towards a goal on a smoothstep curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Glide {
    from: f32,
    to: f32,
    elapsed_s: f32,
    duration_s: f32,
}

impl Glide {
    /// A settled value.
    pub fn settled(value: f32) -> Glide {
        Glide {
            from: value,
            to: value,
            elapsed_s: 0.0,
            duration_s: 0.0,
        }
    }

    /// The current value.
    pub fn value(&self) -> f32 {
        // A hair of slack so that n frames of dt reach an n·dt ramp despite f32 rounding.
        if self.elapsed_s >= self.duration_s * (1.0 - 1e-5) {
            return self.to;
        }
        let t = self.elapsed_s / self.duration_s;
        self.from + (self.to - self.from) * (t * t * (3.0 - 2.0 * t))
    }

    /// The goal.
    pub fn goal(&self) -> f32 {
        self.to
    }

    /// Starts gliding from the current value to `to` over `duration_s` (0 = at once).
    pub fn set(&mut self, to: f32, duration_s: f32) {
        self.from = self.value();
        self.to = to;
        self.elapsed_s = 0.0;
        self.duration_s = duration_s.max(0.0);
    }

    /// Advances the glide by `dt_s`.
    pub fn advance(&mut self, dt_s: f32) {
        if self.elapsed_s < self.duration_s {
            self.elapsed_s += dt_s;
        }
    }

    /// The glide has reached its goal.
    pub fn is_settled(&self) -> bool {
        self.elapsed_s >= self.duration_s
    }
}
