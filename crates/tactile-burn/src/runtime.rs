//! Where a network runs: burn on its `ndarray` or `flex` CPU device, or
//! onnxruntime from the exported graph. Every model wrapper (detector,
//! segmenter, depth) holds a [`Network`] and does its own preparation and
//! post-processing around it, so a frame takes the same path whatever the
//! runtime, in `tactile run`, in `tactile eval`, in Python and in the benches.

use std::fmt;
use std::str::FromStr;

use burn::module::Module;
use burn::tensor::{Device, Tensor, TensorData};
use serde::{Deserialize, Serialize};

use crate::{DeviceKind, Error, Result};

/// The runtimes every network runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Runtime {
    /// burn's NdArray device.
    BurnNdarray,
    /// burn's Flex device.
    BurnFlex,
    /// onnxruntime, from the network's ONNX export.
    Onnx,
}

impl Runtime {
    /// Every runtime, in report order (onnxruntime first: ratios are to it).
    pub const ALL: [Runtime; 3] = [Runtime::Onnx, Runtime::BurnFlex, Runtime::BurnNdarray];

    /// The burn device, or `None` for onnxruntime.
    pub fn device(self) -> Option<DeviceKind> {
        match self {
            Runtime::BurnNdarray => Some(DeviceKind::Ndarray),
            Runtime::BurnFlex => Some(DeviceKind::Flex),
            Runtime::Onnx => None,
        }
    }

    /// The name used on the command line and in records.
    pub fn name(self) -> &'static str {
        match self {
            Runtime::BurnNdarray => "burn-ndarray",
            Runtime::BurnFlex => "burn-flex",
            Runtime::Onnx => "onnx",
        }
    }
}

impl fmt::Display for Runtime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Runtime {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Runtime::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| {
                Error::Config(format!(
                    "unknown runtime '{s}': expected onnx, burn-flex or burn-ndarray"
                ))
            })
    }
}

impl DeviceKind {
    /// The runtime that runs networks on this device.
    pub fn runtime(self) -> Runtime {
        match self {
            DeviceKind::Ndarray => Runtime::BurnNdarray,
            DeviceKind::Flex => Runtime::BurnFlex,
        }
    }
}

/// A network ready to run: a normalised `[N, C, H, W]` input in, its raw
/// output (logits, depth in model units, features) out, flattened.
pub trait Network: Send {
    /// Run on `input`, `shape[0] * shape[1] * shape[2] * shape[3]` values.
    /// Once a stop is requested (Ctrl-C, SIGTERM) every run is refused with
    /// `Interrupted`, so inference over many batches stops between two.
    fn run(&mut self, shape: [usize; 4], input: Vec<f32>) -> Result<Vec<f32>>;
    /// Where it runs.
    fn runtime(&self) -> Runtime;
}

/// A burn module whose forward pass takes a `[N, C, H, W]` batch.
pub trait Forward: Module {
    /// The raw output of `x`, as data.
    fn forward_data(&self, x: Tensor<4>) -> TensorData;

    /// The module made for inference only, giving the same outputs faster
    /// (batch norms folded into the convolutions before them, see
    /// [`crate::nn::fold_batch_norm`]); the default keeps it as it is.
    fn for_inference(self) -> Self
    where
        Self: Sized,
    {
        self
    }
}

/// A burn module on a burn device.
pub struct BurnNetwork<M> {
    model: M,
    device: Device,
    kind: DeviceKind,
}

impl<M: Forward> BurnNetwork<M> {
    /// Wrap `model`, which lives on `kind`'s device, made for inference
    /// ([`Forward::for_inference`]).
    pub fn new(model: M, kind: DeviceKind) -> Self {
        Self {
            model: model.for_inference(),
            device: kind.device(),
            kind,
        }
    }

    /// Wrap `model` as it is, without [`Forward::for_inference`]: what the
    /// benches compare the inference form against.
    pub fn as_trained(model: M, kind: DeviceKind) -> Self {
        Self {
            model,
            device: kind.device(),
            kind,
        }
    }

    /// The module.
    pub fn model(&self) -> &M {
        &self.model
    }
}

impl<M: Forward + Send> Network for BurnNetwork<M> {
    fn run(&mut self, shape: [usize; 4], input: Vec<f32>) -> Result<Vec<f32>> {
        tactile_core::interrupt::check()?;
        let n: usize = shape.iter().product();
        if input.len() != n {
            return Err(Error::shape(
                "network input",
                format!("{n} values for {shape:?}"),
                input.len(),
            ));
        }
        let x = Tensor::<4>::from_data(TensorData::new(input, shape), &self.device);
        self.model
            .forward_data(x)
            .convert::<f32>()
            .try_into_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("network output: {e:?}")))
    }

    fn runtime(&self) -> Runtime {
        match self.kind {
            DeviceKind::Ndarray => Runtime::BurnNdarray,
            DeviceKind::Flex => Runtime::BurnFlex,
        }
    }
}

/// The logistic function, the one place a logit becomes a probability.
pub fn sigmoid(z: f32) -> f32 {
    1.0 / (1.0 + (-z).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runtimes_parse_and_print() {
        for r in Runtime::ALL {
            assert_eq!(r.name().parse::<Runtime>().unwrap(), r);
        }
        let e = "tensorflow".parse::<Runtime>().unwrap_err().to_string();
        assert!(e.contains("tensorflow"), "{e}");
        assert_eq!(sigmoid(0.0), 0.5);
        assert!(sigmoid(-1000.0) >= 0.0 && sigmoid(1000.0) <= 1.0);
    }
}
