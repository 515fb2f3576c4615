//! End-to-end tests of `emoshift serve` on loopback: one binary, one topic per module.

mod control;
mod crash;
mod demo;
mod edit;
mod faults;
mod issue_37;
mod monitor;
mod natnet;
mod no_model;
mod regression_30;
mod session;
mod shutdown;
mod stage;
mod support;
