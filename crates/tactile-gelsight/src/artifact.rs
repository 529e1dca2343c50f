//! A calibrated sensor on disk: `gelsight.json` (the network's shape, the
//! working grid, the ball and scale it was calibrated with) beside
//! `gelsight.bpk` and the background it was calibrated against
//! (`background.png`), so a model folder reconstructs on its own.

use std::path::Path;

use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_onnx::{Exportable, export_batch_dynamic};

use crate::layout::SensorInfo;
use crate::model::{GradientNet, GradientNetConfig};
use crate::prepare::{FEATURES, WorkingGrid};

/// The background's file in a model folder.
pub const BACKGROUND_FILE: &str = tactile_core::io::MODEL_BACKGROUND_FILE;

/// Everything needed to rebuild and run a calibrated sensor model.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GelsightArtifact {
    /// The network.
    pub model: GradientNetConfig,
    /// Frame size and working resolution.
    pub grid: WorkingGrid,
    /// Ball and scale of the calibration.
    pub sensor: SensorInfo,
    /// Slopes integrated only where the colour change shows contact
    /// (`None`: everywhere).
    #[serde(default)]
    pub contact_gate: Option<crate::inference::ContactGate>,
    /// Provenance.
    #[serde(default)]
    pub notes: serde_json::Value,
}

impl Artifact for GelsightArtifact {
    type Model = GradientNet;
    const KIND: &'static str = "calibrated sensor model";
    const CONFIG_FILE: &'static str = "gelsight.json";
    const WEIGHTS_FILE: &'static str = "gelsight.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<GradientNet> {
        self.model.init(device)
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        in_config(file, self.grid.check())?;
        in_config(file, self.sensor.check_config())?;
        if let Some(g) = &self.contact_gate {
            in_config(file, g.check())?;
        }
        Ok(())
    }
}

impl Exportable for GelsightArtifact {
    /// `[N, 8, h, w]` working features -> `[N, 2, h, w]` slopes (mm per mm).
    fn onnx(&self, model: &GradientNet) -> tactile_onnx::Result<Vec<u8>> {
        let (w, h) = (self.grid.width(), self.grid.height());
        export_batch_dynamic(model, [1, FEATURES, h, w], |m: &GradientNet, x| {
            m.forward(x)
        })
    }
}
