//! What training takes in: frames with their missing mask ([`FitData`]), and everything that
//! makes a fit refuse them ([`FitError`]). A leaf of the crate: whitening, FastICA and the fit
//! all read it, none of them is read by it.

mod data;
mod error;
mod pass;

pub use data::FitData;
pub use error::FitError;
pub use pass::Pass;
