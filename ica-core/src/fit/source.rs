//! The streaming fit over caller-provided data: the [`ChunkSource`] of raw frames (read once
//! per pass, twice in all) and the [`WhitenedStore`] the whitened frames are spilled to (read
//! once per FastICA iteration), with in-memory implementations of both.
//!
//! [`FastIcaParams::fit_stream`] drives [`StreamFit`] over them on the calling thread. A
//! parallel driver runs the same [`StreamFit`] passes itself, folding chunks on several threads.

use std::convert::Infallible;
use std::ops::ControlFlow;

use thiserror::Error;

use super::{FastIcaParams, FitData, FitError, FitOutput, Pass, StreamFit};
use crate::whiten::{FromF64, Moments};

/// Raw training frames, read in passes (the daemon's implementation reads take files).
pub trait ChunkSource {
    /// Sample type (`f32` from the wire and files, or `f64`).
    type Sample: Copy + Into<f64>;
    /// What reading can fail with.
    type Error;

    /// Values per frame.
    fn channels(&self) -> usize;

    /// One pass: calls `each` with every frame, as consecutive chunks (frame order, the same
    /// frames on every pass; chunk sizes are free). Stops early, returning `Ok`, when `each`
    /// returns [`ControlFlow::Break`].
    ///
    /// # Errors
    /// Whatever reading fails with.
    fn for_each_chunk(
        &mut self,
        each: &mut dyn FnMut(FitData<'_, Self::Sample>) -> ControlFlow<()>,
    ) -> Result<(), Self::Error>;
}

/// Where the whitened frames are kept between passes (the daemon's implementation is a
/// temporary file: `frames_used x m` values, 136 MB for 1.7 M frames at m = 20 as f32).
pub trait WhitenedStore {
    /// Stored value type: `f32` halves the file, `f64` reproduces the in-memory fit exactly.
    type Sample: FromF64;
    /// What storing or reading can fail with.
    type Error;

    /// Starts over, empty, for frames of `components` values.
    ///
    /// # Errors
    /// Whatever preparing the storage fails with.
    fn begin(&mut self, components: usize) -> Result<(), Self::Error>;

    /// Appends whitened frames (`frames x m`, frame after frame).
    ///
    /// # Errors
    /// Whatever writing fails with.
    fn push(&mut self, z: &[Self::Sample]) -> Result<(), Self::Error>;

    /// One pass: calls `each` with every stored frame in order, as chunks of whole frames.
    /// Stops early, returning `Ok`, when `each` returns [`ControlFlow::Break`].
    ///
    /// # Errors
    /// Whatever reading fails with.
    fn for_each_chunk(
        &mut self,
        each: &mut dyn FnMut(&[Self::Sample]) -> ControlFlow<()>,
    ) -> Result<(), Self::Error>;
}

/// Why a streaming fit failed.
#[derive(Debug, Error)]
pub enum StreamError<S, W> {
    /// The data or parameters were refused.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// Reading the raw frames failed.
    #[error("reading the training frames failed")]
    Source(#[source] S),
    /// Storing or reading the whitened frames failed.
    #[error("storing the whitened frames failed")]
    Store(#[source] W),
}

impl FastIcaParams {
    /// Fits the decomposition to frames read in passes from `source`, spilling the whitened
    /// frames to `store`: the same output as [`FastIcaParams::fit`] on the same frames (within
    /// rounding; exactly the same computation on takes under twice
    /// [`crate::fastica::EXPLORE_FRAMES`] used frames), except that `sources` is `None` and
    /// `used_frames` empty. Memory is bounded by the chunk size, the covariance
    /// (`channels²` f64) and the restarts' subsample, whatever the number of frames.
    ///
    /// Reads `source` twice and `store` once per FastICA iteration plus once.
    ///
    /// ```
    /// use ica_core::fit::{mixture, FastIcaParams, FitData, MemorySource, MemoryStore};
    /// let mix = mixture::face_like(6_000, 30, 4, 0.2, 1);
    /// let data = FitData::new(&mix.samples, mix.channels).expect("whole frames");
    /// let params = FastIcaParams::default().n_components(4);
    /// let mut source = MemorySource::new(data, 1_000);
    /// let mut spill = MemoryStore::<f32>::new(1_000);
    /// let streamed = params.fit_stream(&mut source, &mut spill).expect("fits");
    /// let in_memory = params.fit(&data).expect("fits");
    /// let diff = (&streamed.mixing - &in_memory.mixing).amax();
    /// assert!(diff < 1e-6 * in_memory.mixing.amax());
    /// ```
    ///
    /// # Errors
    /// What [`FastIcaParams::fit`] refuses, or a source or store failure.
    pub fn fit_stream<S: ChunkSource, W: WhitenedStore>(
        &self,
        source: &mut S,
        store: &mut W,
    ) -> Result<FitOutput, StreamError<S::Error, W::Error>> {
        let mut fit = StreamFit::new(self, source.channels())?;
        loop {
            match fit.poll_pass() {
                Pass::Moments => {
                    let moments = moments_pass(&fit, source)?;
                    fit.handle_moments(moments)?;
                }
                Pass::Whiten => {
                    let sub = whiten_pass(&fit, source, store)?;
                    fit.handle_whitened(sub)?;
                }
                Pass::Update => {
                    let mut acc = fit.update_accumulator()?;
                    stored_pass(store, &mut |z| acc.add_chunk(z))?;
                    fit.handle_update(acc)?;
                }
                Pass::Sources => {
                    let mut sums = fit.source_moments()?;
                    stored_pass(store, &mut |z| sums.add_chunk(z))?;
                    fit.handle_sources(sums)?;
                }
                Pass::Done => return Ok(fit.finish()?),
            }
        }
    }
}

/// Keeps the first error and asks the pass to stop.
fn keep_first<E>(slot: &mut Option<E>, result: Result<(), E>) -> ControlFlow<()> {
    match result {
        Ok(()) => ControlFlow::Continue(()),
        Err(e) => {
            *slot = Some(e);
            ControlFlow::Break(())
        }
    }
}

fn moments_pass<S: ChunkSource, W>(
    fit: &StreamFit,
    source: &mut S,
) -> Result<Moments, StreamError<S::Error, W>> {
    let mut moments = fit.moments();
    let mut failed = None;
    source
        .for_each_chunk(&mut |chunk| keep_first(&mut failed, moments.add_chunk(&chunk)))
        .map_err(StreamError::Source)?;
    failed.map_or(Ok(moments), |e| Err(e.into()))
}

fn whiten_pass<S: ChunkSource, W: WhitenedStore>(
    fit: &StreamFit,
    source: &mut S,
    store: &mut W,
) -> Result<crate::fastica::Subsample, StreamError<S::Error, W::Error>> {
    let whitener = fit.whitener().ok_or(FitError::UnexpectedPass {
        expected: fit.poll_pass(),
        got: Pass::Whiten,
    })?;
    let mut sub = fit.subsample()?;
    store
        .begin(whitener.components())
        .map_err(StreamError::Store)?;
    let (mut z, mut scratch) = (Vec::<W::Sample>::new(), Vec::new());
    let mut failed = None;
    source
        .for_each_chunk(&mut |chunk| {
            let step = whitener
                .whiten_into(&chunk, &mut z, &mut scratch)
                .and_then(|_| sub.push(&z))
                .map_err(StreamError::Fit)
                .and_then(|()| store.push(&z).map_err(StreamError::Store));
            keep_first(&mut failed, step)
        })
        .map_err(StreamError::Source)?;
    failed.map_or(Ok(sub), Err)
}

/// Folds one whitened chunk into a pass's accumulator.
type AddChunk<'a, T> = dyn FnMut(&[T]) -> Result<(), FitError> + 'a;

fn stored_pass<S, W: WhitenedStore>(
    store: &mut W,
    add: &mut AddChunk<'_, W::Sample>,
) -> Result<(), StreamError<S, W::Error>> {
    let mut failed = None;
    store
        .for_each_chunk(&mut |z| keep_first(&mut failed, add(z)))
        .map_err(StreamError::Store)?;
    failed.map_or(Ok(()), |e| Err(e.into()))
}

/// A [`ChunkSource`] over frames held in memory, cut into chunks of `chunk_frames` frames.
#[derive(Debug, Clone, Copy)]
pub struct MemorySource<'a, T> {
    data: FitData<'a, T>,
    chunk_frames: usize,
}

impl<'a, T: Copy + Into<f64>> MemorySource<'a, T> {
    /// Serves `data` in chunks of `chunk_frames` frames (at least 1).
    pub fn new(data: FitData<'a, T>, chunk_frames: usize) -> Self {
        Self {
            data,
            chunk_frames: chunk_frames.max(1),
        }
    }
}

impl<T: Copy + Into<f64>> ChunkSource for MemorySource<'_, T> {
    type Sample = T;
    type Error = Infallible;

    fn channels(&self) -> usize {
        self.data.channels()
    }

    fn for_each_chunk(
        &mut self,
        each: &mut dyn FnMut(FitData<'_, T>) -> ControlFlow<()>,
    ) -> Result<(), Infallible> {
        let mut start = 0;
        while start < self.data.frames() {
            let end = (start + self.chunk_frames).min(self.data.frames());
            if each(self.data.slice_frames(start, end)).is_break() {
                break;
            }
            start = end;
        }
        Ok(())
    }
}

/// A [`WhitenedStore`] in memory, read back in chunks of `chunk_frames` frames.
#[derive(Debug, Clone)]
pub struct MemoryStore<T> {
    components: usize,
    chunk_frames: usize,
    z: Vec<T>,
}

impl<T> MemoryStore<T> {
    /// An empty store read back `chunk_frames` frames (at least 1) at a time.
    pub fn new(chunk_frames: usize) -> Self {
        Self {
            components: 0,
            chunk_frames: chunk_frames.max(1),
            z: Vec::new(),
        }
    }

    /// The stored values, `frames x m`.
    pub fn values(&self) -> &[T] {
        &self.z
    }
}

impl<T: FromF64> WhitenedStore for MemoryStore<T> {
    type Sample = T;
    type Error = Infallible;

    fn begin(&mut self, components: usize) -> Result<(), Infallible> {
        self.components = components;
        self.z.clear();
        Ok(())
    }

    fn push(&mut self, z: &[T]) -> Result<(), Infallible> {
        self.z.extend_from_slice(z);
        Ok(())
    }

    fn for_each_chunk(
        &mut self,
        each: &mut dyn FnMut(&[T]) -> ControlFlow<()>,
    ) -> Result<(), Infallible> {
        for chunk in self.z.chunks(self.chunk_frames * self.components.max(1)) {
            if each(chunk).is_break() {
                break;
            }
        }
        Ok(())
    }
}
