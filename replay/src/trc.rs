//! TRC takes. (Being written.)

use std::io::{Read, Write};

use crate::error::{ReadError, WriteError};
use crate::Take;

/// Reads a TRC take.
///
/// # Errors
/// Malformed or truncated content.
pub fn read(_input: impl Read) -> Result<Take, ReadError> {
    Err(ReadError::Malformed("trc reader not written yet".into()))
}

/// Writes a TRC take.
///
/// # Errors
/// I/O failure or a take the format cannot hold.
pub fn write(_take: &Take, _out: &mut impl Write) -> Result<(), WriteError> {
    Err(WriteError::Unrepresentable("trc writer not written yet".into()))
}
