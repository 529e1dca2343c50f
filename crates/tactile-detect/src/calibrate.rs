//! Probability calibration of a trained detector: one temperature, fitted by
//! maximum likelihood on frames the detector was not trained on, that
//! sharpens or softens its logits about the decision threshold. The
//! threshold's logit is the fixed point, so every decision stays the same;
//! only what the probability says about confidence changes. The temperature
//! is folded into the last layer's weights, so every runtime and every ONNX
//! export gives the calibrated probability with nothing else to apply.

use std::path::Path;

use serde::Serialize;
use tactile_burn::{Artifact, DeviceKind, Runtime};
use tactile_core::dataset::Dataset;
use tactile_core::metrics::{Calibration, calibration};

use crate::eval::{CALIBRATION_BINS, evaluate};
use crate::{
    DetectionSet, Detector, DetectorArtifact, DetectorEnsembleArtifact, Error, Result,
    TendonDetector,
};

/// Smallest and largest logit scale searched.
pub const SCALE_RANGE: (f64, f64) = (0.01, 1000.0);

/// Fewest frames of each class a fit needs.
pub const MIN_FRAMES_PER_CLASS: usize = 20;

/// What a calibration did.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationFit {
    /// Factor applied to the logits about the threshold's logit (above 1
    /// sharpens an under-confident detector).
    pub scale: f64,
    /// Frames fitted on.
    pub frames: usize,
    /// Mean negative log-likelihood before and after.
    pub nll: [f64; 2],
    /// Reliability on the fitting frames before.
    pub before: Calibration,
    /// And after.
    pub after: Calibration,
}

impl CalibrationFit {
    /// One line for a person.
    pub fn describe(&self) -> String {
        format!(
            "logit scale {:.3} fitted on {} frames: negative log-likelihood {:.4} -> {:.4}, expected calibration error {:.4} -> {:.4} (decisions unchanged)",
            self.scale, self.frames, self.nll[0], self.nll[1], self.before.ece, self.after.ece
        )
    }
}

fn logit(p: f64) -> f64 {
    let p = p.clamp(1e-7, 1.0 - 1e-7);
    (p / (1.0 - p)).ln()
}

fn scaled(z: f64, scale: f64, centre: f64) -> f64 {
    1.0 / (1.0 + (-(scale * (z - centre) + centre)).exp())
}

fn nll(z: &[f64], truth: &[bool], scale: f64, centre: f64) -> f64 {
    z.iter()
        .zip(truth)
        .map(|(&z, &t)| {
            let q = scaled(z, scale, centre).clamp(1e-12, 1.0 - 1e-12);
            if t { -q.ln() } else { -(1.0 - q).ln() }
        })
        .sum::<f64>()
        / z.len().max(1) as f64
}

/// The logit scale about `threshold` that maximises the likelihood of
/// `truth` under probabilities `p` (golden-section search on log scale; the
/// negative log-likelihood is convex in the scale). Needs both classes.
pub fn fit_scale(p: &[f32], truth: &[bool], threshold: f64) -> Result<CalibrationFit> {
    let positives = truth.iter().filter(|&&t| t).count();
    let negatives = truth.len() - positives;
    if positives.min(negatives) < MIN_FRAMES_PER_CLASS {
        return Err(Error::Core(tactile_core::Error::Invalid(format!(
            "calibration needs at least {MIN_FRAMES_PER_CLASS} frames with and without a tendon; found {positives} and {negatives}"
        ))));
    }
    let z: Vec<f64> = p.iter().map(|&q| logit(q as f64)).collect();
    let centre = logit(threshold);
    let f = |log_s: f64| nll(&z, truth, log_s.exp(), centre);
    let (mut a, mut b) = (SCALE_RANGE.0.ln(), SCALE_RANGE.1.ln());
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..80 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    let scale = ((a + b) / 2.0).exp();
    let after: Vec<f32> = z.iter().map(|&z| scaled(z, scale, centre) as f32).collect();
    Ok(CalibrationFit {
        scale,
        frames: p.len(),
        nll: [f(0.0), f(scale.ln())],
        before: calibration(p, truth, CALIBRATION_BINS),
        after: calibration(&after, truth, CALIBRATION_BINS),
    })
}

/// Fit the logit scale of the detector in `dir` (one network or an
/// ensemble, whose mean logit is scaled) on `sets` (frames it was not
/// trained on) and fold it into its last layer, every member's for an
/// ensemble: weights first, then the config with the fit in its notes,
/// each written atomically.
pub fn calibrate(dir: &Path, sets: &[&DetectionSet]) -> Result<CalibrationFit> {
    let mut detector = TendonDetector::load(dir, Runtime::BurnFlex, 0)?;
    let (mut p, mut truth) = (Vec::new(), Vec::new());
    for set in sets {
        p.extend(evaluate(&mut detector, set)?.probabilities);
        truth.extend(set.tendon.iter().copied());
    }
    let threshold = detector.artifact.threshold;
    let fit = fit_scale(&p, &truth, threshold)?;
    let centre = logit(threshold);
    let device = DeviceKind::Flex.device();
    if DetectorEnsembleArtifact::is_in(dir) {
        let mut loaded = DetectorEnsembleArtifact::load(dir, &device)?;
        for (m, a) in loaded
            .model
            .members
            .iter_mut()
            .zip(&mut loaded.artifact.members)
        {
            scale_logit(m, fit.scale, centre);
            note_calibration(&mut a.notes, &fit);
        }
        note_calibration(&mut loaded.artifact.ensemble.notes, &fit);
        loaded.artifact.save(&loaded.model, dir)?;
    } else {
        let mut loaded = DetectorArtifact::load(dir, &device)?;
        scale_logit(&mut loaded.model, fit.scale, centre);
        note_calibration(&mut loaded.artifact.notes, &fit);
        loaded.artifact.save(&loaded.model, dir)?;
    }
    Ok(fit)
}

/// Undo the logit scale that calibrations folded into the one detector in
/// `dir` (their composed scale is in its notes), and drop the note: the
/// network then gives the logits it was trained to. Nothing to do for a
/// detector never calibrated.
pub fn unfold_calibration(dir: &Path) -> tactile_core::Result<()> {
    // The config alone says whether there is anything to undo; the
    // weights are read only then.
    let Some(scale) = noted_scale(&DetectorArtifact::read(dir)?.notes) else {
        return Ok(());
    };
    if !(scale.is_finite() && scale > 0.0) {
        return Err(tactile_core::Error::Invalid(format!(
            "{}: the calibration scale in its notes is {scale}; expected a finite positive scale",
            dir.display()
        )));
    }
    let mut loaded = DetectorArtifact::load(dir, &DeviceKind::Flex.device())?;
    let centre = logit(loaded.artifact.threshold);
    scale_logit(&mut loaded.model, 1.0 / scale, centre);
    if let serde_json::Value::Object(notes) = &mut loaded.artifact.notes {
        notes.remove("calibration");
    }
    loaded.artifact.save(&loaded.model, dir)?;
    Ok(())
}

/// `z -> scale (z - centre) + centre` folded into the last layer.
fn scale_logit(model: &mut Detector, scale: f64, centre: f64) {
    use burn::module::Param;
    let fc2 = &mut model.fc2;
    let w = fc2.weight.val() * scale;
    fc2.weight = Param::from_tensor(w);
    if let Some(b) = &fc2.bias {
        let b = b.val() * scale + (1.0 - scale) * centre;
        fc2.bias = Some(Param::from_tensor(b));
    }
}

/// The logit scale the calibrations recorded in `notes` folded in, composed
/// (`None`: never calibrated).
fn noted_scale(notes: &serde_json::Value) -> Option<f64> {
    notes
        .get("calibration")
        .and_then(|c| c.get("scale"))
        .and_then(|s| s.as_f64())
}

/// Record the fit in a model's notes, its scale composed with any earlier
/// calibration's.
fn note_calibration(notes: &mut serde_json::Value, fit: &CalibrationFit) {
    let previous = noted_scale(notes).unwrap_or(1.0);
    if let serde_json::Value::Object(notes) = notes {
        notes.insert(
            "calibration".into(),
            serde_json::json!({
                "scale": fit.scale * previous,
                "frames": fit.frames,
                "ece_before": fit.before.ece,
                "ece_after": fit.after.ece,
            }),
        );
    }
}

/// [`calibrate`] on labelled visuo-tactile datasets, read at the
/// detector's input size.
pub fn calibrate_on(dir: &Path, datasets: &[Dataset]) -> Result<CalibrationFit> {
    let model = crate::ensemble::read_config(dir)?.model;
    let sets = datasets
        .iter()
        .map(|d| DetectionSet::from_dataset(d, &model))
        .collect::<Result<Vec<_>>>()?;
    calibrate(dir, &sets.iter().collect::<Vec<_>>())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bad scale in a member's notes is refused, naming the folder, and
    /// the folder is left as it was; a member never calibrated is left
    /// byte for byte.
    #[test]
    #[allow(clippy::unwrap_used)]
    fn unfolding_refuses_a_bad_noted_scale_and_leaves_an_uncalibrated_member_alone() {
        let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/detector/member-0");
        let tmp = tempfile::tempdir().unwrap();
        let files = [
            DetectorArtifact::CONFIG_FILE,
            DetectorArtifact::WEIGHTS_FILE,
        ];
        let copy = |name: &str, scale: Option<f64>| {
            let dir = tmp.path().join(name);
            std::fs::create_dir_all(&dir).unwrap();
            for f in files {
                std::fs::copy(shipped.join(f), dir.join(f)).unwrap();
            }
            let path = dir.join(DetectorArtifact::CONFIG_FILE);
            let mut v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            match scale {
                Some(s) => v["notes"]["calibration"] = serde_json::json!({ "scale": s }),
                None => {
                    v["notes"].as_object_mut().unwrap().remove("calibration");
                }
            }
            std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
            dir
        };
        let bytes = |dir: &Path| files.map(|f| std::fs::read(dir.join(f)).unwrap());
        for bad in [-2.0, 0.0] {
            let dir = copy("bad", Some(bad));
            let before = bytes(&dir);
            let err = unfold_calibration(&dir).unwrap_err().to_string();
            assert!(err.contains(&dir.display().to_string()), "{err}");
            assert!(err.contains("calibration scale"), "{err}");
            assert_eq!(bytes(&dir), before);
        }
        let plain = copy("plain", None);
        let before = bytes(&plain);
        unfold_calibration(&plain).unwrap();
        assert_eq!(bytes(&plain), before);
    }

    #[test]
    fn an_under_confident_detector_is_sharpened_and_its_decisions_kept() {
        // Logits 1/3 of the truth's: the right scale is 3.
        let mut rng = tactile_core::rng::SampleRng::new(5, 0, 0);
        let (mut p, mut t) = (Vec::new(), Vec::new());
        for _ in 0..4000 {
            let z: f64 = 8.0 * (rng.uniform() - 0.5);
            let truth = rng.uniform() < 1.0 / (1.0 + (-z).exp());
            p.push((1.0 / (1.0 + (z / 3.0f64).exp().recip())) as f32);
            t.push(truth);
        }
        let fit = fit_scale(&p, &t, 0.5).unwrap();
        assert!((fit.scale - 3.0).abs() < 0.4, "{}", fit.describe());
        assert!(fit.after.ece < fit.before.ece, "{}", fit.describe());
        assert!(fit.nll[1] < fit.nll[0]);
        // The threshold is the fixed point: no decision moves.
        let centre = logit(0.45);
        for z in [-3.0, -0.3, centre - 1e-3, centre + 1e-3, 0.5, 4.0] {
            let q = scaled(z, fit.scale, centre);
            assert_eq!(q >= 0.45, 1.0 / (1.0 + (-z).exp()) >= 0.45, "{z}");
        }
    }

    #[test]
    fn one_class_is_refused() {
        let e = fit_scale(&[0.9; 50], &[true; 50], 0.5).unwrap_err();
        assert!(e.to_string().contains("with and without"), "{e}");
    }
}
