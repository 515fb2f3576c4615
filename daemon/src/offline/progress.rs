//! Progress of long offline work, as the library reports it: a step with a name, a unit and a
//! total when one is known, then advances. The commands draw it (a bar on a terminal, a line
//! every few seconds in a pipe: [`crate::commands::progress`]); the library never prints.

/// Where long offline work reports how far it got.
pub trait Progress: Send {
    /// A new step begins (the previous one ended): `total` units to go, if known.
    fn step(&mut self, name: &str, unit: &'static str, total: Option<u64>);
    /// `n` more units of the current step are done.
    fn advance(&mut self, n: u64);
    /// A short note about the current step (an iteration's change, a count found).
    fn note(&mut self, _text: &str) {}
    /// The work is over: clear whatever is drawn.
    fn finish(&mut self) {}
    /// The work failed: stop drawing without saying the step was done.
    fn abandon(&mut self) {}
}

/// Reports nothing (tests, library callers that do not draw).
#[derive(Debug, Default, Clone, Copy)]
pub struct Silent;

impl Progress for Silent {
    fn step(&mut self, _name: &str, _unit: &'static str, _total: Option<u64>) {}
    fn advance(&mut self, _n: u64) {}
}
