//! An in-process emoshift for the demo, `emoshift bench` and the end-to-end tests: synthetic
//! models and frames ([`synthetic`]).

pub mod synthetic;
