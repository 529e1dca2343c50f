//! A calibrated sensor's own reconstruction as the depth network's
//! starting point. The calibration (`tactile calibrate ball`) is fitted on
//! the real sensor's frames, so its photometric reconstruction carries
//! over to them; a network trained on renders alone does not (its
//! indentation stopped at 1.15 mm on real 1.88 mm ball presses). A network
//! with a prior takes the reconstruction, in model units, as a fourth
//! channel and adds its output to it: it learns a correction where the
//! renders show the photometric solve is wrong (a tendon's sharp edges,
//! the gel's spread), and starts from the calibration everywhere else.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::Runtime;
use tactile_core::image_io::RgbImage;
use tactile_gelsight::{IndentationMap, Reconstructor};

use crate::Result;

/// Where a depth network's prior comes from, as saved in `depth.json`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct CalibrationPrior {
    /// The calibration folder, relative to the depth network's folder
    /// (`..` when the network sits in the calibration's `depth/`, the
    /// documented layout) or absolute.
    pub calibration: String,
}

impl CalibrationPrior {
    /// The prior of a network saved in `out` whose calibration is in
    /// `calibration`: `..` when that is `out`'s parent, so the pair can be
    /// moved together; the absolute path otherwise.
    pub fn of(calibration: &Path, out: &Path) -> Self {
        let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let (c, o) = (abs(calibration), abs(out));
        let beside = o.parent().is_some_and(|p| p == c);
        Self {
            calibration: if beside {
                "..".into()
            } else {
                c.display().to_string()
            },
        }
    }

    /// The calibration folder of a network in `dir`.
    pub fn folder(&self, dir: &Path) -> PathBuf {
        dir.join(&self.calibration)
    }
}

/// A warning when `data` was rendered from the calibration of another
/// sensor than `dir`'s (its manifest's `calibration`, as `tactile synth
/// gelsight` writes it): a network with that prior would learn to correct
/// another sensor's reconstruction of these frames. The same folder, or a
/// calibration of a sensor of the same name (one recalibrated), says
/// nothing; so does a dataset that names no calibration.
pub fn other_sensor_warning(data: &tactile_core::dataset::Dataset, dir: &Path) -> Option<String> {
    let rendered = data.manifest.extra.get("calibration")?;
    let folder = rendered.get("folder")?.as_str()?;
    let canonical = |p: &Path| std::fs::canonicalize(p).ok();
    if canonical(Path::new(folder)).is_some_and(|f| Some(f) == canonical(dir)) {
        return None;
    }
    let theirs = rendered.get("sensor")?.as_str()?;
    let ours = tactile_gelsight::render_model::rendered_sensor(dir)?;
    (theirs != ours).then(|| {
        format!(
            "{}: these frames were rendered from the calibration of {theirs:?} ({folder}), and the prior is the calibration of {ours:?} ({}): a network would learn to correct another sensor's reconstruction of them; give --prior-calibration the calibration they were rendered from",
            data.root.join("manifest.json").display(),
            dir.display()
        )
    })
}

/// The calibration's reconstruction at a depth network's input size.
pub struct PriorSource {
    reconstructor: Reconstructor,
}

impl std::fmt::Debug for PriorSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PriorSource({:?})", self.reconstructor)
    }
}

impl PriorSource {
    /// Load the calibration in `dir` onto `runtime`.
    pub fn load(dir: &Path, runtime: Runtime, threads: usize) -> Result<Self> {
        Ok(Self {
            reconstructor: Reconstructor::load(dir, runtime, threads)?,
        })
    }

    /// The reconstruction of `frame` (`path` names it in errors) in mm at
    /// `size`.
    pub fn prior_mm(
        &mut self,
        frame: &RgbImage,
        path: &Path,
        size: [usize; 2],
    ) -> Result<Vec<f32>> {
        map_at(&self.reconstructor.reconstruct(frame, path)?, size)
    }
}

/// An indentation map (metres, the frame's size) in mm at `[w, h]`, area
/// averaged as the training depth maps are.
pub fn map_at(map: &IndentationMap, [w, h]: [usize; 2]) -> Result<Vec<f32>> {
    crate::data::depth_m_to_mm(&map.indentation_m, (map.width, map.height), w, h)
        .map_err(Into::into)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DenseNetConfig, DepthNetConfig};
    use burn::nn::Initializer;
    use burn::nn::conv::Conv2dConfig;
    use burn::tensor::{Device, Distribution, Tensor};

    #[test]
    fn a_network_beside_its_calibration_finds_it_after_a_move() {
        let tmp = std::env::temp_dir().join(format!("prior-of-{}", std::process::id()));
        let p = CalibrationPrior::of(&tmp, &tmp.join("depth"));
        assert_eq!(p.calibration, "..");
        let moved = Path::new("/elsewhere/sensor/depth");
        assert_eq!(p.folder(moved), Path::new("/elsewhere/sensor/depth/.."));
        let far = CalibrationPrior::of(&tmp, Path::new("/other/depth"));
        assert_eq!(
            Path::new(&far.calibration),
            std::path::absolute(&tmp).unwrap()
        );
    }

    #[test]
    fn a_network_with_a_prior_adds_its_correction_to_the_fourth_channel() {
        let device = Device::flex();
        let cfg = DepthNetConfig::new(DenseNetConfig::preset("tiny").unwrap(), [64, 32])
            .with_in_channels(4)
            .with_residual_channel(Some(3))
            .with_decoder_width(16);
        let mut net = cfg.init(&device).unwrap();
        // A head that corrects nothing: the output is the prior itself.
        net.head = vec![
            Conv2dConfig::new([8, 1], [1, 1])
                .with_initializer(Initializer::Zeros)
                .init(&device),
        ];
        let x = Tensor::<4>::random([2, 4, 32, 64], Distribution::Normal(0.0, 1.0), &device);
        let prior = x
            .clone()
            .narrow(1, 3, 1)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        let y = net.forward(x).into_data().try_to_vec::<f32>().unwrap();
        assert_eq!(y.len(), prior.len());
        assert!(y.iter().zip(&prior).all(|(a, b)| (a - b).abs() < 1e-6));
        // Only the fourth channel of a four-channel network can be one.
        let bad = cfg.clone().with_residual_channel(Some(1));
        assert!(bad.check().is_err());
        assert!(cfg.with_in_channels(3).check().is_err());
    }
}
