//! The detector scored on a labelled dataset: accuracy, precision, recall
//! and F1 over every frame and over the onset and release frames, how well
//! its probabilities are calibrated, with the probability of each frame.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_burn::Runtime;
use tactile_core::dataset::Dataset;
use tactile_core::metrics::{BinaryScores, Calibration, binary_scores, calibration};
use tactile_core::plot::{Series, line_plot};

use crate::data::DetectionSet;
use crate::inference::TendonDetector;
use crate::{Error, Result};

/// Frames per network call when scoring.
pub const EVAL_BATCH: usize = 32;

/// Bins of the reliability diagram.
pub const CALIBRATION_BINS: usize = 10;

/// A detector's scores on a dataset, on the answers `tactile run` and the
/// Python package give ([`TendonDetector::assess`]: gates applied).
#[derive(Debug, Clone, Serialize)]
pub struct DetectorScores {
    /// Over every frame.
    pub all: BinaryScores,
    /// Over every frame, on the network's own probabilities (no gate): what
    /// the gates change.
    pub ungated: BinaryScores,
    /// Frames a gate stopped: blank ones.
    pub gated_blank: usize,
    /// Frames a gate stopped: foreign ones (outside the input profile, or
    /// of another camera mode).
    pub gated_foreign: usize,
    /// Over frames within two frames of a label change.
    pub onset_release: BinaryScores,
    /// Inference time per frame (batches of [`EVAL_BATCH`], resizing excluded).
    pub ms_per_frame: f64,
    /// Reliability of the probabilities over [`CALIBRATION_BINS`] bins.
    pub calibration: Calibration,
    /// Per-frame tendon probability (the answer's), in dataset order.
    #[serde(skip)]
    pub probabilities: Vec<f32>,
    /// Per-frame decision (the answer's), in dataset order.
    #[serde(skip)]
    pub decisions: Vec<bool>,
    /// The threshold the decisions used.
    pub threshold: f64,
    /// Set when the model's notes say it trained on every frame scored
    /// ([`tactile_burn::artifact::scored_on_fitted`]): the words saying
    /// these are not held-out scores, for the front ends to show.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub warning: Option<String>,
    /// What reading the frames found, each starting "warning: ": frames
    /// that could not be decoded past their header, left out of the scores.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_warnings: Vec<String>,
}

impl DetectorScores {
    /// The scores in a few lines for a person (`device`: where it ran),
    /// the reliability table last.
    pub fn describe(&self, device: impl std::fmt::Display) -> Vec<String> {
        let (s, st) = (&self.all, &self.onset_release);
        let mut lines = vec![
            format!(
                "{} frames ({} with a tendon): {}",
                s.frames,
                s.true_pos + s.false_neg,
                s.rates_text(4, "a tendon")
            ),
            format!(
                "confusion: {} true positive, {} false positive, {} true negative, {} false negative",
                s.true_pos, s.false_pos, s.true_neg, s.false_neg
            ),
            format!(
                "gates: {} blank and {} foreign frames answered without the network; without gates accuracy {:.4}",
                self.gated_blank, self.gated_foreign, self.ungated.accuracy
            ),
            match st.frames {
                0 => "onset/release frames (within 2 frames of a label change in a sequence): none in this set".to_string(),
                _ => format!(
                    "onset/release frames (within 2 frames of a label change): {} frames, accuracy {:.4} ({} false positive, {} false negative)",
                    st.frames, st.accuracy, st.false_pos, st.false_neg
                ),
            },
            format!(
                "calibration: expected calibration error {:.4} over {CALIBRATION_BINS} bins, {} over the {} frames with a probability in [0.1, 0.9]; Brier score {:.4}",
                self.calibration.ece,
                self.calibration.ece_uncertain_text(4),
                self.calibration.uncertain_frames,
                self.calibration.brier
            ),
            format!(
                "{:.2} ms per frame ({device}, batch {EVAL_BATCH}, resize excluded)",
                self.ms_per_frame
            ),
        ];
        lines.extend(self.reliability_table());
        lines
    }

    /// The reliability diagram as a Markdown table.
    pub fn reliability_table(&self) -> Vec<String> {
        let mut lines = vec![
            "| probability | frames | mean probability | observed tendon fraction |".to_string(),
            "|---|---|---|---|".to_string(),
        ];
        for b in &self.calibration.bins {
            let f = |v: f64| {
                if v.is_finite() {
                    format!("{v:.3}")
                } else {
                    "-".into()
                }
            };
            lines.push(format!(
                "| {:.1}-{:.1} | {} | {} | {} |",
                b.low,
                b.high,
                b.frames,
                f(b.mean_probability),
                f(b.observed)
            ));
        }
        lines
    }

    /// Save the reliability diagram: see [`save_reliability_plot`].
    pub fn save_reliability_plot(&self, path: &Path, title: &str) -> Result<()> {
        save_reliability_plot(&self.calibration, path, title)
    }
}

/// Save a reliability diagram (observed tendon fraction against mean
/// probability per bin, beside the diagonal of perfect calibration) as a PNG.
pub fn save_reliability_plot(c: &Calibration, path: &Path, title: &str) -> Result<()> {
    let points: Vec<(f64, f64)> = c
        .bins
        .iter()
        .filter(|b| b.frames > 0)
        .map(|b| (b.mean_probability, b.observed))
        .collect();
    let series = [
        Series {
            name: "perfect calibration".into(),
            points: vec![(0.0, 0.0), (1.0, 1.0)],
        },
        Series {
            name: format!("detector (ECE {:.3})", c.ece),
            points,
        },
    ];
    Ok(line_plot(
        path,
        title,
        "mean predicted tendon probability (per bin)",
        "observed tendon fraction",
        &series,
        false,
    )?)
}

/// Rows of a dataset loaded at once when scoring it: memory stays bounded
/// however many frames the dataset has.
pub const EVAL_CHUNK: usize = 1024;

/// What the detector said of a run of frames: each frame's gate (and input
/// score) and the network's probability, with the network's time.
#[derive(Default)]
struct FrameAnswers {
    gates: Vec<(Option<crate::Gate>, Option<f32>)>,
    network: Vec<f32>,
    network_seconds: f64,
}

impl FrameAnswers {
    /// Add every frame of `data`.
    fn add(&mut self, detector: &mut TendonDetector, data: &DetectionSet) -> Result<()> {
        let size = detector.artifact.model.input_size;
        if [data.width, data.height] != size {
            return Err(Error::InputSize {
                expected: size,
                found: [data.width, data.height],
            });
        }
        let stats = detector.artifact.stats.clone();
        for i in 0..data.len() {
            self.gates.push(detector.gate(&data.image(i))?);
        }
        let t0 = std::time::Instant::now();
        let all: Vec<usize> = (0..data.len()).collect();
        for chunk in all.chunks(EVAL_BATCH) {
            let x = data.inputs(chunk, &stats)?;
            self.network
                .extend(detector.network_probabilities(&x, chunk.len())?);
        }
        self.network_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    /// The scores of these answers against each frame's `tendon` label,
    /// `transition` marking the onset and release frames.
    fn score(
        &self,
        detector: &TendonDetector,
        tendon: &[bool],
        transition: &[bool],
    ) -> DetectorScores {
        let n = self.network.len();
        let answers: Vec<_> = self
            .gates
            .iter()
            .zip(&self.network)
            .map(|(&g, &q)| detector.answer(g, Some(q)))
            .collect();
        let count = |gate| answers.iter().filter(|a| a.gate == Some(gate)).count();
        let p: Vec<f32> = answers.iter().map(|a| a.probability).collect();
        let pred: Vec<bool> = answers.iter().map(|a| a.tendon).collect();
        let ungated: Vec<bool> = self
            .network
            .iter()
            .map(|&q| detector.is_tendon(q))
            .collect();
        let tr: Vec<usize> = (0..n).filter(|&i| transition[i]).collect();
        DetectorScores {
            all: binary_scores(&pred, tendon),
            ungated: binary_scores(&ungated, tendon),
            gated_blank: count(crate::Gate::Blank),
            gated_foreign: count(crate::Gate::Foreign),
            onset_release: binary_scores(
                &tr.iter().map(|&i| pred[i]).collect::<Vec<_>>(),
                &tr.iter().map(|&i| tendon[i]).collect::<Vec<_>>(),
            ),
            ms_per_frame: 1e3 * self.network_seconds / n.max(1) as f64,
            calibration: calibration(&p, tendon, CALIBRATION_BINS),
            probabilities: p,
            decisions: pred,
            threshold: detector.artifact.threshold,
            warning: None,
            frame_warnings: Vec::new(),
        }
    }
}

/// Score `detector` on every frame of `data` (loaded at its input size):
/// each frame gets [`TendonDetector::answer`], the answer `tactile run`
/// gives it, and the network's own probabilities are scored beside it.
pub fn evaluate(detector: &mut TendonDetector, data: &DetectionSet) -> Result<DetectorScores> {
    let mut answers = FrameAnswers::default();
    answers.add(detector, data)?;
    Ok(answers.score(detector, &data.tendon, &data.transition))
}

/// The labels of a dataset's frames, in dataset order, that its scores
/// were counted against.
#[derive(Debug, Clone, Default)]
pub struct FrameLabels {
    /// Each frame's `file`.
    pub files: Vec<String>,
    /// Each frame's `tendon` label.
    pub tendon: Vec<bool>,
    /// Frames within two frames of a label change in their sequence.
    pub transition: Vec<bool>,
}

/// [`evaluate`] on every row of `ds`, read `chunk_rows` rows at a time (the
/// scores do not depend on it; [`EVAL_CHUNK`] for a dataset of any length
/// in bounded memory), with the labels scored against. A frame that cannot
/// be decoded past its header is left out with its labels, named in
/// [`DetectorScores::frame_warnings`] ([`DetectionSet::for_each_chunk`]).
pub fn evaluate_dataset(
    detector: &mut TendonDetector,
    ds: &Dataset,
    chunk_rows: usize,
) -> Result<(DetectorScores, FrameLabels)> {
    let mut answers = FrameAnswers::default();
    let mut labels = FrameLabels::default();
    let config = detector.artifact.model.clone();
    let undecodable = DetectionSet::for_each_chunk(ds, &config, chunk_rows, |part| {
        answers.add(detector, &part)?;
        labels.files.extend(part.files);
        labels.tendon.extend(part.tendon);
        labels.transition.extend(part.transition);
        Ok(())
    })?;
    let mut scores = answers.score(detector, &labels.tendon, &labels.transition);
    scores.frame_warnings.extend(undecodable);
    Ok((scores, labels))
}

/// What an evaluation writes beside its scores (`tactile eval detector`'s
/// flags, `tactile.eval.detector`'s keywords): written once here.
#[derive(Debug, Clone, Default, clap::Args, Serialize, Deserialize)]
pub struct EvalOptions {
    /// Also write every frame's probability and decision to this CSV (file, tendon, probability, predicted, onset_release), to look at the frames it gets wrong.
    #[arg(long)]
    pub frames: Option<PathBuf>,
    /// Also save the reliability diagram (observed tendon fraction against predicted probability) as this PNG.
    #[arg(long)]
    pub reliability: Option<PathBuf>,
}

/// The detector in `model` scored on the labelled dataset in `data`, with
/// the files `options` ask for written (each checked to lie outside the
/// dataset before anything runs): what both front ends call.
pub fn evaluate_folder(
    model: &Path,
    data: &Path,
    runtime: Runtime,
    options: &EvalOptions,
) -> Result<DetectorScores> {
    let ds = Dataset::open(data)?;
    for out in options.frames.iter().chain(&options.reliability) {
        tactile_core::dataset::check_output_file(out, &[&ds])?;
    }
    if let Some(frames) = &options.frames {
        tactile_core::dataset::refuse_misnamed_results(
            frames,
            tactile_core::dataset::ResultsFormat::Csv,
        )?;
    }
    if let (Some(frames), Some(plot)) = (&options.frames, &options.reliability) {
        tactile_core::dataset::refuse_same_output(frames, plot)?;
    }
    let mut det = TendonDetector::load(model, runtime, 0)?;
    let (mut sc, labels) = evaluate_dataset(&mut det, &ds, EVAL_CHUNK)?;
    sc.warning = tactile_burn::artifact::scored_on_fitted::<crate::DetectorArtifact>(model, &ds);
    if let Some(path) = &options.frames {
        write_decisions_csv(path, &labels, &sc)?;
    }
    if let Some(path) = &options.reliability {
        sc.save_reliability_plot(path, "Tendon detector: reliability")?;
    }
    Ok(sc)
}

/// Every frame's probability and decision as CSV (`file, tendon,
/// probability, predicted, onset_release`), to look at the frames it gets
/// wrong.
pub fn write_decisions_csv(path: &Path, data: &FrameLabels, s: &DetectorScores) -> Result<()> {
    let mut csv = String::from("file,tendon,probability,predicted,onset_release\n");
    for (i, p) in s.probabilities.iter().enumerate() {
        csv.push_str(&format!(
            "{},{},{p:.6},{},{}\n",
            data.files[i], data.tendon[i] as u8, s.decisions[i] as u8, data.transition[i] as u8
        ));
    }
    Ok(tactile_core::io::write_atomic(path, csv.as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A researcher's recording of presses without a tendon, scored
    /// perfectly and without sequences: its summary says so, rather than
    /// precision, recall, F1 and an onset/release accuracy of 0.
    #[test]
    fn a_set_without_tendons_or_onsets_reads_as_scored() {
        let (p, truth) = (vec![0.01f32, 0.02, 0.0], vec![false; 3]);
        let decisions = vec![false; 3];
        let all = binary_scores(&decisions, &truth);
        let scores = DetectorScores {
            all,
            ungated: all,
            gated_blank: 0,
            gated_foreign: 0,
            onset_release: binary_scores(&[], &[]),
            ms_per_frame: 1.0,
            calibration: calibration(&p, &truth, CALIBRATION_BINS),
            probabilities: p,
            decisions,
            threshold: 0.5,
            warning: None,
            frame_warnings: Vec::new(),
        };
        let lines = scores.describe("flex");
        assert_eq!(
            lines[0],
            "3 frames (0 with a tendon): accuracy 1.0000, precision -, recall -, F1 - (no frame has a tendon, and none was called one)"
        );
        assert!(lines[3].ends_with("none in this set"), "{}", lines[3]);
        assert!(!lines.iter().any(|l| l.contains("accuracy 0.0000")));
    }
}
