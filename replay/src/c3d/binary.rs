//! Byte order and float encodings of the three C3D processor types, and the 512-byte header.

use crate::error::c3d::C3dError;

/// Bytes in one C3D block; headers, parameters and data all start on block boundaries.
pub const BLOCK: usize = 512;

/// The machine a C3D file was written on, which fixes its integer byte order and float format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Processor {
    /// Intel: little-endian integers, IEEE-754 little-endian floats (processor byte 84).
    Intel,
    /// DEC/VAX: little-endian integers, VAX-F floats (processor byte 85).
    Dec,
    /// MIPS/SGI: big-endian integers and IEEE-754 floats (processor byte 86).
    Mips,
}

impl Processor {
    /// The processor named by byte 4 of the parameter section (83 + type).
    pub fn from_byte(byte: u8) -> Option<Processor> {
        match byte {
            84 => Some(Processor::Intel),
            85 => Some(Processor::Dec),
            86 => Some(Processor::Mips),
            _ => None,
        }
    }

    /// Reads a 16-bit signed integer.
    pub fn i16(self, b: [u8; 2]) -> i16 {
        match self {
            Processor::Intel | Processor::Dec => i16::from_le_bytes(b),
            Processor::Mips => i16::from_be_bytes(b),
        }
    }

    /// Reads a 16-bit unsigned integer (counts and frame numbers are unsigned in practice).
    pub fn u16(self, b: [u8; 2]) -> u16 {
        self.i16(b) as u16
    }

    /// Reads a 32-bit float.
    pub fn f32(self, b: [u8; 4]) -> f32 {
        match self {
            Processor::Intel => f32::from_le_bytes(b),
            Processor::Mips => f32::from_be_bytes(b),
            // VAX-F: the 16-bit halves are swapped relative to IEEE little-endian and the exponent
            // bias is 2 larger, so after swapping the value is 4 times too big.
            Processor::Dec => f32::from_le_bytes([b[2], b[3], b[0], b[1]]) / 4.0,
        }
    }
}

impl Processor {
    /// Writes a 16-bit word (the bit pattern of `v`, signed or not) in this byte order.
    pub fn put_u16(self, v: u16) -> [u8; 2] {
        match self {
            Processor::Intel | Processor::Dec => v.to_le_bytes(),
            Processor::Mips => v.to_be_bytes(),
        }
    }

    /// Writes a 32-bit float in this format (the inverse of [`Processor::f32`]).
    pub fn put_f32(self, v: f32) -> [u8; 4] {
        match self {
            Processor::Intel => v.to_le_bytes(),
            Processor::Mips => v.to_be_bytes(),
            Processor::Dec => {
                let b = (v * 4.0).to_le_bytes();
                [b[2], b[3], b[0], b[1]]
            }
        }
    }
}

/// Reads two bytes at `at`, if present.
pub fn take2(bytes: &[u8], at: usize) -> Option<[u8; 2]> {
    bytes.get(at..at.checked_add(2)?)?.try_into().ok()
}

/// Reads four bytes at `at`, if present.
pub fn take4(bytes: &[u8], at: usize) -> Option<[u8; 4]> {
    bytes.get(at..at.checked_add(4)?)?.try_into().ok()
}

/// The fields of the 512-byte C3D header that locate and describe the 3D point data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// 1-based block number where the parameter section starts.
    pub parameter_block: usize,
    /// Number of 3D points per frame.
    pub points: u16,
    /// Analog samples per 3D frame, all channels together.
    pub analog_per_frame: u16,
    /// Analog samples per channel per 3D frame (word 10).
    pub analog_per_channel: u16,
    /// First frame number.
    pub first_frame: u16,
    /// Last frame number (65535 when the real value does not fit; see TRIAL:ACTUAL_END_FIELD).
    pub last_frame: u16,
    /// Point scale: negative means float32 storage, positive int16 scaled by this factor.
    pub scale: f32,
    /// 1-based block number where the 3D data starts.
    pub data_block: usize,
    /// 3D frame rate in Hz.
    pub rate_hz: f32,
}

/// The second header byte of every C3D file.
pub const SIGNATURE: u8 = 0x50;

/// Finds the processor and parses the header.
///
/// # Errors
/// A file shorter than a header, a wrong signature, a parameter section outside the file, or an
/// unknown processor byte.
pub fn parse_header(bytes: &[u8]) -> Result<(Processor, Header), C3dError> {
    if bytes.len() < BLOCK {
        return Err(C3dError::TooShort { len: bytes.len() });
    }
    if bytes[1] != SIGNATURE {
        return Err(C3dError::NotC3d { byte: bytes[1] });
    }
    let parameter_block = usize::from(bytes[0]);
    let blocks = bytes.len() / BLOCK;
    if parameter_block < 2 || parameter_block > blocks {
        return Err(C3dError::ParameterBlockOutside {
            block: parameter_block,
            blocks,
        });
    }
    let byte = bytes[(parameter_block - 1) * BLOCK + 3];
    let p = Processor::from_byte(byte).ok_or(C3dError::UnknownProcessor { byte })?;
    let w = |at: usize| p.u16([bytes[at], bytes[at + 1]]);
    let f = |at: usize| p.f32([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let header = Header {
        parameter_block,
        points: w(2),
        analog_per_frame: w(4),
        analog_per_channel: w(18),
        first_frame: w(6),
        last_frame: w(8),
        scale: f(12),
        data_block: usize::from(w(16)),
        rate_hz: f(20),
    };
    Ok((p, header))
}

#[cfg(test)]
mod tests;
