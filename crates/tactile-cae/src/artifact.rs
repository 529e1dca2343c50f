//! A trained autoencoder on disk: `cae.json` (architecture, the
//! preprocessing that makes its pin images, provenance) beside `cae.bpk`.

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_onnx::Exportable;
use tactile_preprocess::PreprocessConfig;
use tactile_preprocess::profile::InputProfile;

use crate::model::{Cae, CaeConfig};

/// Everything needed to rebuild and use a saved autoencoder.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CaeArtifact {
    /// The architecture.
    #[serde(alias = "cae")]
    pub model: CaeConfig,
    /// How a frame becomes the pin image it encodes.
    pub preprocess: PreprocessConfig,
    /// Its training frames' pin profile ([`InputProfile::fit_pins`]):
    /// frames far from it (another sensor, another scale) are named in a
    /// warning by `predict`. Absent in models trained before it (`tactile
    /// train profile` adds it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_profile: Option<InputProfile>,
    /// Free-form provenance: how it was trained, on what, with which result.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl Artifact for CaeArtifact {
    type Model = Cae;
    const KIND: &'static str = "CAE model";
    const CONFIG_FILE: &'static str = "cae.json";
    const WEIGHTS_FILE: &'static str = "cae.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<Cae> {
        self.model.check()?;
        Ok(self.model.init(device))
    }

    fn check(&self, file: &std::path::Path) -> tactile_core::Result<()> {
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        if let Some(p) = &self.input_profile {
            p.validate_reading(true)
                .map_err(|m| tactile_core::Error::Config(format!("{}: {m}", file.display())))?;
        }
        in_config(file, self.preprocess.check())?;
        if self.preprocess.output_px != self.model.input_px {
            return Err(tactile_core::Error::model(
                file,
                format!(
                    "preprocessing makes {0}x{0} pin images, the encoder takes {1}x{1}",
                    self.preprocess.output_px, self.model.input_px
                ),
            ));
        }
        Ok(())
    }
}

impl Exportable for CaeArtifact {
    /// The encoder: `[N, 1, S, S]` pin images -> `[N, F]` features (what
    /// runs at inference; [`crate::export::autoencoder_onnx`] exports the
    /// whole autoencoder).
    fn onnx(&self, model: &Cae) -> tactile_onnx::Result<Vec<u8>> {
        crate::export::encoder_onnx(model, self.model.input_px)
    }
}

/// Measure the pin lattice's orientation on `datasets`' frames (the
/// encoder's training frames) and save it in the encoder folder `dir`'s
/// preprocessing, so frames of a sensor mounted turned are turned back
/// before they are encoded (see [`tactile_preprocess::align`]). The
/// weights are untouched, so the estimators trained on it still match.
/// Returns the alignment and the frames it was measured on.
pub fn add_pin_alignment(
    dir: &std::path::Path,
    datasets: &[tactile_core::dataset::Dataset],
) -> crate::Result<(tactile_preprocess::align::PinAlign, usize)> {
    use rayon::prelude::*;
    // Its config is rewritten: never while another run writes it.
    let _lock = tactile_core::io::FolderLock::of_existing(dir)?;
    let mut artifact = CaeArtifact::read(dir)?;
    let mut angles = Vec::new();
    for ds in datasets {
        ds.expect_kind(tactile_core::dataset::DatasetKind::Tactip)?;
        // One frame at a time per thread: only the angles are kept.
        let measured = (0..ds.len())
            .into_par_iter()
            .map(|i| {
                let frame = ds.load_grey(i, "file")?;
                let path = ds.path_of(i, "file")?;
                tactile_preprocess::align::frame_lattice_angle_deg(&frame, &artifact.preprocess)
                    .map_err(|e| crate::Error::from(e.in_file(path)))
            })
            .collect::<crate::Result<Vec<_>>>()?;
        angles.extend(measured);
    }
    let (align, measured) = tactile_preprocess::align::fit_pin_align_to(&angles)?;
    artifact.preprocess.align = Some(align);
    tactile_core::io::write_json_atomic(dir.join(CaeArtifact::CONFIG_FILE), &artifact)?;
    Ok((align, measured))
}
