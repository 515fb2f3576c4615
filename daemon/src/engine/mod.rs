//! The frame engine: a datagram and the caller's `now` in, output datagrams and counters out.
//! Sans-IO: no tokio, no sockets, no clock, no files (`scripts/check-engine` checks it in
//! CI); the [`crate::serve`] shell owns all of those.
//!
//! # A frame's path, socket to socket
//!
//! In the shell (`serve`):
//!
//! 1. The receive task reads the datagram off the frame socket into a pooled buffer and
//!    queues it for the processing thread (a full queue drops the oldest, counted).
//! 2. The processing thread takes it off the queue between commands and hands it to
//!    [`Pipeline::handle_datagram`].
//!
//! In the engine:
//!
//! 3. [`Pipeline::handle_datagram`] **scans** the datagram ([`protocol::messages`]): bundles
//!    flattened, limits enforced; a bad packet is counted by kind and dropped. Labels
//!    (`/mocap/labels`) update the source's layouts ([`protocol::LayoutBook`]).
//! 4. `Pipeline::handle_frame` **decodes** `/mocap/frame` into a reusable
//!    [`protocol::FrameBuf`], finds its layout (the source's latest labels of the same marker
//!    count) and its [`Stream`] (made on the first frame: its model, its performer, its
//!    [`LabelMap`]).
//! 5. [`Stream::process`]: frame order checked (duplicates and stale frames dropped, a restart
//!    noticed); markers gathered into model order; the [`FrameProcessor`] prepares (glitch
//!    checks, head stabilisation) and projects (masked where markers are missing); the
//!    [`EditState`] edits the components; the processor resynthesises and puts the head pose
//!    back.
//! 6. The pipeline's outputs **encode** the frame once per profile a subscriber wants
//!    (compact, flat-split, components; `pipeline::encode`).
//! 7. The caller's `emit` gets the encoded bytes ([`Emitted`]), once per frame.
//!
//! Back in the shell:
//!
//! 8. `emit` sends the bytes to every subscriber of that profile from the processing thread
//!    (`serve::sender::Fanout`), then hands the frame to the recording, if one runs.
//!
//! A NatNet frame (OptiTrack Motive) enters at step 4 instead:
//! [`Pipeline::handle_natnet`] decodes the NAT_FRAMEOFDATA once ([`natnet`]: names, mm,
//! occlusion, timecode) and sends each markerset down steps 4 to 7 as one stream's frame. A
//! `/mocap/timecode` in a datagram, or a NatNet frame's timecode, rides along to the outputs
//! ([`Emitted::time`]).
//!
//! Edits and model swaps reach the engine between two datagrams, so no frame sees half a
//! change ([`Pipeline::handle_edit`], [`Pipeline::set_model`]). Who is subscribed, and until
//! when, is [`clients`]; the shell asks it with its own `now`.

pub mod clients;
mod counters;
pub mod edit_state;
pub mod frame;
pub mod layout;
pub mod monitor;
pub mod natnet;
pub mod pipeline;
pub mod stream;
pub mod streams;

pub use counters::Counters;
pub use edit_state::EditState;
pub use frame::{FramePrep, FrameProcessor, Prepared};
pub use layout::LabelMap;
pub use pipeline::{Emitted, Pipeline, PipelineConfig};
pub use stream::Stream;
pub use streams::{Performer, PerformerConfig, StreamKey, StreamStatus};
