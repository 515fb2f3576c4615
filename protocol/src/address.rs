//! The address space: one constant per OSC address and [`Address`] to route on it.

/// Input frame, `,ihbb` (blob form) or `,ih` + 3n `f` (flat form).
pub const FRAME: &str = "/mocap/frame";
/// The source's SMPTE timecode and clock of the frame in the same bundle, `,iiiii`.
pub const TIMECODE: &str = "/mocap/timecode";
/// Marker names of a layout, `,i s...`.
pub const LABELS: &str = "/mocap/labels";
/// One part of a flat-split output frame, `,iiii f...`.
pub const PART: &str = "/mocap/part";
/// Edit state in the compact profile, `,sf`.
pub const STATE: &str = "/emoshift/state";
/// Current component activations u, `,f...`.
pub const COMPONENTS: &str = "/emoshift/components";
/// VMC blend shape value, `,sf`.
pub const VMC_BLEND_VAL: &str = "/VMC/Ext/Blend/Val";
/// VMC "apply the values sent so far", no arguments.
pub const VMC_BLEND_APPLY: &str = "/VMC/Ext/Blend/Apply";
/// The stream an output bundle belongs to, `,is` (stream id, name); first in the bundle.
pub const STREAM: &str = "/emoshift/stream";
/// The cookie a subscription from beyond loopback must echo, `,i`.
pub const SUBSCRIBE_CHALLENGE: &str = "/subscribe/challenge";
/// Error reply to a control message, `,ss` (address, message).
pub const ERROR: &str = "/emoshift/error";
/// Suffix appended to a control address for its success reply.
pub const CONFIRM_SUFFIX: &str = "/confirm";

/// Control: set the target emotion, `,s`.
pub const EMOTION_TARGET: &str = "/emotion/target";
/// Control: set the edit amount, `,f`.
pub const EMOTION_AMOUNT: &str = "/emotion/amount";
/// Control: set the ramp time in seconds, `,f`.
pub const EMOTION_RAMP: &str = "/emotion/ramp";
/// Control: move towards a blend of named emotions, `,sfsf...` (name, weight pairs).
pub const EMOTION_MIX: &str = "/emotion/mix";
/// Control: ask for the emotion names and their level vectors, `,`.
pub const EMOTION_LIST: &str = "/emotion/list";
/// Control: raw translate of component i, `,if`.
pub const EMOTION_ALPHA: &str = "/emotion/alpha";
/// Control: gain of component i, `,if`.
pub const COMPONENT_GAIN: &str = "/component/gain";
/// Control: bypass on (non-zero) or off, `,i`.
pub const BYPASS: &str = "/bypass";
/// Control: subscribe the sender's host at a port to a profile, `,is`.
pub const SUBSCRIBE: &str = "/subscribe";
/// Control: unsubscribe the sender's host at a port, `,i`.
pub const UNSUBSCRIBE: &str = "/unsubscribe";
/// Control: load a model file, `,s`.
pub const MODEL_LOAD: &str = "/model/load";
/// Control: start recording to a path, `,s`; `,ss` records the raw input to the second.
pub const RECORD_START: &str = "/record/start";
/// Control: stop recording, no arguments.
pub const RECORD_STOP: &str = "/record/stop";
/// Control: ask for the counters, no arguments; answered by `/status/confirm`.
pub const STATUS: &str = "/status";
/// Session control (`emoshift session`): record the prompted take, no arguments.
pub const SESSION_START: &str = "/session/start";
/// Session control: stop the take being recorded and check it, no arguments.
pub const SESSION_STOP: &str = "/session/stop";
/// Session control: record the prompted take again (after a refusal), or the last accepted
/// one again, no arguments.
pub const SESSION_RETAKE: &str = "/session/retake";
/// Session control: leave the prompted take out and go on, no arguments.
pub const SESSION_SKIP: &str = "/session/skip";
/// Session control: go back to the take before the prompted one, no arguments.
pub const SESSION_BACK: &str = "/session/back";
/// Session control: train and analyse what was recorded, no arguments.
pub const SESSION_FINISH: &str = "/session/finish";
/// Session control: after a finish that found takes to redo, record just those again now (in
/// the same sitting), no arguments.
pub const SESSION_REDO: &str = "/session/redo";
/// Session control: ask where the session is, no arguments; answered by
/// `/session/status/confirm ,iiisss` (take index from 0, takes in total, sentence number from
/// 1, emotion, state, sentence text).
pub const SESSION_STATUS: &str = "/session/status";

/// Every address this crate knows, for routing a [`crate::Message`] without string compares
/// scattered through the caller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Address {
    /// [`FRAME`]
    Frame,
    /// [`LABELS`]
    Labels,
    /// [`TIMECODE`]
    Timecode,
    /// [`PART`]
    Part,
    /// [`STATE`]
    State,
    /// [`STREAM`]
    Stream,
    /// [`SUBSCRIBE_CHALLENGE`]
    Challenge,
    /// [`COMPONENTS`]
    Components,
    /// [`VMC_BLEND_VAL`]
    VmcBlendVal,
    /// [`VMC_BLEND_APPLY`]
    VmcBlendApply,
    /// [`ERROR`]
    Error,
    /// One of the control addresses (decode it with [`crate::decode_control`]).
    Control,
    /// A control reply: `<control address>/confirm`.
    Confirm,
}

const CONTROLS: [&str; 22] = [
    EMOTION_TARGET,
    EMOTION_AMOUNT,
    EMOTION_RAMP,
    EMOTION_MIX,
    EMOTION_LIST,
    EMOTION_ALPHA,
    COMPONENT_GAIN,
    BYPASS,
    SUBSCRIBE,
    UNSUBSCRIBE,
    MODEL_LOAD,
    RECORD_START,
    RECORD_STOP,
    STATUS,
    SESSION_START,
    SESSION_STOP,
    SESSION_RETAKE,
    SESSION_SKIP,
    SESSION_BACK,
    SESSION_FINISH,
    SESSION_REDO,
    SESSION_STATUS,
];

impl Address {
    /// Classifies an address; `None` for addresses outside the emoshift space.
    pub fn parse(address: &str) -> Option<Address> {
        Some(match address {
            FRAME => Address::Frame,
            LABELS => Address::Labels,
            TIMECODE => Address::Timecode,
            PART => Address::Part,
            STATE => Address::State,
            STREAM => Address::Stream,
            SUBSCRIBE_CHALLENGE => Address::Challenge,
            COMPONENTS => Address::Components,
            VMC_BLEND_VAL => Address::VmcBlendVal,
            VMC_BLEND_APPLY => Address::VmcBlendApply,
            ERROR => Address::Error,
            a if CONTROLS.contains(&a) => Address::Control,
            a => match a.strip_suffix(CONFIRM_SUFFIX) {
                Some(base) if CONTROLS.contains(&base) => Address::Confirm,
                _ => return None,
            },
        })
    }
}

#[cfg(test)]
mod tests;
