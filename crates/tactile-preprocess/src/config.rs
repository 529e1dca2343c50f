//! The TacTip chain's settings ([`PreprocessConfig`]) and its presets:
//! the authors' chain, the lighting-compensated one for raw frames, and
//! the named presets and JSON files a front end passes.

use serde::{Deserialize, Serialize};

use crate::{Error, MAX_WINDOW_PX, Result, align};

/// How uneven illumination is removed before thresholding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum Lighting {
    /// No compensation: the fixed threshold of the authors' lab set-up.
    None {},
    /// Background subtraction by a white top-hat (the frame minus its
    /// morphological opening with a box larger than a pin), then a pixel is
    /// a pin when it reaches `relative_threshold` of the local top-hat
    /// maximum (a box of `peak_window_px`) and that maximum is at least
    /// `min_contrast` grey levels. Gains, gradients and blobs cancel out.
    TopHat {
        /// Side of the opening box (larger than a pin), pixels.
        background_window_px: usize,
        /// Side of the local-maximum box, pixels.
        peak_window_px: usize,
        /// Fraction of the local top-hat maximum a pin pixel reaches.
        relative_threshold: f32,
        /// Smallest local maximum that counts as a pin, grey levels.
        min_contrast: u8,
        /// Box-blur size applied first to tame sensor noise (1 = off).
        denoise_px: usize,
    },
}

/// Every step of the chain; see the presets. An unknown key is refused: a
/// misspelt `mask_radius_px` would otherwise read as no mask at all.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PreprocessConfig {
    /// Illumination compensation.
    pub lighting: Lighting,
    /// Histogram equalisation (authors: on; pointless after top-hat).
    pub equalize: bool,
    /// Fixed binary threshold applied after equalisation (authors: 170);
    /// `None` when the lighting step already produced a binary image.
    pub threshold: Option<u8>,
    /// Radius of the circular mask around the frame centre (authors: 145 px).
    pub mask_radius_px: Option<f32>,
    /// Side of the square morphological opening (authors: 2; 0 = off).
    pub open_px: usize,
    /// Side of a square dilation after the opening (0 = off). A 300 px
    /// frame shrinks 10.7 times to 28 px, so a 7 px pin covers a third of
    /// an output pixel and flickers in and out with sub-pixel motion;
    /// growing pins first keeps each one visible in the pin image.
    #[serde(default)]
    pub grow_px: usize,
    /// Side of the centred square crop (authors: 300).
    pub crop_px: usize,
    /// Side of the output pin image (28).
    pub output_px: usize,
    /// Offset of the final rounding `round(x/255 + offset)` (authors: 0.3).
    pub binarise_offset: f64,
    /// How the crop shrinks to `output_px` (authors: bilinear sampling).
    #[serde(default)]
    pub downsample: Downsample,
    /// Round to {0, 1} (paper A). `false` keeps the grey levels in [0, 1],
    /// which with [`Downsample::Area`] keep each pin's sub-pixel position:
    /// the fraction of an output pixel it covers.
    #[serde(default = "yes")]
    pub binarise: bool,
    /// Turn each frame whose pin lattice (measured on the binary image
    /// after the lighting step and the mask) is turned from the training
    /// frames' back before the chain ([`align`]: a sensor mounted turned);
    /// `None` = off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub align: Option<align::PinAlign>,
}

fn yes() -> bool {
    true
}

/// Shrinking the crop to the pin image.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Downsample {
    /// OpenCV's `INTER_LINEAR` (what the authors ran): samples a 2x2
    /// neighbourhood, so at a 10x shrink most pixels are never read.
    #[default]
    Linear,
    /// Mean over each output pixel's footprint, with fractional coverage at
    /// its borders: every input pixel counts.
    Area,
}

impl PreprocessConfig {
    /// The authors' released chain for their lab frames.
    pub fn paper() -> Self {
        Self {
            lighting: Lighting::None {},
            equalize: true,
            threshold: Some(170),
            mask_radius_px: Some(145.0),
            open_px: 2,
            grow_px: 0,
            crop_px: 300,
            output_px: 28,
            binarise_offset: 0.3,
            downsample: Downsample::Linear,
            binarise: true,
            align: None,
        }
    }

    /// The chain for raw frames with uneven lighting (the virtual TacTip of
    /// `sensors.md`, or a real sensor without a controlled light).
    pub fn lighting_compensated() -> Self {
        Self {
            lighting: Lighting::TopHat {
                background_window_px: 15,
                peak_window_px: 21,
                relative_threshold: 0.5,
                min_contrast: 25,
                denoise_px: 3,
            },
            equalize: false,
            threshold: None,
            mask_radius_px: Some(145.0),
            // No 2x2 opening: with an even kernel OpenCV's (and kornia's)
            // erode-then-dilate moves every pin by one pixel down and right;
            // the 3x3 denoise already removes isolated noise pixels.
            open_px: 0,
            grow_px: 9,
            crop_px: 300,
            output_px: 28,
            binarise_offset: 0.3,
            downsample: Downsample::Linear,
            binarise: true,
            align: None,
        }
    }

    /// Frames that are already binary pin images (the authors' released
    /// shapes set): only crop, resize and binarise.
    pub fn binary_frames() -> Self {
        Self {
            lighting: Lighting::None {},
            equalize: false,
            threshold: None,
            mask_radius_px: None,
            open_px: 0,
            grow_px: 0,
            crop_px: 300,
            output_px: 28,
            binarise_offset: 0.3,
            downsample: Downsample::Linear,
            binarise: true,
            align: None,
        }
    }

    /// Check every size and value against its limit: windows and boxes up
    /// to [`MAX_WINDOW_PX`], the crop up to 8K, the pin image no larger
    /// than the crop, thresholds and offsets finite.
    pub fn check(&self) -> tactile_core::Result<()> {
        let bad = |m: String| Err(tactile_core::Error::Config(format!("preprocessing: {m}")));
        // (name, side, smallest side): 0 turns an opening, a growth or the
        // denoise off, but the top-hat's boxes of no pixels would measure
        // nothing.
        let windows = [("open_px", self.open_px, 0), ("grow_px", self.grow_px, 0)];
        let lighting = match &self.lighting {
            Lighting::None {} => vec![],
            Lighting::TopHat {
                background_window_px,
                peak_window_px,
                relative_threshold,
                denoise_px,
                ..
            } => {
                if !(0.0..=1.0).contains(relative_threshold) {
                    return bad(format!(
                        "relative_threshold {relative_threshold:?} must be in [0, 1]"
                    ));
                }
                vec![
                    ("background_window_px", *background_window_px, 1),
                    ("peak_window_px", *peak_window_px, 1),
                    ("denoise_px", *denoise_px, 0),
                ]
            }
        };
        for (name, v, min) in windows.into_iter().chain(lighting) {
            if v < min {
                return bad(format!(
                    "{name} must be {min} to {MAX_WINDOW_PX} pixels, got {v}"
                ));
            }
            if v > MAX_WINDOW_PX {
                return bad(format!("{name} {v} is larger than {MAX_WINDOW_PX} pixels"));
            }
        }
        if self.crop_px == 0 || self.crop_px > 7680 {
            return bad(format!("crop_px {} must be 1 to 7680", self.crop_px));
        }
        if self.output_px == 0 || self.output_px > self.crop_px {
            return bad(format!(
                "output_px {} must be 1 to the crop ({})",
                self.output_px, self.crop_px
            ));
        }
        // round(x + offset) of x in [0, 1]: outside [-0.5, 0.5] every
        // pixel rounds to one colour.
        if !(-0.5..=0.5).contains(&self.binarise_offset) {
            return bad(format!(
                "binarise_offset {:?} must be in [-0.5, 0.5] (the pin image is round(x + offset) of x in [0, 1]; beyond, every pixel is one colour)",
                self.binarise_offset
            ));
        }
        if let Some(r) = self
            .mask_radius_px
            .filter(|r| !(r.is_finite() && *r >= 1.0))
        {
            return bad(format!(
                "mask_radius_px {r:?} must be a finite radius of at least 1 pixel (or absent: no mask)"
            ));
        }
        if let Some(a) = &self.align {
            a.check()?;
        }
        Ok(())
    }

    /// Why a `width` x `height` frame does not suit this chain, if it does
    /// not: one smaller than the crop is taken whole, so its pins reach the
    /// pin image at another scale than the training frames' did (a frame
    /// of another camera or resolution) and the estimates mean little.
    pub fn frame_mismatch(&self, width: usize, height: usize) -> Option<String> {
        (width.min(height) < self.crop_px).then(|| {
            format!(
                "the frame is {width}x{height}, smaller than the model's {c}x{c} crop: it was \
                 trained on larger frames, so it reads these pins at another scale; give \
                 frames of the sensor and resolution it was trained on",
                c = self.crop_px
            )
        })
    }

    /// Look a preset up by name (`paper`, `lighting-compensated`, `binary`),
    /// or read a whole configuration from a `.json` file.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "paper" => Ok(Self::paper()),
            "lighting-compensated" => Ok(Self::lighting_compensated()),
            "binary" => Ok(Self::binary_frames()),
            path if path.ends_with(".json") => {
                let c: Self = tactile_core::io::read_json(path)?;
                tactile_core::error::in_config(std::path::Path::new(path), c.check())?;
                Ok(c)
            }
            other => Err(Error::UnknownPreset(other.to_string())),
        }
    }
}

/// A preprocessing given by name: a preset's or a JSON file's
/// ([`PreprocessConfig::preset`]), kept with its name for messages and
/// tables (`--preprocess NAME`).
#[derive(Debug, Clone)]
pub struct NamedPreprocess {
    /// The preset's name or the file's path, as given.
    pub name: String,
    /// What it says.
    pub config: PreprocessConfig,
}

impl std::str::FromStr for NamedPreprocess {
    type Err = Error;
    fn from_str(name: &str) -> Result<Self> {
        Ok(Self {
            name: name.to_string(),
            config: PreprocessConfig::preset(name)?,
        })
    }
}

/// Frame sizes already checked against a model's preprocessings
/// ([`PreprocessConfig::frame_mismatch`]): each size is judged once (a
/// folder may mix sizes), and at most [`Self::MAX_SIZES`] of them, so a
/// stream of ever-new sizes does not warn of each.
#[derive(Debug, Default)]
pub struct FrameSizeCheck {
    seen: Vec<(usize, usize)>,
}

impl FrameSizeCheck {
    /// Distinct sizes judged.
    pub const MAX_SIZES: usize = 8;

    /// Why a frame of a size not seen before does not suit one of `cfgs`
    /// (a model's preprocessings: an ensemble's members may differ), if
    /// it does not; `None` for a size already judged.
    pub fn check<'a>(
        &mut self,
        width: usize,
        height: usize,
        cfgs: impl IntoIterator<Item = &'a PreprocessConfig>,
    ) -> Option<String> {
        let size = (width, height);
        if self.seen.contains(&size) || self.seen.len() >= Self::MAX_SIZES {
            return None;
        }
        self.seen.push(size);
        cfgs.into_iter()
            .find_map(|c| c.frame_mismatch(width, height))
    }
}

#[cfg(test)]
mod tests {
    use super::PreprocessConfig;

    #[test]
    fn a_frame_smaller_than_the_crop_is_named_as_another_scale() {
        let c = PreprocessConfig {
            crop_px: 440,
            ..PreprocessConfig::paper()
        };
        assert_eq!(c.frame_mismatch(445, 440), None);
        assert_eq!(c.frame_mismatch(1920, 1080), None);
        let why = c
            .frame_mismatch(640, 360)
            .expect("360 px is below a 440 px crop");
        assert!(why.contains("640x360") && why.contains("440x440"), "{why}");
    }

    #[test]
    fn top_hat_windows_of_no_pixels_are_refused() {
        let top_hat = |bg: usize, peak: usize, denoise: usize| super::PreprocessConfig {
            lighting: super::Lighting::TopHat {
                background_window_px: bg,
                peak_window_px: peak,
                relative_threshold: 0.5,
                min_contrast: 10,
                denoise_px: denoise,
            },
            ..super::PreprocessConfig::lighting_compensated()
        };
        assert!(top_hat(15, 21, 1).check().is_ok());
        // denoise 0 or 1 is "off", as documented.
        assert!(top_hat(15, 21, 0).check().is_ok());
        for (cfg, name) in [
            (top_hat(0, 21, 1), "background_window_px"),
            (top_hat(15, 0, 1), "peak_window_px"),
        ] {
            let e = cfg.check().unwrap_err().to_string();
            assert!(
                e.contains(&format!("{name} must be 1 to 255 pixels, got 0")),
                "{e}"
            );
        }
    }

    /// A preprocessing file is read whole or refused naming its file and
    /// the key: before, a misspelt `mask_radius_px` read as no mask, a key
    /// of another lighting method was dropped, and an offset that makes
    /// every pixel one colour or a mask of no pixels were taken.
    #[test]
    fn a_preprocessing_file_with_a_stray_key_or_a_useless_value_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("pre.json");
        let read = |text: &str| {
            std::fs::write(&file, text).unwrap();
            PreprocessConfig::preset(file.to_str().unwrap())
        };
        let good = r#"{"lighting": {"method": "none"}, "equalize": false, "threshold": null,
            "mask_radius_px": 100.0, "open_px": 0, "grow_px": 5, "crop_px": 256,
            "output_px": 28, "binarise_offset": 0.3}"#;
        assert_eq!(read(good).unwrap().mask_radius_px, Some(100.0));
        for (edit, want) in [
            (
                good.replace("mask_radius_px", "mask_radius"),
                "unknown field `mask_radius`",
            ),
            (
                good.replace(
                    r#""method": "none""#,
                    r#""method": "none", "background_window_px": 15"#,
                ),
                "unknown field `background_window_px`",
            ),
            (
                good.replace("0.3}", "1e300}"),
                "binarise_offset 1e300 must be in [-0.5, 0.5]",
            ),
            (
                good.replace("100.0", "1e-30"),
                "mask_radius_px 1e-30 must be a finite radius of at least 1 pixel",
            ),
        ] {
            let e = read(&edit).unwrap_err().to_string();
            assert!(e.contains("pre.json") && e.contains(want), "{want}: {e}");
        }
    }

    #[test]
    fn each_frame_size_is_judged_once() {
        let c = PreprocessConfig {
            crop_px: 440,
            ..PreprocessConfig::paper()
        };
        let mut check = super::FrameSizeCheck::default();
        assert!(check.check(640, 360, [&c]).is_some());
        assert_eq!(check.check(640, 360, [&c]), None, "already judged");
        assert_eq!(check.check(445, 440, [&c]), None, "fits the crop");
        assert!(check.check(320, 240, [&c]).is_some(), "another size");
    }
}
