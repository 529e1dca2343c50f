//! A frame as the depth network takes it, written once: training sets
//! ([`DepthSet`](crate::DepthSet)), inference
//! ([`DepthEstimator`](crate::DepthEstimator)) and evaluation go through
//! here. The path: resize to the input size, round to 8 bits per channel
//! as training sets hold frames ([`DepthNetConfig::frame_bytes`]), then
//! the training statistics and, for a network that takes it, the tendon
//! mask as a fourth channel ([`DepthNetConfig::network_input`]).

use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::{ChannelStats, FloatImage, resize_rgb};

use crate::{DepthNetConfig, Error, Result};

/// The frame resized to `w x h`, `H x W x 3` bytes: as training sets hold
/// frames and inference takes them.
pub fn frame_bytes(frame: &RgbImage, [w, h]: [usize; 2]) -> Result<Vec<u8>> {
    Ok(resize_rgb(frame, w, h)?.to_bytes())
}

impl DepthNetConfig {
    /// The frame resized to the input, `H x W x 3` bytes ([`frame_bytes`]).
    pub fn frame_bytes(&self, frame: &RgbImage) -> Result<Vec<u8>> {
        frame_bytes(frame, self.input_size)
    }

    /// Bytes made by [`Self::frame_bytes`] as a `[0, 1]` image.
    pub fn image_of_bytes(&self, bytes: &[u8]) -> FloatImage {
        let [w, h] = self.input_size;
        FloatImage::from_bytes(w, h, 3, bytes)
    }

    /// Whether the network takes the tendon mask as a fourth channel.
    pub fn takes_mask(&self) -> bool {
        self.in_channels == 4
    }

    /// The normalised `C x H x W` input of a frame image: its channels
    /// by `stats`, then `mask` (`H x W`, at the input size) as 0/1 when the
    /// network takes it; a mask is required exactly then.
    pub fn network_input(
        &self,
        img: &FloatImage,
        stats: &ChannelStats,
        mask: Option<&[bool]>,
    ) -> Result<Vec<f32>> {
        let [w, h] = self.input_size;
        let mut x = stats.to_chw(img)?;
        match (self.takes_mask(), mask) {
            (true, Some(m)) if m.len() == w * h => x.extend(m.iter().map(|&b| b as u8 as f32)),
            (true, _) => return Err(Error::MaskRequired { size: [w, h] }),
            (false, _) => {}
        }
        Ok(x)
    }

    /// [`Self::network_input`] of an RGB frame of any size.
    pub fn frame_input(
        &self,
        frame: &RgbImage,
        stats: &ChannelStats,
        mask: Option<&[bool]>,
    ) -> Result<Vec<f32>> {
        let img = self.image_of_bytes(&self.frame_bytes(frame)?);
        self.network_input(&img, stats, mask)
    }
}
