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

#[test]
fn an_overwriting_spill_reads_the_old_records_and_keeps_its_own() {
    let mut old = Spill::new(8).expect("temp file");
    let values: Vec<f32> = (0..3_000 * 2).map(|i| i as f32).collect();
    let mut bytes = Vec::new();
    f32_bytes(&values, &mut bytes);
    old.push(&bytes).expect("writes");
    assert!(
        old.overwrite(12).is_err(),
        "longer records would overtake the reader"
    );
    let mut new = old.overwrite(4).expect("same file");
    // Each record's first value, written as soon as it is read, in chunks of 700.
    let mut seen = Vec::new();
    old.for_each_chunk(700, &mut |b| {
        let mut chunk = Vec::new();
        f32_values(b, &mut chunk);
        let firsts: Vec<f32> = chunk.chunks_exact(2).map(|p| p[0]).collect();
        seen.extend_from_slice(&chunk);
        let mut out = Vec::new();
        f32_bytes(&firsts, &mut out);
        new.push(&out)
    })
    .expect("reads and writes");
    assert_eq!(seen, values, "the reader saw the old records intact");
    assert!(old.push(&bytes[..8]).is_err(), "the old spill is read only");
    drop(old);
    new.trim().expect("trims");
    assert_eq!(
        new.file.get_ref().metadata().expect("meta").len(),
        3_000 * 4
    );
    let mut back = Vec::new();
    new.for_each_chunk(1_000, &mut |b| {
        let mut chunk = Vec::new();
        f32_values(b, &mut chunk);
        back.extend_from_slice(&chunk);
        Ok(())
    })
    .expect("reads");
    let want: Vec<f32> = values.chunks_exact(2).map(|p| p[0]).collect();
    assert_eq!(back, want);
    // And it appends after its own records.
    new.push(&bytes[..4]).expect("appends");
    assert_eq!(new.records(), 3_001);
}
