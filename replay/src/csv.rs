//! CSV takes. (Being written.)

use std::io::{Read, Write};

use crate::error::{ReadError, WriteError};
use crate::Take;

/// Reads a CSV take.
///
/// # Errors
/// Malformed or truncated content.
pub fn read(_input: impl Read) -> Result<Take, ReadError> {
    Err(ReadError::Malformed("csv reader not written yet".into()))
}

/// Writes a CSV take.
///
/// # Errors
/// I/O failure or a take the format cannot hold.
pub fn write(_take: &Take, _out: &mut impl Write) -> Result<(), WriteError> {
    Err(WriteError::Unrepresentable("csv writer not written yet".into()))
}
