use nalgebra::DMatrix;

use super::*;

#[test]
fn f_tail_matches_known_values() {
    // Tables: F(1, 10) = 4.965 at p = 0.05; F(2, 20) = 5.849 at p = 0.01;
    // F(3, 30) = 7.054 at p = 0.001.
    for (f, d1, d2, p) in [
        (4.965, 1.0, 10.0, 0.05),
        (5.849, 2.0, 20.0, 0.01),
        (7.054, 3.0, 30.0, 0.001),
    ] {
        let got = f_upper_tail(f, d1, d2);
        assert!(
            (got - p).abs() < 2e-4 * p.max(1e-3) * 10.0,
            "F({d1},{d2}) = {f}: {got} vs {p}"
        );
    }
    assert_eq!(f_upper_tail(0.0, 2.0, 5.0), 1.0);
    assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
}

/// Residual sum of squares of the least-squares fit of `y` on the columns of `x`.
fn dense_rss(x: &DMatrix<f64>, y: &DVector<f64>) -> f64 {
    let xtx = x.transpose() * x;
    let beta = xtx
        .cholesky()
        .expect("full rank")
        .solve(&(x.transpose() * y));
    (y - x * beta).norm_squared()
}

#[test]
fn block_fits_match_dense_dummy_designs_on_an_unbalanced_session() {
    // 7 sentences x up to 3 emotions, some cells empty, some repeated.
    let (mut sentence, mut emotion) = (Vec::new(), Vec::new());
    for si in 0..7 {
        for ei in 0..3 {
            for _ in 0..(si + ei) % 3 {
                sentence.push(si);
                emotion.push(ei);
            }
        }
        sentence.extend([si, si]);
        emotion.extend([0, 1]);
    }
    let n = sentence.len();
    let y: Vec<f64> = (0..n)
        .map(|r| (r as f64 * 0.77).sin() + emotion[r] as f64 * 0.4 + sentence[r] as f64)
        .collect();
    let design = |sent: bool, emo: bool| {
        let (cs, ce) = (if sent { 6 } else { 0 }, if emo { 2 } else { 0 });
        DMatrix::from_fn(n, 1 + cs + ce, |r, c| match c {
            0 => 1.0,
            c if c <= cs => f64::from(u8::from(sentence[r] == c)),
            c => f64::from(u8::from(emotion[r] == c - cs)),
        })
    };
    let yv = DVector::from_column_slice(&y);
    let fits = Blocks::new(sentence.clone(), emotion.clone(), 7, 3)
        .fit(&y)
        .expect("not confounded");
    for (got, x) in [
        (fits.full, design(true, true)),
        (fits.sentences, design(true, false)),
        (fits.emotions, design(false, true)),
    ] {
        let want = dense_rss(&x, &yv);
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
    }
}

#[test]
fn emotion_shifts_are_found_and_sentence_content_is_not() {
    // 6 sentences x 3 emotions. Component 0: an emotion level; 1: sentence content only;
    // 2: small noise.
    let sentences = ["s1", "s2", "s3", "s4", "s5", "s6"];
    let emotions = ["neutral", "happy", "sad"];
    let level = |e: &str| match e {
        "happy" => 1.0,
        "sad" => -0.8,
        _ => 0.0,
    };
    let mut rows = Vec::new();
    for (i, s) in sentences.iter().enumerate() {
        for (j, e) in emotions.iter().enumerate() {
            let wiggle = ((i * 7 + j * 3) % 5) as f64 * 0.02 - 0.04;
            rows.push((
                *s,
                *e,
                vec![level(e) + wiggle, i as f64 * 0.7 + wiggle, wiggle],
            ));
        }
    }
    let takes: Vec<TakeMeans<'_>> = rows
        .iter()
        .map(|(s, e, v)| TakeMeans {
            sentence: s,
            emotion: e,
            means: v,
        })
        .collect();
    let effects = emotion_effects(&takes, 3);
    assert_eq!(emotion_subspace(&effects), vec![0], "{effects:?}");
    assert_eq!(effects[0].df_effect, 2);
    assert_eq!(effects[0].df_error, 18 - 6 - 3 + 1);
    assert!(effects[0].sentence_share < 0.2, "{effects:?}");
    assert!(effects[1].sentence_share > 0.95, "{effects:?}");
    // Unpaired takes carry no information.
    let lonely = [TakeMeans {
        sentence: "s1",
        emotion: "happy",
        means: &[1.0],
    }];
    assert_eq!(emotion_effects(&lonely, 1)[0].p, 1.0);
}
