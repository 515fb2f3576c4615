use super::*;

#[test]
fn batches_cover_every_item_once() {
    assert_eq!(
        batches(&[5, 5, 5, 30, 1], 40),
        vec![0..2, 2..4, 4..5],
        "a quarter, a half, then the target"
    );
    assert_eq!(batches(&[5; 12], 20), vec![0..1, 1..3, 3..7, 7..11, 11..12]);
    assert_eq!(batches(&[], 10), Vec::<Range<usize>>::new());
    assert_eq!(batches(&[100], 10), vec![0..1]);
}
