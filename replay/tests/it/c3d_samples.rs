//! Every C3D file under `../shared/data/c3d-samples` (present on developer machines and in CI)
//! loads with the marker count, frame range and rate that the folder's verified SOURCE.txt table
//! gives, or fails with one clear line; none panics.

use std::path::{Path, PathBuf};

/// (file, markers, first frame, last frame, rate Hz rounded to 0.01 as the table prints it), from
/// SOURCE.txt. sample_08's files hold
/// Eb015pi's data with moved blocks.
const TABLE: &[(&str, usize, i64, i64, f64)] = &[
    ("sample_01/Eb015pi.c3d", 26, 1, 450, 50.0),
    ("sample_01/Eb015pr.c3d", 26, 1, 450, 50.0),
    ("sample_01/Eb015vi.c3d", 26, 1, 450, 50.0),
    ("sample_01/Eb015vr.c3d", 26, 1, 450, 50.0),
    ("sample_01/Eb015si.c3d", 26, 1, 450, 50.0),
    ("sample_01/Eb015sr.c3d", 26, 1, 450, 50.0),
    ("sample_02/pc_int.c3d", 36, 1, 89, 50.0),
    ("sample_02/pc_real.c3d", 36, 1, 89, 50.0),
    ("sample_02/dec_int.c3d", 36, 1, 89, 50.0),
    ("sample_02/dec_real.c3d", 36, 1, 89, 50.0),
    ("sample_02/sgi_int.c3d", 36, 1, 89, 50.0),
    ("sample_02/sgi_real.c3d", 36, 1, 89, 50.0),
    ("sample_08/TESTBPI.c3d", 26, 1, 450, 50.0),
    ("sample_08/TESTCPI.c3d", 26, 1, 450, 50.0),
    ("sample_08/TESTDPI.c3d", 26, 1, 450, 50.0),
    ("sample_03/gait-raw.c3d", 27, 1, 142, 50.0),
    ("sample_03/gait-pig-nz.c3d", 85, 300, 600, 120.0),
    (
        "sample_00/Vicon Motion Systems/pyCGM2 lower limb CGM24 Walking01.c3d",
        171,
        63,
        555,
        100.0,
    ),
    ("sample_13/Dance.c3d", 40, 1, 499, 65.05),
    ("sample_20/phasespace_sample.c3d", 40, 1, 701, 30.0),
    ("sample_29/Facial-Sing.c3d", 38, 1, 3000, 100.0),
];

fn samples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/c3d-samples")
}

/// Every C3D file under `dir`, sorted; `None` when the folder is absent, which fails in CI.
fn sample_files(dir: &Path) -> Option<Vec<PathBuf>> {
    if !dir.is_dir() {
        assert!(
            std::env::var_os("CI").is_none(),
            "{} absent in CI: put ../shared beside the checkout",
            dir.display()
        );
        eprintln!("{} absent: nothing to walk", dir.display());
        return None;
    }
    let mut files = Vec::new();
    walk(dir, &mut files);
    files.sort();
    assert!(files.len() >= TABLE.len(), "found {} files", files.len());
    Some(files)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            walk(&path, out);
        } else if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("c3d"))
        {
            out.push(path);
        }
    }
}

#[test]
fn every_sample_file_matches_the_verified_table_or_fails_cleanly() {
    let dir = samples_dir();
    let Some(files) = sample_files(&dir) else {
        return;
    };
    let mut problems = Vec::new();
    for path in &files {
        let rel = path.strip_prefix(&dir).expect("walked under dir");
        let rel = rel.to_string_lossy().replace('\\', "/");
        let result = std::panic::catch_unwind(|| replay::load(path));
        let Ok(result) = result else {
            problems.push(format!("{rel}: panicked"));
            continue;
        };
        let expected = TABLE.iter().find(|row| row.0 == rel);
        match (result, expected) {
            (Ok(take), Some(&(_, markers, first, last, rate))) => {
                let got_last = take.first_frame + take.n_frames() as i64 - 1;
                let got = (take.n_markers(), take.first_frame, got_last);
                if got != (markers, first, last) || (take.rate_hz - rate).abs() > 0.005 {
                    problems.push(format!(
                        "{rel}: {got:?} at {} Hz, expected {:?} at {rate} Hz",
                        take.rate_hz,
                        (markers, first, last)
                    ));
                }
            }
            (Ok(_), None) => problems.push(format!("{rel}: not in the table")),
            // A file the table does not list may fail, with one clear line.
            (Err(e), None) if !e.to_string().is_empty() && !e.to_string().contains('\n') => {}
            (Err(e), _) => problems.push(format!("{rel}: {e}")),
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The reader decodes every frame with emoshift's own decoder and asks c3dio about a sample of
/// frames only; on every sample file c3dio reads whole on its own, the two agree on every frame
/// (every sample the take holds, in file units), so the sample does not hide a disagreement. And
/// the take without the cross-check (what training reads) is the same take.
#[test]
fn c3dio_agrees_with_the_own_decoder_on_every_frame_of_every_sample() {
    let dir = samples_dir();
    let Some(files) = sample_files(&dir) else {
        return;
    };
    let limit = replay::file::DEFAULT_MAX_TAKE_BYTES;
    let (mut compared, mut whole) = (0, 0);
    for path in &files {
        let Ok(take) = replay::load(path) else {
            continue;
        };
        let own = replay::load_with(path, limit, replay::C3dDecoding::Own)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        // Positions are finite (missing samples are stored as 0.0), so equality is exact.
        assert!(own == take, "{}: the takes differ", path.display());
        compared += 1;
        // c3dio alone reads files with their parameters at block 2 (not sample_08's).
        let whole_file = std::panic::catch_unwind(|| c3dio::C3d::load_path(path.clone()).ok());
        let Ok(Some(c)) = whole_file else {
            continue;
        };
        let (n, frames) = (take.n_markers(), take.n_frames());
        if c.points.cols() != n || c.points.rows() != frames {
            continue;
        }
        let to_mm = take.source_units.to_mm();
        for f in 0..frames {
            for m in 0..n {
                let Some(ours) = take.sample(f, m) else {
                    continue;
                };
                for (a, b) in c.points[f][m].point.iter().zip(ours) {
                    let a = a * to_mm;
                    assert!(
                        (a - b).abs() <= 1e-4 * b.abs().max(1.0),
                        "{}: frame {f} marker {m}: c3dio {a} mm, ours {b} mm",
                        path.display()
                    );
                }
            }
        }
        whole += 1;
    }
    assert!(compared >= TABLE.len(), "compared {compared} files");
    assert!(
        whole * 2 >= compared,
        "c3dio read only {whole} of {compared} whole"
    );
}

/// Issue 36: no sample file is taken for a take cut off by a crash: the data of every file that
/// reads ends where its header says (the zero padding after it is not a frame).
#[test]
fn no_sample_file_holds_frames_past_its_header() {
    let dir = samples_dir();
    let Some(files) = sample_files(&dir) else {
        return;
    };
    let (mut inspected, mut problems) = (0, Vec::new());
    for path in &files {
        if replay::load(path).is_err() {
            continue;
        }
        let extent =
            replay::repair::inspect(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if let Some(p) = extent.problem() {
            problems.push(format!("{}: {p}", path.display()));
        }
        inspected += 1;
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(inspected >= TABLE.len(), "inspected {inspected} files");
}
