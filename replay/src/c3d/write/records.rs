//! The parameter section's records, written one after the other: each record's offset to the
//! next is patched when the next one starts.

/// Builds group and parameter records; each record's "offset to next" is patched when the next
/// one starts, and the last stays 0, which ends the section.
#[derive(Default)]
pub(super) struct Records {
    pub(super) buf: Vec<u8>,
    /// Position of the previous record's offset word.
    pub(super) pending: Option<usize>,
}

impl Records {
    pub(super) fn start(&mut self, id: i8, name: &str) {
        let here = self.buf.len();
        if let Some(at) = self.pending {
            let offset = (here - at) as u16;
            self.buf[at..at + 2].copy_from_slice(&offset.to_le_bytes());
        }
        self.buf.push(name.len() as u8);
        self.buf.push(id as u8);
        self.buf.extend_from_slice(name.as_bytes());
        self.pending = Some(self.buf.len());
        self.buf.extend_from_slice(&[0, 0]);
    }

    pub(super) fn group(&mut self, id: i8, name: &str, description: &str) {
        self.start(-id, name);
        self.buf.push(description.len() as u8);
        self.buf.extend_from_slice(description.as_bytes());
    }

    pub(super) fn param(&mut self, group: i8, name: &str, ty: i8, dims: &[u8], data: &[u8]) {
        self.start(group, name);
        self.buf.push(ty as u8);
        self.buf.push(dims.len() as u8);
        self.buf.extend_from_slice(dims);
        self.buf.extend_from_slice(data);
        self.buf.push(0); // no description
    }

    pub(super) fn int(&mut self, group: i8, name: &str, values: &[u16]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.param(group, name, 2, &number_dims(values.len()), &data);
    }

    pub(super) fn float(&mut self, group: i8, name: &str, values: &[f32]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.param(group, name, 4, &number_dims(values.len()), &data);
    }

    /// A character array of `strings.len()` strings, blank-padded to the longest (at least 1:
    /// a zero dimension upsets some readers). Callers keep strings within 255 bytes.
    pub(super) fn chars(&mut self, group: i8, name: &str, strings: &[String]) {
        let width = strings.iter().map(String::len).max().unwrap_or(0).max(1);
        let mut data = Vec::with_capacity(width * strings.len());
        for s in strings {
            data.extend_from_slice(s.as_bytes());
            data.resize(data.len() + width - s.len(), b' ');
        }
        let dims = if strings.len() == 1 {
            vec![width as u8]
        } else {
            vec![width as u8, strings.len() as u8]
        };
        self.param(group, name, -1, &dims, &data);
    }

    pub(super) fn finish(self) -> Vec<u8> {
        self.buf
    }
}

/// Dimensions of a numeric parameter of `count` values: none for a scalar, else one
/// (callers write a few values at most).
fn number_dims(count: usize) -> Vec<u8> {
    if count == 1 {
        vec![]
    } else {
        vec![count as u8]
    }
}
