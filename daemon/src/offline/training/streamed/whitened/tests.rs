use super::*;

/// Every frame back, in order and in the same chunks, whatever the hold.
#[test]
fn frames_come_back_in_the_same_chunks_held_or_spilled() {
    let m = 3;
    let values: Vec<f32> = (0..1_003 * m).map(|i| i as f32 * 0.25).collect();
    let read = |held_bytes: usize| {
        let mut store = Whitened::new(m, 100, held_bytes).expect("temp file");
        for piece in values.chunks(77 * m) {
            store.push(piece).expect("writes");
        }
        assert_eq!(store.frames(), 1_003);
        let mut chunks = Vec::new();
        for _ in 0..2 {
            chunks.clear();
            store
                .for_each_chunk(&mut |z| {
                    chunks.push(z.to_vec());
                    Ok(())
                })
                .expect("reads");
        }
        (chunks, store.held.len() / m)
    };
    let (all_spilled, none) = read(0);
    assert_eq!(none, 0);
    // 1,050 frames' worth of bytes: 1,000 frames held (whole chunks), the rest spilled.
    let (part_held, some) = read(4 * m * 1_050);
    assert_eq!(some, 1_000);
    let (all_held, all) = read(1 << 20);
    assert_eq!(all, 1_003);
    assert_eq!(all_spilled.len(), 11);
    assert_eq!(all_spilled.concat(), values);
    assert_eq!(part_held, all_spilled);
    assert_eq!(all_held, all_spilled);
}
