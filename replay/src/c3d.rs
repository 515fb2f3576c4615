//! C3D takes. (Being written.)

use std::io::{Read, Write};

use crate::error::{ReadError, WriteError};
use crate::Take;

/// Reads a C3D take.
///
/// # Errors
/// Malformed or truncated content.
pub fn read(_input: impl Read) -> Result<Take, ReadError> {
    Err(ReadError::Malformed("c3d reader not written yet".into()))
}

/// Writes a C3D take.
///
/// # Errors
/// I/O failure or a take the format cannot hold.
pub fn write(_take: &Take, _out: &mut impl Write) -> Result<(), WriteError> {
    Err(WriteError::Unrepresentable("c3d writer not written yet".into()))
}
