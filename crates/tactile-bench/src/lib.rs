//! Measurements of tactile-rs, run in process with typed results: every
//! model's speed on each runtime against its error ([`models`], [`cae`]),
//! the virtual sensors' rate ([`synth`]), paper A's feature-count sweep
//! ([`sweep`]), feature sets against estimators ([`compare`]), the
//! robustness study ([`robustness`]) and the results page ([`report`]).
//! Each writes its table as Markdown with a plot and its rows as JSON.

#![deny(missing_docs)]

pub mod cae;
pub mod calibration;
pub mod compare;
pub mod devices;
mod error;
pub mod latency;
pub mod models;
pub mod ood;
pub mod output;
pub mod own_sensor;
pub mod pin_profile;
pub mod pose;
pub mod report;
pub mod resolution;
pub mod robustness;
pub mod shared;
pub mod surface;
pub mod sweep;
pub mod synth;

pub use error::{Error, Result};
