//! emoshift's frame engine: a source's frame in, the edited frame to every output. Sans-IO by
//! construction: this package depends on `ica-core` and `protocol` only (CI checks that
//! `cargo tree -e normal -p engine` lists no tokio), so it cannot open a socket, read a clock
//! or touch a file; the daemon's `serve` shell owns all of those.
//!
//! # The two ports
//!
//! - **In**: [`SourceFrame`], the one frame type every live source produces (OSC, NatNet, and
//!   next QTM): stream key, the source's name for the performer, labels, positions with
//!   missing flags, frame number, capture time, timecode. What only one protocol knows
//!   (NatNet's model definitions, its clock offset) stays in that source, in the daemon.
//! - **Out**: [`Sink`], which every output implements (the OSC profiles, the session
//!   recording, the monitor feed, and next the NatNet and QTM servers). It declares what it
//!   reads ([`Needs`]), gets each [`Processed`] frame once, and owns its clients
//!   ([`subscribers`] is the bookkeeping they share).
//!
//! # A frame's path through the engine
//!
//! 1. [`Pipeline::handle_frame`] finds the frame's [`Stream`] by its key, or makes it on its
//!    first frame: its model (a performer's, or the default), its name, its [`LabelMap`] from
//!    the source's labels to the model's (a stream whose source relabels it starts over).
//! 2. [`Stream::process`]: frame order checked (duplicates and stale frames dropped, a restart
//!    noticed); markers gathered into model order; the [`FrameProcessor`] prepares (glitch
//!    checks, head stabilisation) and projects (masked where markers are missing); the
//!    [`EditState`] edits the components; when a sink reads markers, the processor
//!    resynthesises and puts the head pose back.
//! 3. The sink gets the [`Processed`] frame, once; the OSC output encodes it once per profile
//!    its subscribers want and sends the same bytes to each of them.
//!
//! Call order (the shell's one processing thread): `handle_frame` per frame, then
//! [`Pipeline::poll_refusal`]; [`Pipeline::handle_edit`] and [`Pipeline::set_model`] between
//! frames, so no frame sees half a change; [`Pipeline::forget_quiet_streams`] every
//! [`pipeline::SWEEP_SECONDS`] of the caller's clock. Time the engine needs comes from the
//! frames (frame numbers and the model rate drive every glide), or from the caller (`now`
//! arguments of [`subscribers`] and [`monitor`]).
//!
//! ```
//! use std::sync::Arc;
//!
//! use engine::{Each, Pipeline, PipelineConfig, SourceFrame, StreamKey};
//! use protocol::{FrameBuf, FrameTime};
//!
//! let model = Arc::new(engine::synthetic::random_model(12, 4, 1));
//! let mut pipeline = Pipeline::new(Arc::clone(&model), vec![], PipelineConfig::default());
//! let labels: Arc<[String]> = model.labels().into();
//! let mut xyz = vec![0.0; 12 * 3];
//! engine::synthetic::frame_into(&model, 0, &mut xyz);
//! let mut frame = FrameBuf::with_max_markers(12);
//! frame.set_frame(0, 0, &xyz).expect("finite");
//! let key = StreamKey { source: "127.0.0.1:7000".parse().expect("addr"), layout_id: 0 };
//! let source = SourceFrame { key, performer: None, labels: &labels, frame: &frame, time: FrameTime::default() };
//! let mut out = Vec::new();
//! pipeline.handle_frame(&source, &mut Each(|p: &engine::Processed<'_>| out.push(p.frame_number())));
//! assert_eq!(out, [0]);
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod counters;
pub mod edit_state;
pub mod frame;
pub mod input;
pub mod layout;
pub mod monitor;
pub mod output;
pub mod pipeline;
pub mod stream;
pub mod streams;
pub mod subscribers;
pub mod synthetic;

pub use counters::Counters;
pub use edit_state::EditState;
pub use frame::{FramePrep, FrameProcessor, Prepared};
pub use input::SourceFrame;
pub use layout::LabelMap;
pub use output::{Discard, Each, Needs, Processed, Sink};
pub use pipeline::{Pipeline, PipelineConfig, Refusal};
pub use stream::Stream;
pub use streams::{Performer, PerformerConfig, StreamKey, StreamStatus};
