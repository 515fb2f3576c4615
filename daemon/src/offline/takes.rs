//! Offline glue between takes and models: loading the inputs of a command, putting takes in a
//! model's marker order, projecting and resynthesising whole takes.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{bail, Context, Result};
use ica_core::model::IcaModel;
use ica_core::project::FrameStatus;
use replay::session::Session;
use replay::Take;

use engine::frame::{FrameProcessor, Prepared};
use engine::layout::LabelMap;

/// A take loaded from disk, with where it came from.
#[derive(Debug, Clone)]
pub struct LoadedTake {
    /// The file.
    pub path: PathBuf,
    /// The take.
    pub take: Take,
}

/// Largest input file the offline commands read, bytes (`--max-input-mb`).
static INPUT_LIMIT: AtomicU64 = AtomicU64::new(replay::file::DEFAULT_MAX_TAKE_BYTES);

/// Sets the largest input file (take, model, manifest) the offline commands read.
pub fn set_input_limit(bytes: u64) {
    INPUT_LIMIT.store(bytes, Ordering::Relaxed);
}

/// The largest input file the offline commands read, bytes.
pub fn input_limit() -> u64 {
    INPUT_LIMIT.load(Ordering::Relaxed)
}

/// Loads a take, naming the file in the error; rejects an empty take, a file that is not a
/// regular one and a file over the input limit.
///
/// # Errors
/// Unreadable, malformed or empty file.
pub fn load_take(path: &Path) -> Result<Take> {
    load_take_with(path, replay::C3dDecoding::CrossChecked)
}

/// [`load_take`], decoding a C3D file's points as `decoding` says.
///
/// # Errors
/// As [`load_take`].
pub fn load_take_with(path: &Path, decoding: replay::C3dDecoding) -> Result<Take> {
    let take = replay::load_with(path, input_limit(), decoding)
        .with_context(|| format!("{}", path.display()))?;
    if take.n_frames() == 0 {
        bail!("{}: take has no frames", path.display());
    }
    Ok(take)
}

/// Loads and validates a model file, naming the file in the error.
///
/// # Errors
/// Unreadable file, not a regular file, over the input limit, or not a valid model.
pub fn load_model(path: &Path) -> Result<IcaModel> {
    load_model_limited(path, input_limit())
}

/// [`load_model`] of a file of at most `max_bytes`.
///
/// # Errors
/// As [`load_model`].
pub fn load_model_limited(path: &Path, max_bytes: u64) -> Result<IcaModel> {
    let file = replay::file::open_bounded(path, max_bytes)?;
    IcaModel::load(std::io::BufReader::new(file))
        .with_context(|| format!("{}: not a valid model", path.display()))
}

/// Loads a session manifest, naming the file in the error.
///
/// # Errors
/// Unreadable or invalid manifest.
pub fn load_session(path: &Path) -> Result<Session> {
    // Its errors name the file already.
    Ok(Session::load(path)?)
}

/// A take in a model's marker order: frames x model markers x 3, and the missing mask.
#[derive(Debug, Clone, Default)]
pub struct ModelFrames {
    /// Positions in model order (mm).
    pub xyz: Vec<f32>,
    /// Missing flags in model order.
    pub missing: Vec<bool>,
    /// Markers per frame (the model's).
    pub markers: usize,
}

impl ModelFrames {
    /// Frames held.
    pub fn frames(&self) -> usize {
        self.missing.len() / self.markers.max(1)
    }

    /// One frame's positions and mask.
    pub fn frame(&self, f: usize) -> (&[f32], &[bool]) {
        let n = self.markers;
        (
            &self.xyz[f * n * 3..(f + 1) * n * 3],
            &self.missing[f * n..(f + 1) * n],
        )
    }
}

/// Gathers a whole take into model order.
pub fn to_model_order(take: &Take, map: &LabelMap) -> ModelFrames {
    frames_in_model_order(take, map, 0..take.n_frames())
}

/// Gathers frames `range` of a take into model order.
pub fn frames_in_model_order(take: &Take, map: &LabelMap, range: Range<usize>) -> ModelFrames {
    let mut frames = ModelFrames::default();
    frames_in_model_order_into(take, map, range, &mut frames);
    frames
}

/// [`frames_in_model_order`] into the buffers of `out`, which a block reader reuses: a new
/// `ModelFrames` per block was a fresh allocation of megabytes, whose pages the kernel
/// faulted in and zeroed for every block (a tenth of `project`'s time on a long take).
pub fn frames_in_model_order_into(
    take: &Take,
    map: &LabelMap,
    range: Range<usize>,
    out: &mut ModelFrames,
) {
    let markers = map.model_to_take.len();
    let frames = range.len();
    out.markers = markers;
    out.xyz.clear();
    out.missing.clear();
    let identity = markers == take.n_markers()
        && map
            .model_to_take
            .iter()
            .enumerate()
            .all(|(i, t)| *t == Some(i));
    if identity {
        // The take has the model's markers in its order: one copy, then the missing
        // samples zeroed (as gathering leaves them).
        let (xyz, missing) = (&mut out.xyz, &mut out.missing);
        xyz.extend_from_slice(&take.positions[range.start * markers * 3..range.end * markers * 3]);
        missing.extend_from_slice(&take.missing[range.start * markers..range.end * markers]);
        for (p, &gone) in xyz.chunks_exact_mut(3).zip(missing.iter()) {
            if gone {
                p.fill(0.0);
            }
        }
        return;
    }
    out.xyz.resize(frames * markers * 3, 0.0);
    out.missing.resize(frames * markers, true);
    for (k, f) in range.enumerate() {
        map.gather_into(
            take.frame(f),
            take.frame_missing(f),
            &mut out.xyz[k * markers * 3..(k + 1) * markers * 3],
            &mut out.missing[k * markers..(k + 1) * markers],
        );
    }
}

/// What a user should hear about a take before trusting what a model made of it: markers
/// that differ from the model's (the model's markers the take lacks are filled or left empty,
/// the take's the model does not have are passed through or ignored), and a rate other than
/// the model's (frames are projected one by one, as they are). Empty when the take matches.
pub fn take_notices(model: &IcaModel, take: (&[String], f64), map: &LabelMap) -> Vec<String> {
    let (labels, rate_hz) = take;
    let mut notices: Vec<String> = map
        .differences(model.labels(), labels)
        .describe("model")
        .into_iter()
        .collect();
    if (rate_hz - model.rate_hz()).abs() > 1e-6 * model.rate_hz() {
        notices.push(format!(
            "is at {rate_hz} Hz, the model at {} Hz",
            model.rate_hz()
        ));
    }
    notices
}

/// Analog samples per frame of a C3D take (force plates, EMG, audio), which emoshift does not
/// read and its outputs leave out. `None` for other files, unreadable ones (their reading
/// reports them) and C3Ds without analog data.
pub fn analog_samples(path: &Path) -> Option<usize> {
    use std::io::Read as _;
    if replay::Format::from_path(path) != Some(replay::Format::C3d) {
        return None;
    }
    // The header and the parameter section's first block, wherever the header puts it.
    let mut head = Vec::new();
    let file = std::fs::File::open(path).ok()?;
    file.take(256 * 512).read_to_end(&mut head).ok()?;
    let blocks = usize::from(*head.first()?);
    head.truncate(blocks.max(2) * 512);
    replay::c3d::analog_per_frame(&head).ok().filter(|&n| n > 0)
}

/// The warning for an output written from a take with [`analog_samples`].
pub fn analog_left_out(path: &Path) -> Option<String> {
    analog_samples(path).map(|n| {
        format!(
            "has analog data ({n} samples per frame), which emoshift does not read: the output keeps the markers only"
        )
    })
}

/// The warning for a take cut off by a crash (data past its header, a torn last frame), with
/// what to do: "holds 363 frames, header says 1: run `emoshift repair live.c3d`". `None` for
/// a whole take, and for a file whose header cannot be read (its reading reports it).
pub fn cut_off(path: &Path) -> Option<String> {
    let problem = replay::repair::inspect(path).ok()?.problem()?;
    Some(format!(
        "{problem}: run `emoshift repair {}`",
        path.display()
    ))
}

/// Matches a take to a model by label.
///
/// # Errors
/// No shared marker, naming the file.
pub fn match_take(model: &IcaModel, take: &Take, path: &Path) -> Result<LabelMap> {
    LabelMap::new(model.labels(), &take.labels).with_context(|| format!("{}", path.display()))
}

/// Component series of a take: frames x m (`f32`), with what preparing each frame found.
#[derive(Debug, Clone)]
pub struct Projected {
    /// Components, frames x m.
    pub u: Vec<f32>,
    /// Per-frame projection status (masked, held...).
    pub status: Vec<FrameStatus>,
    /// Per-frame preparation (head pose, glitches).
    pub prepared: Vec<Prepared>,
    /// Components per frame.
    pub m: usize,
}

impl Projected {
    /// Component `k` over the take, as `f64`.
    pub fn component(&self, k: usize) -> Vec<f64> {
        self.u
            .chunks_exact(self.m)
            .map(|row| f64::from(row[k]))
            .collect()
    }

    /// The whole series as `f64`, frames x m.
    pub fn as_f64(&self) -> Vec<f64> {
        self.u.iter().map(|&v| f64::from(v)).collect()
    }

    /// Samples dropped as glitches over the take.
    pub fn glitches(&self) -> usize {
        self.prepared.iter().map(|p| p.glitches).sum()
    }
}

/// Projects every frame of a take through the shared [`FrameProcessor`] (glitch check, head
/// stabilisation, masked projection).
///
/// # Errors
/// A frame buffer that does not match the model (an internal invariant).
pub fn project_take(model: &IcaModel, frames: &ModelFrames) -> Result<Projected> {
    let mut processor = FrameProcessor::new(model);
    let m = model.components();
    let n = frames.frames();
    let mut u = vec![0.0f32; n * m];
    let mut status = Vec::with_capacity(n);
    let mut prepared = Vec::with_capacity(n);
    for f in 0..n {
        let (xyz, missing) = frames.frame(f);
        let p = processor.project(xyz, missing, &mut u[f * m..(f + 1) * m])?;
        status.push(p.status);
        prepared.push(p);
    }
    Ok(Projected {
        u,
        status,
        prepared,
        m,
    })
}

/// Resynthesises a take from its components, each frame's components edited in place by
/// `edit(frame, u)`, putting each frame's head pose back.
///
/// # Errors
/// A buffer that does not match the model (an internal invariant), or `edit`'s own error.
pub fn resynthesise(
    model: &IcaModel,
    projected: &Projected,
    mut edit: impl FnMut(usize, &mut [f32]) -> Result<()>,
) -> Result<Vec<f32>> {
    let mut processor = FrameProcessor::new(model);
    let m = projected.m;
    let channels = model.channels();
    let frames = projected.u.len() / m.max(1);
    let mut out = vec![0.0f32; frames * channels];
    let mut u = vec![0.0f32; m];
    for f in 0..frames {
        u.copy_from_slice(&projected.u[f * m..(f + 1) * m]);
        edit(f, &mut u)?;
        let pose = projected.prepared[f].pose;
        processor.resynthesise(
            pose.as_ref(),
            &u,
            &mut out[f * channels..(f + 1) * channels],
        )?;
    }
    Ok(out)
}
