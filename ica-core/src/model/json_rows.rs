//! A JSON layout for model files that stays readable and diffable: objects one key per line,
//! arrays of scalars (a matrix row, the mean, the labels) on one line, arrays of arrays one
//! element per line. serde_json's pretty printer puts every number of a 327 x 20 matrix on its
//! own line, which makes a model diff unreadable; a `Value` round trip would lose field order
//! (and change it whenever someone enables `preserve_order`), breaking the golden file.
//!
//! An array's layout is decided lazily by its first element: a scalar makes it inline, a
//! container makes it a block.

use serde_json::ser::{CharEscape, CompactFormatter, Formatter};
use std::io::{self, Write};

const INDENT: &[u8] = b"  ";

#[derive(Debug, Clone, Copy, PartialEq)]
enum Layout {
    Undecided,
    Inline,
    Block,
}

/// Streaming formatter for [`serde_json::Serializer::with_formatter`].
#[derive(Debug, Default)]
pub(crate) struct RowsFormatter {
    /// Layout of each open array; objects push `Block`.
    stack: Vec<Layout>,
    /// Set by `begin_array_value`: the next value's first token decides the separator.
    /// The bool says whether it is the array's first element.
    pending: Option<bool>,
}

impl RowsFormatter {
    fn newline_indent<W: ?Sized + Write>(&self, w: &mut W, depth: usize) -> io::Result<()> {
        w.write_all(b"\n")?;
        for _ in 0..depth {
            w.write_all(INDENT)?;
        }
        Ok(())
    }

    /// Writes the separator owed to a pending array element, now that we know whether the
    /// element is a scalar or a container.
    fn resolve<W: ?Sized + Write>(&mut self, w: &mut W, container: bool) -> io::Result<()> {
        let Some(first) = self.pending.take() else {
            return Ok(());
        };
        let depth = self.stack.len();
        let top = self
            .stack
            .last_mut()
            .expect("a pending element lives in an open array");
        if *top == Layout::Undecided {
            *top = if container {
                Layout::Block
            } else {
                Layout::Inline
            };
        }
        let layout = *top;
        if !first {
            w.write_all(b",")?;
        }
        match layout {
            Layout::Block => self.newline_indent(w, depth),
            _ if first => Ok(()),
            _ => w.write_all(b" "),
        }
    }
}

macro_rules! scalar {
    ($($name:ident: $ty:ty),* $(,)?) => {$(
        fn $name<W: ?Sized + Write>(&mut self, w: &mut W, value: $ty) -> io::Result<()> {
            self.resolve(w, false)?;
            CompactFormatter.$name(w, value)
        }
    )*};
}

impl Formatter for RowsFormatter {
    scalar!(
        write_bool: bool, write_i8: i8, write_i16: i16, write_i32: i32, write_i64: i64,
        write_i128: i128, write_u8: u8, write_u16: u16, write_u32: u32, write_u64: u64,
        write_u128: u128, write_f32: f32, write_f64: f64, write_number_str: &str,
        write_byte_array: &[u8], write_raw_fragment: &str,
    );

    fn write_null<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.resolve(w, false)?;
        w.write_all(b"null")
    }

    fn begin_string<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.resolve(w, false)?;
        w.write_all(b"\"")
    }

    fn write_char_escape<W: ?Sized + Write>(&mut self, w: &mut W, e: CharEscape) -> io::Result<()> {
        CompactFormatter.write_char_escape(w, e)
    }

    fn begin_array<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.resolve(w, true)?;
        self.stack.push(Layout::Undecided);
        w.write_all(b"[")
    }

    fn end_array<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        let layout = self
            .stack
            .pop()
            .expect("serde_json balances begin_array/end_array");
        if layout == Layout::Block {
            self.newline_indent(w, self.stack.len())?;
        }
        w.write_all(b"]")
    }

    fn begin_array_value<W: ?Sized + Write>(&mut self, _w: &mut W, first: bool) -> io::Result<()> {
        self.pending = Some(first);
        Ok(())
    }

    fn end_array_value<W: ?Sized + Write>(&mut self, _w: &mut W) -> io::Result<()> {
        Ok(())
    }

    fn begin_object<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.resolve(w, true)?;
        // Objects start undecided too so that an empty object prints as `{}`.
        self.stack.push(Layout::Undecided);
        w.write_all(b"{")
    }

    fn end_object<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        let layout = self
            .stack
            .pop()
            .expect("serde_json balances begin_object/end_object");
        if layout == Layout::Block {
            self.newline_indent(w, self.stack.len())?;
        }
        w.write_all(b"}")
    }

    fn begin_object_key<W: ?Sized + Write>(&mut self, w: &mut W, first: bool) -> io::Result<()> {
        let depth = self.stack.len();
        if let Some(top) = self.stack.last_mut() {
            *top = Layout::Block;
        }
        if !first {
            w.write_all(b",")?;
        }
        self.newline_indent(w, depth)
    }

    fn begin_object_value<W: ?Sized + Write>(&mut self, w: &mut W) -> io::Result<()> {
        w.write_all(b": ")
    }

    fn end_object_value<W: ?Sized + Write>(&mut self, _w: &mut W) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests;
