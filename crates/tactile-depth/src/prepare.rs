//! A frame as the depth network takes it, written once: training sets
//! ([`DepthSet`](crate::DepthSet)), inference
//! ([`DepthEstimator`](crate::DepthEstimator)) and evaluation go through
//! here. The path: resize to the input size, round to 8 bits per channel
//! as training sets hold frames ([`DepthNetConfig::frame_bytes`]), then
//! the training statistics and, for a network that takes one, the tendon
//! mask or the calibration's reconstruction as a fourth channel
//! ([`DepthNetConfig::network_input`]).

use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::{ChannelStats, FloatImage, resize_rgb};

use crate::{DepthNetConfig, DepthScale, Error, Result};

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
        self.in_channels == 4 && self.residual_channel.is_none()
    }

    /// Whether the network takes a prior (the calibration's
    /// reconstruction) as its fourth channel and corrects it.
    pub fn takes_prior(&self) -> bool {
        self.in_channels == 4 && self.residual_channel.is_some()
    }

    /// The normalised `C x H x W` input of a frame image: its channels
    /// by `stats`, then the fourth channel the network takes (the mask as
    /// 0/1, or the prior in model units); exactly that one is required.
    pub fn network_input(
        &self,
        img: &FloatImage,
        stats: &ChannelStats,
        fourth: FourthChannel<'_>,
    ) -> Result<Vec<f32>> {
        let [w, h] = self.input_size;
        let mut x = stats.to_chw(img)?;
        match fourth {
            FourthChannel::Mask(m) if self.takes_mask() && m.len() == w * h => {
                x.extend(m.iter().map(|&b| b as u8 as f32))
            }
            FourthChannel::Prior(p, scale) if self.takes_prior() && p.len() == w * h => {
                x.extend(p.iter().map(|&v| scale.to_model(v)))
            }
            FourthChannel::Nothing if self.in_channels == 3 => {}
            _ if self.takes_mask() => return Err(Error::MaskRequired { size: [w, h] }),
            _ if self.takes_prior() => return Err(Error::PriorRequired { size: [w, h] }),
            _ => {
                return Err(tactile_core::Error::Invalid(
                    "this depth network takes the frame only (RGB)".into(),
                )
                .into());
            }
        }
        Ok(x)
    }

    /// [`Self::network_input`] of an RGB frame of any size.
    pub fn frame_input(
        &self,
        frame: &RgbImage,
        stats: &ChannelStats,
        fourth: FourthChannel<'_>,
    ) -> Result<Vec<f32>> {
        let img = self.image_of_bytes(&self.frame_bytes(frame)?);
        self.network_input(&img, stats, fourth)
    }
}

/// What goes into a depth network's fourth input channel, at its input
/// size.
#[derive(Debug, Clone, Copy)]
pub enum FourthChannel<'a> {
    /// Nothing: an RGB network.
    Nothing,
    /// The tendon mask (a mask-channel network).
    Mask(&'a [bool]),
    /// The calibration's reconstruction, mm, and the network's depth scale
    /// that turns it into model units (a network with a prior).
    Prior(&'a [f32], DepthScale),
}
