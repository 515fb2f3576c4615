//! The frame engine: a datagram and the caller's `now` in, output datagrams and counters out.
//! Sans-IO: no tokio, no sockets, no clock, no files (CI checks it); the [`crate::serve`]
//! shell owns all of those.
//!
//! # A frame's path
//!
//! [`Pipeline::handle_datagram`] (source address, bytes):
//!
//! 1. **Scan** the datagram ([`protocol::messages`]): bundles flattened, limits enforced; a bad
//!    packet is counted by kind and dropped.
//! 2. **Labels** (`/mocap/labels`) update the source's layouts ([`protocol::LayoutBook`]).
//! 3. **Frame** (`/mocap/frame`): decoded into a reusable [`protocol::FrameBuf`]; its layout is
//!    the source's latest labels of the same marker count; frames without one are counted.
//! 4. **Stream**: the (source, layout) pair's [`Stream`] is found or created (its model, its
//!    performer, its [`LabelMap`] from the source's labels to the model's markers).
//! 5. [`Stream::process`]: frame order checked (duplicates and stale frames dropped, a restart
//!    noticed); markers gathered into model order; [`FrameProcessor`] prepares (glitch checks,
//!    head stabilisation), projects (masked where markers are missing), the [`EditState`]
//!    edits the components, the processor resynthesises and puts the head pose back.
//! 6. **Encode** once per wanted profile ([`pipeline`]): compact, flat-split, components.
//! 7. **Emit**: the encoded bytes go to the caller's sink ([`Emitted`]), once per frame.
//!
//! Control reaches the engine between frames as [`Command`]s ([`Pipeline::handle_command`]).

pub mod clients;
mod counters;
pub mod edit_state;
pub mod frame;
pub mod layout;
pub mod pipeline;
pub mod streams;

pub use counters::Counters;
pub use edit_state::EditState;
pub use frame::{FramePrep, FrameProcessor, Prepared};
pub use layout::LabelMap;
pub use pipeline::{Emitted, Pipeline, PipelineConfig};
pub use streams::{Performer, Stream, StreamStatus};
