//! The models composed into what a robot runs. Paper B's palpation
//! pipeline ([`Pipeline`]): the detector on every frame, the segmenter,
//! direction and depth only on tendon frames, on burn or onnxruntime, with
//! a run loop over datasets and folders of frames ([`run`](mod@run)). Paper A's
//! perception ([`tactip`]): one encoder, every estimator of its folder on
//! one encoding, and the training of those estimators.

#![deny(missing_docs)]

pub mod calibrate;
pub mod demo;
pub mod ensemble;
mod error;
pub mod export;
pub mod hysteresis;
pub mod options;
pub mod overlay;
pub mod palpation;
pub mod profile;
pub mod reconstruct;
pub mod run;
pub mod tactip;

pub use error::{Error, Result};
pub use hysteresis::Hysteresis;
pub use overlay::{FrameViews, SensorView, TendonView};
pub use palpation::{FrameRecord, PalpationModels, Pipeline};
pub use run::{
    ContactSummary, Flow, RunItem, RunOptions, RunOutcome, RunSummary, UnreadableFrames, run,
    run_collect,
};
pub use tactile_burn::Runtime;
pub use tactile_core::source::{
    Frame, FrameEntry, FrameList, FrameSource, MissingFrames, SourceKind, SourceOptions, SourceSpec,
};
