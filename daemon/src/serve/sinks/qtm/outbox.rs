//! One client's TCP output, never blocking: writes go straight to a non-blocking socket; what
//! the kernel does not take waits in a bounded buffer. A frame finds the buffer non-empty (the
//! client does not read fast enough): the frame is dropped and counted, the client stays. A
//! reply that would overflow the buffer ends the client (it stopped reading).

use std::io::{ErrorKind, Write};

/// The bytes a client may owe us before it is dropped.
pub const MAX_PENDING: usize = 256 * 1024;

/// Why a write did not go out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    /// The client is behind: a frame was dropped.
    Behind,
    /// The client is gone or stopped reading: close it.
    Dead,
}

/// A client's writer and the bytes it has not taken yet.
pub struct Outbox {
    writer: Box<dyn Write + Send>,
    pending: Vec<u8>,
    /// Once dead, always dead: the connection is beyond saving.
    dead: bool,
}

impl std::fmt::Debug for Outbox {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Outbox")
            .field("pending", &self.pending.len())
            .finish()
    }
}

impl Outbox {
    /// Over a non-blocking writer.
    pub fn new(writer: Box<dyn Write + Send>) -> Outbox {
        Outbox {
            writer,
            pending: Vec::new(),
            dead: false,
        }
    }

    /// Writes what is pending.
    ///
    /// # Errors
    /// [`Refused::Dead`] when the socket failed.
    pub fn flush(&mut self) -> Result<(), Refused> {
        let r = self.write_pending();
        self.dead |= r.is_err();
        r
    }

    fn write_pending(&mut self) -> Result<(), Refused> {
        if self.dead {
            return Err(Refused::Dead);
        }
        while !self.pending.is_empty() {
            match self.writer.write(&self.pending) {
                Ok(0) => return Err(Refused::Dead),
                Ok(n) => {
                    self.pending.drain(..n);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(()),
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return Err(Refused::Dead),
            }
        }
        Ok(())
    }

    /// A reply or event: always queued (within [`MAX_PENDING`]).
    ///
    /// # Errors
    /// [`Refused::Dead`] when the socket failed or the client owes too much.
    pub fn send_reply(&mut self, bytes: &[u8]) -> Result<(), Refused> {
        self.flush()?;
        if self.pending.len() + bytes.len() > MAX_PENDING {
            self.dead = true;
            return Err(Refused::Dead);
        }
        self.pending.extend_from_slice(bytes);
        self.flush()
    }

    /// A frame: dropped when the client is behind.
    ///
    /// # Errors
    /// [`Refused::Behind`] (dropped) or [`Refused::Dead`].
    pub fn send_frame(&mut self, bytes: &[u8]) -> Result<(), Refused> {
        self.flush()?;
        if !self.pending.is_empty() {
            return Err(Refused::Behind);
        }
        self.send_reply(bytes)
    }
}
