//! The multilayer perceptron every estimator is made of, and the one loop
//! that fits one in memory on feature vectors.

use burn::module::Module;
use burn::nn::{Linear, LinearConfig};
use burn::optim::AdamConfig;
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Device, Int, Tensor, TensorData};
use serde::{Deserialize, Serialize};
use tactile_burn::train::{FitConfig, Schedule, fit};

use crate::Result;

/// Hidden-layer activation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    /// `max(0, x)`.
    Relu,
    /// The logistic function (the authors' shape head).
    Sigmoid,
}

/// Most features an estimator takes.
pub const MAX_INPUTS: usize = 1 << 16;
/// Widest hidden layer accepted.
pub const MAX_HIDDEN_WIDTH: usize = 4096;
/// Most hidden layers accepted.
pub const MAX_HIDDEN_LAYERS: usize = 16;

/// Check an MLP's sizes against the limits before it is built.
pub fn check_sizes(
    inputs: usize,
    hidden: &[(usize, Activation)],
    outputs: usize,
) -> tactile_core::Result<()> {
    let bad = |m: String| Err(tactile_core::Error::Config(m));
    if inputs == 0 || inputs > MAX_INPUTS {
        return bad(format!("{inputs} inputs: must be 1 to {MAX_INPUTS}"));
    }
    if outputs == 0 || outputs > MAX_INPUTS {
        return bad(format!("{outputs} outputs: must be 1 to {MAX_INPUTS}"));
    }
    if hidden.len() > MAX_HIDDEN_LAYERS {
        return bad(format!(
            "{} hidden layers: at most {MAX_HIDDEN_LAYERS}",
            hidden.len()
        ));
    }
    if let Some((w, _)) = hidden
        .iter()
        .find(|(w, _)| *w == 0 || *w > MAX_HIDDEN_WIDTH)
    {
        return bad(format!("hidden width {w}: must be 1 to {MAX_HIDDEN_WIDTH}"));
    }
    tactile_burn::artifact::check_parameters("MLP", parameters(inputs, hidden, outputs))
}

/// Weights and biases of an MLP.
pub fn parameters(inputs: usize, hidden: &[(usize, Activation)], outputs: usize) -> u64 {
    let dims: Vec<u64> = std::iter::once(inputs)
        .chain(hidden.iter().map(|h| h.0))
        .chain(std::iter::once(outputs))
        .map(|d| d as u64)
        .collect();
    dims.windows(2)
        .map(|w| w[0].saturating_mul(w[1]).saturating_add(w[1]))
        .fold(0u64, u64::saturating_add)
}

/// Refuse standardisation statistics of another length than `n`, or with
/// a non-finite mean or a scale that is not a positive finite number.
pub fn check_scaler<T: Into<f64> + Copy>(
    what: &str,
    mean: &[T],
    std: &[T],
    n: usize,
) -> tactile_core::Result<()> {
    let bad = |m: String| Err(tactile_core::Error::Config(format!("{what}: {m}")));
    if mean.len() != n || std.len() != n {
        return bad(format!(
            "{} means and {} deviations for {n} values",
            mean.len(),
            std.len()
        ));
    }
    if let Some(m) = mean
        .iter()
        .map(|&m| m.into())
        .find(|m: &f64| !m.is_finite())
    {
        return bad(format!("a mean is {m}"));
    }
    if let Some(s) = std
        .iter()
        .map(|&s| s.into())
        .find(|s: &f64| !(s.is_finite() && *s > 0.0))
    {
        return bad(format!("a standard deviation is {s}: it must be positive"));
    }
    Ok(())
}

/// Fully connected layers with an activation after each hidden one.
#[derive(Module, Debug)]
pub struct Mlp {
    /// Input to first hidden, ..., last hidden to output.
    pub layers: Vec<Linear>,
    /// One per hidden layer.
    #[module(skip)]
    pub activations: Vec<Activation>,
}

impl Mlp {
    /// Layers of sizes `dims` (inputs, hidden..., outputs) with burn's
    /// default initialisation; `activations` follow each hidden layer.
    pub fn new(dims: &[usize], activations: &[Activation], device: &Device) -> Self {
        Mlp {
            layers: dims
                .windows(2)
                .map(|w| LinearConfig::new(w[0], w[1]).init(device))
                .collect(),
            activations: activations.to_vec(),
        }
    }

    /// `inputs -> hidden... -> outputs`.
    pub fn with_hidden(
        inputs: usize,
        hidden: &[(usize, Activation)],
        outputs: usize,
        device: &Device,
    ) -> Self {
        let mut dims = vec![inputs];
        dims.extend(hidden.iter().map(|h| h.0));
        dims.push(outputs);
        let acts: Vec<Activation> = hidden.iter().map(|h| h.1).collect();
        Self::new(&dims, &acts, device)
    }

    /// Outputs `[N, last]` (class logits, or standardised targets).
    ///
    /// # Shapes
    /// - `x`: `[N, inputs]`
    /// - output: `[N, outputs]`
    pub fn forward(&self, x: Tensor<2>) -> Tensor<2> {
        match self.layers.last() {
            Some(out) => out.forward(self.hidden(x)),
            None => x,
        }
    }

    /// The outputs, and the outputs again computed from the last hidden
    /// layer with its gradient stopped: what trains only the output layer
    /// (a regressor's uncertainty) reads the second.
    ///
    /// # Shapes
    /// - `x`: `[N, inputs]`
    /// - outputs: `[N, outputs]` each
    pub fn forward_and_detached(&self, x: Tensor<2>) -> (Tensor<2>, Tensor<2>) {
        let h = self.hidden(x);
        match self.layers.last() {
            Some(out) => (out.forward(h.clone()), out.forward(h.detach())),
            None => (h.clone(), h.detach()),
        }
    }

    /// The last hidden layer's activations (the input when there is none).
    ///
    /// # Shapes
    /// - `x`: `[N, inputs]`
    /// - output: `[N, last hidden width]`
    pub fn hidden(&self, mut x: Tensor<2>) -> Tensor<2> {
        let last = self.layers.len().saturating_sub(1);
        for (layer, act) in self.layers[..last].iter().zip(&self.activations) {
            x = match act {
                Activation::Relu => relu(layer.forward(x)),
                Activation::Sigmoid => sigmoid(layer.forward(x)),
            };
        }
        x
    }
}

/// A `[rows, cols]` tensor of row-major values.
pub fn matrix(rows: usize, cols: usize, data: Vec<f32>, device: &Device) -> Tensor<2> {
    Tensor::from_data(TensorData::new(data, [rows, cols]), device)
}

/// Indices as an integer tensor.
pub fn indices(idx: &[usize], device: &Device) -> Tensor<1, Int> {
    Tensor::from_data(
        TensorData::new(
            idx.iter().map(|&i| i as i64).collect::<Vec<_>>(),
            [idx.len()],
        ),
        device,
    )
}

/// Fit `mlp` (built on an autodiff device) with Adam on the rows of `x`
/// (`n` of them, already on that device) through the workspace's one
/// training loop, in memory: `loss` gets the model, the rows of a batch
/// and the batch's indices; `validate` returns the loss early stopping
/// watches. Returns the best epoch's model.
pub fn fit_in_memory(
    schedule: &Schedule,
    mlp: Mlp,
    n: usize,
    mut loss: impl FnMut(&Mlp, Tensor<1, Int>) -> Tensor<1>,
    mut validate: impl FnMut(&Mlp) -> Result<f64>,
    device: &Device,
) -> Result<Mlp> {
    let mut best: Option<Mlp> = None;
    let items: Vec<usize> = (0..n).collect();
    let (last, _) = fit::<_, crate::Error>(
        &FitConfig::new(schedule, "estimator"),
        mlp,
        AdamConfig::new().init(),
        (&items, 0),
        |m: &Mlp, batch, _| Ok(loss(m, indices(batch, device))),
        |m| Ok((validate(m)?, None)),
        |m| {
            best = Some(m.clone());
            Ok(())
        },
    )?;
    Ok(best.unwrap_or_else(|| last.valid()))
}
