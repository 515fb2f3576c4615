//! Renders a synthetic take and its counterfactual: the same sentence at the same timing in
//! another emotion (the truth an emotion edit is measured against).
//!
//! `cargo run -p replay --example counterfactual -- SEED SENTENCES EMOTIONS DIMS SENTENCE FROM TO OUT_FROM OUT_TO`
//! e.g. `... 3 8 neutral,happy 1 0 neutral happy a.c3d b.c3d`

use replay::synth::{Synth, SynthParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() != 9 {
        return Err("usage: SEED SENTENCES EMOTIONS DIMS SENTENCE FROM TO OUT_FROM OUT_TO".into());
    }
    let synth = Synth::new(SynthParams {
        seed: a[0].parse()?,
        sentences: a[1].parse()?,
        emotions: a[2].split(',').map(str::to_string).collect(),
        emotion_dims: a[3].parse()?,
        ..SynthParams::default()
    })?;
    let sentence: usize = a[4].parse()?;
    let from = synth.take_spec(sentence, &a[5])?;
    let to = synth.take_spec(sentence, &a[6])?.with_timing_of(&from);
    replay::save(std::path::Path::new(&a[7]), &synth.render_take(&from)?.take)?;
    replay::save(std::path::Path::new(&a[8]), &synth.render_take(&to)?.take)?;
    Ok(())
}
