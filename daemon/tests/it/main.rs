//! The daemon's integration tests: one binary, one topic per module (the `emoshift` binary run as
//! a user runs it, the engine's allocation-free frame path, real and synthetic faces).
//!
//! One test binary per crate links the crate once instead of once per file (matklad, "Delete
//! Cargo Integration Tests"). The allocation tests share it: allocation-counter's global
//! allocator counts per thread, so the other tests running beside them do not count.

mod analysis_stream;
mod cli;
mod common;
mod edit_range;
mod emotion;
mod emotion_captures;
mod emotion_cli;
mod emotion_space;
mod emotion_variants;
mod issue_37;
mod natnet_alloc;
mod pipeline_alloc;
mod realdata;
mod repair_cli;
mod replay_cli;
mod safety;
mod streamed;
mod take_range;
mod train_stream;
mod transfer;
mod unseen_faces;
