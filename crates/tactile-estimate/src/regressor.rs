//! A shallow MLP regressor on feature vectors (paper A's pose, depth and
//! force estimators), predicting several targets at once from one vector.
//! Inputs and linear targets are standardised with training statistics
//! saved beside the weights; angle targets are regressed as sin/cos.

use std::path::Path;

use burn::config::Config;
use burn::tensor::Device;
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_burn::nn::RegressionLoss;
use tactile_burn::train::Schedule;

use crate::head::check_features;
use crate::mlp::{Activation, Mlp, fit_in_memory, matrix};
use crate::target::{Target, TargetKind};
use crate::{Error, Result};

/// Architecture and training of a regressor.
#[derive(Config, Debug, PartialEq)]
pub struct RegressorConfig {
    /// Feature count.
    pub inputs: usize,
    /// What it predicts, in output order.
    pub targets: Vec<Target>,
    /// Hidden layers (the authors' force head: 16 -> 32 -> 16 -> 1).
    #[config(default = "vec![(32, Activation::Relu), (16, Activation::Relu)]")]
    pub hidden: Vec<(usize, Activation)>,
    /// Adam's schedule; early stopping on the validation MSE.
    #[config(default = "Schedule::new(64, 2000, 100, 1e-3).with_seed(7)")]
    pub schedule: Schedule,
    /// The loss on the standardised outputs, in training and for early
    /// stopping (`None`: mean squared error, as regressors saved before
    /// this option were trained).
    #[config(default = "None")]
    pub loss: Option<RegressionLoss>,
}

impl RegressorConfig {
    /// Network outputs (an angle takes two).
    fn outputs(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }
}

/// Per-column standardisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scaler {
    /// Column means.
    pub mean: Vec<f64>,
    /// Column standard deviations (never 0).
    pub std: Vec<f64>,
}

impl Scaler {
    /// Means and deviations of the columns of `rows`.
    pub fn fit(rows: &[Vec<f64>]) -> Self {
        let k = rows.first().map_or(0, Vec::len);
        let n = rows.len().max(1) as f64;
        let mean: Vec<f64> = (0..k)
            .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / n)
            .collect();
        let std = tactile_core::metrics::safe_scales(
            (0..k).map(|j| (rows.iter().map(|r| (r[j] - mean[j]).powi(2)).sum::<f64>() / n).sqrt()),
        );
        Self { mean, std }
    }

    /// `rows` standardised, row-major.
    pub fn apply(&self, rows: &[Vec<f64>]) -> Vec<f32> {
        rows.iter()
            .flat_map(|r| {
                r.iter()
                    .zip(&self.mean)
                    .zip(&self.std)
                    .map(|((v, m), s)| ((v - m) / s) as f32)
            })
            .collect()
    }

    /// One standardised row back in its columns' own units.
    pub fn unscale(&self, row: &[f32]) -> Vec<f64> {
        row.iter()
            .zip(&self.mean)
            .zip(&self.std)
            .map(|((v, mu), s)| *v as f64 * s + mu)
            .collect()
    }
}

/// A regressor on disk: `regressor.json` (config and both scalers) beside
/// `regressor.bpk`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RegressorArtifact {
    /// Architecture and training.
    #[serde(alias = "config")]
    pub model: RegressorConfig,
    /// Feature standardisation.
    pub inputs: Scaler,
    /// Output standardisation (identity on sin/cos columns).
    pub outputs: Scaler,
    /// Fingerprint of the encoder whose features it was trained on; `None`
    /// for features read from a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub encoder: Option<String>,
    /// The contact shapes it was trained on, when only some (a sphere's
    /// position, say): its estimates are for frames of those shapes, and
    /// beside a shape head they replace the other regressors' on the
    /// frames the head puts in them (see `Estimators::estimate`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shapes: Vec<String>,
}

impl Artifact for RegressorArtifact {
    type Model = Mlp;
    const KIND: &'static str = "regressor";
    const CONFIG_FILE: &'static str = "regressor.json";
    const WEIGHTS_FILE: &'static str = "regressor.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<Mlp> {
        let m = &self.model;
        crate::mlp::check_sizes(m.inputs, &m.hidden, m.outputs())?;
        Ok(Mlp::with_hidden(m.inputs, &m.hidden, m.outputs(), device))
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::error::in_config;
        let m = &self.model;
        in_config(
            file,
            crate::mlp::check_sizes(m.inputs, &m.hidden, m.outputs()),
        )?;
        in_config(
            file,
            crate::mlp::check_scaler(
                "feature scaling",
                &self.inputs.mean,
                &self.inputs.std,
                m.inputs,
            ),
        )?;
        in_config(
            file,
            crate::mlp::check_scaler(
                "target scaling",
                &self.outputs.mean,
                &self.outputs.std,
                m.outputs(),
            ),
        )
    }
}

/// A trained regressor.
pub struct Regressor {
    /// Config and scalers.
    pub artifact: RegressorArtifact,
    /// The network.
    pub mlp: Mlp,
    /// Where it runs.
    pub device: Device,
}

fn to64(v: &[Vec<f32>]) -> Vec<Vec<f64>> {
    v.iter()
        .map(|r| r.iter().map(|&a| a as f64).collect())
        .collect()
}

/// Encode label rows (one value per target) into network columns.
pub fn encode(targets: &[Target], y: &[Vec<f64>]) -> Vec<Vec<f64>> {
    y.iter()
        .map(|r| {
            targets
                .iter()
                .zip(r)
                .flat_map(|(t, v)| t.encode(*v))
                .collect()
        })
        .collect()
}

/// The output standardisation of encoded target columns: linear columns
/// standardised, sin/cos columns left on the unit circle.
pub fn output_scaler(targets: &[Target], encoded: &[Vec<f64>]) -> Scaler {
    let mut outputs = Scaler::fit(encoded);
    let mut col = 0;
    for t in targets {
        if let TargetKind::Angle { .. } = t.kind {
            outputs.mean[col..col + 2].copy_from_slice(&[0.0, 0.0]);
            outputs.std[col..col + 2].copy_from_slice(&[1.0, 1.0]);
        }
        col += t.width();
    }
    outputs
}

/// One network output row (standardised columns) back to one value per
/// target, in the labels' units.
pub fn decode(targets: &[Target], outputs: &Scaler, row: &[f32]) -> Vec<f64> {
    decode_columns(targets, &outputs.unscale(row))
}

/// Encoded columns, in their own units (an angle's cos/sin pair), to one
/// value per target in the labels' units.
pub fn decode_columns(targets: &[Target], cols: &[f64]) -> Vec<f64> {
    let mut at = 0;
    targets
        .iter()
        .map(|t| {
            let v = t.decode(&cols[at..(at + t.width()).min(cols.len())]);
            at += t.width();
            v
        })
        .collect()
}

impl Regressor {
    /// Load a regressor folder.
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let l = RegressorArtifact::load(dir.as_ref(), device)?;
        Ok(Self {
            artifact: l.artifact,
            mlp: l.model,
            device: l.device,
        })
    }

    /// Save into `dir`.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<()> {
        Ok(self.artifact.save(&self.mlp, dir.as_ref())?)
    }

    /// The targets, in column order.
    pub fn targets(&self) -> &[Target] {
        &self.artifact.model.targets
    }

    /// Train on `(x, y)`, early-stopping on the loss (mean squared error
    /// unless the config says otherwise) of `val`;
    /// `y` rows hold one value per target, in `config.targets` order.
    pub fn train(
        config: RegressorConfig,
        (x, y): (&[Vec<f32>], &[Vec<f64>]),
        (val_x, val_y): (&[Vec<f32>], &[Vec<f64>]),
        device: &Device,
    ) -> Result<Self> {
        if x.is_empty() || val_x.is_empty() {
            return Err(Error::TooFewSamples(
                "regressor needs training and validation samples".into(),
            ));
        }
        if x.len() != y.len() || val_x.len() != val_y.len() {
            return Err(tactile_core::Error::Invalid(
                "as many label rows as feature vectors are needed".into(),
            )
            .into());
        }
        check_features(x, config.inputs)?;
        check_features(val_x, config.inputs)?;
        config.schedule.check()?;
        crate::mlp::check_sizes(config.inputs, &config.hidden, config.outputs())?;
        let nt = config.targets.len();
        if let Some(bad) = y.iter().chain(val_y).find(|r| r.len() != nt) {
            return Err(tactile_core::Error::shape("label row", nt, bad.len()).into());
        }
        let (x64, vx64) = (to64(x), to64(val_x));
        let inputs = Scaler::fit(&x64);
        let (ey, evy) = (encode(&config.targets, y), encode(&config.targets, val_y));
        let outputs = output_scaler(&config.targets, &ey);
        let (k, m) = (config.inputs, config.outputs());
        let ad = device.clone().autodiff();
        ad.seed(config.schedule.seed);
        let artifact = RegressorArtifact {
            model: config,
            inputs,
            outputs,
            encoder: None,
            shapes: Vec::new(),
        };
        let mlp = artifact.init(&ad)?;
        let xt = matrix(x.len(), k, artifact.inputs.apply(&x64), &ad);
        let yt = matrix(x.len(), m, artifact.outputs.apply(&ey), &ad);
        let vx = matrix(val_x.len(), k, artifact.inputs.apply(&vx64), device);
        let vy = matrix(val_x.len(), m, artifact.outputs.apply(&evy), device);
        let loss = artifact.model.loss.unwrap_or_default();
        let mlp = fit_in_memory(
            &artifact.model.schedule,
            mlp,
            x.len(),
            |mlp, bi| {
                let pred = mlp.forward(xt.clone().select(0, bi.clone()));
                loss.penalty(pred - yt.clone().select(0, bi)).mean()
            },
            |v| {
                let vl: f32 = loss
                    .penalty(v.forward(vx.clone()) - vy.clone())
                    .mean()
                    .into_scalar();
                Ok(tactile_burn::train::ensure_finite(
                    "the regressor's validation loss",
                    vl as f64,
                )?)
            },
            &ad,
        )?;
        Ok(Self {
            artifact,
            mlp,
            device: device.clone(),
        })
    }

    /// Predictions, one row of target values per feature vector.
    pub fn predict(&self, x: &[Vec<f32>]) -> Result<Vec<Vec<f64>>> {
        let targets = &self.artifact.model.targets;
        Ok(self
            .predict_columns(x)?
            .iter()
            .map(|cols| decode_columns(targets, cols))
            .collect())
    }

    /// The network's outputs per feature vector in their own units, before
    /// decoding (an angle's cos/sin pair): what an ensemble averages, so
    /// that angles are averaged on the circle.
    pub fn predict_columns(&self, x: &[Vec<f32>]) -> Result<Vec<Vec<f64>>> {
        let a = &self.artifact;
        check_features(x, a.model.inputs)?;
        if x.is_empty() {
            return Ok(Vec::new());
        }
        let m = a.model.outputs();
        let out = self
            .mlp
            .forward(matrix(
                x.len(),
                a.model.inputs,
                a.inputs.apply(&to64(x)),
                &self.device,
            ))
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .map_err(|e| tactile_core::Error::Invalid(format!("reading predictions: {e:?}")))?;
        Ok(out.chunks(m).map(|r| a.outputs.unscale(r)).collect())
    }

    /// Mean absolute error per target on `(x, y)`.
    pub fn evaluate(&self, x: &[Vec<f32>], y: &[Vec<f64>]) -> Result<Vec<f64>> {
        Ok(target_mae(self.targets(), &self.predict(x)?, y))
    }
}

/// Mean absolute error per target of prediction rows against label rows,
/// in the labels' units (angles on their circle).
pub fn target_mae(targets: &[Target], pred: &[Vec<f64>], y: &[Vec<f64>]) -> Vec<f64> {
    targets
        .iter()
        .enumerate()
        .map(|(j, t)| {
            let p: Vec<f64> = pred.iter().map(|r| r[j]).collect();
            let tr: Vec<f64> = y.iter().map(|r| r[j]).collect();
            t.mae(&p, &tr)
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use tactile_burn::DeviceKind;

    /// `y = (2 x0 - x1, angle 40 x2 degrees)` with small noise-free structure.
    pub(crate) fn data(n: usize, offset: usize) -> (Vec<Vec<f32>>, Vec<Vec<f64>>) {
        (0..n)
            .map(|i| {
                let k = (i + offset) as f64;
                let x = [(k * 0.37).sin(), (k * 0.11).cos(), ((k * 0.53).sin() * 2.0)];
                (
                    x.iter().map(|&v| v as f32).collect(),
                    vec![2.0 * x[0] - x[1], 40.0 * x[2]],
                )
            })
            .unzip()
    }

    #[test]
    fn learns_a_line_and_an_angle_and_round_trips() {
        let dev = DeviceKind::Flex.device();
        let cfg = RegressorConfig::new(
            3,
            vec![Target::linear("a"), Target::angle("theta_deg", 180.0)],
        )
        .with_schedule(Schedule::new(64, 300, 40, 1e-3).with_seed(7));
        let (x, y) = data(400, 0);
        let (vx, vy) = data(100, 1000);
        let r = Regressor::train(cfg, (&x, &y), (&vx, &vy), &dev).unwrap();
        let (tx, ty) = data(100, 5000);
        let err = r.evaluate(&tx, &ty).unwrap();
        // Spread of the targets: a about 1.1, theta about 57 degrees.
        assert!(err[0] < 0.15 && err[1] < 6.0, "{err:?}");
        let dir = tempfile::tempdir().unwrap();
        r.save(dir.path()).unwrap();
        let back = Regressor::load(dir.path(), &dev).unwrap();
        assert_eq!(back.predict(&tx).unwrap(), r.predict(&tx).unwrap());
    }

    #[test]
    fn an_l1_regressor_is_not_pulled_by_a_few_wild_labels() {
        // One label in ten is off by +8 (a spread of about 1.1): MSE fits
        // their mean and shifts every estimate; L1 fits the median and
        // stays on the clean line.
        let dev = DeviceKind::Flex.device();
        let (x, mut y) = data(400, 0);
        let (vx, mut vy) = data(100, 1000);
        for row in y.iter_mut().step_by(10).chain(vy.iter_mut().step_by(10)) {
            row[0] += 8.0;
        }
        let (tx, ty) = data(100, 5000);
        let fit = |loss| {
            let cfg = RegressorConfig::new(3, vec![Target::linear("a"), Target::linear("b")])
                .with_schedule(Schedule::new(64, 300, 40, 1e-3).with_seed(7))
                .with_loss(loss);
            let r = Regressor::train(cfg, (&x, &y), (&vx, &vy), &dev).unwrap();
            r.evaluate(&tx, &ty).unwrap()[0]
        };
        let (mse, l1) = (fit(None), fit(Some(RegressionLoss::L1)));
        assert!(l1 < 0.25 && l1 < 0.6 * mse, "L1 {l1}, MSE {mse}");
    }
}
