use super::*;

fn labels(id: i32, names: &[&str]) -> Labels {
    Labels {
        layout_id: id,
        names: names.iter().map(|s| s.to_string()).collect(),
    }
}

#[test]
fn frames_bind_to_latest_labels_of_matching_size() {
    let mut book = LayoutBook::new(2);
    assert_eq!(
        book.handle_labels(&1, labels(7, &["a", "b"])),
        LayoutChange::Added
    );
    assert_eq!(
        book.handle_labels(&1, labels(8, &["a", "b", "c"])),
        LayoutChange::Added
    );
    assert_eq!(
        book.handle_labels(&1, labels(7, &["a", "b"])),
        LayoutChange::Unchanged
    );
    assert_eq!(book.layout_for(&1, 2).map(|l| l.layout_id), Some(7));
    assert_eq!(book.layout_for(&1, 3).map(|l| l.layout_id), Some(8));
    assert_eq!(
        book.handle_labels(&1, labels(9, &["x", "y"])),
        LayoutChange::Replaced
    );
    assert_eq!(book.layout_for(&1, 2).map(|l| l.layout_id), Some(9));
    assert_eq!(book.layout_for(&2, 2), None, "layouts are per source");
    assert_eq!(
        book.layout_for(&1, 4),
        None,
        "unknown size: drop until labels arrive"
    );
    book.handle_labels(&2, labels(1, &["a"]));
    assert_eq!(
        book.handle_labels(&3, labels(1, &["a"])),
        LayoutChange::Rejected
    );
    book.forget(&2);
    assert_eq!(
        book.handle_labels(&3, labels(1, &["a"])),
        LayoutChange::Added
    );
}

#[test]
fn a_source_keeps_a_bounded_number_of_layouts() {
    let mut book = LayoutBook::new(1);
    let names: Vec<String> = (0..20).map(|i| format!("m{i}")).collect();
    for n in 1..=20 {
        let l = Labels {
            layout_id: n as i32,
            names: names[..n].to_vec(),
        };
        book.handle_labels(&0, l);
    }
    assert_eq!(book.layout_for(&0, 1), None);
    assert!(book.layout_for(&0, 20).is_some());
    assert_eq!(book.sources[&0].len(), MAX_LAYOUTS_PER_SOURCE);
}

#[test]
fn bad_labels_are_typed_errors() {
    let mut out = Vec::new();
    encode_labels_into(&labels(3, &["a", "a"]), &mut out).expect("no nul");
    assert_eq!(
        decode_labels(&out),
        Err(DecodeError::DuplicateLabel { index: 2 })
    );
    encode_labels_into(&labels(3, &[""]), &mut out).expect("no nul");
    assert_eq!(
        decode_labels(&out),
        Err(DecodeError::OutOfRange { index: 1 })
    );
    encode_labels_into(&labels(3, &[]), &mut out).expect("no nul");
    assert_eq!(decode_labels(&out), Err(DecodeError::WrongTypeTags));
    assert_eq!(
        encode_labels_into(&labels(3, &["a\0"]), &mut out),
        Err(EncodeError::NulInString)
    );
    encode_labels_into(&labels(-4, &["lip", "brow"]), &mut out).expect("no nul");
    assert_eq!(decode_labels(&out), Ok(labels(-4, &["lip", "brow"])));
}
