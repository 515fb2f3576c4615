//! The edited take, assembled frame by frame.

use anyhow::{bail, Result};
use replay::Take;

use engine::LabelMap;

/// The output take: the model's markers edited (gaps filled from the model unless
/// `keep_gaps`), followed by the take's extra markers unchanged, so nothing the user gave is
/// lost. Built frame by frame, by both the whole-take and the streaming edits.
pub(crate) struct Output<'a> {
    /// The frames assembled so far.
    pub(crate) take: Take,
    map: &'a LabelMap,
    xyz: Vec<f32>,
    missing: Vec<bool>,
}

impl<'a> Output<'a> {
    /// An output of no frames for a take with `take`'s rate, first frame and units.
    pub(crate) fn new(take: &Take, model_labels: &[String], map: &'a LabelMap) -> Self {
        let model_markers = map.model_to_take.len();
        let mut labels: Vec<String> = Vec::with_capacity(model_markers + map.extra.len());
        labels.extend_from_slice(model_labels);
        labels.extend(map.extra.iter().map(|&t| take.labels[t].clone()));
        let mut out = Take::new(labels, take.rate_hz, take.first_frame);
        out.source_units = take.source_units;
        let width = out.n_markers();
        Output {
            take: out,
            map,
            xyz: vec![0.0; width * 3],
            missing: vec![false; width],
        }
    }

    /// Whether frames carry markers of the take the model lacks, copied from it.
    pub(crate) fn copies_extra(&self) -> bool {
        !self.map.extra.is_empty()
    }

    /// Appends frame index `f` (counted from the take's first frame, for the error): the
    /// edited model markers and their input gaps, then the source frame's extra markers.
    ///
    /// # Errors
    /// A non-finite edited position.
    pub(crate) fn push_frame(
        &mut self,
        f: usize,
        (source, source_missing): (&[f32], &[bool]),
        (edited, model_missing): (&[f32], &[bool]),
        keep_gaps: bool,
    ) -> Result<()> {
        let model_markers = model_missing.len();
        self.xyz[..model_markers * 3].copy_from_slice(edited);
        for (gone, &was) in self.missing.iter_mut().zip(model_missing) {
            *gone = keep_gaps && was;
        }
        for (j, &t) in self.map.extra.iter().enumerate() {
            let slot = model_markers + j;
            self.xyz[slot * 3..slot * 3 + 3].copy_from_slice(&source[t * 3..t * 3 + 3]);
            self.missing[slot] = source_missing[t];
        }
        if !protocol::all_finite(&self.xyz) {
            bail!("frame {f}: the edit produced a non-finite position");
        }
        self.take.push_frame(&self.xyz, &self.missing);
        Ok(())
    }
}
