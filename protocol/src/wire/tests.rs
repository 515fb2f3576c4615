use super::*;

#[test]
fn string_padding_follows_osc_rules() {
    let mut out = Vec::new();
    put_str_unchecked(&mut out, "abc");
    assert_eq!(out, b"abc\0");
    out.clear();
    put_str_unchecked(&mut out, "abcd");
    assert_eq!(out, b"abcd\0\0\0\0");
    let mut r = Reader::new(&out);
    assert_eq!(r.str_bytes(), Ok(&b"abcd"[..]));
    assert_eq!(r.remaining(), 0);
}

#[test]
fn truncated_values_are_errors() {
    let mut r = Reader::new(b"ab");
    assert_eq!(r.i32(), Err(DecodeError::Truncated { offset: 0 }));
    let mut r = Reader::new(b"abcd");
    assert_eq!(r.str_bytes(), Err(DecodeError::Truncated { offset: 0 }));
    // a blob claiming 5 bytes needs 8 after its size
    let mut r = Reader::new(&[0, 0, 0, 5, 1, 2, 3, 4, 5]);
    assert_eq!(r.blob(), Err(DecodeError::Truncated { offset: 0 }));
    let mut r = Reader::new(&[0xff, 0xff, 0xff, 0xff]);
    assert_eq!(r.blob(), Err(DecodeError::Truncated { offset: 0 }));
}
