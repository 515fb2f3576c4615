//! Offline work over takes and models, as library functions the commands and the demo call:
//! loading and projecting takes ([`takes`]), a command's input takes with their ranges
//! ([`inputs`]), preparing captures for training and the model's quality report
//! ([`training`], streaming long sessions), progress reports ([`progress`]), the analysis of a
//! paired session ([`analysis`]), edit planning ([`edit`]), real captures cut into a paired
//! session with a known signal ([`inject`]), a calibration session's script, checks and takes
//! ([`session`]), and `project` and `edit` streamed from file to output in blocks
//! ([`streamed`]).

pub mod analysis;
pub mod edit;
pub mod inject;
pub mod inputs;
pub mod output;
pub mod progress;
pub mod regions;
pub mod session;
pub mod streamed;
pub mod takes;
pub mod training;
pub mod trim;

pub use inputs::{load_inputs, session_inputs, take_inputs, TakeInput};
pub use takes::{
    load_model, load_model_limited, load_session, load_take, load_take_with, match_take,
    project_take, resynthesise, set_input_limit, take_notices, to_model_order, LoadedTake,
    ModelFrames, Projected,
};
