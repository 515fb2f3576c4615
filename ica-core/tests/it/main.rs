//! ica-core's integration tests: one binary, one topic per module.
//!
//! One test binary per crate links the crate once instead of once per file (matklad, "Delete
//! Cargo Integration Tests"). The allocation tests share it: allocation-counter's global
//! allocator counts per thread, so the other tests running beside them do not count.

mod alloc;
mod fit;
mod fit_whiten;
mod model_file;
mod moments;
mod project;
mod project_masked;
mod stream;
mod stream_alloc;
