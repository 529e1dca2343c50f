//! Adadelta (Zeiler 2012), which paper A trains with and burn 0.22 lacks.
//! Implemented on burn's `Optimizer` trait so that `ModuleOptimizer` saves
//! and restores its state with the model (resumable training).

use burn::config::Config;
use burn::optim::{LearningRate, ModuleOptimizer, Optimizer, RecordState, StateSink, StateSource};
use burn::tensor::{Device, Tensor};

/// Adadelta settings; the defaults are Keras' (`rho` 0.95, `epsilon` 1e-7, lr 1.0).
#[derive(Config, Debug)]
pub struct AdadeltaConfig {
    /// Decay of the running averages.
    #[config(default = 0.95)]
    pub rho: f64,
    /// Added inside the square roots.
    #[config(default = 1e-7)]
    pub epsilon: f64,
}

/// The Adadelta update rule.
#[derive(Clone, Debug)]
pub struct Adadelta {
    rho: f64,
    epsilon: f64,
}

/// Per-parameter running averages of squared gradients and squared updates.
#[derive(Clone)]
pub struct AdadeltaState<const D: usize> {
    /// Running mean of squared gradients.
    pub square_avg: Tensor<D>,
    /// Running mean of squared updates.
    pub acc_delta: Tensor<D>,
}

impl<const D: usize> RecordState for AdadeltaState<D> {
    fn state_flatten(&self, prefix: &str, out: &mut StateSink) {
        out.push_tensor(prefix, "square_avg", self.square_avg.clone().into_data());
        out.push_tensor(prefix, "acc_delta", self.acc_delta.clone().into_data());
    }

    fn state_unflatten(prefix: &str, src: &mut StateSource, device: &Device) -> Option<Self> {
        Some(Self {
            square_avg: Tensor::from_data(src.take_tensor(prefix, "square_avg")?, device),
            acc_delta: Tensor::from_data(src.take_tensor(prefix, "acc_delta")?, device),
        })
    }
}

impl Optimizer for Adadelta {
    type State<const D: usize> = AdadeltaState<D>;

    fn step<const D: usize>(
        &self,
        lr: LearningRate,
        tensor: Tensor<D>,
        grad: Tensor<D>,
        state: Option<Self::State<D>>,
    ) -> (Tensor<D>, Option<Self::State<D>>) {
        let (square_avg, acc_delta) = match state {
            Some(s) => (s.square_avg, s.acc_delta),
            None => (grad.zeros_like(), grad.zeros_like()),
        };
        let rho = self.rho as f32;
        let eps = self.epsilon as f32;
        let square_avg = square_avg.mul_scalar(rho) + grad.clone().square().mul_scalar(1.0 - rho);
        let delta = grad * acc_delta.clone().add_scalar(eps).sqrt()
            / square_avg.clone().add_scalar(eps).sqrt();
        let acc_delta = acc_delta.mul_scalar(rho) + delta.clone().square().mul_scalar(1.0 - rho);
        let updated = tensor - delta.mul_scalar(lr as f32);
        (
            updated,
            Some(AdadeltaState {
                square_avg,
                acc_delta,
            }),
        )
    }

    fn to_device<const D: usize>(state: Self::State<D>, device: &Device) -> Self::State<D> {
        AdadeltaState {
            square_avg: state.square_avg.to_device(device),
            acc_delta: state.acc_delta.to_device(device),
        }
    }
}

impl AdadeltaConfig {
    /// The bare update rule.
    pub fn build(&self) -> Adadelta {
        Adadelta {
            rho: self.rho,
            epsilon: self.epsilon,
        }
    }

    /// A whole-module optimizer whose state can be saved and restored.
    pub fn init(&self) -> ModuleOptimizer {
        ModuleOptimizer::from(self.build())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::module::Module;
    use burn::nn::{Linear, LinearConfig};
    use burn::optim::GradientsParams;

    fn grads(model: &Linear, x: &Tensor<2>) -> GradientsParams {
        let loss = model.forward(x.clone()).square().mean();
        GradientsParams::from_grads(loss.backward(), model)
    }

    #[test]
    fn first_step_matches_the_formula_and_state_resumes() {
        let device = Device::flex().autodiff();
        let mut model = LinearConfig::new(3, 2).init(&device);
        let x = Tensor::<2>::from_floats([[1.0, -2.0, 0.5], [0.3, 0.1, -1.0]], &device);
        let w0: Vec<f32> = model.weight.val().into_data().try_to_vec::<f32>().unwrap();
        let g = grads(&model, &x);
        let gw: Vec<f32> = g
            .get::<2>(model.weight.id)
            .unwrap()
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();
        let mut opt = AdadeltaConfig::new().init();
        model = opt.step(1.0, model, g);
        let w1: Vec<f32> = model.weight.val().into_data().try_to_vec::<f32>().unwrap();
        for i in 0..w0.len() {
            let sq = 0.05 * gw[i] * gw[i];
            let expect = w0[i] - gw[i] * (1e-7f32).sqrt() / (sq + 1e-7).sqrt();
            assert!((w1[i] - expect).abs() < 1e-6, "{} vs {}", w1[i], expect);
        }
        // Save and restore the state: the next step must be identical.
        let bytes = opt.into_bytes().unwrap();
        let mut restored = AdadeltaConfig::new().init().from_bytes(bytes).unwrap();
        let a = opt.step(1.0, model.clone(), grads(&model, &x));
        let b = restored.step(1.0, model.clone(), grads(&model, &x));
        let (a, b): (Vec<f32>, Vec<f32>) = (
            a.weight.val().into_data().try_to_vec::<f32>().unwrap(),
            b.weight.val().into_data().try_to_vec::<f32>().unwrap(),
        );
        assert_eq!(a, b);
        let _ = model.num_params();
    }
}
