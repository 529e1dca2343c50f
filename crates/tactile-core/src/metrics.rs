//! Metrics shared by training, evaluation, benchmarks and reports.

/// Fraction of equal labels.
pub fn accuracy(pred: &[usize], truth: &[usize]) -> f64 {
    if truth.is_empty() {
        return 0.0;
    }
    pred.iter().zip(truth).filter(|(a, b)| a == b).count() as f64 / truth.len() as f64
}

/// Confusion matrix `m[truth][pred]`.
pub fn confusion(pred: &[usize], truth: &[usize], classes: usize) -> Vec<Vec<usize>> {
    let mut m = vec![vec![0; classes]; classes];
    for (&p, &t) in pred.iter().zip(truth) {
        if p < classes && t < classes {
            m[t][p] += 1;
        }
    }
    m
}

/// Mean of per-class recalls (the "mean per-class accuracy" of paper A's Bayes baseline).
pub fn mean_per_class_accuracy(pred: &[usize], truth: &[usize], classes: usize) -> f64 {
    let m = confusion(pred, truth, classes);
    let recalls: Vec<f64> = m
        .iter()
        .enumerate()
        .filter(|(_, row)| row.iter().sum::<usize>() > 0)
        .map(|(i, row)| row[i] as f64 / row.iter().sum::<usize>() as f64)
        .collect();
    if recalls.is_empty() {
        0.0
    } else {
        recalls.iter().sum::<f64>() / recalls.len() as f64
    }
}

/// Mean absolute error.
pub fn mae(pred: &[f64], truth: &[f64]) -> f64 {
    if truth.is_empty() {
        return 0.0;
    }
    pred.iter()
        .zip(truth)
        .map(|(a, b)| (a - b).abs())
        .sum::<f64>()
        / truth.len() as f64
}

/// Means-removed second moments of two equally long series:
/// `(covariance, variance of a, variance of b)`, each summed, not divided.
fn centred_moments(a: &[f64], b: &[f64]) -> (f64, f64, f64) {
    let n = a.len().min(b.len());
    let (ma, mb) = (
        a[..n].iter().sum::<f64>() / n as f64,
        b[..n].iter().sum::<f64>() / n as f64,
    );
    a[..n]
        .iter()
        .zip(&b[..n])
        .fold((0.0, 0.0, 0.0), |(c, va, vb), (x, y)| {
            let (dx, dy) = (x - ma, y - mb);
            (c + dx * dy, va + dx * dx, vb + dy * dy)
        })
}

/// Gain of estimates on the truth: the least-squares slope of `pred`
/// against `truth`. 1 when the estimates follow every change of the truth,
/// 0 when they ignore it; what an estimator recovers of a quantity the
/// frame shows only in part. NaN with fewer than two distinct truths.
pub fn gain(pred: &[f64], truth: &[f64]) -> f64 {
    if truth.len().min(pred.len()) < 2 {
        return f64::NAN;
    }
    let (cov, var, _) = centred_moments(truth, pred);
    if var > 0.0 { cov / var } else { f64::NAN }
}

/// Pearson correlation of two equally long series. Of two models' errors
/// on the same frames: near 1 when they err alike, so what is left is in
/// the frames (or their labels) rather than in either model. NaN with
/// fewer than two values or a constant series.
pub fn correlation(a: &[f64], b: &[f64]) -> f64 {
    if a.len().min(b.len()) < 2 {
        return f64::NAN;
    }
    let (cov, va, vb) = centred_moments(a, b);
    if va > 0.0 && vb > 0.0 {
        cov / (va * vb).sqrt()
    } else {
        f64::NAN
    }
}

/// Largest absolute difference between two equally long slices.
pub fn max_abs_diff(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

/// Median of a sample (NaN-free); 0 for an empty one.
pub fn median(values: &[f64]) -> f64 {
    percentile(values, 50.0)
}

/// Linear-interpolated percentile `p` in [0, 100].
pub fn percentile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let pos = (p / 100.0).clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gain_is_the_slope_of_estimates_on_truth() {
        let truth = [-2.0, -1.0, 0.0, 1.0, 2.0];
        let half: Vec<f64> = truth.iter().map(|t| 0.5 * t + 3.0).collect();
        assert!((gain(&half, &truth) - 0.5).abs() < 1e-12);
        assert!(gain(&[1.0; 5], &truth).abs() < 1e-12);
        assert!(gain(&truth, &[1.0; 5]).is_nan());
        assert!(gain(&[1.0], &[1.0]).is_nan());
    }

    #[test]
    fn correlation_measures_how_alike_two_errors_are() {
        let common = [1.0, -1.0, 1.0, -1.0];
        let own = [1.0, 1.0, -1.0, -1.0];
        // Each error half common, half its own (orthogonal) part: the
        // shared part is half of each one's variance.
        let a: Vec<f64> = common.iter().zip(&own).map(|(c, o)| c + o).collect();
        let b: Vec<f64> = common.iter().zip(&own).map(|(c, o)| c - o).collect();
        assert!(correlation(&a, &b).abs() < 1e-12);
        let a2: Vec<f64> = common.iter().zip(&own).map(|(c, o)| 2.0 * c + o).collect();
        let b2: Vec<f64> = common.iter().zip(&own).map(|(c, o)| 2.0 * c - o).collect();
        assert!((correlation(&a2, &b2) - 0.6).abs() < 1e-12);
        let scaled: Vec<f64> = a.iter().map(|x| -3.0 * x + 1.0).collect();
        assert!((correlation(&a, &scaled) + 1.0).abs() < 1e-12);
        assert!(correlation(&a, &[2.0; 4]).is_nan());
        assert!(correlation(&[1.0], &[1.0]).is_nan());
    }

    #[test]
    fn basic_metrics() {
        assert_eq!(accuracy(&[0, 1, 1], &[0, 1, 0]), 2.0 / 3.0);
        assert_eq!(
            mean_per_class_accuracy(&[0, 1, 1, 1], &[0, 1, 0, 0], 2),
            (1.0 / 3.0 + 1.0) / 2.0
        );
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(percentile(&[0.0, 10.0], 90.0), 9.0);
        assert_eq!(max_abs_diff(&[1.0, 2.0], &[1.5, 2.0]), 0.5);
    }

    #[test]
    fn binary_scores_count_each_cell() {
        let s = binary_scores(
            &[true, true, false, false, true],
            &[true, false, false, true, true],
        );
        assert_eq!(
            (s.true_pos, s.false_pos, s.true_neg, s.false_neg),
            (2, 1, 1, 1)
        );
        assert_eq!(s.accuracy, 0.6);
        assert!((s.precision - 2.0 / 3.0).abs() < 1e-12 && (s.recall - 2.0 / 3.0).abs() < 1e-12);
        let none = binary_scores(&[false, false], &[false, false]);
        assert_eq!((none.accuracy, none.precision, none.f1), (1.0, 0.0, 0.0));
        assert_eq!(
            none.rates_text(4, "a tendon"),
            "accuracy 1.0000, precision -, recall -, F1 - (no frame has a tendon, and none was called one)"
        );
        assert_eq!(
            binary_scores(&[true, false], &[false, false]).rates_text(2, "a tendon"),
            "accuracy 0.50, precision 0.00, recall -, F1 0.00 (no frame has a tendon: recall has nothing to count)"
        );
        assert_eq!(
            binary_scores(&[false, false], &[true, false]).rates_text(2, "a tendon"),
            "accuracy 0.50, precision -, recall 0.00, F1 0.00 (no frame was called a tendon: precision has nothing to count)"
        );
        assert_eq!(
            binary_scores(&[], &[]).rates_text(2, "a tendon"),
            "accuracy -, precision -, recall -, F1 -"
        );
        assert_eq!(
            s.rates_text(3, "a tendon"),
            "accuracy 0.600, precision 0.667, recall 0.667, F1 0.667"
        );
    }

    #[test]
    fn iou_of_masks() {
        assert_eq!(iou(&[true, true, false], &[true, false, false]), 0.5);
        assert_eq!(iou(&[false; 3], &[false; 3]), 1.0);
        assert_eq!(iou(&[true, false], &[false, true]), 0.0);
    }

    #[test]
    fn ssim_of_flat_equal_and_different_maps() {
        let flat = vec![15.0f32; 100];
        assert_eq!(ssim(&flat, &flat, 10, 10, 6.0), 1.0);
        let other = vec![15.5f32; 100];
        let s = ssim(&flat, &other, 10, 10, 6.0);
        assert!(s.is_finite() && s < 1.0 && s > 0.0, "{s}");
        let ramp: Vec<f32> = (0..100).map(|i| (i % 10) as f32).collect();
        assert!((ssim(&ramp, &ramp, 10, 10, 9.0) - 1.0).abs() < 1e-12);
        let neg: Vec<f32> = ramp.iter().map(|v| 9.0 - v).collect();
        assert!(ssim(&ramp, &neg, 10, 10, 9.0) < 0.0);
    }

    #[test]
    fn masked_errors() {
        let (p, t) = ([1.0f32, 2.0, 4.0], [1.0f32, 1.0, 1.0]);
        assert_eq!(masked_mae(&p, &t, None), Some(4.0 / 3.0));
        assert_eq!(masked_mae(&p, &t, Some(&[false, true, false])), Some(1.0));
        assert_eq!(masked_mae(&p, &t, Some(&[false; 3])), None);
        assert_eq!(masked_rmse(&p, &t, Some(&[false, false, true])), Some(3.0));
    }

    #[test]
    fn scales_never_blow_a_nearly_constant_column_up() {
        // A pixel lit in one training frame of thousands: std 1e-4.
        assert_eq!(
            safe_scales([0.3, 1e-4, 0.0, f64::NAN]),
            [0.3, 0.003, 0.003, 0.003]
        );
        assert_eq!(safe_scales([0.0, 0.0]), [1.0, 1.0]);
    }
}

/// Binary classification scores, positives = `true`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BinaryScores {
    /// Frames scored.
    pub frames: usize,
    /// Fraction of right decisions.
    pub accuracy: f64,
    /// True positives over predicted positives.
    pub precision: f64,
    /// True positives over actual positives.
    pub recall: f64,
    /// Harmonic mean of precision and recall.
    pub f1: f64,
    /// Positives predicted positive.
    pub true_pos: usize,
    /// Negatives predicted positive.
    pub false_pos: usize,
    /// Negatives predicted negative.
    pub true_neg: usize,
    /// Positives predicted negative.
    pub false_neg: usize,
}

impl BinaryScores {
    /// The four rates in words for a person, `-` where a rate has nothing
    /// to count (precision with no frame called positive, recall with no
    /// positive frame, F1 with neither, accuracy of no frame), followed by
    /// why: a set of negatives scored perfectly reads as that, not as a
    /// precision, recall and F1 of 0. The JSON keeps 0 there, as documented.
    /// `positive` names what a positive frame shows ("a tendon").
    pub fn rates_text(&self, digits: usize, positive: &str) -> String {
        let (tp, fp, fneg) = (self.true_pos, self.false_pos, self.false_neg);
        let rate = |v: f64, defined: bool| match defined {
            true => format!("{v:.digits$}"),
            false => "-".to_string(),
        };
        let mut text = format!(
            "accuracy {}, precision {}, recall {}, F1 {}",
            rate(self.accuracy, self.frames > 0),
            rate(self.precision, tp + fp > 0),
            rate(self.recall, tp + fneg > 0),
            rate(self.f1, tp + fp + fneg > 0),
        );
        if self.frames > 0 && tp + fneg == 0 {
            text.push_str(&match fp {
                0 => format!(" (no frame has {positive}, and none was called one)"),
                _ => format!(" (no frame has {positive}: recall has nothing to count)"),
            });
        } else if self.frames > 0 && tp + fp == 0 {
            text.push_str(&format!(
                " (no frame was called {positive}: precision has nothing to count)"
            ));
        }
        text
    }
}

/// Accuracy, precision, recall and F1 (0 when undefined, e.g. no positive
/// predicted).
pub fn binary_scores(pred: &[bool], truth: &[bool]) -> BinaryScores {
    let mut c = [0usize; 4];
    for (&p, &t) in pred.iter().zip(truth) {
        c[(p as usize) << 1 | t as usize] += 1;
    }
    let [tn, fneg, fp, tp] = c;
    let div = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    let (precision, recall) = (div(tp, tp + fp), div(tp, tp + fneg));
    let f1 = if precision + recall > 0.0 {
        2.0 * precision * recall / (precision + recall)
    } else {
        0.0
    };
    BinaryScores {
        frames: truth.len(),
        accuracy: div(tp + tn, truth.len()),
        precision,
        recall,
        f1,
        true_pos: tp,
        false_pos: fp,
        true_neg: tn,
        false_neg: fneg,
    }
}

/// One bin of a reliability diagram.
#[derive(Debug, Clone, serde::Serialize, PartialEq)]
pub struct CalibrationBin {
    /// Lower edge of the predicted probability.
    pub low: f64,
    /// Upper edge.
    pub high: f64,
    /// Frames whose probability falls in the bin.
    pub frames: usize,
    /// Their mean predicted probability.
    pub mean_probability: f64,
    /// The fraction of them that are positive.
    pub observed: f64,
}

/// How well predicted probabilities match observed frequencies.
#[derive(Debug, Clone, serde::Serialize, PartialEq)]
pub struct Calibration {
    /// Equal-width bins over [0, 1] (empty bins included, `frames` 0).
    pub bins: Vec<CalibrationBin>,
    /// Expected calibration error: the frame-weighted mean of
    /// |observed - mean probability| over the bins.
    pub ece: f64,
    /// The same over frames with a probability in [0.1, 0.9], the ones
    /// near the decision threshold (NaN when there are none).
    pub ece_uncertain: f64,
    /// Frames with a probability in [0.1, 0.9].
    pub uncertain_frames: usize,
    /// Mean squared difference of probability and label.
    pub brier: f64,
}

impl Calibration {
    /// [`Self::ece_uncertain`] with `decimals` for a table or a sentence:
    /// "-" when no frame had a probability in [0.1, 0.9], not "NaN".
    pub fn ece_uncertain_text(&self, decimals: usize) -> String {
        if self.uncertain_frames == 0 || !self.ece_uncertain.is_finite() {
            "-".into()
        } else {
            format!("{:.decimals$}", self.ece_uncertain)
        }
    }
}

/// Reliability over `bins` equal-width bins (at least 1) of the predicted
/// probabilities `p` against the labels `truth`. Non-finite probabilities
/// count in no bin.
pub fn calibration(p: &[f32], truth: &[bool], bins: usize) -> Calibration {
    let bins = bins.max(1);
    let mut acc = vec![(0usize, 0.0f64, 0usize); bins];
    let mut brier = (0.0, 0usize);
    let mut uncertain = vec![(0usize, 0.0f64, 0usize); bins];
    for (&q, &t) in p.iter().zip(truth) {
        if !q.is_finite() {
            continue;
        }
        let q = (q as f64).clamp(0.0, 1.0);
        let b = ((q * bins as f64) as usize).min(bins - 1);
        for (target, keep) in [(&mut acc, true), (&mut uncertain, (0.1..=0.9).contains(&q))] {
            if keep {
                target[b].0 += 1;
                target[b].1 += q;
                target[b].2 += usize::from(t);
            }
        }
        brier.0 += (q - f64::from(u8::from(t))).powi(2);
        brier.1 += 1;
    }
    let ece = |a: &[(usize, f64, usize)]| {
        let n: usize = a.iter().map(|b| b.0).sum();
        if n == 0 {
            return f64::NAN;
        }
        a.iter()
            .filter(|b| b.0 > 0)
            .map(|&(k, sum, pos)| (pos as f64 / k as f64 - sum / k as f64).abs() * k as f64)
            .sum::<f64>()
            / n as f64
    };
    Calibration {
        bins: acc
            .iter()
            .enumerate()
            .map(|(i, &(k, sum, pos))| CalibrationBin {
                low: i as f64 / bins as f64,
                high: (i + 1) as f64 / bins as f64,
                frames: k,
                mean_probability: if k > 0 { sum / k as f64 } else { f64::NAN },
                observed: if k > 0 {
                    pos as f64 / k as f64
                } else {
                    f64::NAN
                },
            })
            .collect(),
        ece: ece(&acc),
        ece_uncertain: ece(&uncertain),
        uncertain_frames: uncertain.iter().map(|b| b.0).sum(),
        brier: if brier.1 > 0 {
            brier.0 / brier.1 as f64
        } else {
            f64::NAN
        },
    }
}

/// Intersection over union of two binary masks; 1 when both are empty
/// (nothing to find, nothing found).
pub fn iou(pred: &[bool], truth: &[bool]) -> f64 {
    let (mut inter, mut union) = (0usize, 0usize);
    for (&p, &t) in pred.iter().zip(truth) {
        inter += (p && t) as usize;
        union += (p || t) as usize;
    }
    if union == 0 {
        1.0
    } else {
        inter as f64 / union as f64
    }
}

/// Mean absolute error over the pixels where `mask` holds (all when
/// `None`); `None` when no pixel counts.
pub fn masked_mae(pred: &[f32], truth: &[f32], mask: Option<&[bool]>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, (&p, &t)) in pred.iter().zip(truth).enumerate() {
        if mask.is_none_or(|m| m[i]) {
            sum += (p as f64 - t as f64).abs();
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// Root mean square error over the pixels where `mask` holds.
pub fn masked_rmse(pred: &[f32], truth: &[f32], mask: Option<&[bool]>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, (&p, &t)) in pred.iter().zip(truth).enumerate() {
        if mask.is_none_or(|m| m[i]) {
            sum += (p as f64 - t as f64).powi(2);
            n += 1;
        }
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// Side of the SSIM window.
pub const SSIM_WINDOW: usize = 7;

/// Mean structural similarity (Wang et al. 2004) of two `w x h` maps over
/// all 7x7 windows, with the paper's constants `C1 = (0.01 L)^2` and
/// `C2 = (0.03 L)^2` for a dynamic range `L`: two flat maps compare
/// without dividing by zero (equal ones give exactly 1).
pub fn ssim(a: &[f32], b: &[f32], w: usize, h: usize, range: f64) -> f64 {
    let k = SSIM_WINDOW.min(w).min(h).max(1);
    let (c1, c2) = ((0.01 * range).powi(2), (0.03 * range).powi(2));
    let n = (k * k) as f64;
    let (mut total, mut count) = (0.0, 0usize);
    for y0 in 0..=h.saturating_sub(k) {
        for x0 in 0..=w.saturating_sub(k) {
            let (mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for y in y0..y0 + k {
                for x in x0..x0 + k {
                    let (p, q) = (a[y * w + x] as f64, b[y * w + x] as f64);
                    sa += p;
                    sb += q;
                    saa += p * p;
                    sbb += q * q;
                    sab += p * q;
                }
            }
            let (ma, mb) = (sa / n, sb / n);
            let va = (saa / n - ma * ma).max(0.0);
            let vb = (sbb / n - mb * mb).max(0.0);
            let cov = sab / n - ma * mb;
            total += ((2.0 * ma * mb + c1) * (2.0 * cov + c2))
                / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            count += 1;
        }
    }
    if count == 0 {
        1.0
    } else {
        total / count as f64
    }
}

/// Standardisation scales from per-column standard deviations.
///
/// A column that barely varies in training (a pixel that a few frames touch)
/// would be divided by a tiny number and turn a small change at test time
/// into a huge input; every scale is therefore at least 1 % of the largest
/// (and 1 when every column is constant).
pub fn safe_scales(std: impl IntoIterator<Item = f64>) -> Vec<f64> {
    let std: Vec<f64> = std.into_iter().collect();
    let max = std
        .iter()
        .copied()
        .filter(|s| s.is_finite())
        .fold(0.0, f64::max);
    let floor = if max > 0.0 { 0.01 * max } else { 1.0 };
    std.into_iter()
        .map(|s| if s.is_finite() && s > floor { s } else { floor })
        .collect()
}

/// A uniform sample of at most `capacity` values of a stream of any
/// length (reservoir sampling, a fixed seed): medians and percentiles of a
/// day-long live run in bounded memory, exact while the stream fits.
#[derive(Debug, Clone)]
pub struct Reservoir {
    values: Vec<f64>,
    capacity: usize,
    seen: u64,
    state: u64,
}

impl Reservoir {
    /// Values kept by [`Reservoir::default`].
    pub const DEFAULT_CAPACITY: usize = 1 << 16;

    /// An empty sample of at most `capacity` values.
    pub fn new(capacity: usize) -> Self {
        Self {
            values: Vec::new(),
            capacity: capacity.max(1),
            seen: 0,
            state: 0x9E37_79B9_7F4A_7C15,
        }
    }

    /// Offer one value.
    pub fn push(&mut self, v: f64) {
        self.seen += 1;
        if self.values.len() < self.capacity {
            self.values.push(v);
            return;
        }
        // xorshift64*: a slot in 0..seen; kept when it falls in the sample.
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        let r = self.state.wrapping_mul(0x2545_F491_4F6C_DD1D) % self.seen;
        if (r as usize) < self.capacity {
            self.values[r as usize] = v;
        }
    }

    /// Values offered so far.
    pub fn seen(&self) -> u64 {
        self.seen
    }

    /// Median and 95th percentile of the sample; `None` when empty.
    pub fn median_p95(&self) -> Option<[f64; 2]> {
        (!self.values.is_empty()).then(|| [median(&self.values), percentile(&self.values, 95.0)])
    }
}

impl Default for Reservoir {
    fn default() -> Self {
        Self::new(Self::DEFAULT_CAPACITY)
    }
}

/// The process's peak resident memory (VmHWM), MB, where the system
/// reports it (Linux).
pub fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

#[cfg(test)]
mod reservoir_tests {
    use super::*;

    #[test]
    fn reservoir_is_exact_while_it_fits_and_bounded_after() {
        let mut r = Reservoir::new(1000);
        for i in 0..101 {
            r.push(i as f64);
        }
        assert_eq!(r.median_p95().unwrap()[0], 50.0);
        for i in 0..100_000 {
            r.push((i % 101) as f64);
        }
        assert_eq!(r.values.len(), 1000);
        let m = r.median_p95().unwrap()[0];
        assert!((m - 50.0).abs() < 6.0, "median of a uniform stream: {m}");
    }

    #[test]
    fn calibration_is_zero_for_honest_probabilities_and_large_for_overconfident_ones() {
        // Probability 0.3 on 10 frames, 3 positive: perfectly calibrated.
        let p = vec![0.3f32; 10];
        let t: Vec<bool> = (0..10).map(|i| i < 3).collect();
        let c = calibration(&p, &t, 10);
        assert!(c.ece.abs() < 1e-6, "{c:?}");
        assert_eq!(c.bins[3].frames, 10);
        assert_eq!(c.uncertain_frames, 10);
        assert_eq!(c.ece_uncertain_text(3), "0.000");
        // Probability 0.95 on frames that are positive half the time.
        let p = vec![0.95f32; 10];
        let t: Vec<bool> = (0..10).map(|i| i % 2 == 0).collect();
        let c = calibration(&p, &t, 10);
        assert!((c.ece - 0.45).abs() < 1e-6, "{c:?}");
        assert!(c.ece_uncertain.is_nan());
        assert_eq!(c.ece_uncertain_text(3), "-", "tables say no frame, not NaN");
        assert!((c.brier - (0.5 * 0.05f64.powi(2) + 0.5 * 0.95f64.powi(2))).abs() < 1e-6);
        // NaN probabilities are skipped, not binned.
        let c = calibration(&[f32::NAN, 1.0], &[true, true], 5);
        assert_eq!(c.bins.iter().map(|b| b.frames).sum::<usize>(), 1);
    }
}
