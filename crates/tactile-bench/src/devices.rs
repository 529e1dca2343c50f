//! Each paper B model at batch 1 on every device: burn's ndarray and flex
//! as trained and in the inference form (batch norms folded into their
//! convolutions), beside onnxruntime; and what the folding changes in the
//! outputs.

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_burn::runtime::{BurnNetwork, Forward};
use tactile_burn::{Artifact, DeviceKind, Network, Runtime};
use tactile_core::bench::Machine;
use tactile_onnx::{Exportable, load_network};

use crate::Result;
use crate::latency::{stand_in_input, threads, time_network};

/// One model's medians, ms, and the largest output difference folding made.
#[derive(Debug, Clone, Serialize)]
pub struct DeviceRow {
    /// Which model.
    pub model: String,
    /// Its input shape.
    pub input: [usize; 4],
    /// burn ndarray, as trained.
    pub ndarray_ms: f64,
    /// burn ndarray, inference form.
    pub ndarray_folded_ms: f64,
    /// burn flex, as trained.
    pub flex_ms: f64,
    /// burn flex, inference form.
    pub flex_folded_ms: f64,
    /// onnxruntime (`None` when it is not installed).
    pub onnxruntime_ms: Option<f64>,
    /// Largest absolute difference of the raw outputs, folded against as
    /// trained, on flex.
    pub folding_max_diff: f32,
    /// Operations in its exported graph, by kind.
    pub ops: Vec<(String, usize)>,
}

/// One operation timed alone on each runtime, µs.
#[derive(Debug, Clone, Serialize)]
pub struct OpRow {
    /// What it is.
    pub op: String,
    /// burn ndarray.
    pub ndarray_us: f64,
    /// burn flex.
    pub flex_us: f64,
    /// onnxruntime, the same module exported.
    pub onnxruntime_us: Option<f64>,
}

/// Convolutions of one of the paper B models' kinds in a chain (in -> out,
/// out -> in, ...), so a runtime's fixed cost per call is shared by all.
#[derive(burn::module::Module, Debug)]
struct ConvProbe {
    convs: Vec<burn::nn::conv::Conv2d>,
}

impl ConvProbe {
    fn forward(&self, x: burn::tensor::Tensor<4>) -> burn::tensor::Tensor<4> {
        self.convs.iter().fold(x, |x, c| c.forward(x))
    }
}

impl Forward for ConvProbe {
    fn forward_data(&self, x: burn::tensor::Tensor<4>) -> burn::tensor::TensorData {
        self.forward(x).into_data()
    }
}

/// Convolutions per probe chain.
const CHAIN: usize = 8;

/// Convolutions like the models' (k x k, in -> out channels, groups, at
/// H x W), timed per convolution in a chain on ndarray, flex and
/// onnxruntime: where burn's time goes.
pub fn conv_probes(runs: usize) -> Result<Vec<OpRow>> {
    tactile_core::bench::check_runs(runs)?;
    use burn::nn::PaddingConfig2d;
    use burn::nn::conv::Conv2dConfig;
    // (what, kernel, in, out, groups, [height, width])
    type Probe = (&'static str, usize, usize, usize, usize, [usize; 2]);
    let probes: [Probe; 5] = [
        (
            "segmenter: 3x3 conv, 4 -> 8 channels, 48x48",
            3,
            4,
            8,
            1,
            [48, 48],
        ),
        (
            "detector: 3x3 stride-1 depthwise conv, 16 channels, 30x40",
            3,
            16,
            16,
            16,
            [30, 40],
        ),
        (
            "detector: 1x1 conv, 16 -> 48 channels, 15x20",
            1,
            16,
            48,
            1,
            [15, 20],
        ),
        (
            "depth: 1x1 conv, 64 -> 32 channels, 16x24",
            1,
            64,
            32,
            1,
            [16, 24],
        ),
        (
            "depth: 3x3 conv, 32 -> 8 channels, 16x24",
            3,
            32,
            8,
            1,
            [16, 24],
        ),
    ];
    let mut rows = Vec::new();
    for (name, k, i, o, g, [h, w]) in probes {
        let shape = [1, i, h, w];
        let input = stand_in_input(shape.iter().product());
        let make = |device: &burn::tensor::Device| ConvProbe {
            convs: (0..CHAIN)
                .map(|j| {
                    let io = if j % 2 == 0 { [i, o] } else { [o, i] };
                    Conv2dConfig::new(io, [k, k])
                        .with_groups(g)
                        .with_padding(PaddingConfig2d::Explicit(k / 2, k / 2, k / 2, k / 2))
                        .init(device)
                })
                .collect(),
        };
        let per_conv = CHAIN as f64 / 1e3;
        let us = |kind: DeviceKind| {
            let mut net = BurnNetwork::new(make(&kind.device()), kind);
            time_network(&mut net, shape, &input, runs) / per_conv
        };
        let (ndarray_us, flex_us) = (us(DeviceKind::Ndarray), us(DeviceKind::Flex));
        let probe = make(&DeviceKind::Flex.device());
        let bytes =
            tactile_onnx::export::export_batch_dynamic(&probe, shape, |m: &ConvProbe, x| {
                m.forward(x)
            })?;
        let onnxruntime_us = match tactile_onnx::runtime::OrtModel::from_bytes(&bytes, threads()) {
            Ok(mut m) => Some(time_network(&mut m, shape, &input, runs) / per_conv),
            Err(_) => None,
        };
        rows.push(OpRow {
            op: name.to_string(),
            ndarray_us,
            flex_us,
            onnxruntime_us,
        });
    }
    Ok(rows)
}

fn row<A>(name: &str, dir: &Path, shape: [usize; 4], runs: usize) -> Result<DeviceRow>
where
    A: Exportable,
    A::Model: Forward + Send + Clone + 'static,
{
    tactile_core::note!("{name}: {}", dir.display());
    let input = stand_in_input(shape.iter().product());
    let ms = |kind: DeviceKind, folded: bool| -> Result<(f64, Vec<f32>)> {
        let model = A::load(dir, &kind.device())?.model;
        let mut net: Box<dyn Network> = match folded {
            true => Box::new(BurnNetwork::new(model, kind)),
            false => Box::new(BurnNetwork::as_trained(model, kind)),
        };
        let out = net.run(shape, input.clone())?;
        Ok((time_network(net.as_mut(), shape, &input, runs), out))
    };
    let (ndarray_ms, _) = ms(DeviceKind::Ndarray, false)?;
    let (ndarray_folded_ms, _) = ms(DeviceKind::Ndarray, true)?;
    let (flex_ms, plain) = ms(DeviceKind::Flex, false)?;
    let (flex_folded_ms, folded) = ms(DeviceKind::Flex, true)?;
    let folding_max_diff = plain
        .iter()
        .zip(&folded)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    let loaded = A::load(dir, &DeviceKind::Flex.device())?;
    let ops = tactile_onnx::standalone::op_counts(&loaded.artifact.onnx(&loaded.model)?)?;
    let onnxruntime_ms = match load_network::<A>(dir, Runtime::Onnx, threads()) {
        Ok((_, mut net)) => Some(time_network(net.as_mut(), shape, &input, runs)),
        Err(e) => {
            tactile_core::note!("onnxruntime skipped: {e}");
            None
        }
    };
    Ok(DeviceRow {
        model: name.into(),
        input: shape,
        ndarray_ms,
        ndarray_folded_ms,
        flex_ms,
        flex_folded_ms,
        onnxruntime_ms,
        folding_max_diff,
        ops,
    })
}

/// The shipped detector, segmenter and depth network in `models`.
pub fn bench_devices(models: &Path, runs: usize) -> Result<Vec<DeviceRow>> {
    tactile_core::bench::check_runs(runs)?;
    use tactile_depth::DepthArtifact;
    use tactile_detect::DetectorArtifact;
    use tactile_segment::SegmenterArtifact;
    let d: PathBuf = models.join("detector");
    let [w, h] = tactile_detect::ensemble::read_config(&d)?.model.input_size;
    let s_dir = models.join("segmenter");
    let s = SegmenterArtifact::read(&s_dir)?.model.side;
    let z_dir = models.join("depth");
    let dep = tactile_depth::ensemble::read_config(&z_dir)?;
    let [zw, zh] = dep.model.input_size;
    let zc = dep.model.in_channels;
    Ok(vec![
        if tactile_detect::DetectorEnsembleArtifact::is_in(&d) {
            row::<tactile_detect::DetectorEnsembleArtifact>("detector", &d, [1, 3, h, w], runs)?
        } else {
            row::<DetectorArtifact>("detector", &d, [1, 3, h, w], runs)?
        },
        row::<SegmenterArtifact>("segmenter", &s_dir, [1, 3, s, s], runs)?,
        if tactile_depth::DepthEnsembleArtifact::is_in(&z_dir) {
            row::<tactile_depth::DepthEnsembleArtifact>("depth", &z_dir, [1, zc, zh, zw], runs)?
        } else {
            row::<DepthArtifact>("depth", &z_dir, [1, zc, zh, zw], runs)?
        },
    ])
}

/// The table: per model and device, the speed-up folding gives and each
/// burn device against onnxruntime; then what limits burn: single
/// convolutions of the models' kinds on every runtime.
pub fn devices_markdown(rows: &[DeviceRow], probes: &[OpRow], runs: usize) -> String {
    let mut md = format!(
        "Machine: {}. Batch 1, median of {runs} runs after 3 warm-ups, {} threads (burn's rayon pool \
         and onnxruntime's intra-op threads). \"as trained\": the saved module; \"inference\": batch \
         norms folded into the convolutions before them (`Forward::for_inference`, what every burn \
         path of the toolkit runs). Largest output change from folding: float rounding only.\n\n\
         | model | input | ndarray as trained (ms) | ndarray inference (ms) | flex as trained (ms) | flex inference (ms) | onnxruntime (ms) | flex / onnxruntime | folding: largest output change |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        Machine::detect().describe(),
        threads()
    );
    for r in rows {
        let [_, c, h, w] = r.input;
        md.push_str(&format!(
            "| {} | {c}x{h}x{w} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {:.1e} |\n",
            r.model,
            r.ndarray_ms,
            r.ndarray_folded_ms,
            r.flex_ms,
            r.flex_folded_ms,
            r.onnxruntime_ms.map_or("-".into(), |v| format!("{v:.2}")),
            r.onnxruntime_ms
                .map_or("-".into(), |v| format!("{:.1}x", r.flex_folded_ms / v)),
            r.folding_max_diff
        ));
    }
    md.push_str(
        "\nWhere burn's time goes: convolutions of the models' kinds, each timed per convolution \
         in a chain of 8 (so a runtime's fixed cost per call is shared) on every runtime (the \
         same module exported to ONNX for onnxruntime):\n\n\
         | convolution | ndarray (µs) | flex (µs) | onnxruntime (µs) | flex / onnxruntime |\n|---|---|---|---|---|\n",
    );
    for p in probes {
        md.push_str(&format!(
            "| {} | {:.1} | {:.1} | {} | {} |\n",
            p.op,
            p.ndarray_us,
            p.flex_us,
            p.onnxruntime_us.map_or("-".into(), |v| format!("{v:.1}")),
            p.onnxruntime_us
                .map_or("-".into(), |v| format!("{:.1}x", p.flex_us / v.max(1e-9)))
        ));
    }
    md.push_str("\nOperations per exported graph (onnxruntime fuses many of them): ");
    let ops: Vec<String> = rows
        .iter()
        .map(|r| {
            let n: usize = r.ops.iter().map(|o| o.1).sum();
            let top: Vec<String> = r
                .ops
                .iter()
                .take(3)
                .map(|(k, c)| format!("{k} {c}"))
                .collect();
            format!("{} {n} ({})", r.model, top.join(", "))
        })
        .collect();
    md.push_str(&ops.join("; "));
    md.push_str(".\n");
    md
}
