use super::*;
use crate::synth::columns::MAX_EMOTION_DIMS;

fn at(m: &[f64], layout: SourceLayout, marker: usize, source: usize) -> [f64; 3] {
    std::array::from_fn(|a| m[(marker * 3 + a) * layout.count() + source])
}

fn moved(m: &[f64], layout: SourceLayout, marker: usize, source: usize) -> f64 {
    let v = at(m, layout, marker, source);
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[test]
fn each_field_stays_in_its_regions() {
    let face = FaceGeometry::standard();
    let l = SourceLayout::default();
    let m = mixing_matrix(&face, false, l);
    let upper = [Region::Eyebrows, Region::Eyelids, Region::Forehead];
    for (i, mk) in face.markers.iter().enumerate() {
        for s in 0..l.speech_count() {
            if upper.contains(&mk.region) || mk.region == Region::HeadReference {
                assert_eq!(moved(&m, l, i, s), 0.0, "speech {s} moves {}", mk.label);
            }
        }
        if mk.region == Region::Mouth {
            assert!(moved(&m, l, i, 0) > 0.5 || mk.label.starts_with("UpperLip"));
            assert!(moved(&m, l, i, 1) > 1.0 && moved(&m, l, i, 2) > 1.0);
        }
        let lid = mk.region == Region::Eyelids;
        assert_eq!(
            moved(&m, l, i, l.blink()) > 0.0,
            lid,
            "blink on {}",
            mk.label
        );
        let brow = matches!(mk.region, Region::Eyebrows | Region::Forehead)
            || mk.label.starts_with("LidUpper");
        let raise = moved(&m, l, i, l.brow_raise()) > 0.0;
        assert_eq!(raise, brow, "brow on {}", mk.label);
        let face_part = matches!(
            mk.region,
            Region::Mouth | Region::Cheeks | Region::Eyebrows | Region::Eyelids
        );
        if face_part && !mk.label.starts_with("Cheek") {
            let e = moved(&m, l, i, l.emotion(0));
            assert!(e > 0.3, "emotion on {}", mk.label);
        }
        if mk.region == Region::HeadReference {
            assert_eq!(moved(&m, l, i, l.emotion(0)), 0.0);
        }
    }
}

#[test]
fn more_directions_insert_columns_and_keep_the_others() {
    let face = FaceGeometry::standard();
    for soft in [false, true] {
        let one = SourceLayout::default();
        let m1 = mixing_matrix(&face, soft, one);
        for k in 2..=MAX_EMOTION_DIMS {
            let l = SourceLayout::new(k).expect("in range");
            let m = mixing_matrix(&face, soft, l);
            let same = |a: usize, b: usize| {
                (0..face.markers.len()).all(|i| at(&m1, one, i, a) == at(&m, l, i, b))
            };
            for s in 0..=one.emotion(0) {
                assert!(same(s, s), "column {s}");
            }
            assert!(same(one.brow_raise(), l.brow_raise()));
            assert!(same(one.blink(), l.blink()));
            for h in 0..HEAD_COLUMNS {
                assert!(same(one.head() + h, l.head() + h));
            }
        }
    }
}

#[test]
fn anger_knits_and_presses_sadness_lifts_inner_brows_and_drops_corners() {
    let face = FaceGeometry::standard();
    let l = SourceLayout::new(3).expect("in range");
    let m = mixing_matrix(&face, false, l);
    let idx = |label: &str| {
        face.markers
            .iter()
            .position(|mk| mk.label == label)
            .expect("standard label")
    };
    let (knit, sad) = (l.emotion(1), l.emotion(2));
    let brow = at(&m, l, idx("BrowL1"), knit);
    assert!(brow[0] < -1.0 && brow[1] < -2.0, "inner brow {brow:?}");
    let upper = at(&m, l, idx("UpperLip4"), knit);
    let lower = at(&m, l, idx("LowerLip4"), knit);
    assert!(
        upper[1] < -1.0 && lower[1] > 1.0,
        "press {upper:?} {lower:?}"
    );
    assert!(at(&m, l, idx("NoseAlaL"), knit)[0] > 1.0, "flare");
    assert!(at(&m, l, idx("BrowR1"), sad)[1] > 2.5, "inner brow raise");
    assert!(at(&m, l, idx("BrowR6"), sad)[1] < 0.0, "outer brow sags");
    assert!(at(&m, l, idx("MouthCornerL"), sad)[1] < -2.5, "corner down");
    assert!(at(&m, l, idx("Chin"), sad)[1] > 1.0, "chin up");
    for d in 0..l.emotion_dims() {
        for (i, mk) in face.markers.iter().enumerate() {
            if mk.region == Region::HeadReference {
                assert_eq!(moved(&m, l, i, l.emotion(d)), 0.0);
            }
        }
        let regions = Region::ALL
            .iter()
            .filter(|r| {
                face.indices(**r)
                    .iter()
                    .any(|&i| moved(&m, l, i, l.emotion(d)) > 0.5)
            })
            .count();
        assert!(regions >= 4, "direction {d} moves {regions} regions");
    }
}
