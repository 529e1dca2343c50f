//! A frame as the detector takes it, written once: training sets
//! ([`DetectionSet`](crate::DetectionSet)), inference
//! ([`TendonDetector`](crate::TendonDetector)), evaluation, the input
//! profile and the standalone ONNX export's input all go through here.
//!
//! The path: resize to the input size, round to the input's bits per
//! channel ([`DetectorConfig::frame_levels`]: what training sets hold and
//! the standalone model takes), read back as `[0, 1]` floats
//! ([`DetectorConfig::image_of_levels`]: what the gates and the input
//! profile read), the exposure divided out when the detector was trained
//! so ([`DetectorConfig::network_view`]), then the training statistics
//! ([`DetectorConfig::network_input`]).

use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::{ChannelStats, FloatImage, normalise_exposure, resize_rgb};

use crate::{DetectorConfig, Result};

impl DetectorConfig {
    /// The frame resized to the input and rounded to its bits per channel:
    /// `H x W x 3` levels of `2^bits - 1`, as training sets hold frames and
    /// as the standalone ONNX model's `frame` input takes them.
    pub fn frame_levels(&self, frame: &RgbImage) -> Result<Vec<u16>> {
        let [w, h] = self.input_size;
        Ok(resize_rgb(frame, w, h)?.to_levels(self.bits()))
    }

    /// Levels made by [`Self::frame_levels`] as a `[0, 1]` image: what
    /// the gates and the input profile read.
    pub fn image_of_levels(&self, levels: &[u16]) -> FloatImage {
        let [w, h] = self.input_size;
        FloatImage::from_levels(w, h, 3, levels, self.bits())
    }

    /// [`Self::frame_levels`] read back as [`Self::image_of_levels`].
    pub fn frame_image(&self, frame: &RgbImage) -> Result<FloatImage> {
        Ok(self.image_of_levels(&self.frame_levels(frame)?))
    }

    /// The frame image as the network takes it, before the channel
    /// statistics: with `normalise_exposure`, its gain divided out.
    pub fn network_view(&self, mut img: FloatImage) -> FloatImage {
        if self.normalises_exposure() {
            normalise_exposure(&mut img);
        }
        img
    }

    /// The normalised `3 x H x W` network input of a frame image (made by
    /// [`Self::frame_image`] or [`Self::image_of_levels`]).
    pub fn network_input(&self, img: FloatImage, stats: &ChannelStats) -> Result<Vec<f32>> {
        Ok(stats.to_chw(&self.network_view(img))?)
    }
}
