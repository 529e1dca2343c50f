//! torchvision DenseNet weights (`densenet121`/`densenet161` state dicts
//! saved as safetensors) into the depth network's encoder. Nothing is
//! downloaded: a user who has the weights converts them once in Python,
//!
//! ```text
//! import torchvision, safetensors.torch as st
//! m = torchvision.models.densenet121(weights="IMAGENET1K_V1")
//! st.save_file({k: v.float() for k, v in m.state_dict().items()}, "densenet121.safetensors")
//! ```
//!
//! and passes the file to `tactile train depth --pretrained FILE`.
//!
//! Key mapping (torchvision -> ours; `b`, `l`, `t` count from 1 there, from 0 here):
//!
//! | torchvision | tactile-depth encoder |
//! |---|---|
//! | `features.conv0.weight` | `conv0.weight` (a 4th, mask input channel starts at zero) |
//! | `features.norm0.{weight,bias,running_mean,running_var}` | `norm0.{gamma,beta,running_mean,running_var}` |
//! | `features.denseblock{b}.denselayer{l}.norm1.*`, `.conv1.weight`, `.norm2.*`, `.conv2.weight` | `blocks[b-1].layers[l-1].norm1`, `conv1`, `norm2`, `conv2` |
//! | `features.transition{t}.norm.*`, `.conv.weight` | `transitions[t-1].norm`, `conv` |
//! | `features.norm5.*` | `norm5` |
//! | `classifier.*`, `*.num_batches_tracked` | ignored |

use std::path::Path;

use burn::module::{Param, RunningState};
use burn::nn::BatchNorm;
use burn::nn::conv::Conv2d;
use burn::tensor::{Device, Tensor, TensorData};
use safetensors::SafeTensors;
use tactile_burn::module_io::safetensors_f32;
use tactile_core::{Error, Result};

use crate::model::DenseNetEncoder;

struct Source<'a> {
    st: SafeTensors<'a>,
    path: &'a Path,
    device: Device,
}

impl Source<'_> {
    fn get(&self, name: &str, shape: &[usize]) -> Result<Vec<f32>> {
        let (s, v) = safetensors_f32(&self.st, self.path, name)?;
        if s != shape {
            return Err(Error::shape(
                format!("{}: {name}", self.path.display()),
                format!("{shape:?}"),
                format!("{s:?}"),
            ));
        }
        Ok(v)
    }

    fn vec1(&self, v: Vec<f32>) -> Tensor<1> {
        let n = v.len();
        Tensor::from_data(TensorData::new(v, [n]), &self.device)
    }

    fn conv(&self, conv: &mut Conv2d, name: &str) -> Result<()> {
        let dims = conv.weight.val().dims();
        let v = self.get(&format!("{name}.weight"), &dims)?;
        conv.weight = Param::from_tensor(Tensor::from_data(TensorData::new(v, dims), &self.device));
        Ok(())
    }

    fn norm(&self, bn: &mut BatchNorm, name: &str) -> Result<()> {
        let c = bn.gamma.val().dims()[0];
        bn.gamma = Param::from_tensor(self.vec1(self.get(&format!("{name}.weight"), &[c])?));
        bn.beta = Param::from_tensor(self.vec1(self.get(&format!("{name}.bias"), &[c])?));
        bn.running_mean =
            RunningState::new(self.vec1(self.get(&format!("{name}.running_mean"), &[c])?));
        bn.running_var =
            RunningState::new(self.vec1(self.get(&format!("{name}.running_var"), &[c])?));
        Ok(())
    }
}

/// Copy torchvision DenseNet weights into `encoder` (built with the same
/// preset); every tensor must be present with the right shape, or the
/// error names it.
pub fn load_torchvision_encoder(
    path: impl AsRef<Path>,
    mut encoder: DenseNetEncoder,
    device: &Device,
) -> Result<DenseNetEncoder> {
    let path = path.as_ref();
    let bytes = tactile_core::io::read_limited(path, tactile_core::io::MAX_WEIGHTS_BYTES)?;
    let st = SafeTensors::deserialize(&bytes)
        .map_err(|e| Error::model(path, format!("not a safetensors file: {e}")))?;
    let src = Source {
        st,
        path,
        device: device.clone(),
    };
    // The stem: torchvision takes RGB; a mask channel starts at zero.
    let [o, i, kh, kw] = encoder.conv0.weight.val().dims();
    let rgb = src.get("features.conv0.weight", &[o, 3, kh, kw])?;
    let mut w = vec![0f32; o * i * kh * kw];
    for co in 0..o {
        for ci in 0..3.min(i) {
            let k = kh * kw;
            w[(co * i + ci) * k..(co * i + ci + 1) * k]
                .copy_from_slice(&rgb[(co * 3 + ci) * k..(co * 3 + ci + 1) * k]);
        }
    }
    encoder.conv0.weight = Param::from_tensor(Tensor::from_data(
        TensorData::new(w, [o, i, kh, kw]),
        device,
    ));
    src.norm(&mut encoder.norm0, "features.norm0")?;
    for (b, block) in encoder.blocks.iter_mut().enumerate() {
        for (l, layer) in block.layers.iter_mut().enumerate() {
            let p = format!("features.denseblock{}.denselayer{}", b + 1, l + 1);
            src.norm(&mut layer.norm1, &format!("{p}.norm1"))?;
            src.conv(&mut layer.conv1, &format!("{p}.conv1"))?;
            src.norm(&mut layer.norm2, &format!("{p}.norm2"))?;
            src.conv(&mut layer.conv2, &format!("{p}.conv2"))?;
        }
    }
    for (t, tr) in encoder.transitions.iter_mut().enumerate() {
        let p = format!("features.transition{}", t + 1);
        src.norm(&mut tr.norm, &format!("{p}.norm"))?;
        src.conv(&mut tr.conv, &format!("{p}.conv"))?;
    }
    src.norm(&mut encoder.norm5, "features.norm5")?;
    Ok(encoder)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DenseNetConfig;
    use std::collections::HashMap;

    /// Write an encoder's weights under torchvision's names, as the Python
    /// snippet above would (plus the keys torchvision has that we ignore).
    fn torchvision_fixture(enc: &DenseNetEncoder, path: &Path) {
        let mut t: Vec<(String, Vec<usize>, Vec<f32>)> = Vec::new();
        let mut put = |name: String, x: Tensor<1>| {
            let n = x.dims()[0];
            t.push((name, vec![n], x.into_data().try_to_vec::<f32>().unwrap()));
        };
        let mut norm = |name: &str, bn: &BatchNorm| {
            put(format!("{name}.weight"), bn.gamma.val());
            put(format!("{name}.bias"), bn.beta.val());
            put(format!("{name}.running_mean"), bn.running_mean.value());
            put(format!("{name}.running_var"), bn.running_var.value());
        };
        norm("features.norm0", &enc.norm0);
        for (b, block) in enc.blocks.iter().enumerate() {
            for (l, layer) in block.layers.iter().enumerate() {
                let p = format!("features.denseblock{}.denselayer{}", b + 1, l + 1);
                norm(&format!("{p}.norm1"), &layer.norm1);
                norm(&format!("{p}.norm2"), &layer.norm2);
            }
        }
        for (k, tr) in enc.transitions.iter().enumerate() {
            norm(&format!("features.transition{}.norm", k + 1), &tr.norm);
        }
        norm("features.norm5", &enc.norm5);
        let mut convs: Vec<(String, &Conv2d)> = vec![("features.conv0".into(), &enc.conv0)];
        for (b, block) in enc.blocks.iter().enumerate() {
            for (l, layer) in block.layers.iter().enumerate() {
                let p = format!("features.denseblock{}.denselayer{}", b + 1, l + 1);
                convs.push((format!("{p}.conv1"), &layer.conv1));
                convs.push((format!("{p}.conv2"), &layer.conv2));
            }
        }
        for (k, tr) in enc.transitions.iter().enumerate() {
            convs.push((format!("features.transition{}.conv", k + 1), &tr.conv));
        }
        for (name, c) in convs {
            let v = c.weight.val();
            let dims = v.dims().to_vec();
            t.push((
                format!("{name}.weight"),
                dims,
                v.into_data().try_to_vec::<f32>().unwrap(),
            ));
        }
        t.push(("classifier.weight".into(), vec![2, 3], vec![0.0; 6]));
        let bytes: Vec<(String, Vec<usize>, Vec<u8>)> = t
            .into_iter()
            .map(|(n, s, v)| (n, s, v.iter().flat_map(|x| x.to_le_bytes()).collect()))
            .collect();
        let views: HashMap<String, safetensors::tensor::TensorView> = bytes
            .iter()
            .map(|(n, s, b)| {
                (
                    n.clone(),
                    safetensors::tensor::TensorView::new(safetensors::Dtype::F32, s.clone(), b)
                        .unwrap(),
                )
            })
            .collect();
        safetensors::serialize_to_file(&views, None, path).unwrap();
    }

    #[test]
    fn torchvision_names_load_into_the_encoder_exactly() {
        let device = Device::flex();
        let cfg = DenseNetConfig::preset("tiny").unwrap();
        // Source: trained-looking weights: random convolutions and norms
        // whose four vectors all differ (a swapped pair would show).
        let mut src = cfg.init(3, &device);
        let rand_norm = |bn: &mut BatchNorm| {
            let c = bn.gamma.val().dims()[0];
            let r = |lo: f64, hi: f64| {
                Tensor::<1>::random([c], burn::tensor::Distribution::Uniform(lo, hi), &device)
            };
            bn.gamma = Param::from_tensor(r(0.5, 1.5));
            bn.beta = Param::from_tensor(r(-0.5, 0.5));
            bn.running_mean = RunningState::new(r(-0.2, 0.2));
            bn.running_var = RunningState::new(r(0.5, 2.0));
        };
        rand_norm(&mut src.norm0);
        rand_norm(&mut src.norm5);
        for block in &mut src.blocks {
            for layer in &mut block.layers {
                rand_norm(&mut layer.norm1);
                rand_norm(&mut layer.norm2);
            }
        }
        for tr in &mut src.transitions {
            rand_norm(&mut tr.norm);
        }
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("densenet.safetensors");
        torchvision_fixture(&src, &file);
        let loaded = load_torchvision_encoder(&file, cfg.init(3, &device), &device).unwrap();
        let x = Tensor::<4>::random([1, 3, 64, 64], burn::tensor::Distribution::Default, &device);
        let (mut a, da) = src.forward(x.clone());
        let (mut b, db) = loaded.forward(x);
        a.push(da);
        b.push(db);
        for (p, q) in a.into_iter().zip(b) {
            let d: f32 = (p - q).abs().max().into_scalar();
            assert_eq!(d, 0.0);
        }
        // A mask channel is added with zero weights: RGB behaviour unchanged.
        let four = load_torchvision_encoder(&file, cfg.init(4, &device), &device).unwrap();
        assert_eq!(four.conv0.weight.val().dims()[1], 4);
        // A file for another preset is refused, naming the tensor.
        let other = DenseNetConfig::preset("small").unwrap().init(3, &device);
        let e = load_torchvision_encoder(&file, other, &device)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("densenet.safetensors") && e.contains("features."),
            "{e}"
        );
    }
}
