//! A shallow classifier on feature vectors (paper A's "validation by use").
//! The authors' released shape head is 16 -> 16 ReLU -> 64 sigmoid ->
//! 32 sigmoid -> classes; that is the default here. Features are
//! standardised with training-set statistics that are saved with the head.

use std::path::Path;

use burn::config::Config;
use burn::module::Module;
use burn::nn::loss::CrossEntropyLossConfig;
use burn::nn::{Linear, LinearConfig};
use burn::optim::{AdamConfig, GradientsParams};
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Int, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_core::train::{EarlyStopping, Verdict, shuffled_batches};
use tactile_core::{Error, Result};

use crate::artifact::{load_module, save_module};

/// Hidden-layer activation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    Relu,
    Sigmoid,
}

/// Architecture and training of a classifier head.
#[derive(Config, Debug)]
pub struct HeadConfig {
    pub inputs: usize,
    pub classes: Vec<String>,
    #[config(
        default = "vec![(16, Activation::Relu), (64, Activation::Sigmoid), (32, Activation::Sigmoid)]"
    )]
    pub hidden: Vec<(usize, Activation)>,
    #[config(default = 1e-2)]
    pub learning_rate: f64,
    #[config(default = 3000)]
    pub max_epochs: usize,
    #[config(default = 300)]
    pub patience: usize,
    #[config(default = 64)]
    pub batch_size: usize,
    #[config(default = 7)]
    pub seed: u64,
}

/// The classifier network.
#[derive(Module, Debug)]
pub struct Mlp {
    pub layers: Vec<Linear>,
    #[module(skip)]
    pub activations: Vec<Activation>,
}

impl Mlp {
    /// Class logits `[N, classes]`.
    pub fn forward(&self, mut x: Tensor<2>) -> Tensor<2> {
        let last = self.layers.len() - 1;
        for (i, layer) in self.layers.iter().enumerate() {
            x = layer.forward(x);
            if i < last {
                x = match self.activations[i] {
                    Activation::Relu => relu(x),
                    Activation::Sigmoid => sigmoid(x),
                };
            }
        }
        x
    }
}

impl HeadConfig {
    fn init_mlp(&self, device: &Device) -> Mlp {
        let mut dims = vec![self.inputs];
        dims.extend(self.hidden.iter().map(|h| h.0));
        dims.push(self.classes.len());
        Mlp {
            layers: dims
                .windows(2)
                .map(|w| LinearConfig::new(w[0], w[1]).init(device))
                .collect(),
            activations: self.hidden.iter().map(|h| h.1).collect(),
        }
    }
}

/// A trained head: config, standardisation and network.
pub struct ClassifierHead {
    pub config: HeadConfig,
    pub mean: Vec<f32>,
    pub std: Vec<f32>,
    pub mlp: Mlp,
}

#[derive(Serialize, Deserialize)]
struct HeadFile {
    config: HeadConfig,
    mean: Vec<f32>,
    std: Vec<f32>,
}

fn standardise(x: &[Vec<f32>], mean: &[f32], std: &[f32]) -> Vec<f32> {
    x.iter()
        .flat_map(|v| v.iter().zip(mean).zip(std).map(|((a, m), s)| (a - m) / s))
        .collect()
}

fn to_tensor(x: &[Vec<f32>], mean: &[f32], std: &[f32], device: &Device) -> Tensor<2> {
    let k = mean.len();
    Tensor::from_data(
        TensorData::new(standardise(x, mean, std), [x.len(), k]),
        device,
    )
}

impl ClassifierHead {
    /// Train on `(x, y)` with `val` for early stopping; keeps the best epoch.
    pub fn train(
        config: HeadConfig,
        x: &[Vec<f32>],
        y: &[usize],
        val_x: &[Vec<f32>],
        val_y: &[usize],
        device: &Device,
    ) -> Result<Self> {
        if x.is_empty() || val_x.is_empty() {
            return Err(Error::Invalid(
                "classifier needs training and validation samples".into(),
            ));
        }
        if let Some(bad) = x.iter().chain(val_x).find(|v| v.len() != config.inputs) {
            return Err(Error::shape("feature vector", config.inputs, bad.len()));
        }
        let k = config.inputs;
        let n = x.len() as f32;
        let mean: Vec<f32> = (0..k)
            .map(|j| x.iter().map(|v| v[j]).sum::<f32>() / n)
            .collect();
        let std: Vec<f32> = (0..k)
            .map(|j| {
                ((x.iter().map(|v| (v[j] - mean[j]).powi(2)).sum::<f32>() / n).sqrt()).max(1e-6)
            })
            .collect();
        let ad = device.clone().autodiff();
        ad.seed(config.seed);
        let mut mlp = config.init_mlp(&ad);
        let mut optim = AdamConfig::new().init();
        let loss_fn = CrossEntropyLossConfig::new().init(&ad);
        let xt = to_tensor(x, &mean, &std, &ad);
        let yt = Tensor::<1, Int>::from_data(
            TensorData::new(y.iter().map(|&c| c as i64).collect::<Vec<_>>(), [y.len()]),
            &ad,
        );
        let vx = to_tensor(val_x, &mean, &std, device);
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
                let logits = mlp.forward(xt.clone().select(0, bi.clone()));
                let loss = loss_fn.forward(logits, yt.clone().select(0, bi));
                let grads = GradientsParams::from_grads(loss.backward(), &mlp);
                mlp = optim.step(config.learning_rate, mlp, grads);
            }
            // Validation error rate, with cross-entropy as the tie-breaker.
            let v = mlp.valid();
            let val_logits = v.forward(vx.clone());
            let pred = argmax_rows(val_logits.clone());
            let err =
                pred.iter().zip(val_y).filter(|(a, b)| a != b).count() as f64 / val_y.len() as f64;
            let vl = {
                let vy = Tensor::<1, Int>::from_data(
                    TensorData::new(
                        val_y.iter().map(|&c| c as i64).collect::<Vec<_>>(),
                        [val_y.len()],
                    ),
                    device,
                );
                let l: f32 = CrossEntropyLossConfig::new()
                    .init(device)
                    .forward(val_logits, vy)
                    .into_scalar();
                l as f64
            };
            match early.update(epoch, err + 1e-3 * vl) {
                Verdict::Improved => best = v,
                Verdict::Stop => break,
                Verdict::Continue => {}
            }
        }
        Ok(Self {
            config,
            mean,
            std,
            mlp: best,
        })
    }

    /// Predicted class index per feature vector.
    pub fn predict(&self, x: &[Vec<f32>], device: &Device) -> Result<Vec<usize>> {
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
        Ok(argmax_rows(
            self.mlp
                .forward(to_tensor(x, &self.mean, &self.std, device)),
        ))
    }

    /// Save as `head.json` + `head.bpk` in `dir`.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        tactile_core::io::create_dir_all(dir)?;
        save_module(&self.mlp, &dir.join("head.bpk"))?;
        tactile_core::io::write_json_atomic(
            dir.join("head.json"),
            &HeadFile {
                config: self.config.clone(),
                mean: self.mean.clone(),
                std: self.std.clone(),
            },
        )
    }

    /// Load from `dir`.
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let dir = dir.as_ref();
        let f: HeadFile = tactile_core::io::read_json(dir.join("head.json"))?;
        let mlp = load_module(f.config.init_mlp(device), &dir.join("head.bpk"))?;
        Ok(Self {
            config: f.config,
            mean: f.mean,
            std: f.std,
            mlp,
        })
    }
}

fn argmax_rows(logits: Tensor<2>) -> Vec<usize> {
    let [n, _] = logits.dims();
    let idx: Vec<i64> = logits
        .argmax(1)
        .reshape([n])
        .into_data()
        .convert::<i64>()
        .try_to_vec::<i64>()
        .unwrap_or_default();
    idx.into_iter().map(|i| i as usize).collect()
}
