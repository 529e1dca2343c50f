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
use crate::uncertainty::ValuesWithStd;
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
    /// Also give each target's uncertainty: per target a second output,
    /// the log of a Laplace scale trained on the likelihood of the
    /// regressor's own error ([`crate::uncertainty`]) from the last hidden
    /// layer with its gradient stopped (the estimates train as without
    /// it), calibrated on the early-stopping rows; linear targets only
    /// (`None` in regressors saved before this option: no uncertainty).
    #[config(default = "None")]
    pub uncertainty: Option<bool>,
}

impl RegressorConfig {
    /// Target columns (an angle takes two).
    fn outputs(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }

    /// Whether it gives each target's uncertainty.
    pub fn has_uncertainty(&self) -> bool {
        self.uncertainty == Some(true)
    }

    /// Network outputs: the target columns, then with uncertainty one log
    /// scale per target.
    fn network_outputs(&self) -> usize {
        self.outputs()
            + if self.has_uncertainty() {
                self.targets.len()
            } else {
                0
            }
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
    /// With uncertainty: per target, the factor that turns the network's
    /// Laplace scale into a standard deviation whose ±1 interval holds
    /// 68.3 % of the calibration rows' errors.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std_scale: Option<Vec<f64>>,
    /// Free-form provenance (where its uncertainty was calibrated).
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub notes: serde_json::Value,
}

impl Artifact for RegressorArtifact {
    type Model = Mlp;
    const KIND: &'static str = "regressor";
    const CONFIG_FILE: &'static str = "regressor.json";
    const WEIGHTS_FILE: &'static str = "regressor.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<Mlp> {
        let m = &self.model;
        crate::mlp::check_sizes(m.inputs, &m.hidden, m.network_outputs())?;
        Ok(Mlp::with_hidden(
            m.inputs,
            &m.hidden,
            m.network_outputs(),
            device,
        ))
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::error::in_config;
        let m = &self.model;
        in_config(
            file,
            crate::mlp::check_sizes(m.inputs, &m.hidden, m.network_outputs()),
        )?;
        if m.has_uncertainty() {
            crate::uncertainty::check_std_scale(&m.targets, self.std_scale.as_deref())
                .map_err(|e| tactile_core::Error::model(file, e))?;
        }
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
        crate::mlp::check_sizes(config.inputs, &config.hidden, config.network_outputs())?;
        if config.has_uncertainty() {
            crate::uncertainty::check_linear(&config.targets)
                .map_err(tactile_core::Error::Config)?;
        }
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
            std_scale: None,
            notes: serde_json::Value::Null,
        };
        let mlp = artifact.init(&ad)?;
        let xt = matrix(x.len(), k, artifact.inputs.apply(&x64), &ad);
        let yt = matrix(x.len(), m, artifact.outputs.apply(&ey), &ad);
        let vx = matrix(val_x.len(), k, artifact.inputs.apply(&vx64), device);
        let vy = matrix(val_x.len(), m, artifact.outputs.apply(&evy), device);
        let loss = artifact.model.loss.unwrap_or_default();
        let uncertain = artifact.model.has_uncertainty();
        let mlp = fit_in_memory(
            &artifact.model.schedule,
            mlp,
            x.len(),
            |mlp, bi| {
                let x = xt.clone().select(0, bi.clone());
                if !uncertain {
                    return loss
                        .penalty(mlp.forward(x) - yt.clone().select(0, bi))
                        .mean();
                }
                // The scales read the hidden layer with its gradient
                // stopped, and the error's is stopped too: the estimates
                // learn exactly as without them.
                let (out, detached) = mlp.forward_and_detached(x);
                let error = out.narrow(1, 0, m) - yt.clone().select(0, bi);
                let nll = crate::uncertainty::laplace_nll(error.clone(), detached.narrow(1, m, nt));
                loss.penalty(error).mean() + nll.mean()
            },
            |v| {
                let vl: f32 = loss
                    .penalty(v.forward(vx.clone()).narrow(1, 0, m) - vy.clone())
                    .mean()
                    .into_scalar();
                Ok(tactile_burn::train::ensure_finite(
                    "the regressor's validation loss",
                    vl as f64,
                )?)
            },
            &ad,
        )?;
        let mut r = Self {
            artifact,
            mlp,
            device: device.clone(),
        };
        if uncertain {
            // One factor per target makes ±1 deviation hold 68.3 % of the
            // early-stopping rows' errors (standardised units).
            // Linear targets only: a column is a target (m = nt).
            let (raw, ey) = (r.run(val_x)?, r.artifact.outputs.apply(&evy));
            r.artifact.std_scale = Some(crate::uncertainty::calibrate_raw(
                raw.chunks(m + nt),
                &ey,
                nt,
            ));
        }
        Ok(r)
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
        Ok(self.predict_columns_with_std(x)?.0)
    }

    /// [`Self::predict_columns`] and, with uncertainty, per feature vector
    /// each target's standard deviation in the labels' units (the targets
    /// are then linear: a column is a target).
    pub fn predict_columns_with_std(&self, x: &[Vec<f32>]) -> Result<ValuesWithStd> {
        let a = &self.artifact;
        let (m, nt) = (a.model.outputs(), a.model.targets.len());
        let raw = self.run(x)?;
        let width = a.model.network_outputs();
        let cols = raw
            .chunks(width)
            .map(|r| a.outputs.unscale(&r[..m]))
            .collect();
        let std = match (&a.std_scale, a.model.has_uncertainty()) {
            (Some(f), true) => Some(
                raw.chunks(width)
                    .map(|r| {
                        (0..nt)
                            .map(|j| {
                                crate::uncertainty::deviation(r[m + j], a.outputs.std[j], f[j])
                            })
                            .collect()
                    })
                    .collect(),
            ),
            _ => None,
        };
        Ok((cols, std))
    }

    /// The network's raw outputs, row-major, one row per feature vector.
    fn run(&self, x: &[Vec<f32>]) -> Result<Vec<f32>> {
        let a = &self.artifact;
        check_features(x, a.model.inputs)?;
        if x.is_empty() {
            return Ok(Vec::new());
        }
        Ok(self
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
            .map_err(|e| tactile_core::Error::Invalid(format!("reading predictions: {e:?}")))?)
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

    /// Two targets, like a tap's depth and its shear: `depth = x0`
    /// exactly, and `shear = x1 + noise` whose Laplace spread grows as
    /// the tap gets shallower (0.05 at `x0 = 1` to 0.55 at `x0 = 0`),
    /// drawn per row from a fixed seed. Returns the features, the labels
    /// and each row's shear spread.
    pub(crate) fn noisy(n: usize, seed: u64) -> (Vec<Vec<f32>>, Vec<Vec<f64>>, Vec<f64>) {
        let mut rng = tactile_core::rng::SampleRng::new(seed, 0, 0);
        let mut out = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..n {
            let (x0, x1) = (rng.uniform(), rng.uniform() * 2.0 - 1.0);
            let b = 0.05 + 0.5 * (1.0 - x0);
            let u: f64 = rng.uniform() - 0.5;
            let e = -b * u.signum() * (1.0 - 2.0 * u.abs()).max(1e-12).ln();
            out.0.push(vec![x0 as f32, x1 as f32]);
            out.1.push(vec![x0, x1 + e]);
            out.2.push(b);
        }
        out
    }

    #[test]
    fn an_uncertain_regressor_says_where_it_errs_and_its_intervals_hold() {
        let dev = DeviceKind::Flex.device();
        let cfg = RegressorConfig::new(2, vec![Target::linear("depth"), Target::linear("shear")])
            .with_hidden(vec![(32, Activation::Relu), (16, Activation::Relu)])
            .with_schedule(Schedule::new(64, 200, 30, 3e-3).with_seed(7))
            .with_loss(Some(RegressionLoss::L1))
            .with_uncertainty(Some(true));
        let (x, y, _) = noisy(2000, 1);
        let (vx, vy, _) = noisy(500, 2);
        let r = Regressor::train(cfg, (&x, &y), (&vx, &vy), &dev).unwrap();
        let dir = tempfile::tempdir().unwrap();
        r.save(dir.path()).unwrap();
        let r = Regressor::load(dir.path(), &dev).unwrap();
        let (tx, ty, tb) = noisy(2000, 3);
        let (cols, std) = r.predict_columns_with_std(&tx).unwrap();
        let std = std.expect("deviations");
        let errors: Vec<Vec<f64>> = cols
            .iter()
            .zip(&ty)
            .map(|(p, t)| vec![p[0] - t[0], p[1] - t[1]])
            .collect();
        // Calibrated on the early-stopping rows, the intervals hold on
        // rows it never saw: a Laplace's ±1 and ±1.96 hold 68.3 % and 89.5 %.
        let c68 = crate::uncertainty::coverage(&errors, &std, 1.0)[1];
        let c95 = crate::uncertainty::coverage(&errors, &std, crate::uncertainty::Z95)[1];
        assert!(
            (0.63..0.74).contains(&c68) && (0.85..0.95).contains(&c95),
            "{c68} {c95}"
        );
        // The shear's deviation follows its noise, which the estimate of
        // the depth carries: rows of the noisiest quarter are given at
        // least 3x the deviation of the quietest quarter's.
        let mean_std = |keep: &dyn Fn(f64) -> bool| {
            let v: Vec<f64> = std
                .iter()
                .zip(&tb)
                .filter(|(_, b)| keep(**b))
                .map(|(s, _)| s[1])
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let (quiet, loud) = (mean_std(&|b| b < 0.175), mean_std(&|b| b > 0.425));
        assert!(loud > 3.0 * quiet, "{quiet} {loud}");
        // An angle has no deviation of its own column: refused up front.
        let angle = RegressorConfig::new(2, vec![Target::angle("theta_deg", 180.0)])
            .with_uncertainty(Some(true));
        let err = Regressor::train(angle, (&x, &y), (&vx, &vy), &dev)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("theta_deg is an angle"), "{err}");
        // A regressor.json whose factors were removed is refused, naming it.
        let file = dir.path().join("regressor.json");
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        v.as_object_mut().unwrap().remove("std_scale");
        std::fs::write(&file, v.to_string()).unwrap();
        let err = Regressor::load(dir.path(), &dev).err().unwrap().to_string();
        assert!(
            err.contains("regressor.json") && err.contains("std_scale"),
            "{err}"
        );
    }
}
