#![deny(missing_docs)]
//! datasets-synth: the two virtual sensors of `shared/spec/sensors.md`
//! (version 1), written as datasets in the layout of `datasets.md`.
//!
//! - [`tactip`]: the virtual TacTip (paper A): 127 pins in a hemispherical
//!   tip, seven contact shapes, position, orientation, depth and force.
//! - [`visuotactile`]: the virtual visuo-tactile palpation sensor (paper B):
//!   RGB frames, tendon masks, directions and depth maps, in palpation videos.
//! - [`calibrated`]: a real GelSight-like sensor's own palpation videos,
//!   rendered through its ball-press calibration (optics and gel), with
//!   indentation maps.
//!
//! Every sample has its own random stream keyed by the seed and its index,
//! so datasets are byte-identical on every machine, render in parallel, and
//! can be extended without changing earlier samples.

pub mod calibrated;
mod error;
pub use error::{Error, Result};
pub use tactile_core::npy;
pub mod preview;
pub mod raster;
pub use tactile_core::rng;
pub mod tactip;
pub mod visuotactile;
pub use visuotactile::render_alternate;
pub mod write;

pub use calibrated::{CalibratedConfig, CalibratedSensor};
pub use rng::Range;
pub use tactip::{SHAPES, TactipConfig};
pub use visuotactile::{Renderer, TendonPath, VisuotactileConfig};
pub use write::{
    GENERATOR, TactipLabels, WriteOptions, calibrated_position, check_count, render_frames,
    visuotactile_position, write_calibrated, write_tactip, write_visuotactile,
};
