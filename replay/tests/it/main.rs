//! replay's integration tests: one binary, one topic per module.
//!
//! One test binary per crate links the crate once instead of once per file (matklad, "Delete
//! Cargo Integration Tests"). The allocation tests share it: allocation-counter's global
//! allocator counts per thread, so the other tests running beside them do not count.

mod blocks;
mod c3d;
mod c3d_samples;
mod pacer;
mod recorder;
mod repair;
mod synth;
mod synth_pins;
mod synth_space;
mod synth_variants;
mod text_formats;
