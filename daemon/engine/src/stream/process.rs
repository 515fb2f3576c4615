//! A frame's way through its stream ([`Stream::process`]): order check, markers into model
//! order, then the edit (projection, the live edit, resynthesis), or without a model the
//! frame as received.

use protocol::{FrameBuf, FrameHeader};

use super::{Order, Outcome, Stream};
use crate::Counters;

impl Stream {
    /// Takes one received frame through the stream into `output`: order check, markers into
    /// model order, projection (masked where markers are missing), the live edit, and (when
    /// `output` is `Some`: a sink reads the markers) resynthesis with the head pose put back.
    /// Without a model the frame goes to `output` as received. `None` when the frame is
    /// dropped (counted in `counters`).
    pub fn process(
        &mut self,
        header: &FrameHeader,
        input: &FrameBuf,
        output: Option<&mut FrameBuf>,
        counters: &mut Counters,
    ) -> Option<Outcome> {
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
        let done = match self.processor.is_some() {
            true => self.edit_frame(header, frames, output, counters),
            false => self.pass_frame(header, output),
        };
        if !done {
            counters.frame_errors += 1;
            return None;
        }
        let rate = self.rate_hz;
        let labels_due =
            self.frames_since_labels == 0 || f64::from(self.frames_since_labels) >= rate;
        self.frames_since_labels = if labels_due {
            1
        } else {
            self.frames_since_labels + 1
        };
        Some(Outcome {
            frames_since_last: frames,
            labels_due,
        })
    }

    /// Projection, the live edit and (into `output`, when given) resynthesis of the gathered
    /// frame, `frames` frame numbers after the last. `false` when the processor refused (an
    /// internal invariant).
    fn edit_frame(
        &mut self,
        header: &FrameHeader,
        frames: u32,
        output: Option<&mut FrameBuf>,
        counters: &mut Counters,
    ) -> bool {
        let Some(processor) = self.processor.as_mut() else {
            return false;
        };
        let Ok(prepared) = processor.project(&self.xyz, &self.missing, &mut self.u) else {
            return false;
        };
        counters.glitches += prepared.glitches as u64;
        let rate = self.rate_hz;
        // A gap of many frames moves the glides by at most a second.
        let dt = (f64::from(frames.min(rate.max(1.0) as u32)) / rate) as f32;
        self.u_in.copy_from_slice(&self.u);
        self.edit.apply(dt, &mut self.u);
        match output {
            Some(output) => {
                let (pose, held) = (prepared.pose.as_ref(), prepared.status.held);
                self.resynthesise(header, pose, held, output)
            }
            None => true,
        }
    }

    /// The gathered frame into `self.out` as received: seen markers as they are, missing ones
    /// as NaN.
    fn copy_as_received(&mut self) {
        for ((out, xyz), &gone) in self
            .out
            .chunks_exact_mut(3)
            .zip(self.xyz.chunks_exact(3))
            .zip(&self.missing)
        {
            if gone {
                out.fill(f32::NAN);
            } else {
                out.copy_from_slice(xyz);
            }
        }
    }

    /// Without a model: the gathered frame (the source's markers, in its order) as the
    /// output, missing markers missing. `false` when the frame refused it (an internal
    /// invariant).
    fn pass_frame(&mut self, header: &FrameHeader, output: Option<&mut FrameBuf>) -> bool {
        self.copy_as_received();
        output.is_none_or(|output| {
            output
                .set_frame(header.frame_number, header.capture_time_us, &self.out)
                .is_ok()
        })
    }

    /// The edited components back to markers, into `self.out` and `output`; a frame too
    /// occluded to estimate (`held`) goes out as received instead. `false` when the processor
    /// or the frame refused (an internal invariant).
    fn resynthesise(
        &mut self,
        header: &FrameHeader,
        pose: Option<&ica_core::stabilise::Pose>,
        held: bool,
        output: &mut FrameBuf,
    ) -> bool {
        let Some(processor) = self.processor.as_mut() else {
            return false;
        };
        let resynthesised = processor.resynthesise(pose, &self.u, &mut self.out);
        if held {
            // Too few markers to estimate the face: what was seen goes out as received, the
            // rest as missing, rather than the last estimate passed off as data.
            self.copy_as_received();
        }
        resynthesised.is_ok()
            && output
                .set_frame(header.frame_number, header.capture_time_us, &self.out)
                .is_ok()
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
}
