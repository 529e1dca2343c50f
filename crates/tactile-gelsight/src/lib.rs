//! GelSight-like sensors: calibrate a real sensor from presses of a ball
//! of known radius, and reconstruct its skin's indentation from a frame.
//!
//! A calibration folder ([`layout`]) holds the skin at rest and the
//! presses. Each press's contact circle ([`circle`]) and the ball's
//! geometry ([`geometry`]) give the skin's slopes where they are known;
//! a small convolutional network ([`model`]) learns colour to slope on
//! the working grid ([`prepare`]), and a Poisson solve ([`poisson`])
//! integrates slopes to height ([`inference`]). [`eval`] scores a
//! reconstruction against the geometry. [`render_model`] fits the sensor
//! forward (optics and the gel's spread) so its own training data can be
//! rendered.

#![deny(missing_docs)]

pub mod artifact;
pub mod bench;
pub mod circle;
mod error;
pub mod eval;
pub mod geometry;
pub mod gs_sdk;
pub mod gs_sdk_config;
pub mod inference;
pub mod layout;
pub mod lookup;
pub mod model;
pub mod negatives;
mod npz;
pub mod options;
pub mod poisson;
pub mod prepare;
pub mod reconstruct;
pub mod render_model;
pub mod taxim;
pub mod training;

pub use artifact::GelsightArtifact;
pub use error::{Error, Result};
pub use inference::{IndentationMap, Reconstructor};
pub use layout::{BallPresses, Circle, SensorInfo};
pub use model::GradientNetConfig;
pub use options::BallOptions;
pub use training::{CalibrationConfig, CircleSource, calibrate};
