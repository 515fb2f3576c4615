//! Where a frame number falls in a stream's order: the next frames, a duplicate, a late frame,
//! or a restarted source.

use super::Stream;

/// A backwards jump of more than this many frames is a restarted source (a looping replay, a
/// restarted capture), not a late frame: the stream starts over instead of dropping it.
pub const RESTART_FRAMES: i64 = 240;
/// Older frames in a row, each the one after the last, that are a restarted source counting
/// up again from a lower number (a capture restarted within [`RESTART_FRAMES`] of where it
/// stopped), not late frames: late frames come one at a time between newer ones.
pub const RESTART_RUN: u32 = 3;

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

impl Stream {
    /// Classifies `frame_number` against the last frame and, unless it is dropped, makes it
    /// the last frame. Counts duplicates and stale frames.
    pub fn check_order(&mut self, frame_number: i32) -> Order {
        let Some(last) = self.last_frame else {
            self.last_frame = Some(frame_number);
            self.frames += 1;
            return Order::Next { frames: 1 };
        };
        let delta = i64::from(frame_number) - i64::from(last);
        let mut order = match delta {
            0 => Order::Duplicate,
            d if d < -RESTART_FRAMES => Order::Restart,
            d if d < 0 => Order::Stale,
            d => Order::Next {
                frames: u32::try_from(d).unwrap_or(u32::MAX),
            },
        };
        if order == Order::Stale {
            let (run, prev) = self.stale_run;
            let run = if run > 0 && prev.checked_add(1) == Some(frame_number) {
                run + 1
            } else {
                1
            };
            self.stale_run = (run, frame_number);
            if run >= RESTART_RUN {
                order = Order::Restart;
            }
        }
        if order != Order::Stale {
            self.stale_run = (0, 0);
        }
        match order {
            Order::Duplicate => self.duplicates += 1,
            Order::Stale => self.stale += 1,
            Order::Restart => {
                if let Some(processor) = &mut self.processor {
                    processor.reset();
                }
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
