//! The segmenter at work: a frame of any size in, the kept tendon region
//! and its direction out, on any runtime. `tactile run`, `tactile eval
//! segmenter`, the Python package and the benches all go through
//! [`TendonSegmenter`].

use std::path::Path;

use tactile_burn::runtime::sigmoid;
use tactile_burn::{Network, Runtime};
use tactile_core::image_io::RgbImage;
use tactile_preprocess::visuo::{FloatImage, is_blank};

use crate::Result;
use crate::artifact::SegmenterArtifact;
use crate::postprocess::Tendon;

/// The file of a segmenter folder that holds its sensor's rest frame
/// (`tactile train segmenter --rest`).
pub const REST_FILE: &str = "rest.png";

/// A loaded segmenter with its post-processing, ready for frames of any size.
pub struct TendonSegmenter {
    /// Window, statistics, threshold and post-processing.
    pub artifact: SegmenterArtifact,
    net: Box<dyn Network>,
    rest: Option<RestFrame>,
}

/// A sensor's frame with nothing touching it, as the segmenter's
/// direction reads it: a real gel's own texture (scratches, streaks of its
/// paint) shades every frame alike, and read against the rest frame it
/// no longer pulls the tendon's direction toward its own.
#[derive(Debug, Clone)]
pub struct RestFrame {
    /// Frame width, pixels: frames of this size (or scaled from it) are
    /// read against it.
    pub width: usize,
    /// Frame height, pixels.
    pub height: usize,
    /// Its window, as the segmenter cuts a frame's.
    window: FloatImage,
    /// The window's fine texture ([`detail`]).
    detail: Vec<f64>,
}

/// The least correlation of a window's fine texture with its rest frame's
/// for the direction to read against the rest frame. A frame of the gel
/// the rest frame was taken of shares its texture (0.15-0.99 on the
/// calibrated R1.5's renders, noise lowering it); another gel's, or the
/// same gel moved, shares none (at most 0.01 against the R1.5's rest frame
/// mirrored), and read against that rest frame its texture would be added
/// rather than taken away.
pub const MIN_SHARED_TEXTURE: f64 = 0.08;

/// What the segmenter made of one frame.
#[derive(Debug, Clone)]
pub struct Segmentation {
    /// The window it looked at (`S x S x 3`, in [0, 1]).
    pub window: FloatImage,
    /// Per-pixel probabilities (`None` for a blank window).
    pub probabilities: Option<Vec<f32>>,
    /// The kept region and its direction.
    pub tendon: Tendon,
}

impl TendonSegmenter {
    /// Load the segmenter in `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime; 0 = its default).
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let (artifact, net) =
            tactile_onnx::load_network::<SegmenterArtifact>(dir.as_ref(), runtime, threads)?;
        let rest_file = dir.as_ref().join(REST_FILE);
        let rest = match rest_file.exists() {
            true => Some(RestFrame::of(
                &artifact,
                &tactile_core::image_io::load_rgb(&rest_file)?,
            )?),
            false => None,
        };
        Ok(Self {
            artifact,
            net,
            rest,
        })
    }

    /// The sensor's rest frame its directions read shading against, when
    /// its folder has one ([`REST_FILE`]).
    pub fn rest(&self) -> Option<&RestFrame> {
        self.rest.as_ref()
    }

    /// Read directions against `rest` from now on (`None`: each window's
    /// own shading).
    pub fn set_rest(&mut self, rest: Option<RestFrame>) {
        self.rest = rest;
    }

    /// The window whose shading gives the direction of a frame of
    /// `frame_size`: `window` less the rest frame's window (plus one half),
    /// when the segmenter has a rest frame of that size (or of its shape,
    /// scaled alike) whose fine texture the window shares
    /// ([`MIN_SHARED_TEXTURE`]); `None`: the window's own shading.
    pub fn shading_window(
        &self,
        window: &FloatImage,
        frame_size: (usize, usize),
    ) -> Option<FloatImage> {
        let rest = self.rest.as_ref()?;
        // Frames that scale to the same size before the window is cut (the
        // rest frame's size, or the pipeline's working frame of it) share
        // its window.
        let scaled = |(w, h)| self.artifact.model.window().scaled_size(w, h);
        if scaled(frame_size) != scaled((rest.width, rest.height))
            || rest.window.data.len() != window.data.len()
        {
            return None;
        }
        // NaN (a flat window) shares nothing either.
        let shared = tactile_core::metrics::correlation(&detail(window), &rest.detail);
        if shared.is_nan() || shared < MIN_SHARED_TEXTURE {
            return None;
        }
        let mut relative = window.clone();
        for (v, r) in relative.data.iter_mut().zip(&rest.window.data) {
            *v = *v - *r + 0.5;
        }
        Some(relative)
    }

    /// Where the network runs.
    pub fn runtime(&self) -> Runtime {
        self.net.runtime()
    }

    /// Per-pixel probabilities of `n` normalised windows laid end to end,
    /// one `S * S` vector per window.
    pub fn probabilities(&mut self, inputs: &[f32], n: usize) -> Result<Vec<Vec<f32>>> {
        let s = self.artifact.model.side;
        let z = self.net.run([n, 3, s, s], inputs.to_vec())?;
        Ok(z.chunks(s * s)
            .map(|c| c.iter().copied().map(sigmoid).collect())
            .collect())
    }

    /// Segment a window already cut (see
    /// [`UNetConfig::frame_window`](crate::UNetConfig::frame_window)). A blank window (see
    /// [`is_blank`]) gives an empty mask without running the network.
    /// Its direction reads the window's own shading (see
    /// [`Self::segment`]).
    pub fn segment_window(&mut self, window: FloatImage) -> Result<Segmentation> {
        self.segment_window_against(window, None)
    }

    /// [`Self::segment_window`], the direction read from `shading` when
    /// given ([`Self::shading_window`]).
    fn segment_window_against(
        &mut self,
        window: FloatImage,
        shading: Option<FloatImage>,
    ) -> Result<Segmentation> {
        let probabilities = if is_blank(&window) {
            None
        } else {
            let x = self
                .artifact
                .model
                .window_input(&window, &self.artifact.stats)?;
            self.probabilities(&x, 1)?.pop()
        };
        let a = &self.artifact;
        let tendon = crate::postprocess::window_tendon(
            a.model.side,
            probabilities.as_deref(),
            shading.as_ref().unwrap_or(&window),
            a.threshold,
            &a.postprocess,
        )?;
        Ok(Segmentation {
            window,
            probabilities,
            tendon,
        })
    }

    /// Segment the window of an RGB frame of any size: the kept region and
    /// its direction (or why there is none), read against the sensor's
    /// rest frame when the segmenter has one of the frame's size.
    pub fn segment(&mut self, frame: &RgbImage) -> Result<Segmentation> {
        let window = self.artifact.model.frame_window(frame)?;
        let shading = self.shading_window(&window, (frame.width(), frame.height()));
        self.segment_window_against(window, shading)
    }

    /// [`Self::segment`] of a frame file; errors name the file.
    pub fn segment_file(&mut self, path: impl AsRef<Path>) -> Result<Segmentation> {
        let path = path.as_ref();
        let frame = tactile_core::image_io::load_rgb(path)?;
        self.segment(&frame)
            .map_err(|e| tactile_core::Error::image(path, e.to_string()).into())
    }
}

impl RestFrame {
    /// The rest frame `frame` as the segmenter of `artifact` reads it.
    pub fn of(artifact: &SegmenterArtifact, frame: &RgbImage) -> Result<Self> {
        let window = artifact.model.frame_window(frame)?;
        Ok(Self {
            width: frame.width(),
            height: frame.height(),
            detail: detail(&window),
            window,
        })
    }
}

/// A window's fine texture: each value less the mean of its 3 x 3
/// neighbourhood (edges clamped), channel by channel. Not kornia's
/// `box_blur`: it pads with zeros, and the border that leaves is the same
/// in every window, so any two windows would share texture there (another
/// gel's rest frame then passed [`MIN_SHARED_TEXTURE`] in the test).
fn detail(img: &FloatImage) -> Vec<f64> {
    let (w, h, c) = (img.width, img.height, img.channels);
    let at = |u: isize, v: isize, k: usize| {
        let (u, v) = (u.clamp(0, w as isize - 1), v.clamp(0, h as isize - 1));
        img.data[(v as usize * w + u as usize) * c + k]
    };
    let mut out = Vec::with_capacity(img.data.len());
    for v in 0..h as isize {
        for u in 0..w as isize {
            for k in 0..c {
                let mut sum = 0.0;
                for dv in -1..=1 {
                    for du in -1..=1 {
                        sum += at(u + du, v + dv, k);
                    }
                }
                out.push(f64::from(at(u, v, k) - sum / 9.0));
            }
        }
    }
    out
}
