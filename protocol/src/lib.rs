//! protocol
#![warn(missing_docs)]
