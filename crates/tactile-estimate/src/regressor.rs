//! A shallow MLP regressor on feature vectors (paper A's pose, depth and
//! force estimators), predicting several targets at once from one vector.
//! Inputs and linear targets are standardised with training statistics
//! saved beside the weights; angle targets are regressed as sin/cos.

use std::path::Path;

use burn::config::Config;
use burn::module::Module;
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::{Device, Int, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_cae::artifact::{load_module, save_module};
use tactile_cae::head::{Activation, Mlp};
use tactile_core::train::{EarlyStopping, Verdict, shuffled_batches};
use tactile_core::{Error, Result};

use crate::target::{Target, TargetKind};

/// Architecture and training of a regressor.
#[derive(Config, Debug)]
pub struct RegressorConfig {
    pub inputs: usize,
    pub targets: Vec<Target>,
    /// Hidden layers (the authors' force head: 16 -> 32 -> 16 -> 1).
    #[config(default = "vec![(32, Activation::Relu), (16, Activation::Relu)]")]
    pub hidden: Vec<(usize, Activation)>,
    #[config(default = 1e-3)]
    pub learning_rate: f64,
    #[config(default = 2000)]
    pub max_epochs: usize,
    #[config(default = 100)]
    pub patience: usize,
    #[config(default = 64)]
    pub batch_size: usize,
    #[config(default = 7)]
    pub seed: u64,
}

impl RegressorConfig {
    fn outputs(&self) -> usize {
        self.targets.iter().map(Target::width).sum()
    }

    fn init_mlp(&self, device: &Device) -> Mlp {
        let mut dims = vec![self.inputs];
        dims.extend(self.hidden.iter().map(|h| h.0));
        dims.push(self.outputs());
        let acts: Vec<Activation> = self.hidden.iter().map(|h| h.1).collect();
        Mlp::new(&dims, &acts, device)
    }
}

/// Per-column standardisation.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Scaler {
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
}

impl Scaler {
    fn fit(rows: &[Vec<f64>]) -> Self {
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

    fn identity(k: usize) -> Self {
        Self {
            mean: vec![0.0; k],
            std: vec![1.0; k],
        }
    }

    fn apply(&self, rows: &[Vec<f64>]) -> Vec<f32> {
        rows.iter()
            .flat_map(|r| {
                r.iter()
                    .zip(&self.mean)
                    .zip(&self.std)
                    .map(|((v, m), s)| ((v - m) / s) as f32)
            })
            .collect()
    }
}

/// A trained regressor.
pub struct Regressor {
    pub config: RegressorConfig,
    pub inputs: Scaler,
    pub outputs: Scaler,
    pub mlp: Mlp,
}

#[derive(Serialize, Deserialize)]
struct RegressorFile {
    config: RegressorConfig,
    inputs: Scaler,
    outputs: Scaler,
}

fn tensor(rows: usize, cols: usize, data: Vec<f32>, device: &Device) -> Tensor<2> {
    Tensor::from_data(TensorData::new(data, [rows, cols]), device)
}

impl Regressor {
    /// Encode label rows (one value per target) into network columns.
    fn encode(targets: &[Target], y: &[Vec<f64>]) -> Vec<Vec<f64>> {
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

    /// Train on `(x, y)`, early-stopping on the mean squared error of `val`;
    /// `y` rows hold one value per target, in `config.targets` order.
    pub fn train(
        config: RegressorConfig,
        (x, y): (&[Vec<f32>], &[Vec<f64>]),
        (val_x, val_y): (&[Vec<f32>], &[Vec<f64>]),
        device: &Device,
    ) -> Result<Self> {
        if x.is_empty() || val_x.is_empty() {
            return Err(Error::Invalid(
                "regressor needs training and validation samples".into(),
            ));
        }
        if x.len() != y.len() || val_x.len() != val_y.len() {
            return Err(Error::Invalid(
                "as many label rows as feature vectors are needed".into(),
            ));
        }
        if let Some(bad) = x.iter().chain(val_x).find(|v| v.len() != config.inputs) {
            return Err(Error::shape("feature vector", config.inputs, bad.len()));
        }
        let nt = config.targets.len();
        if let Some(bad) = y.iter().chain(val_y).find(|r| r.len() != nt) {
            return Err(Error::shape("label row", nt, bad.len()));
        }
        let to64 = |v: &[Vec<f32>]| -> Vec<Vec<f64>> {
            v.iter()
                .map(|r| r.iter().map(|&a| a as f64).collect())
                .collect()
        };
        let (x64, vx64) = (to64(x), to64(val_x));
        let inputs = Scaler::fit(&x64);
        let (ey, evy) = (
            Self::encode(&config.targets, y),
            Self::encode(&config.targets, val_y),
        );
        // Standardise linear columns; sin/cos columns stay on the unit circle.
        let mut outputs = Scaler::fit(&ey);
        let mut col = 0;
        for t in &config.targets {
            if let TargetKind::Angle { .. } = t.kind {
                let id = Scaler::identity(2);
                outputs.mean[col..col + 2].copy_from_slice(&id.mean);
                outputs.std[col..col + 2].copy_from_slice(&id.std);
            }
            col += t.width();
        }
        let (k, m) = (config.inputs, config.outputs());
        let ad = device.clone().autodiff();
        ad.seed(config.seed);
        let mut mlp = config.init_mlp(&ad);
        let mut optim = AdamConfig::new().init();
        let xt = tensor(x.len(), k, inputs.apply(&x64), &ad);
        let yt = tensor(x.len(), m, outputs.apply(&ey), &ad);
        let vx = tensor(val_x.len(), k, inputs.apply(&vx64), device);
        let vy = tensor(val_x.len(), m, outputs.apply(&evy), device);
        let mut early = EarlyStopping::new(config.patience);
        let mut best = mlp.valid();
        let idx: Vec<usize> = (0..x.len()).collect();
        for epoch in 0..config.max_epochs {
            for b in shuffled_batches(
                &idx,
                config.batch_size,
                config.seed.wrapping_add(epoch as u64),
            ) {
                let bi = Tensor::<1, Int>::from_data(
                    TensorData::new(b.iter().map(|&i| i as i64).collect::<Vec<_>>(), [b.len()]),
                    &ad,
                );
                let pred = mlp.forward(xt.clone().select(0, bi.clone()));
                let loss = (pred - yt.clone().select(0, bi)).powi_scalar(2).mean();
                let grads = GradientsParams::from_grads(loss.backward(), &mlp);
                mlp = optim.step(config.learning_rate, mlp, grads);
            }
            let v = mlp.valid();
            let vl: f32 = (v.forward(vx.clone()) - vy.clone())
                .powi_scalar(2)
                .mean()
                .into_scalar();
            if !vl.is_finite() {
                return Err(Error::Invalid(format!(
                    "regressor diverged at epoch {epoch} (validation loss {vl})"
                )));
            }
            match early.update(epoch, vl as f64) {
                Verdict::Improved => best = v,
                Verdict::Stop => break,
                Verdict::Continue => {}
            }
        }
        Ok(Self {
            config,
            inputs,
            outputs,
            mlp: best,
        })
    }

    /// Predictions, one row of target values per feature vector.
    pub fn predict(&self, x: &[Vec<f32>], device: &Device) -> Result<Vec<Vec<f64>>> {
        if let Some(bad) = x.iter().find(|v| v.len() != self.config.inputs) {
            return Err(Error::shape(
                "feature vector",
                self.config.inputs,
                bad.len(),
            ));
        }
        if x.is_empty() {
            return Ok(Vec::new());
        }
        let rows: Vec<Vec<f64>> = x
            .iter()
            .map(|r| r.iter().map(|&a| a as f64).collect())
            .collect();
        let m = self.config.outputs();
        let out = self
            .mlp
            .forward(tensor(
                x.len(),
                self.config.inputs,
                self.inputs.apply(&rows),
                device,
            ))
            .into_data()
            .convert::<f32>()
            .try_to_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("reading predictions: {e:?}")))?;
        Ok(out
            .chunks(m)
            .map(|r| {
                let cols: Vec<f64> = r
                    .iter()
                    .zip(&self.outputs.mean)
                    .zip(&self.outputs.std)
                    .map(|((v, mu), s)| *v as f64 * s + mu)
                    .collect();
                let mut at = 0;
                self.config
                    .targets
                    .iter()
                    .map(|t| {
                        let v = t.decode(&cols[at..at + t.width()]);
                        at += t.width();
                        v
                    })
                    .collect()
            })
            .collect())
    }

    /// Mean absolute error per target on `(x, y)`.
    pub fn evaluate(&self, x: &[Vec<f32>], y: &[Vec<f64>], device: &Device) -> Result<Vec<f64>> {
        let pred = self.predict(x, device)?;
        Ok(self
            .config
            .targets
            .iter()
            .enumerate()
            .map(|(j, t)| {
                let p: Vec<f64> = pred.iter().map(|r| r[j]).collect();
                let tr: Vec<f64> = y.iter().map(|r| r[j]).collect();
                t.mae(&p, &tr)
            })
            .collect())
    }

    /// Save as `regressor.json` + `regressor.bpk` in `dir`.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        tactile_core::io::create_dir_all(dir)?;
        save_module(&self.mlp, &dir.join("regressor.bpk"))?;
        tactile_core::io::write_json_atomic(
            dir.join("regressor.json"),
            &RegressorFile {
                config: self.config.clone(),
                inputs: self.inputs.clone(),
                outputs: self.outputs.clone(),
            },
        )
    }

    /// Load from `dir`.
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let dir = dir.as_ref();
        let f: RegressorFile = tactile_core::io::read_json(dir.join("regressor.json"))?;
        let mlp = load_module(f.config.init_mlp(device), &dir.join("regressor.bpk"))?;
        Ok(Self {
            config: f.config,
            inputs: f.inputs,
            outputs: f.outputs,
            mlp,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactile_core::DeviceKind;

    /// `y = (2 x0 - x1, angle 40 x2 degrees)` with small noise-free structure.
    fn data(n: usize, offset: usize) -> (Vec<Vec<f32>>, Vec<Vec<f64>>) {
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
        .with_max_epochs(300)
        .with_patience(40);
        let (x, y) = data(400, 0);
        let (vx, vy) = data(100, 1000);
        let r = Regressor::train(cfg, (&x, &y), (&vx, &vy), &dev).unwrap();
        let (tx, ty) = data(100, 5000);
        let err = r.evaluate(&tx, &ty, &dev).unwrap();
        // Spread of the targets: a about 1.1, theta about 57 degrees.
        assert!(err[0] < 0.15 && err[1] < 6.0, "{err:?}");
        let dir = tempfile::tempdir().unwrap();
        r.save(dir.path()).unwrap();
        let back = Regressor::load(dir.path(), &dev).unwrap();
        assert_eq!(
            back.predict(&tx, &dev).unwrap(),
            r.predict(&tx, &dev).unwrap()
        );
    }
}
