use super::*;

fn msg(addr: &str, tags: &str, args: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    crate::wire::put_str_unchecked(&mut out, addr);
    crate::wire::put_str_unchecked(&mut out, tags);
    out.extend_from_slice(args);
    out
}

fn bundle(elements: &[Vec<u8>]) -> Vec<u8> {
    let mut out = Vec::new();
    crate::wire::put_bundle_header(&mut out);
    for e in elements {
        crate::wire::put_u32(&mut out, e.len() as u32);
        out.extend_from_slice(e);
    }
    out
}

#[test]
fn nested_bundles_flatten_in_order_with_inner_timetag() {
    let a = msg("/a", ",i", &7i32.to_be_bytes());
    let b = msg("/b", ",", &[]);
    let d = bundle(&[a.clone(), bundle(std::slice::from_ref(&b)), a.clone()]);
    let got: Vec<_> = messages(&d, &Limits::default())
        .expect("valid")
        .map(|m| (m.address, m.bytes.len(), m.timetag))
        .collect();
    let imm = Some(TimeTag::IMMEDIATE);
    assert_eq!(
        got,
        vec![
            ("/a", a.len(), imm),
            ("/b", b.len(), imm),
            ("/a", a.len(), imm)
        ]
    );
}

#[test]
fn deep_bundles_are_rejected_before_recursing() {
    let mut d = msg("/x", ",", &[]);
    for _ in 0..9 {
        d = bundle(&[d]);
    }
    assert_eq!(
        messages(&d, &Limits::default()).err(),
        Some(DecodeError::BundleTooDeep { max: 8 })
    );
    // 8 levels pass
    let mut d = msg("/x", ",", &[]);
    for _ in 0..8 {
        d = bundle(&[d]);
    }
    assert_eq!(
        messages(&d, &Limits::default()).expect("8 levels").count(),
        1
    );
}

#[test]
fn thousands_of_bundle_headers_do_not_overflow() {
    // the shape that aborts rosc 0.11 (stack overflow at 3,000 levels, 60 KB, on a 2 MiB
    // thread, measured): each bundle's one element claims the rest of the datagram
    let levels = 3000;
    let mut d = Vec::new();
    for level in 0..levels {
        d.extend_from_slice(b"#bundle\0\0\0\0\0\0\0\0\x01");
        let rest = (levels - level - 1) * 20 + 8;
        d.extend_from_slice(&(rest as u32).to_be_bytes());
    }
    d.extend_from_slice(&msg("/x", ",", &[]));
    assert_eq!(
        messages(&d, &Limits::default()).err(),
        Some(DecodeError::BundleTooDeep { max: 8 })
    );
}

#[test]
fn structural_errors_are_typed() {
    let l = Limits::default();
    let ok = msg("/a", ",i", &1i32.to_be_bytes());
    assert_eq!(check_datagram(&[], &l), Err(DecodeError::Empty));
    let mut trailing = ok.clone();
    trailing.extend_from_slice(&[0; 4]);
    assert_eq!(
        check_datagram(&trailing, &l),
        Err(DecodeError::TrailingBytes {
            offset: 12,
            extra: 4
        })
    );
    assert_eq!(
        check_datagram(&ok[..10], &l),
        Err(DecodeError::Truncated { offset: 8 })
    );
    let small = Limits {
        max_datagram: 8,
        ..l
    };
    assert_eq!(
        check_datagram(&ok, &small),
        Err(DecodeError::Oversize { len: 12, max: 8 })
    );
    let no_tags = msg("/a", "", &[]);
    assert!(matches!(
        check_datagram(&no_tags[..4], &l),
        Err(DecodeError::MissingTypeTags { .. })
    ));
    assert_eq!(
        check_datagram(&msg("/a", ",S", &[]), &l),
        Err(DecodeError::BadTypeTag {
            tag: b'S',
            offset: 5
        })
    );
    assert_eq!(
        check_datagram(&msg("a", ",", &[]), &l),
        Err(DecodeError::BadAddress { offset: 0 })
    );
    let deep = format!(",{}{}", "[".repeat(9), "]".repeat(9));
    assert_eq!(
        check_datagram(&msg("/a", &deep, &[]), &l),
        Err(DecodeError::ArrayTooDeep { max: 8 })
    );
    let mut bad_elem = bundle(std::slice::from_ref(&ok));
    bad_elem[16..20].copy_from_slice(&13u32.to_be_bytes());
    assert_eq!(
        check_datagram(&bad_elem, &l),
        Err(DecodeError::BadElementSize {
            size: 13,
            offset: 16
        })
    );
}
