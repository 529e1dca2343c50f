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
use burn::tensor::activation::{relu, sigmoid, softmax};
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
    /// Ensemble members (folds), at least 2.
    #[config(default = 10)]
    pub folds: usize,
    /// Repeats of the k-fold split with fresh shuffles (repeated k-fold);
    /// the ensemble has `folds x repeats` members.
    #[config(default = 3)]
    pub repeats: usize,
}

/// The classifier network.
#[derive(Module, Debug)]
pub struct Mlp {
    pub layers: Vec<Linear>,
    #[module(skip)]
    pub activations: Vec<Activation>,
}

impl Mlp {
    /// Layers of sizes `dims` (inputs, hidden..., outputs) with burn's default
    /// initialisation; `activations` follow each hidden layer.
    pub fn new(dims: &[usize], activations: &[Activation], device: &Device) -> Self {
        Mlp {
            layers: dims
                .windows(2)
                .map(|w| LinearConfig::new(w[0], w[1]).init(device))
                .collect(),
            activations: activations.to_vec(),
        }
    }

    /// Outputs `[N, last]` (class logits for a classifier).
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
        let acts: Vec<Activation> = self.hidden.iter().map(|h| h.1).collect();
        Mlp::new(&dims, &acts, device)
    }
}

/// A trained head: config, standardisation and the members' networks.
pub struct ClassifierHead {
    pub config: HeadConfig,
    pub mean: Vec<f32>,
    pub std: Vec<f32>,
    pub members: Vec<Mlp>,
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
    /// Train the k-fold ensemble on `(x, y)`.
    pub fn train(config: HeadConfig, x: &[Vec<f32>], y: &[usize], device: &Device) -> Result<Self> {
        if config.folds < 2 {
            return Err(Error::Config(format!(
                "head folds must be at least 2, got {}",
                config.folds
            )));
        }
        if x.len() < config.folds || x.len() != y.len() {
            return Err(Error::Invalid(format!(
                "classifier needs at least {} labelled samples, got {} vectors and {} labels",
                config.folds,
                x.len(),
                y.len()
            )));
        }
        if let Some(bad) = x.iter().find(|v| v.len() != config.inputs) {
            return Err(Error::shape("feature vector", config.inputs, bad.len()));
        }
        if let Some(&bad) = y.iter().find(|&&c| c >= config.classes.len()) {
            return Err(Error::Invalid(format!(
                "class index {bad} out of range for {} classes",
                config.classes.len()
            )));
        }
        let k = config.inputs;
        let n = x.len() as f32;
        let mean: Vec<f32> = (0..k)
            .map(|j| x.iter().map(|v| v[j]).sum::<f32>() / n)
            .collect();
        let std: Vec<f32> = tactile_core::metrics::safe_scales((0..k).map(|j| {
            ((x.iter().map(|v| (v[j] - mean[j]).powi(2)).sum::<f32>() / n).sqrt()) as f64
        }))
        .into_iter()
        .map(|s| s as f32)
        .collect();
        let mut members = Vec::with_capacity(config.folds * config.repeats.max(1));
        for repeat in 0..config.repeats.max(1) {
            // Folds from one seeded shuffle per repeat.
            let order = shuffled_batches(
                &(0..x.len()).collect::<Vec<_>>(),
                x.len(),
                config.seed.wrapping_add(7919 * repeat as u64),
            )
            .concat();
            for fold in 0..config.folds {
                let (mut tr, mut va) = (Vec::new(), Vec::new());
                for (pos, &i) in order.iter().enumerate() {
                    if pos % config.folds == fold {
                        va.push(i);
                    } else {
                        tr.push(i);
                    }
                }
                let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<usize>) {
                    (
                        idx.iter().map(|&i| x[i].clone()).collect(),
                        idx.iter().map(|&i| y[i]).collect(),
                    )
                };
                let (tx, ty) = pick(&tr);
                let (vx, vy) = pick(&va);
                members.push(train_member(
                    &config,
                    config
                        .seed
                        .wrapping_add(1000 * fold as u64 + 100_000 * repeat as u64),
                    (&tx, &ty),
                    (&vx, &vy),
                    (&mean, &std),
                    device,
                ));
            }
        }
        Ok(Self {
            config,
            mean,
            std,
            members,
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
        Ok(argmax_rows(self.probabilities(x, device)))
    }

    /// Mean class probabilities of the members, `[N, classes]`.
    fn probabilities(&self, x: &[Vec<f32>], device: &Device) -> Tensor<2> {
        let xt = to_tensor(x, &self.mean, &self.std, device);
        let mut sum: Option<Tensor<2>> = None;
        for m in &self.members {
            let p = softmax(m.forward(xt.clone()), 1);
            sum = Some(match sum {
                Some(s) => s + p,
                None => p,
            });
        }
        sum.map(|s| s / self.members.len() as f32)
            .unwrap_or_else(|| Tensor::zeros([x.len(), self.config.classes.len()], device))
    }

    /// Save as `head.json` + `member<k>.bpk` in `dir`.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        tactile_core::io::create_dir_all(dir)?;
        for (i, m) in self.members.iter().enumerate() {
            save_module(m, &dir.join(format!("member{i}.bpk")))?;
        }
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
        let members = (0..f.config.folds * f.config.repeats.max(1))
            .map(|i| {
                load_module(
                    f.config.init_mlp(device),
                    &dir.join(format!("member{i}.bpk")),
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            config: f.config,
            mean: f.mean,
            std: f.std,
            members,
        })
    }
}

/// One member: Adam on `train`, early stopping on the `val` error rate.
fn train_member(
    config: &HeadConfig,
    seed: u64,
    (x, y): (&[Vec<f32>], &[usize]),
    (val_x, val_y): (&[Vec<f32>], &[usize]),
    (mean, std): (&[f32], &[f32]),
    device: &Device,
) -> Mlp {
    let ad = device.clone().autodiff();
    ad.seed(seed);
    let mut mlp = config.init_mlp(&ad);
    let mut optim = AdamConfig::new().init();
    let loss_fn = CrossEntropyLossConfig::new().init(&ad);
    let xt = to_tensor(x, mean, std, &ad);
    let yt = Tensor::<1, Int>::from_data(
        TensorData::new(y.iter().map(|&c| c as i64).collect::<Vec<_>>(), [y.len()]),
        &ad,
    );
    let vx = to_tensor(val_x, mean, std, device);
    let vy = Tensor::<1, Int>::from_data(
        TensorData::new(
            val_y.iter().map(|&c| c as i64).collect::<Vec<_>>(),
            [val_y.len()],
        ),
        device,
    );
    let val_loss = CrossEntropyLossConfig::new().init(device);
    let mut early = EarlyStopping::new(config.patience);
    let mut best = mlp.valid();
    let idx: Vec<usize> = (0..x.len()).collect();
    for epoch in 0..config.max_epochs {
        for b in shuffled_batches(&idx, config.batch_size, seed.wrapping_add(epoch as u64)) {
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
        let vl: f32 = val_loss.forward(val_logits, vy.clone()).into_scalar();
        match early.update(epoch, err + 1e-3 * vl as f64) {
            Verdict::Improved => best = v,
            Verdict::Stop => break,
            Verdict::Continue => {}
        }
    }
    best
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

#[cfg(test)]
mod tests {
    use super::*;
    use tactile_core::DeviceKind;

    /// Three noisy clusters in 4-D, seeded.
    fn clusters(n: usize, seed: u64) -> (Vec<Vec<f32>>, Vec<usize>) {
        let mut s = seed;
        let mut noise = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f32 / (1u64 << 31) as f32) - 0.5
        };
        let centres = [
            [2.0, 0.0, 0.0, 1.0],
            [0.0, 2.0, 0.0, 1.0],
            [0.0, 0.0, 2.0, 1.0],
        ];
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in 0..n {
            let c = i % 3;
            x.push(centres[c].iter().map(|v| v + noise()).collect());
            y.push(c);
        }
        (x, y)
    }

    #[test]
    fn ensemble_learns_and_round_trips() {
        let dev = DeviceKind::Flex.device();
        let (x, y) = clusters(90, 1);
        let cfg = HeadConfig::new(4, vec!["a".into(), "b".into(), "c".into()])
            .with_max_epochs(60)
            .with_patience(20)
            .with_folds(3)
            .with_repeats(2);
        let head = ClassifierHead::train(cfg, &x, &y, &dev).unwrap();
        assert_eq!(head.members.len(), 6);
        let (tx, ty) = clusters(60, 2);
        let pred = head.predict(&tx, &dev).unwrap();
        let acc = pred.iter().zip(&ty).filter(|(a, b)| a == b).count() as f64 / 60.0;
        assert!(acc > 0.9, "accuracy {acc}");
        let dir = tempfile::tempdir().unwrap();
        head.save(dir.path()).unwrap();
        let back = ClassifierHead::load(dir.path(), &dev).unwrap();
        assert_eq!(back.predict(&tx, &dev).unwrap(), pred);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let dev = DeviceKind::Flex.device();
        let (x, y) = clusters(9, 1);
        let cfg = HeadConfig::new(4, vec!["a".into(), "b".into(), "c".into()]).with_folds(3);
        let e = ClassifierHead::train(cfg.clone().with_folds(1), &x, &y, &dev);
        assert!(e.err().unwrap().to_string().contains("folds"));
        let mut wide = cfg.clone();
        wide.inputs = 5;
        let e = ClassifierHead::train(wide, &x, &y, &dev);
        assert!(e.err().unwrap().to_string().contains("feature vector"));
        let mut bad = y.clone();
        bad[0] = 7;
        let e = ClassifierHead::train(cfg.clone(), &x, &bad, &dev);
        assert!(e.err().unwrap().to_string().contains("class index 7"));
        let e = ClassifierHead::train(cfg.with_folds(10), &x, &y, &dev);
        assert!(e.err().unwrap().to_string().contains("at least 10"));
    }
}
