//! protocol's integration tests: one binary, one topic per module (property tests against rosc,
//! NatNet captures and versions, the allocation-free frame path).
//!
//! One test binary per crate links the crate once instead of once per file (matklad, "Delete
//! Cargo Integration Tests"). The allocation tests share it: allocation-counter's global
//! allocator counts per thread, so the other tests running beside them do not count.

mod alloc;
mod control;
mod docs_osc;
mod frames;
mod natnet_alloc;
mod natnet_capture;
mod natnet_client;
mod natnet_fixtures;
mod natnet_props;
mod natnet_versions;
mod props;
