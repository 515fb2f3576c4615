//! Spill files of streaming training: fixed-size records appended once and read back in
//! chunks as often as needed, in an anonymous temporary file (removed when dropped, even on a
//! crash), so memory holds one chunk whatever the session's length.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::os::unix::fs::FileExt;

use anyhow::{Context, Result};

/// Records of `record_bytes` bytes in a temporary file.
#[derive(Debug)]
pub(super) struct Spill {
    file: BufWriter<File>,
    record_bytes: usize,
    records: usize,
    buffer: Vec<u8>,
    /// Another spill writes over this one's file ([`Spill::overwrite`]): read only.
    overwritten: bool,
}

impl Spill {
    /// An empty spill file of records of `record_bytes` bytes.
    ///
    /// # Errors
    /// The temporary file cannot be created.
    pub(super) fn new(record_bytes: usize) -> Result<Self> {
        let file = tempfile::tempfile().context("cannot create a temporary spill file")?;
        Ok(Self::on(file, record_bytes))
    }

    /// An empty spill of records of `record_bytes` bytes writing at `file`'s offset.
    fn on(file: File, record_bytes: usize) -> Self {
        Self {
            file: BufWriter::with_capacity(1 << 20, file),
            record_bytes: record_bytes.max(1),
            records: 0,
            buffer: Vec::new(),
            overwritten: false,
        }
    }

    /// A new, empty spill of records of `record_bytes` bytes (at most this one's) that writes
    /// over this one's file from its start, for a pass that reads this spill once, in order,
    /// and writes record `k` only after reading record `k` of this one: the records it writes
    /// are never longer, so they never reach what is still unread. One file instead of two
    /// halves the temporary space and the page cache a long session dirties. This spill stays
    /// readable, and can no longer be written.
    ///
    /// # Errors
    /// Records longer than this spill's, or the file failing.
    pub(super) fn overwrite(&mut self, record_bytes: usize) -> Result<Self> {
        anyhow::ensure!(
            record_bytes <= self.record_bytes,
            "records of {record_bytes} bytes cannot overwrite records of {}",
            self.record_bytes
        );
        self.file.flush().context("cannot write the spill file")?;
        self.overwritten = true;
        // The handles share the file offset: this spill reads at positions and never writes.
        let mut file = self
            .file
            .get_ref()
            .try_clone()
            .context("cannot reopen the spill file")?;
        file.seek(SeekFrom::Start(0))
            .context("cannot write the spill file")?;
        Ok(Self::on(file, record_bytes))
    }

    /// Cuts the file after the last record written (what an overwritten spill left behind).
    ///
    /// # Errors
    /// The file failing.
    pub(super) fn trim(&mut self) -> Result<()> {
        self.file.flush().context("cannot write the spill file")?;
        let end = (self.records * self.record_bytes) as u64;
        self.file
            .get_ref()
            .set_len(end)
            .context("cannot trim the spill file")
    }

    /// Records written.
    pub(super) fn records(&self) -> usize {
        self.records
    }

    /// Appends whole records.
    ///
    /// # Errors
    /// Writing fails (a full disk).
    pub(super) fn push(&mut self, bytes: &[u8]) -> Result<()> {
        debug_assert_eq!(bytes.len() % self.record_bytes, 0);
        anyhow::ensure!(
            !self.overwritten,
            "a spill another one overwrites cannot grow"
        );
        self.file
            .write_all(bytes)
            .context("cannot write the spill file")?;
        self.records += bytes.len() / self.record_bytes;
        Ok(())
    }

    /// Reads every record back in order, in groups of `groups[i]` records (which must add up
    /// to the records written).
    ///
    /// # Errors
    /// Reading fails, or `each` does.
    pub(super) fn for_each_group(
        &mut self,
        groups: &[usize],
        each: &mut dyn FnMut(usize, &[u8]) -> Result<()>,
    ) -> Result<()> {
        debug_assert_eq!(groups.iter().sum::<usize>(), self.records);
        self.file.flush().context("cannot write the spill file")?;
        // Reads at positions: the file offset stays where the next record is appended (or
        // where a spill overwriting this one writes).
        let mut at = 0u64;
        for (i, &n) in groups.iter().enumerate() {
            self.buffer.resize(n * self.record_bytes, 0);
            self.file
                .get_ref()
                .read_exact_at(&mut self.buffer, at)
                .context("cannot read the spill file")?;
            at += self.buffer.len() as u64;
            each(i, &self.buffer)?;
        }
        Ok(())
    }

    /// Reads records `first..` into `out` (a whole number of records).
    ///
    /// # Errors
    /// Reading fails, or `out` reaches past the last record.
    pub(super) fn read_at(&mut self, first: usize, out: &mut [u8]) -> Result<()> {
        debug_assert_eq!(out.len() % self.record_bytes, 0);
        anyhow::ensure!(
            first * self.record_bytes + out.len() <= self.records * self.record_bytes,
            "a read past the spill file's last record"
        );
        self.file.flush().context("cannot write the spill file")?;
        self.file
            .get_ref()
            .read_exact_at(out, (first * self.record_bytes) as u64)
            .context("cannot read the spill file")
    }

    /// Reads every record back in order, `chunk_records` at a time.
    ///
    /// # Errors
    /// Reading fails, or `each` does.
    pub(super) fn for_each_chunk(
        &mut self,
        chunk_records: usize,
        each: &mut dyn FnMut(&[u8]) -> Result<()>,
    ) -> Result<()> {
        let chunk = chunk_records.max(1);
        let mut groups = vec![chunk; self.records / chunk];
        if self.records % chunk > 0 {
            groups.push(self.records % chunk);
        }
        self.for_each_group(&groups, &mut |_, bytes| each(bytes))
    }
}

/// Appends `values` as little-endian bytes.
pub(super) fn f32_bytes(values: &[f32], out: &mut Vec<u8>) {
    out.extend(values.iter().flat_map(|v| v.to_le_bytes()));
}

/// Reads little-endian `f32`s back.
pub(super) fn f32_values(bytes: &[u8], out: &mut Vec<f32>) {
    out.clear();
    out.extend(
        bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    );
}

#[cfg(test)]
mod tests;
