//! The checks a take passes the moment it is stopped ([`check`]): its length against the
//! sentence's range, the markers seen, no label change mid-take, not a copy of the previous
//! take. A refusal ([`Refusal`]) says why and what to do.

use replay::Take;

/// Share of the model markers' samples a take must hold by default.
pub const DEFAULT_MIN_SEEN: f64 = 0.9;
/// Largest difference, mm, at which two takes count as the same recording.
const COPY_TOLERANCE_MM: f32 = 1e-3;

/// What a take is checked against.
#[derive(Debug, Clone)]
pub struct Expect<'a> {
    /// Accepted length, seconds `(shortest, longest)`.
    pub seconds: (f64, f64),
    /// The markers the model will be trained on: the first accepted take's labels (`None`
    /// for the first take: its own).
    pub markers: Option<&'a [String]>,
    /// Share of those markers' samples the take must hold, 0 to 1.
    pub min_seen: f64,
}

/// Why a take was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// No frame of the stream came.
    #[error("no frames arrived: is the source sending? Then retake")]
    Empty,
    /// Shorter than the sentence's range.
    #[error("the take is {seconds:.1} s, shorter than the {shortest:.1} s this sentence needs: retake, saying the whole sentence")]
    TooShort {
        /// Its length.
        seconds: f64,
        /// The range's start.
        shortest: f64,
    },
    /// Longer than the sentence's range.
    #[error("the take is {seconds:.1} s, longer than the {longest:.1} s this sentence takes: retake, stopping after the sentence")]
    TooLong {
        /// Its length.
        seconds: f64,
        /// The range's end.
        longest: f64,
    },
    /// Too few marker samples seen.
    #[error("only {seen:.0} % of the model markers' samples were seen (at least {min:.0} % needed); {missing} markers were never seen: check the cameras' view of the face and that every marker is on, then retake")]
    MarkersMissing {
        /// Percent seen.
        seen: f64,
        /// Percent needed.
        min: f64,
        /// Model markers never seen in the take.
        missing: usize,
    },
    /// The stream's labels changed while recording.
    #[error("the marker labels changed during the take ({frames} frames came with other labels and are not in it): keep the capture system's labelling fixed, then retake")]
    LabelsChanged {
        /// Frames with other labels.
        frames: u64,
    },
    /// The same frames as the previous take.
    #[error("the take is a copy of the previous one ({frames} identical frames): is the source replaying? Then retake")]
    Copy {
        /// Frames compared.
        frames: usize,
    },
}

/// Checks `take` (`relabelled`: its stream's frames that came with other labels, as the
/// capture counted them) against `expect` and the
/// previous accepted take.
///
/// # Errors
/// The first check it fails.
pub fn check(
    take: &Take,
    relabelled: u64,
    expect: &Expect<'_>,
    previous: Option<&Take>,
) -> Result<(), Refusal> {
    let frames = take.n_frames();
    if frames == 0 {
        return Err(Refusal::Empty);
    }
    if relabelled > 0 {
        return Err(Refusal::LabelsChanged { frames: relabelled });
    }
    let seconds = frames as f64 / take.rate_hz;
    let (shortest, longest) = expect.seconds;
    if seconds < shortest {
        return Err(Refusal::TooShort { seconds, shortest });
    }
    if seconds > longest {
        return Err(Refusal::TooLong { seconds, longest });
    }
    seen(take, expect)?;
    if previous.is_some_and(|p| is_copy(take, p)) {
        return Err(Refusal::Copy { frames });
    }
    Ok(())
}

/// At least `min_seen` of the model markers' samples present (a model marker the take lacks
/// counts as never seen).
fn seen(take: &Take, expect: &Expect<'_>) -> Result<(), Refusal> {
    let markers = expect.markers.unwrap_or(&take.labels);
    let frames = take.n_frames();
    let (mut present, mut never) = (0usize, 0usize);
    for name in markers {
        let count = match take.labels.iter().position(|l| l == name) {
            Some(m) => (0..frames).filter(|&f| !take.is_missing(f, m)).count(),
            None => 0,
        };
        present += count;
        never += usize::from(count == 0);
    }
    let share = present as f64 / (markers.len().max(1) * frames) as f64;
    if share + 1e-12 < expect.min_seen {
        return Err(Refusal::MarkersMissing {
            seen: 100.0 * share,
            min: 100.0 * expect.min_seen,
            missing: never,
        });
    }
    Ok(())
}

/// The same labels, frame count and samples as `previous`.
fn is_copy(take: &Take, previous: &Take) -> bool {
    take.labels == previous.labels
        && take.n_frames() == previous.n_frames()
        && take.missing == previous.missing
        && take
            .positions
            .iter()
            .zip(&previous.positions)
            .all(|(a, b)| (a - b).abs() <= COPY_TOLERANCE_MM || (a.is_nan() && b.is_nan()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn take(frames: usize, markers: usize, shift: f32) -> Take {
        let labels = (0..markers).map(|m| format!("m{m}")).collect();
        let mut t = Take::new(labels, 100.0, 1);
        t.positions = (0..frames * markers * 3)
            .map(|i| i as f32 * 0.01 + shift)
            .collect();
        t.missing = vec![false; frames * markers];
        t
    }

    fn expect() -> Expect<'static> {
        Expect {
            seconds: (1.0, 10.0),
            markers: None,
            min_seen: DEFAULT_MIN_SEEN,
        }
    }

    #[test]
    fn each_check_refuses_what_it_should_and_a_good_take_passes() {
        let good = take(300, 10, 0.0);
        assert_eq!(check(&good, 0, &expect(), None), Ok(()));
        assert!(matches!(
            check(&take(50, 10, 0.0), 0, &expect(), None),
            Err(Refusal::TooShort { .. })
        ));
        assert!(matches!(
            check(&take(1_100, 10, 0.0), 0, &expect(), None),
            Err(Refusal::TooLong { .. })
        ));
        assert!(matches!(
            check(&good, 2, &expect(), None),
            Err(Refusal::LabelsChanged { frames: 2 })
        ));
        assert_eq!(
            check(&good, 0, &expect(), Some(&good)),
            Err(Refusal::Copy { frames: 300 })
        );
        assert_eq!(
            check(&good, 0, &expect(), Some(&take(300, 10, 1.0))),
            Ok(())
        );
        let mut gappy = good.clone();
        for f in 0..300 {
            for m in 0..2 {
                gappy.missing[f * 10 + m] = true;
            }
        }
        let refused = check(&gappy, 0, &expect(), None);
        assert!(
            matches!(refused, Err(Refusal::MarkersMissing { missing: 2, .. })),
            "{refused:?}"
        );
        // A model marker the take does not have counts as never seen.
        let model: Vec<String> = (0..12).map(|m| format!("m{m}")).collect();
        let e = Expect {
            markers: Some(&model),
            ..expect()
        };
        assert!(matches!(
            check(&good, 0, &e, None),
            Err(Refusal::MarkersMissing { missing: 2, .. })
        ));
        let e = Expect {
            markers: Some(&model),
            min_seen: 0.8,
            ..expect()
        };
        assert_eq!(check(&good, 0, &e, None), Ok(()));
    }
}
