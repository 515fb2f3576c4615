use super::*;

#[test]
fn count_is_bounded_by_remaining_bytes() {
    let mut buf = Vec::new();
    put_i32(&mut buf, i32::MAX);
    buf.extend_from_slice(&[0; 12]);
    let mut r = Reader::at(&buf, 0);
    assert!(matches!(r.count(12), Err(NatNetError::BadCount { .. })));
    let mut r = Reader::at(&[0xff, 0xff, 0xff, 0xff], 0);
    assert_eq!(
        r.count(1),
        Err(NatNetError::BadCount {
            count: -1,
            offset: 0
        })
    );
}

#[test]
fn strings() {
    let mut r = Reader::at(b"ab\0cd", 0);
    assert_eq!(r.cstr(), Ok("ab"));
    assert_eq!(r.cstr(), Err(NatNetError::BadString { offset: 3 }));
    let mut r = Reader::at(b"Motive\0ib\xae\x14", 0);
    assert_eq!(r.fixed_str(11), Ok("Motive"));
    let mut out = Vec::new();
    assert_eq!(
        put_fixed_str(&mut out, "abcd", 4),
        Err(NatNetEncodeError::StringTooLong { len: 4, max: 4 })
    );
}
