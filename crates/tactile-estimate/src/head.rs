//! A shallow classifier on feature vectors (paper A's "validation by use"),
//! trained as a repeated k-fold ensemble. The authors' released shape head
//! is 16 -> 16 ReLU -> 64 sigmoid -> 32 sigmoid -> classes; that is the
//! default here. Features are standardised with training-set statistics
//! that are saved with the head.

use std::path::Path;

use burn::config::Config;
use burn::module::Module;
use burn::nn::loss::CrossEntropyLossConfig;
use burn::tensor::activation::softmax;
use burn::tensor::{Device, Tensor};
use serde::{Deserialize, Serialize};
use tactile_burn::Artifact;
use tactile_burn::train::{Schedule, shuffled_batches};

use crate::mlp::{Activation, Mlp, fit_in_memory, indices, matrix};
use crate::{Error, Result};

/// Architecture and training of a classifier head.
#[derive(Config, Debug, PartialEq)]
pub struct HeadConfig {
    /// Feature count.
    pub inputs: usize,
    /// Class names, in output order.
    pub classes: Vec<String>,
    /// Hidden layers.
    #[config(
        default = "vec![(16, Activation::Relu), (64, Activation::Sigmoid), (32, Activation::Sigmoid)]"
    )]
    pub hidden: Vec<(usize, Activation)>,
    /// Ensemble members per repeat (folds), at least 2.
    #[config(default = 10)]
    pub folds: usize,
    /// Repeats of the k-fold split with fresh shuffles (repeated k-fold);
    /// the ensemble has `folds x repeats` members.
    #[config(default = 3)]
    pub repeats: usize,
    /// Each member's schedule (Adam; the seed is offset per member).
    #[config(default = "Schedule::new(64, 3000, 300, 1e-2).with_seed(7)")]
    pub schedule: Schedule,
}

impl HeadConfig {
    /// Members of the ensemble.
    pub fn members(&self) -> usize {
        self.folds * self.repeats.max(1)
    }

    fn init_mlp(&self, device: &Device) -> Mlp {
        Mlp::with_hidden(self.inputs, &self.hidden, self.classes.len(), device)
    }
}

/// The ensemble's networks.
#[derive(Module, Debug)]
pub struct HeadEnsemble {
    /// One network per fold and repeat.
    pub members: Vec<Mlp>,
}

/// A head on disk: `head.json` (config and standardisation) beside
/// `head.bpk` (every member's weights).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HeadArtifact {
    /// Architecture and training.
    #[serde(alias = "config")]
    pub model: HeadConfig,
    /// Feature means of the training set.
    pub mean: Vec<f32>,
    /// Feature standard deviations of the training set.
    pub std: Vec<f32>,
    /// Fingerprint of the encoder whose features it was trained on (see
    /// `tactile_burn::artifact::fingerprint`); `None` for features read from
    /// a file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub encoder: Option<String>,
    /// How it was trained beyond its config (the augmentation, for one).
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub notes: serde_json::Value,
}

/// Most ensemble members accepted.
pub const MAX_MEMBERS: usize = 1024;

impl HeadConfig {
    /// Check the sizes against the limits before anything is built.
    pub fn check(&self) -> tactile_core::Result<()> {
        crate::mlp::check_sizes(self.inputs, &self.hidden, self.classes.len())?;
        let each = crate::mlp::parameters(self.inputs, &self.hidden, self.classes.len());
        tactile_burn::artifact::check_parameters(
            "head ensemble",
            each.saturating_mul(self.members() as u64),
        )?;
        if self.folds < 2 || self.members() > MAX_MEMBERS {
            return Err(tactile_core::Error::Config(format!(
                "a head needs at least 2 folds and at most {MAX_MEMBERS} members, got {} folds x {} repeats",
                self.folds, self.repeats
            )));
        }
        Ok(())
    }
}

impl Artifact for HeadArtifact {
    type Model = HeadEnsemble;
    const KIND: &'static str = "classifier head";
    const CONFIG_FILE: &'static str = "head.json";
    const WEIGHTS_FILE: &'static str = "head.bpk";

    fn init(&self, device: &Device) -> tactile_core::Result<HeadEnsemble> {
        self.model.check()?;
        Ok(HeadEnsemble {
            members: (0..self.model.members())
                .map(|_| self.model.init_mlp(device))
                .collect(),
        })
    }

    fn check(&self, file: &Path) -> tactile_core::Result<()> {
        use tactile_core::error::in_config;
        in_config(file, self.model.check())?;
        in_config(
            file,
            crate::mlp::check_scaler("feature scaling", &self.mean, &self.std, self.model.inputs),
        )
    }
}

/// Standardised features as a `[N, inputs]` tensor.
fn standardised(x: &[Vec<f32>], mean: &[f32], std: &[f32], device: &Device) -> Tensor<2> {
    let data = x
        .iter()
        .flat_map(|v| v.iter().zip(mean).zip(std).map(|((a, m), s)| (a - m) / s))
        .collect();
    matrix(x.len(), mean.len(), data, device)
}

/// A trained head, ready to classify feature vectors.
pub struct ClassifierHead {
    /// Config and standardisation.
    pub artifact: HeadArtifact,
    /// The members.
    pub net: HeadEnsemble,
    /// Where they run.
    pub device: Device,
}

/// The `(fit, stop)` rows of each member of a repeated k-fold ensemble:
/// per repeat, one seeded shuffle of the frames (`frames[i]` names row
/// `i`'s frame), the frame at position `p` stopping fold `p mod folds`; a
/// frame's rows go with it. With every row its own frame these are the
/// folds of a shuffle of the rows, as heads were always trained.
fn folds_by_frame(
    frames: &[usize],
    folds: usize,
    repeats: usize,
    seed: u64,
) -> Result<Vec<(Vec<usize>, Vec<usize>)>> {
    let groups = tactile_core::dataset::FrameGroups::new(frames.iter().copied().enumerate());
    let firsts = &groups.frames;
    if firsts.len() < folds {
        return Err(Error::TooFewSamples(format!(
            "classifier needs at least {folds} frames (one per fold), got {}",
            firsts.len()
        )));
    }
    let mut out = Vec::with_capacity(folds * repeats);
    for repeat in 0..repeats {
        // Folds from one seeded shuffle per repeat.
        let order = shuffled_batches(
            firsts,
            firsts.len(),
            seed.wrapping_add(7919 * repeat as u64),
        )
        .concat();
        for fold in 0..folds {
            let (mut fit, mut stop) = (Vec::new(), Vec::new());
            for (pos, first) in order.iter().enumerate() {
                let side = if pos % folds == fold {
                    &mut stop
                } else {
                    &mut fit
                };
                side.extend_from_slice(groups.rows(*first));
            }
            out.push((fit, stop));
        }
    }
    Ok(out)
}

impl ClassifierHead {
    /// Load a head folder.
    pub fn load(dir: impl AsRef<Path>, device: &Device) -> Result<Self> {
        let l = HeadArtifact::load(dir.as_ref(), device)?;
        Ok(Self {
            artifact: l.artifact,
            net: l.model,
            device: l.device,
        })
    }

    /// Save into `dir`.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<()> {
        Ok(self.artifact.save(&self.net, dir.as_ref())?)
    }

    /// The class names.
    pub fn classes(&self) -> &[String] {
        &self.artifact.model.classes
    }

    /// Train the k-fold ensemble on `(x, y)` (class indices), each row its
    /// own frame.
    pub fn train(config: HeadConfig, x: &[Vec<f32>], y: &[usize], device: &Device) -> Result<Self> {
        let frames: Vec<usize> = (0..x.len()).collect();
        Self::train_by_frame(config, x, y, &frames, device)
    }

    /// Train the k-fold ensemble on `(x, y)` (class indices), where
    /// `frames[i]` names the frame row `i` was read from: rows of one frame
    /// (a frame listed twice, its rotated copies) fit or stop a member
    /// together, so no member stops early on a frame it fitted.
    pub fn train_by_frame(
        config: HeadConfig,
        x: &[Vec<f32>],
        y: &[usize],
        frames: &[usize],
        device: &Device,
    ) -> Result<Self> {
        config.schedule.check()?;
        if config.folds < 2 {
            return Err(tactile_core::Error::Config(format!(
                "head folds must be at least 2, got {}",
                config.folds
            ))
            .into());
        }
        if x.len() < config.folds || x.len() != y.len() {
            return Err(Error::TooFewSamples(format!(
                "classifier needs at least {} labelled samples, got {} vectors and {} labels",
                config.folds,
                x.len(),
                y.len()
            )));
        }
        if frames.len() != x.len() {
            return Err(tactile_core::Error::Invalid(format!(
                "{} frame names for {} feature vectors",
                frames.len(),
                x.len()
            ))
            .into());
        }
        check_features(x, config.inputs)?;
        config.check()?;
        if let Some(&bad) = y.iter().find(|&&c| c >= config.classes.len()) {
            return Err(tactile_core::Error::Invalid(format!(
                "class index {bad} out of range for {} classes",
                config.classes.len()
            ))
            .into());
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
        let repeats = config.repeats.max(1);
        let folds = folds_by_frame(frames, config.folds, repeats, config.schedule.seed)?;
        let mut members = Vec::with_capacity(config.members());
        for (member, (tr, va)) in folds.iter().enumerate() {
            let (repeat, fold) = (member / config.folds, member % config.folds);
            let pick = |idx: &[usize]| -> (Vec<Vec<f32>>, Vec<usize>) {
                (
                    idx.iter().map(|&i| x[i].clone()).collect(),
                    idx.iter().map(|&i| y[i]).collect(),
                )
            };
            let seed = config
                .schedule
                .seed
                .wrapping_add(1000 * fold as u64 + 100_000 * repeat as u64);
            members.push(train_member(
                &config,
                seed,
                pick(tr),
                pick(va),
                (&mean, &std),
                device,
            )?);
        }
        Ok(Self {
            artifact: HeadArtifact {
                model: config,
                mean,
                std,
                encoder: None,
                notes: serde_json::Value::Null,
            },
            net: HeadEnsemble { members },
            device: device.clone(),
        })
    }

    /// Predicted class index per feature vector.
    pub fn predict(&self, x: &[Vec<f32>]) -> Result<Vec<usize>> {
        check_features(x, self.artifact.model.inputs)?;
        if x.is_empty() {
            return Ok(Vec::new());
        }
        Ok(argmax_rows(self.probabilities(x)))
    }

    /// Mean class probabilities of the members, `[N, classes]`.
    fn probabilities(&self, x: &[Vec<f32>]) -> Tensor<2> {
        let a = &self.artifact;
        let xt = standardised(x, &a.mean, &a.std, &self.device);
        let mut sum: Option<Tensor<2>> = None;
        for m in &self.net.members {
            let p = softmax(m.forward(xt.clone()), 1);
            sum = Some(match sum {
                Some(s) => s + p,
                None => p,
            });
        }
        sum.map(|s| s / self.net.members.len() as f32)
            .unwrap_or_else(|| Tensor::zeros([x.len(), a.model.classes.len()], &self.device))
    }
}

/// Every vector has `inputs` values.
pub(crate) fn check_features(x: &[Vec<f32>], inputs: usize) -> Result<()> {
    match x.iter().find(|v| v.len() != inputs) {
        Some(bad) => Err(Error::Features {
            expected: inputs,
            found: bad.len(),
        }),
        None => Ok(()),
    }
}

/// One member: Adam on `train`, early stopping on the `val` error rate
/// (cross-entropy breaks ties).
fn train_member(
    config: &HeadConfig,
    seed: u64,
    (x, y): (Vec<Vec<f32>>, Vec<usize>),
    (val_x, val_y): (Vec<Vec<f32>>, Vec<usize>),
    (mean, std): (&[f32], &[f32]),
    device: &Device,
) -> Result<Mlp> {
    let ad = device.clone().autodiff();
    ad.seed(seed);
    let mlp = config.init_mlp(&ad);
    let loss_fn = CrossEntropyLossConfig::new().init(&ad);
    let xt = standardised(&x, mean, std, &ad);
    let yt = indices(&y, &ad);
    let vx = standardised(&val_x, mean, std, device);
    let vy = indices(&val_y, device);
    let val_loss = CrossEntropyLossConfig::new().init(device);
    let schedule = config.schedule.clone().with_seed(seed);
    fit_in_memory(
        &schedule,
        mlp,
        x.len(),
        |m, bi| {
            let logits = m.forward(xt.clone().select(0, bi.clone()));
            loss_fn.forward(logits, yt.clone().select(0, bi))
        },
        |v| {
            let val_logits = v.forward(vx.clone());
            let pred = argmax_rows(val_logits.clone());
            let err =
                pred.iter().zip(&val_y).filter(|(a, b)| a != b).count() as f64 / val_y.len() as f64;
            let vl: f32 = val_loss.forward(val_logits, vy.clone()).into_scalar();
            Ok(err + 1e-3 * vl as f64)
        },
        &ad,
    )
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
    use tactile_burn::DeviceKind;

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

    fn abc() -> Vec<String> {
        vec!["a".into(), "b".into(), "c".into()]
    }

    #[test]
    fn ensemble_learns_and_round_trips() {
        let dev = DeviceKind::Flex.device();
        let (x, y) = clusters(90, 1);
        let cfg = HeadConfig::new(4, abc())
            .with_schedule(Schedule::new(64, 60, 20, 1e-2).with_seed(7))
            .with_folds(3)
            .with_repeats(2);
        let head = ClassifierHead::train(cfg, &x, &y, &dev).unwrap();
        assert_eq!(head.net.members.len(), 6);
        let (tx, ty) = clusters(60, 2);
        let pred = head.predict(&tx).unwrap();
        let acc = pred.iter().zip(&ty).filter(|(a, b)| a == b).count() as f64 / 60.0;
        assert!(acc > 0.9, "accuracy {acc}");
        let dir = tempfile::tempdir().unwrap();
        head.save(dir.path()).unwrap();
        let back = ClassifierHead::load(dir.path(), &dev).unwrap();
        assert_eq!(back.predict(&tx).unwrap(), pred);
    }

    #[test]
    fn a_frame_on_several_rows_fits_or_stops_a_member_never_both() {
        // Rows of one frame (listed twice, or its rotated copies): before,
        // folds split rows, so a member could stop early on a frame it
        // fitted and stop later than on a frame it never saw.
        // Each row its own frame: the folds of one shuffle of the rows per
        // repeat, as heads were always trained (the shipped ones too).
        let rows: Vec<usize> = (0..12).collect();
        let mut old = Vec::new();
        for repeat in 0..2u64 {
            let order = shuffled_batches(&rows, 12, 7 + 7919 * repeat).concat();
            for fold in 0..3 {
                let (mut fit, mut stop) = (Vec::new(), Vec::new());
                for (pos, &i) in order.iter().enumerate() {
                    if pos % 3 == fold {
                        stop.push(i);
                    } else {
                        fit.push(i);
                    }
                }
                old.push((fit, stop));
            }
        }
        assert_eq!(folds_by_frame(&rows, 3, 2, 7).unwrap(), old);
        // 10 frames, each on 3 rows spread over the list, and 5 frames once.
        let frames: Vec<usize> = (0..30).map(|i| i % 10).chain(10..15).collect();
        let members = folds_by_frame(&frames, 4, 3, 11).unwrap();
        assert_eq!(members.len(), 12);
        for (m, (fit, stop)) in members.iter().enumerate() {
            let of = |rows: &[usize]| -> std::collections::BTreeSet<usize> {
                rows.iter().map(|&i| frames[i]).collect()
            };
            assert!(of(fit).is_disjoint(&of(stop)), "member {m}");
            let mut all = [fit.clone(), stop.clone()].concat();
            all.sort_unstable();
            assert_eq!(all, (0..35).collect::<Vec<_>>(), "member {m}");
        }
        // Each repeat's stopping rows cover every row once.
        for repeat in members.chunks(4) {
            let mut stops: Vec<usize> = repeat.iter().flat_map(|(_, s)| s.clone()).collect();
            stops.sort_unstable();
            assert_eq!(stops, (0..35).collect::<Vec<_>>());
        }
        // Fewer frames than folds is named, however many rows they have.
        let two = [0, 1, 0, 1, 0, 1];
        let e = folds_by_frame(&two, 3, 1, 7).unwrap_err().to_string();
        assert!(
            e.contains("at least 3 frames") && e.contains("got 2"),
            "{e}"
        );
        let dev = DeviceKind::Flex.device();
        let (x, y) = clusters(6, 1);
        let cfg = HeadConfig::new(4, abc()).with_folds(3);
        let e = ClassifierHead::train_by_frame(cfg.clone(), &x, &y, &two, &dev);
        assert!(e.err().unwrap().to_string().contains("at least 3 frames"));
        let e = ClassifierHead::train_by_frame(cfg, &x, &y, &two[..5], &dev);
        assert!(e.err().unwrap().to_string().contains("5 frame names for 6"));
    }

    #[test]
    fn bad_inputs_are_errors() {
        let dev = DeviceKind::Flex.device();
        let (x, y) = clusters(9, 1);
        let cfg = HeadConfig::new(4, abc()).with_folds(3);
        let e = ClassifierHead::train(cfg.clone().with_folds(1), &x, &y, &dev);
        assert!(e.err().unwrap().to_string().contains("folds"));
        let mut wide = cfg.clone();
        wide.inputs = 5;
        let e = ClassifierHead::train(wide, &x, &y, &dev);
        assert!(matches!(
            e,
            Err(Error::Features {
                expected: 5,
                found: 4
            })
        ));
        let mut bad = y.clone();
        bad[0] = 7;
        let e = ClassifierHead::train(cfg.clone(), &x, &bad, &dev);
        assert!(e.err().unwrap().to_string().contains("class index 7"));
        let e = ClassifierHead::train(cfg.with_folds(10), &x, &y, &dev);
        assert!(e.err().unwrap().to_string().contains("at least 10"));
    }
}
