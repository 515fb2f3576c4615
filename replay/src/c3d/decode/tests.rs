use super::c3dio_walk_ends;
use crate::c3d::binary::Processor;

/// A parameter section: the 4-byte header, then records of (name length, group id, name,
/// little-endian offset to the next record from the offset's own position, 3 filler bytes).
fn section(records: &[(u8, i8)]) -> Vec<u8> {
    let mut s = vec![0, 0, 1, 0x54];
    for &(len, group) in records {
        let name = usize::from((len as i8).unsigned_abs());
        s.push(len);
        s.push(group as u8);
        s.extend(std::iter::repeat_n(b'A', name));
        s.extend_from_slice(&5u16.to_le_bytes());
        s.extend_from_slice(&[0, 0, 0]);
    }
    s.resize(512, 0);
    s
}

#[test]
fn a_well_formed_section_is_walked_to_its_end() {
    let s = section(&[(5, -1), (6, 1), (0xFC, 1)]);
    assert_eq!(c3dio_walk_ends(&s, Processor::Intel), Ok(()));
}

#[test]
fn a_name_length_of_minus_128_on_the_walk_is_refused_before_c3dio_loops() {
    let s = section(&[(5, -1), (0x80, 1)]);
    let err = c3dio_walk_ends(&s, Processor::Intel).expect_err("refused");
    assert!(err.contains("-128"), "{err}");
    // The same byte where no record starts is not on the walk.
    let mut s = section(&[(5, -1), (6, 1)]);
    s[8] = 0x80;
    assert_eq!(c3dio_walk_ends(&s, Processor::Intel), Ok(()));
}
