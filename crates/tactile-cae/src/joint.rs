//! Semi-supervised training of the autoencoder: besides reconstructing
//! its input, the encoder's features feed a small head that predicts label
//! columns, so the features keep what those labels need. Paper A's encoder
//! learns its features unsupervised; on the real edge set its 16 features
//! lose most of the edge pose (an MLP on them is 2x the error of one on the
//! raw pixels). Only the autoencoder is saved: estimators are then trained
//! on its features as for any encoder, so "one encoder, many cheap heads"
//! still holds.

use burn::config::Config;
use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Tensor, TensorData};
use tactile_burn::nn::RegressionLoss;
use tactile_core::dataset::Dataset;
use tactile_estimate::Target;
use tactile_estimate::regressor::{Scaler, encode, output_scaler};

use crate::model::{Cae, hwc_flatten};

/// Widest head accepted.
pub const MAX_HEAD_HIDDEN: usize = 4096;

/// What the features are also trained to predict.
#[derive(Config, Debug, PartialEq)]
pub struct JointTargets {
    /// Label columns the head predicts (an angle takes two columns).
    pub targets: Vec<Target>,
    /// Weight of the head's loss (on standardised columns) beside the
    /// reconstruction's binary cross-entropy.
    #[config(default = 1.0)]
    pub weight: f64,
    /// The head's loss (`None`: mean squared error, as configs written
    /// before this option were trained).
    #[config(default = "None")]
    pub loss: Option<RegressionLoss>,
    /// Hidden units of the head (one ReLU layer).
    #[config(default = 64)]
    pub hidden: usize,
}

impl JointTargets {
    /// Check every value before anything is allocated.
    pub fn check(&self) -> tactile_core::Result<()> {
        let bad = |m: String| Err(tactile_core::Error::Config(m));
        if self.targets.is_empty() || self.targets.len() > 32 {
            return bad(format!(
                "joint training: 1 to 32 targets, got {}",
                self.targets.len()
            ));
        }
        if !(self.weight.is_finite() && self.weight > 0.0 && self.weight <= 1e3) {
            return bad(format!(
                "joint training: the head's weight must be in (0, 1000], got {:?}",
                self.weight
            ));
        }
        if self.hidden == 0 || self.hidden > MAX_HEAD_HIDDEN {
            return bad(format!(
                "joint training: the head's hidden width must be 1 to {MAX_HEAD_HIDDEN}, got {}",
                self.hidden
            ));
        }
        Ok(())
    }

    /// Joint training on the targets named as `NAME` or `NAME:PERIOD`
    /// (checked); `None` when no name is given.
    pub fn from_names(
        names: &[String],
        weight: f64,
        hidden: usize,
        loss: RegressionLoss,
    ) -> crate::Result<Option<Self>> {
        if names.is_empty() {
            return Ok(None);
        }
        let targets = names
            .iter()
            .map(|t| Target::parse(t).map_err(|e| tactile_core::Error::Config(e.to_string())))
            .collect::<tactile_core::Result<Vec<_>>>()?;
        let j = Self::new(targets)
            .with_weight(weight)
            .with_hidden(hidden)
            .with_loss(Some(loss));
        j.check()?;
        Ok(Some(j))
    }

    /// The head's loss (mean squared error when the config names none).
    pub fn head_loss(&self) -> RegressionLoss {
        self.loss.unwrap_or_default()
    }

    /// What training minimises, for the curves' title.
    pub fn describe(&self) -> String {
        format!(
            "binary cross-entropy + {} x the head's {}",
            self.weight,
            self.head_loss().name()
        )
    }

    /// Network columns of the targets.
    pub fn columns(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }
}

/// The autoencoder with a head on its features per task that has joint
/// targets (none: reconstruction only).
#[derive(Module, Debug)]
pub struct JointCae {
    /// The autoencoder (what is saved).
    pub cae: Cae,
    /// Per head, features to hidden units, hidden units to standardised
    /// columns.
    pub heads: Vec<(Linear, Linear)>,
}

impl JointCae {
    /// `cae` with a fresh head for each of `joints` on its `features`.
    pub fn new(cae: Cae, joints: &[&JointTargets], features: usize, device: &Device) -> Self {
        let heads = joints
            .iter()
            .map(|j| {
                (
                    LinearConfig::new(features, j.hidden).init(device),
                    LinearConfig::new(j.hidden, j.columns()).init(device),
                )
            })
            .collect();
        Self { cae, heads }
    }

    /// Reconstruction logits and each head's standardised columns.
    ///
    /// # Shapes
    /// - `x`: `[N, 1, 28, 28]`
    /// - output: `[N, 1, 28, 28]` and, per head, `[N, K]`
    pub fn forward(&self, x: Tensor<4>) -> (Tensor<4>, Vec<Tensor<2>>) {
        let z = self.cae.encoder.latent(x);
        let columns = if self.heads.is_empty() {
            Vec::new()
        } else {
            let flat = hwc_flatten(z.clone());
            self.heads
                .iter()
                .map(|(a, b)| b.forward(relu(a.forward(flat.clone()))))
                .collect()
        };
        (self.cae.decoder.forward_latent(z), columns)
    }
}

/// Standardised label columns of every row of a dataset (`None` where a
/// target is unlabelled), with the scaler fitted on `fit_rows`.
pub struct JointLabels {
    /// Per dataset row.
    pub columns: Vec<Option<Vec<f32>>>,
    /// The standardisation.
    pub scaler: Scaler,
    /// A warning for each target one value labels on every fitted row
    /// ([`tactile_estimate::target::unvarying_targets`]).
    pub warnings: Vec<String>,
}

impl JointLabels {
    /// Read and standardise `joint`'s targets.
    pub fn read(ds: &Dataset, joint: &JointTargets, fit_rows: &[usize]) -> crate::Result<Self> {
        let mut raw = Vec::with_capacity(ds.len());
        for i in 0..ds.len() {
            let row: Vec<Option<f64>> = joint
                .targets
                .iter()
                .map(|t| ds.target_opt(i, &t.name))
                .collect::<tactile_core::Result<_>>()?;
            raw.push(
                row.into_iter()
                    .map(|v| v.filter(|v| v.is_finite()))
                    .collect::<Option<Vec<f64>>>(),
            );
        }
        let fit: Vec<Vec<f64>> = fit_rows.iter().filter_map(|&i| raw[i].clone()).collect();
        if fit.is_empty() {
            return Err(tactile_core::Error::dataset(
                ds.labels_path(),
                None,
                format!(
                    "joint training: no training row has every target labelled ({})",
                    joint
                        .targets
                        .iter()
                        .map(|t| t.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
            .into());
        }
        let scaler = output_scaler(&joint.targets, &encode(&joint.targets, &fit));
        let warnings = tactile_estimate::target::unvarying_targets(
            &joint.targets,
            &fit,
            &ds.labels_path().display().to_string(),
        );
        let columns = raw
            .into_iter()
            .map(|r| r.map(|r| scaler.apply(&encode(&joint.targets, &[r]))))
            .collect();
        Ok(Self {
            columns,
            scaler,
            warnings,
        })
    }

    /// These labels as rows `offset..` of `total` rows, the others
    /// unlabelled (a dataset's rows among several datasets').
    pub fn placed(mut self, offset: usize, total: usize) -> Self {
        let mut columns = vec![None; offset];
        columns.append(&mut self.columns);
        columns.resize(total.max(columns.len()), None);
        Self { columns, ..self }
    }

    /// How many of `rows` are labelled.
    pub fn labelled(&self, rows: &[usize]) -> usize {
        rows.iter().filter(|&&i| self.columns[i].is_some()).count()
    }

    /// Mean `loss` of `predicted` columns against the labels of `rows`
    /// (unlabelled rows count for nothing).
    pub fn loss(&self, predicted: Tensor<2>, rows: &[usize], loss: RegressionLoss) -> Tensor<1> {
        let device = predicted.device();
        let [n, k] = predicted.dims();
        let (mut y, mut mask) = (Vec::with_capacity(n * k), Vec::with_capacity(n));
        for &i in rows {
            match &self.columns[i] {
                Some(c) => {
                    y.extend_from_slice(c);
                    mask.push(1.0f32);
                }
                None => {
                    y.extend(std::iter::repeat_n(0.0, k));
                    mask.push(0.0);
                }
            }
        }
        let labelled = mask.iter().sum::<f32>().max(1.0);
        let y = Tensor::<2>::from_data(TensorData::new(y, [n, k]), &device);
        let mask = Tensor::<2>::from_data(TensorData::new(mask, [n, 1]), &device);
        (loss.penalty(predicted - y) * mask).sum() / (labelled * k as f32)
    }
}

/// The command-line flags of joint training.
#[derive(clap::Args, serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct JointArgs {
    /// Semi-supervised: also train the features to predict these label columns through a small head, e.g. x_mm,theta_deg:180,depth_mm (only the autoencoder is saved).
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub joint_targets: Vec<String>,
    /// Weight of the head's loss beside the reconstruction's.
    #[arg(long, default_value_t = JointTargets::new(vec![]).weight)]
    pub joint_weight: f64,
    /// Hidden units of the joint head.
    #[arg(long, default_value_t = JointTargets::new(vec![]).hidden)]
    pub joint_hidden: usize,
    /// The joint head's loss on the standardised columns.
    #[arg(long, value_enum, default_value_t = RegressionLoss::Mse)]
    pub joint_loss: RegressionLoss,
}

impl JointArgs {
    /// Refuse a head setting that nothing would use: without targets
    /// (here or in further datasets, `heads_elsewhere`) there is no head,
    /// and a weight, width or loss given for it would be ignored.
    pub fn check_used(&self, heads_elsewhere: bool) -> crate::Result<()> {
        let default = JointTargets::new(Vec::new());
        let unused = [
            (self.joint_weight != default.weight, "joint_weight"),
            (self.joint_hidden != default.hidden, "joint_hidden"),
            (self.joint_loss != RegressionLoss::Mse, "joint_loss"),
        ]
        .into_iter()
        .filter_map(|(given, name)| given.then_some(name))
        .collect::<Vec<_>>();
        if self.joint_targets.is_empty() && !heads_elsewhere && !unused.is_empty() {
            return Err(tactile_core::Error::Config(format!(
                "{} set the joint head, and no joint_targets (nor also_tasks) ask for one: \
                 give joint_targets too, or leave them out",
                unused.join(", ")
            ))
            .into());
        }
        Ok(())
    }

    /// `None` without `--joint-targets`.
    pub fn config(&self) -> crate::Result<Option<JointTargets>> {
        JointTargets::from_names(
            &self.joint_targets,
            self.joint_weight,
            self.joint_hidden,
            self.joint_loss,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unlabelled_rows_count_for_nothing_and_values_are_checked() {
        let device = Device::flex();
        let labels = JointLabels {
            columns: vec![Some(vec![0.0, 0.0]), None, Some(vec![1.0, 1.0])],
            scaler: Scaler {
                mean: vec![0.0; 2],
                std: vec![1.0; 2],
            },
            warnings: Vec::new(),
        };
        let pred = Tensor::<2>::from_data(
            TensorData::new(vec![1.0f32, 1.0, 50.0, 50.0, 1.0, 3.0], [3, 2]),
            &device,
        );
        // Row 0 is off by 1 and 1, row 2 by 0 and 2; row 1 has no label.
        let mse = labels
            .loss(pred.clone(), &[0, 1, 2], RegressionLoss::Mse)
            .into_scalar::<f32>();
        assert!((mse - 6.0 / 4.0).abs() < 1e-6, "{mse}");
        let l1 = labels
            .loss(pred, &[0, 1, 2], RegressionLoss::L1)
            .into_scalar::<f32>();
        assert!((l1 - 4.0 / 4.0).abs() < 1e-6, "{l1}");
        let ok = JointTargets::new(vec![Target::linear("x_mm")]);
        ok.check().unwrap();
        for bad in [
            JointTargets::new(vec![]),
            ok.clone().with_weight(0.0),
            ok.clone().with_weight(f64::NAN),
            ok.clone().with_hidden(0),
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let l1 = RegressionLoss::L1;
        assert!(
            JointTargets::from_names(&[], 1.0, 64, l1)
                .unwrap()
                .is_none()
        );
        let j = JointTargets::from_names(&names(&["x_mm", "theta_deg:180"]), 1.0, 64, l1)
            .unwrap()
            .unwrap();
        assert_eq!((j.columns(), j.loss), (3, Some(l1)));
        assert!(JointTargets::from_names(&names(&["theta_deg:-5"]), 1.0, 64, l1).is_err());
    }
}
