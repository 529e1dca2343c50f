//! A per-frame uncertainty for every target: the network gives, beside
//! each standardised output, the log of a Laplace scale `b`, trained on
//! the negative log-likelihood `log b + |error| / b` of its own error with
//! the error's gradient stopped (so the outputs learn exactly as without
//! it). The scales are then calibrated on frames the training did not fit:
//! one factor per target makes the ±1 standard deviation interval hold
//! 68.3 % of their errors. The 95 % interval is ±1.96 of it; how often it
//! holds is measured, not assumed.

use burn::tensor::Tensor;

/// Log scales are clamped to this range, so a frame far from training
/// gives a large but finite deviation and the loss never divides by 0.
pub const LOG_SCALE_RANGE: (f32, f32) = (-9.0, 6.0);

/// Fraction of errors inside ±1 standard deviation of a normal variable.
pub const ONE_SIGMA: f64 = 0.682_689_492;

/// Half-width of the 95 % interval, in standard deviations.
pub const Z95: f64 = 1.959_964;

/// The Laplace negative log-likelihood (without its constant) of `error`
/// (prediction minus label, standardised) under the scales `exp(log_scale)`;
/// the error's gradient is stopped.
///
/// # Shapes
/// - `error`, `log_scale`: `[N, K]`; output `[N, K]`
pub fn laplace_nll(error: Tensor<2>, log_scale: Tensor<2>) -> Tensor<2> {
    let s = log_scale.clamp(LOG_SCALE_RANGE.0, LOG_SCALE_RANGE.1);
    s.clone() + error.detach().abs() * s.neg().exp()
}

/// A network's raw scale from its log-scale output.
pub fn scale(log_scale: f32) -> f64 {
    (log_scale.clamp(LOG_SCALE_RANGE.0, LOG_SCALE_RANGE.1) as f64).exp()
}

/// Per target, the factor that makes `factor * scale` cover 68.3 % of the
/// errors: `ratios[j]` holds `|error| / scale` of each calibration frame
/// for target `j`. A target with no finite ratio gets 1.
pub fn calibrate(ratios: &[Vec<f64>]) -> Vec<f64> {
    ratios
        .iter()
        .map(|r| {
            let mut r: Vec<f64> = r.iter().copied().filter(|v| v.is_finite()).collect();
            if r.is_empty() {
                return 1.0;
            }
            r.sort_by(f64::total_cmp);
            let at = ((r.len() as f64 * ONE_SIGMA).ceil() as usize).clamp(1, r.len()) - 1;
            r[at].max(1e-9)
        })
        .collect()
}

/// Fraction of `errors` inside `±z * std`, per target (columns of rows).
pub fn coverage(errors: &[Vec<f64>], std: &[Vec<f64>], z: f64) -> Vec<f64> {
    let k = errors.first().map_or(0, Vec::len);
    (0..k)
        .map(|j| {
            let n = errors.len().max(1) as f64;
            errors
                .iter()
                .zip(std)
                .filter(|(e, s)| e[j].abs() <= z * s[j])
                .count() as f64
                / n
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::{Device, TensorData};

    #[test]
    fn calibration_covers_68_percent_and_the_loss_is_finite_at_extremes() {
        // Ratios 1..=100: the 69th smallest leaves 68.3 % at or below it.
        let r: Vec<f64> = (1..=100).map(f64::from).collect();
        let c = calibrate(&[r.clone(), vec![f64::NAN], vec![]]);
        assert_eq!(c, vec![69.0, 1.0, 1.0]);
        let errors: Vec<Vec<f64>> = r.iter().map(|&e| vec![e]).collect();
        let std: Vec<Vec<f64>> = r.iter().map(|_| vec![c[0]]).collect();
        assert!((coverage(&errors, &std, 1.0)[0] - 0.69).abs() < 1e-9);
        // Huge or tiny log scales stay finite.
        let dev = Device::flex();
        let e = Tensor::<2>::from_data(TensorData::new(vec![1e6f32, 0.0], [1, 2]), &dev);
        let s = Tensor::<2>::from_data(TensorData::new(vec![-1e6f32, 1e6], [1, 2]), &dev);
        let v: Vec<f32> = laplace_nll(e, s).into_data().try_to_vec().unwrap();
        assert!(v.iter().all(|x| x.is_finite()), "{v:?}");
        assert!(scale(1e9).is_finite() && scale(-1e9) > 0.0);
    }
}
