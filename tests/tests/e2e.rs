//! End-to-end tests of `emoshift serve` on loopback: one binary, one topic per file.

mod e2e {
    mod support;

    mod control;
    mod edit;
    mod faults;
    mod monitor;
    mod natnet;
    mod regression_30;
    mod shutdown;
    mod stage;
}
