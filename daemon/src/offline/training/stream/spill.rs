//! Spill files of streaming training: fixed-size records appended once and read back in
//! chunks as often as needed, in an anonymous temporary file (removed when dropped, even on a
//! crash), so memory holds one chunk whatever the session's length.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};

use anyhow::{Context, Result};

/// Records of `record_bytes` bytes in a temporary file.
#[derive(Debug)]
pub(super) struct Spill {
    file: BufWriter<File>,
    record_bytes: usize,
    records: usize,
    buffer: Vec<u8>,
}

impl Spill {
    /// An empty spill file of records of `record_bytes` bytes.
    ///
    /// # Errors
    /// The temporary file cannot be created.
    pub(super) fn new(record_bytes: usize) -> Result<Self> {
        let file = tempfile::tempfile().context("cannot create a temporary spill file")?;
        Ok(Self {
            file: BufWriter::with_capacity(1 << 20, file),
            record_bytes: record_bytes.max(1),
            records: 0,
            buffer: Vec::new(),
        })
    }

    /// Bytes per record.
    pub(super) fn record_bytes(&self) -> usize {
        self.record_bytes
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
        let file = self.file.get_mut();
        file.seek(SeekFrom::Start(0))
            .context("cannot read the spill file")?;
        let mut reader = BufReader::with_capacity(1 << 20, &*file);
        for (i, &n) in groups.iter().enumerate() {
            self.buffer.resize(n * self.record_bytes, 0);
            reader
                .read_exact(&mut self.buffer)
                .context("cannot read the spill file")?;
            each(i, &self.buffer)?;
        }
        drop(reader);
        file.seek(SeekFrom::End(0))
            .context("cannot write the spill file")?;
        Ok(())
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
mod tests {
    use super::*;

    #[test]
    fn records_come_back_in_chunks_as_often_as_asked() {
        let mut spill = Spill::new(8).expect("temp file");
        let values: Vec<f32> = (0..2_001 * 2).map(|i| i as f32 * 0.5).collect();
        let mut bytes = Vec::new();
        f32_bytes(&values, &mut bytes);
        spill.push(&bytes[..8 * 1_000]).expect("writes");
        spill.push(&bytes[8 * 1_000..]).expect("writes");
        assert_eq!(spill.records(), 2_001);
        for _ in 0..2 {
            let mut back = Vec::new();
            let mut chunk = Vec::new();
            spill
                .for_each_chunk(300, &mut |b| {
                    assert!(b.len() <= 300 * 8);
                    f32_values(b, &mut chunk);
                    back.extend_from_slice(&chunk);
                    Ok(())
                })
                .expect("reads");
            assert_eq!(back, values);
        }
    }
}
