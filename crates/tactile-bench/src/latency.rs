//! Timing a saved model on every runtime through the same
//! [`Network`] path inference uses.

use std::path::Path;

use serde::Serialize;
use tactile_burn::runtime::Forward;
use tactile_burn::{Network, Runtime};
use tactile_core::bench::median_seconds;
use tactile_onnx::{Exportable, load_network};

use crate::Result;

/// Median milliseconds per runtime; `None` where the runtime was not
/// available (onnxruntime missing).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct RuntimeMs {
    /// burn's NdArray device.
    #[serde(rename = "burn ndarray")]
    pub ndarray: Option<f64>,
    /// burn's Flex device.
    #[serde(rename = "burn flex")]
    pub flex: Option<f64>,
    /// onnxruntime.
    #[serde(rename = "onnxruntime 1.31.1")]
    pub onnxruntime: Option<f64>,
}

impl RuntimeMs {
    /// The runtimes in table order, with their series names.
    pub fn named(&self) -> Vec<(&'static str, Option<f64>)> {
        vec![
            ("burn ndarray", self.ndarray),
            ("burn flex", self.flex),
            ("onnxruntime 1.31.1", self.onnxruntime),
        ]
    }

    /// Models run one after another (an ensemble's members): per runtime
    /// the sum, where every model has a time.
    pub fn sum(parts: &[RuntimeMs]) -> RuntimeMs {
        let add = |f: fn(&RuntimeMs) -> Option<f64>| {
            parts
                .iter()
                .map(f)
                .sum::<Option<f64>>()
                .filter(|_| !parts.is_empty())
        };
        RuntimeMs {
            ndarray: add(|r| r.ndarray),
            flex: add(|r| r.flex),
            onnxruntime: add(|r| r.onnxruntime),
        }
    }

    /// The milliseconds of `runtime`.
    pub fn get(&self, runtime: Runtime) -> Option<f64> {
        match runtime {
            Runtime::BurnNdarray => self.ndarray,
            Runtime::BurnFlex => self.flex,
            Runtime::Onnx => self.onnxruntime,
        }
    }

    fn set(&mut self, runtime: Runtime, ms: f64) {
        match runtime {
            Runtime::BurnNdarray => self.ndarray = Some(ms),
            Runtime::BurnFlex => self.flex = Some(ms),
            Runtime::Onnx => self.onnxruntime = Some(ms),
        }
    }
}

/// A table cell: `ms` with two decimals, or `-`.
pub fn ms_cell(ms: Option<f64>) -> String {
    ms.map_or("-".into(), |v| format!("{v:.2}"))
}

/// Threads every bench gives onnxruntime: all cores (burn's rayon uses them too).
pub fn threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// Seeded stand-in input values (latency does not depend on them).
pub fn stand_in_input(n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| ((i * 7919) % 255) as f32 / 128.0 - 1.0)
        .collect()
}

/// Median milliseconds of `runs` calls of `net` on `input` (3 warm-ups).
pub fn time_network(net: &mut dyn Network, shape: [usize; 4], input: &[f32], runs: usize) -> f64 {
    1e3 * median_seconds(3, runs, || {
        let _ = net.run(shape, input.to_vec());
    })
}

/// Median milliseconds of the encoder folder `dir`'s estimators on one
/// stand-in feature vector, on the burn device each runtime runs them on
/// (onnxruntime runs the encoder only; its estimators run on burn's Flex,
/// as `tactile predict` runs them, so that row takes Flex's time), with
/// their summed parameters.
pub fn estimator_latencies(dir: &Path, runs: usize) -> Result<(usize, RuntimeMs)> {
    use tactile_burn::DeviceKind;
    let time = |device: DeviceKind| -> Result<(usize, f64)> {
        let est = tactile_estimate::Estimators::load(dir, &[], &device.device())?;
        let k = est.items.first().map_or(0, |(_, e)| e.inputs());
        let feats = vec![stand_in_input(k)];
        let ms = 1e3
            * median_seconds(3, runs, || {
                let _ = est.estimate(&feats);
            });
        Ok((est.parameters(), ms))
    };
    let (params, ndarray) = time(DeviceKind::Ndarray)?;
    let (_, flex) = time(DeviceKind::Flex)?;
    Ok((
        params,
        RuntimeMs {
            ndarray: Some(ndarray),
            flex: Some(flex),
            onnxruntime: Some(flex),
        },
    ))
}

/// Median batch-1 milliseconds of the model in `dir` on every runtime
/// (burn ndarray, burn flex, onnxruntime), on a stand-in input of `shape`.
/// A runtime that cannot load (onnxruntime not installed) is skipped with
/// a note on stderr.
pub fn model_latencies<A>(dir: &Path, shape: [usize; 4], runs: usize) -> Result<RuntimeMs>
where
    A: Exportable,
    A::Model: Forward + Send + 'static,
{
    let input = stand_in_input(shape.iter().product());
    let mut out = RuntimeMs::default();
    for runtime in [Runtime::BurnNdarray, Runtime::BurnFlex, Runtime::Onnx] {
        match load_network::<A>(dir, runtime, threads()) {
            Ok((_, mut net)) => out.set(runtime, time_network(net.as_mut(), shape, &input, runs)),
            Err(e) if runtime == Runtime::Onnx => tactile_core::note!("onnxruntime skipped: {e}"),
            Err(e) => return Err(e.into()),
        }
    }
    Ok(out)
}
