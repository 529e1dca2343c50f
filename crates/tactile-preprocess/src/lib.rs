//! TacTip preprocessing (paper A): a 300x300 sensor frame becomes a binary
//! 28x28 [`PinImage`] (pins 1, background 0).
//!
//! The authors' chain, every step configurable: grey -> (lighting
//! compensation) -> histogram equalisation -> threshold -> circular mask ->
//! open 2x2 -> crop -> resize to 28x28 (OpenCV `INTER_LINEAR`, byte-exact
//! through kornia's OpenCV-compatible path) -> `/255` -> `round(x + 0.3)`.
//! The lighting compensation (white top-hat plus a threshold relative to the
//! local pin contrast) is what makes raw frames with illumination gradients,
//! light blobs and noise come out as clean pin images.
//!
//! Also here: visuo-tactile frames as model inputs ([`visuo`]), pin tracking
//! ([`pins`]) and the camera perturbations of the robustness study
//! ([`perturb`]).

#![deny(missing_docs)]

pub mod align;
mod chain;
mod config;
mod error;
mod morphology;
pub mod perturb;
pub mod pins;
pub mod profile;
mod resize;
pub mod visuo;

pub(crate) use chain::lit_and_masked;
pub use chain::{
    FLAT_FRAME_LEVELS, MAX_WINDOW_PX, PinImage, binarise, is_flat_frame, preprocess,
    preprocess_each, preprocess_each_by, preprocess_each_noting_flat,
};
pub use config::{Downsample, FrameSizeCheck, Lighting, NamedPreprocess, PreprocessConfig};
pub use error::{Error, Result};
pub use resize::{
    enlarge_f32, resize_area, resize_area_f32, resize_area_interleaved, resize_linear,
    shrink_rgb_by,
};
