//! A frame as the segmenter takes it, written once: training windows
//! ([`SegmentSet`](crate::SegmentSet), rotated copies), inference
//! ([`TendonSegmenter`](crate::TendonSegmenter)) and evaluation cut their
//! windows here.
//!
//! The path: scale the frame so its shorter side is the window's side
//! ([`SquareWindow::scaled_size`]), cut the centred square (rotated for
//! augmentation, [`cut_frame`]), round to 8 bits per channel as training
//! windows are held, then normalise with the training statistics
//! ([`UNetConfig::window_input`]).

use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::{
    ChannelStats, FloatImage, SquareWindow, binarise_mask, resize_rgb,
};

use crate::model::UNetConfig;
use crate::{Error, Result};

/// The window of one scaled frame (and its mask), rotated by `deg`: `S x
/// S x 3` bytes and, with a mask, `S x S` tendon flags.
pub fn cut_frame(
    frame: &FloatImage,
    mask: Option<&FloatImage>,
    window: SquareWindow,
    deg: f64,
) -> (Vec<u8>, Option<Vec<bool>>) {
    let bytes = window.cut(frame, deg).to_bytes();
    let m = mask.map(|m| {
        binarise_mask(&window.cut(m, deg))
            .into_iter()
            .map(|v| v > 0.5)
            .collect()
    });
    (bytes, m)
}

impl UNetConfig {
    /// The square window the segmenter looks at.
    pub fn window(&self) -> SquareWindow {
        SquareWindow { side: self.side }
    }

    /// The (unrotated) window of an RGB frame of any size, at 8 bits per
    /// channel as training windows are held ([`cut_frame`] at 0 degrees).
    pub fn frame_window(&self, frame: &RgbImage) -> Result<FloatImage> {
        let win = self.window();
        let (sw, sh) = win.scaled_size(frame.width(), frame.height());
        Ok(win.cut(&resize_rgb(frame, sw, sh)?, 0.0).quantised())
    }

    /// The normalised `3 x S x S` network input of a window.
    pub fn window_input(&self, window: &FloatImage, stats: &ChannelStats) -> Result<Vec<f32>> {
        let s = self.side;
        if (window.width, window.height) != (s, s) {
            return Err(Error::WindowSize {
                what: "window",
                expected: [s, s],
                found: [window.width, window.height],
            });
        }
        Ok(stats.to_chw(window)?)
    }
}
