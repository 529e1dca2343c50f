//! `docs/own-sensor.md`: a calibrated sensor's own palpation pipeline
//! measured where it matters: its detector, segmenter and depth network on
//! renders no training used; the real ball presses (no tendon on any; the
//! depth network's indentation scored against the ball as the calibration
//! is); frames of other sensors flagged as foreign; and the time of each
//! step of the loop that made it (`scripts/own-sensor.sh`).

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_burn::{Artifact, Runtime};
use tactile_core::dataset::Dataset;
use tactile_core::image_io::{RgbImage, rgb_image};
use tactile_depth::DepthEstimator;
use tactile_gelsight::eval::{PressScore, score_full};
use tactile_gelsight::training::{CalibrationConfig, CircleSource, prepare_presses};
use tactile_gelsight::{BallPresses, IndentationMap, Reconstructor};
use tactile_pipeline::palpation::Pipeline;

use crate::Result;

/// What the page is made from (`tactile bench own-sensor`'s flags).
#[derive(Debug, Clone, clap::Args)]
pub struct OwnSensorBench {
    /// The calibrated sensor's folder with detector/, segmenter/ and depth/.
    #[arg(long, default_value = "models/gelsight-r15")]
    pub models: PathBuf,
    /// Held-out renders of the sensor (tactile synth gelsight, a seed no training used).
    #[arg(long)]
    pub test: PathBuf,
    /// The real ball presses (the calibration layout).
    #[arg(long, default_value = "../shared/real/gelsight-ball")]
    pub ball: PathBuf,
    /// The loop's step times (JSON: step name to seconds; scripts/own-sensor.sh writes it).
    #[arg(long)]
    pub times: Option<PathBuf>,
    /// Where the networks run.
    #[arg(long, value_enum, default_value_t = Runtime::Onnx)]
    pub runtime: Runtime,
    /// The training set, when real presses joined it (its manifest's
    /// `real_frames` says which): those presses are scored apart from the held-out ones.
    #[arg(long)]
    pub train: Option<PathBuf>,
    /// Other renders of the sensor, scored as the held-out ones are (one
    /// row each): another simulator's (scripts/gelsight_independent.py), or
    /// this one's with other settings.
    #[arg(long = "other-renders", num_args = 1..)]
    pub other_renders: Vec<PathBuf>,
}

/// A press this deep or less is light: a punch's rim or a plate's edge then
/// shades a line as a light tendon does.
pub const LIGHT_PRESS_MM: f64 = 0.3;

/// The detector's answers on one kind of frame.
#[derive(Debug, Clone, Serialize)]
pub struct KindRow {
    /// What the frames show, from their labels ([`frame_kind`]).
    pub kind: String,
    /// Frames of that kind.
    pub frames: usize,
    /// Of those, answered as labelled.
    pub correct: usize,
}

/// A set of the sensor's renders through its three networks.
#[derive(Debug, Clone, Serialize)]
pub struct RenderScores {
    /// The set's folder.
    pub set: String,
    /// The detector on every frame.
    pub detector: tactile_detect::DetectorScores,
    /// The detector by kind of frame, in [`KINDS`] order.
    pub kinds: Vec<KindRow>,
    /// The segmenter on the tendon frames.
    pub segmenter: tactile_segment::eval::SegmenterScores,
    /// The depth network (indentation over the whole frame).
    pub depth: tactile_depth::eval::DepthScores,
    /// Its ms per frame.
    pub depth_ms: f64,
}

/// The kinds of frame [`frame_kind`] tells, in the page's order.
pub const KINDS: [&str; 10] = [
    "no contact",
    "tendon, light press",
    "tendon, deeper press",
    "touching a tendon, under the mask's threshold",
    "sphere, light press",
    "sphere, deeper press",
    "punch, light press",
    "punch, deeper press",
    "plate edge, light press",
    "plate edge, deeper press",
];

/// What row `i` of a calibrated sensor's renders shows, from its `tendon`,
/// `path` and `press_mm` (light: at most [`LIGHT_PRESS_MM`]); `None` for
/// rows the kinds do not cover (a real press, an unknown path, no press
/// recorded).
pub fn frame_kind(ds: &Dataset, i: usize) -> Result<Option<&'static str>> {
    let Some(press) = ds.number_opt(i, "press_mm")? else {
        return Ok(None);
    };
    let light = press <= LIGHT_PRESS_MM;
    let pick = |l: &'static str, d: &'static str| Some(if light { l } else { d });
    Ok(match ds.text_opt(i, "path").unwrap_or("") {
        _ if press <= 0.0 => Some(KINDS[0]),
        "none" => Some(KINDS[0]),
        "straight" | "arc" | "s-curve" if ds.number(i, "tendon")? > 0.5 => pick(KINDS[1], KINDS[2]),
        "straight" | "arc" | "s-curve" => Some(KINDS[3]),
        "sphere" => pick(KINDS[4], KINDS[5]),
        "punch" => pick(KINDS[6], KINDS[7]),
        "flat" => pick(KINDS[8], KINDS[9]),
        _ => None,
    })
}

/// A calibrated sensor's three palpation networks, loaded once for every
/// set the page scores.
pub struct PalpationNetworks {
    /// `detector/`.
    pub detector: tactile_detect::TendonDetector,
    /// `segmenter/`, with its rest frame when it keeps one.
    pub segmenter: tactile_segment::TendonSegmenter,
    /// `depth/`.
    pub depth: DepthEstimator,
}

impl PalpationNetworks {
    /// The networks beside the calibration in `models`, on `runtime`.
    pub fn load(models: &Path, runtime: Runtime) -> Result<Self> {
        Ok(Self {
            detector: tactile_detect::TendonDetector::load(models.join("detector"), runtime, 0)?,
            segmenter: tactile_segment::TendonSegmenter::load(
                models.join("segmenter"),
                runtime,
                0,
            )?,
            depth: DepthEstimator::load(models.join("depth"), runtime, 0)?,
        })
    }
}

/// The three networks on the renders `ds`, the detector also by kind of
/// frame.
pub fn score_renders(nets: &mut PalpationNetworks, ds: &Dataset) -> Result<RenderScores> {
    tactile_core::note!(
        "detector, segmenter and depth network on {}",
        ds.root.display()
    );
    let (detector, labels) = tactile_detect::eval::evaluate_dataset(
        &mut nets.detector,
        ds,
        tactile_detect::eval::EVAL_CHUNK,
    )?;
    let mut kind_of = std::collections::HashMap::new();
    for i in 0..ds.len() {
        if let Some(k) = frame_kind(ds, i)?.and_then(|k| KINDS.iter().position(|x| *x == k)) {
            kind_of.insert(ds.text(i, "file")?.to_string(), k);
        }
    }
    let mut kinds: Vec<KindRow> = KINDS
        .iter()
        .map(|k| KindRow {
            kind: k.to_string(),
            frames: 0,
            correct: 0,
        })
        .collect();
    for ((file, truth), said) in labels
        .files
        .iter()
        .zip(&labels.tendon)
        .zip(&detector.decisions)
    {
        if let Some(&k) = kind_of.get(file) {
            kinds[k].frames += 1;
            kinds[k].correct += usize::from(truth == said);
        }
    }
    let segmenter = tactile_segment::eval::evaluate(&mut nets.segmenter, ds)?;
    let (depth, depth_ms, _) = tactile_depth::eval::evaluate(&mut nets.depth, ds)?;
    Ok(RenderScores {
        set: ds.root.display().to_string(),
        detector,
        kinds,
        segmenter,
        depth,
        depth_ms,
    })
}

/// One real ball press.
#[derive(Debug, Clone, Serialize)]
pub struct BallRow {
    /// Its frame.
    pub file: String,
    /// The pipeline's decision.
    pub tendon: bool,
    /// The detector's probability.
    pub probability: f32,
    /// Flagged as foreign.
    pub foreign: bool,
    /// The press joined the training set (as a real negative).
    pub in_training: bool,
    /// The depth network's indentation against the ball.
    pub network: PressScore,
    /// The calibration's reconstruction against the ball.
    pub calibration: PressScore,
}

/// Real ball presses summed up: one row of the page's table, and what
/// `scripts/own_sensor_depth_seeds.py` reads of a run's page (so the means
/// are taken once, here).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BallSummary {
    /// Which presses: `all`, or `held-out` (those that never joined
    /// training).
    pub presses: String,
    /// How many.
    pub count: usize,
    /// Reported as showing a tendon.
    pub tendon: usize,
    /// Flagged as foreign.
    pub foreign: usize,
    /// The largest tendon probability among them.
    pub max_probability: f32,
    /// The depth network's mean shape error inside the contact, mm.
    pub network_shape_mm: f64,
    /// The depth network's mean far field, mm.
    pub network_far_field_mm: f64,
    /// The calibration's mean shape error inside the contact, mm.
    pub calibration_shape_mm: f64,
    /// The calibration's mean far field, mm.
    pub calibration_far_field_mm: f64,
    /// The network's shape error over the calibration's.
    pub shape_ratio: f64,
    /// How deep the network says the ball went, mean over the presses, mm.
    pub network_peak_mm: f64,
    /// How deep the calibration says it went, mm.
    pub calibration_peak_mm: f64,
}

impl BallSummary {
    /// The summary of `rows` under the name `presses` (`None`: no rows).
    pub fn of(presses: &str, rows: &[&BallRow]) -> Option<Self> {
        if rows.is_empty() {
            return None;
        }
        let m = |f: fn(&BallRow) -> f64| mean(rows.iter().map(|r| f(r)));
        let network_shape_mm = m(|r| r.network.shape_mae_mm);
        let calibration_shape_mm = m(|r| r.calibration.shape_mae_mm);
        Some(Self {
            presses: presses.into(),
            count: rows.len(),
            tendon: rows.iter().filter(|r| r.tendon).count(),
            foreign: rows.iter().filter(|r| r.foreign).count(),
            max_probability: rows.iter().map(|r| r.probability).fold(0f32, f32::max),
            network_shape_mm,
            network_far_field_mm: m(|r| r.network.far_field_mm),
            calibration_shape_mm,
            calibration_far_field_mm: m(|r| r.calibration.far_field_mm),
            shape_ratio: network_shape_mm / calibration_shape_mm.max(1e-9),
            network_peak_mm: m(|r| r.network.peak_mm),
            calibration_peak_mm: m(|r| r.calibration.peak_mm),
        })
    }

    /// The summaries a page shows: every press, and apart those that never
    /// joined training when some did.
    pub fn of_presses(ball: &[BallRow]) -> Vec<Self> {
        let all: Vec<&BallRow> = ball.iter().collect();
        let held: Vec<&BallRow> = ball.iter().filter(|r| !r.in_training).collect();
        let mut out: Vec<Self> = Self::of("all", &all).into_iter().collect();
        if held.len() < all.len() {
            out.extend(Self::of("held-out", &held));
        }
        out
    }
}

/// One set of frames through the pipeline.
#[derive(Debug, Clone, Serialize)]
pub struct ForeignRow {
    /// What the frames are.
    pub set: String,
    /// Whether they are the sensor's own.
    pub own: bool,
    /// Frames.
    pub frames: usize,
    /// Flagged as foreign.
    pub flagged: usize,
    /// Reported as showing a tendon.
    pub tendon: usize,
}

/// The sensor's frames recorded one way (as they are, through a codec, or
/// with a noisier camera's noise).
#[derive(Debug, Clone, Serialize)]
pub struct RecordingRow {
    /// How the frames were recorded.
    pub recording: String,
    /// Real frames: the rest frame and every press.
    pub real_frames: usize,
    /// Of those, reported as showing a tendon.
    pub real_tendon: usize,
    /// The largest tendon probability among them.
    pub real_probability: f32,
    /// The calibration's reconstruction of the presses against the ball:
    /// mean shape and far-field errors, mm.
    pub calibration_mm: (f64, f64),
    /// Each press's contact area (indentation past the contact threshold)
    /// over its area as recorded: the median.
    pub contact_area_ratio: f64,
    /// Held-out renders through the same recording.
    pub renders: usize,
    /// The detector's accuracy on them.
    pub render_accuracy: f64,
}

/// The page's numbers.
#[derive(Debug, Clone, Serialize)]
pub struct OwnSensorReport {
    /// Each step of the loop and its seconds.
    pub times: Vec<(String, f64)>,
    /// Frames rendered for training (from the times file).
    pub frames: Option<u64>,
    /// The three networks on the held-out renders.
    pub test: RenderScores,
    /// The same on each `--other-renders` set.
    pub other_renders: Vec<RenderScores>,
    /// The calibration's own reconstruction on the same renders: mean
    /// |error| over the frame, mm.
    pub reconstruction_mae_mm: f64,
    /// Every real ball press.
    pub ball: Vec<BallRow>,
    /// The presses summed up ([`BallSummary::of_presses`]).
    pub ball_summary: Vec<BallSummary>,
    /// The presses in words: `32 presses of a 4 mm ball`.
    pub ball_presses: String,
    /// The pipeline's rate over the held-out renders, frames/s.
    pub pipeline_fps: f64,
    /// Frames of this and other sensors.
    pub foreign: Vec<ForeignRow>,
    /// The real presses and held-out renders as a camera or recorder
    /// compresses them, and with a noisier camera's noise.
    pub recordings: Vec<RecordingRow>,
    /// The detector trained with photometric augmentation (`--augment`),
    /// as its training record says (`None`: no record).
    pub detector_augmented: Option<bool>,
    /// What that augmentation changed, in words (`None`: none, or no
    /// record).
    pub detector_augmentation: Option<String>,
    /// The depth network corrects the calibration's reconstruction (it
    /// takes it as a fourth channel) rather than reading the frame alone.
    pub depth_prior: bool,
    /// Depth networks trained apart whose mean `depth/` gives (1: one
    /// network).
    pub depth_networks: usize,
    /// The segmenter reads directions against the sensor's rest frame
    /// (`segmenter/rest.png`).
    #[serde(default)]
    pub segmenter_rest: bool,
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}

impl OwnSensorReport {
    /// The page's section on the real presses: every press, and apart
    /// those that never joined training when some did.
    fn ball_section(&self) -> String {
        let (all, held) = (
            self.ball.len(),
            self.ball.iter().filter(|r| !r.in_training).count(),
        );
        let joined = all - held;
        let mut md = String::from("## On the real ball presses\n\n");
        md.push_str(&if joined > 0 {
            format!("{joined} of the {all} presses joined the training set as real negatives (as copies under the renders' exposure and noise, labelled with the calibration's reconstruction; `tactile synth gelsight --real-presses`); the other {held} never did and are the held-out check. ")
        } else {
            "No real frame joined training: the networks saw renders only. ".into()
        });
        md.push_str("Each press goes through the pipeline; the depth network and the calibration's reconstruction are scored against the ball as in `docs/calibration.md` (shape inside the contact with its median offset removed, and the far field beyond three contact radii). The calibration was fitted on all of these presses. The last column compares how deep each one says the ball went (a network of the frame alone stopped at 1.15 mm against the calibration's 1.88 mm, 4.9x its shape error: what it learnt of the renders' look did not carry over to the real frames at the deepest presses; correcting the calibration's reconstruction instead, which was fitted on this sensor's frames, starts from what carries over).\n\n| presses | count | reported as a tendon | flagged foreign | largest tendon probability | depth network shape / far field (mm) | calibration shape / far field (mm) | ratio (shape) | deepest point, network / calibration (mm, mean) |\n|---|---|---|---|---|---|---|---|---|\n");
        for b in &self.ball_summary {
            let name = match b.presses.as_str() {
                "held-out" => "held out (never in training)",
                other => other,
            };
            md.push_str(&format!(
                "| {name} | {} | {} | {} | {:.3} | {:.3} / {:.4} | {:.3} / {:.4} | {:.2}x | {:.2} / {:.2} |\n",
                b.count,
                b.tendon,
                b.foreign,
                b.max_probability,
                b.network_shape_mm,
                b.network_far_field_mm,
                b.calibration_shape_mm,
                b.calibration_far_field_mm,
                b.shape_ratio,
                b.network_peak_mm,
                b.calibration_peak_mm,
            ));
        }
        md.push('\n');
        md
    }

    /// The page's section on recordings: the real frames and held-out
    /// renders as cameras and recorders compress them.
    fn recordings_section(&self) -> String {
        let Some(first) = self.recordings.first() else {
            return String::new();
        };
        let mut md = format!(
            "\n## Recorded through a camera or a recorder\n\nA real sensor's frames rarely reach the toolkit as they left its camera's chip: a USB camera (a GelSight Mini's) sends Motion JPEG, and a recording (`ffmpeg -i /dev/video0 rec.mp4`, a phone, a ROS 2 bag of `ffmpeg_image_transport`) stores H.264 with half the colour resolution. Here the {} real frames (the rest frame and every press) and the first {} held-out renders go through FFmpeg each way (each set one video, in its order) and back, then through the pipeline; last, with a noisier camera's noise instead. A tendon on a real frame is a false alarm: {} The calibration's reconstruction is scored against the ball as above, and each press's contact area (indentation past {} mm) is compared with its area as recorded. {}\n\n| recording | real frames reported as a tendon | largest tendon probability | calibration shape / far field (mm) | contact area against as recorded (median) | detector accuracy on the renders |\n|---|---|---|---|---|---|\n",
            first.real_frames,
            first.renders,
            match self.recordings.iter().filter(|r| r.real_tendon > 0).count() {
                0 => "none shows one.".to_string(),
                n => format!("{n} of the {} recordings show one.", self.recordings.len()),
            },
            tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM,
            match self.detector_augmented {
                Some(true) => format!(
                    "The detector trained with photometric augmentation (`tactile train detector --augment`, at its input size: {}), which is what holds it here: trained without it on the same renders, it took the compression for light presses.",
                    self.detector_augmentation.as_deref().unwrap_or("as its record says")
                ),
                Some(false) =>
                    "The detector trained without photometric augmentation (`tactile train detector --augment`).".into(),
                None => String::new(),
            }
        );
        for r in &self.recordings {
            md.push_str(&format!(
                "| {} | {} of {} | {:.3} | {:.3} / {:.4} | {:.2}x | {:.4} |\n",
                r.recording,
                r.real_tendon,
                r.real_frames,
                r.real_probability,
                r.calibration_mm.0,
                r.calibration_mm.1,
                r.contact_area_ratio,
                r.render_accuracy
            ));
        }
        if self.recordings.len() < recording_ways().len() + 1 {
            md.push_str("\nFFmpeg was not found, so the Motion JPEG and H.264 rows are left out: `bash scripts/install-ffmpeg.sh` installs it, then run this page's command again.\n");
        }
        md.push_str("\nThe calibration's shape inside the contact holds under every recording. H.264's halved colour resolution adds a little indentation about the contact's edge, so the area past the threshold grows by the factor shown: a contact area compares between frames recorded one way, and a sensor whose frames will be recorded compressed is best calibrated from presses recorded the same way.\n");
        md
    }

    /// The same over `b`.
    /// Each `--other-renders` set's scores, one row each.
    fn other_renders_section(&self) -> String {
        if self.other_renders.is_empty() {
            return String::new();
        }
        let mut md = String::from(
            "## On renders of other simulators\n\nThe same networks on renders no choice was made on, from another simulator of this sensor (`scripts/gelsight_independent.py`: Taxim's recipe, its colour change a lookup of the slope alone fitted on the same ball presses, its own gel spread, objects and camera) or from this one with other settings. Flagged: frames the input profile took for another sensor's.\n\n| set | frames (tendon) | detector accuracy | flagged | segmenter IoU / direction median / p90 / coverage | depth MAE over the frame |\n|---|---|---|---|---|---|\n",
        );
        for r in &self.other_renders {
            let d = &r.detector.all;
            let seg = r.segmenter.paths.first();
            md.push_str(&format!(
                "| `{}` | {} ({}) | {:.4} | {} | {} | {:.4} mm |\n",
                r.set,
                d.frames,
                d.true_pos + d.false_neg,
                d.accuracy,
                r.detector.gated_foreign,
                seg.map_or("-".into(), |p| format!(
                    "{:.3} / {:.2} deg / {:.2} deg / {:.1} %",
                    p.mean_iou,
                    p.direction.median_deg,
                    p.direction.p90_deg,
                    100.0 * p.direction.coverage
                )),
                r.depth.mae_mm
            ));
        }
        md.push('\n');
        md
    }

    /// The detector's accuracy by kind of frame on every set of renders.
    fn kinds_section(&self) -> String {
        let sets: Vec<&RenderScores> = std::iter::once(&self.test)
            .chain(&self.other_renders)
            .collect();
        let mut md = format!(
            "### By kind of frame\n\nThe detector's accuracy (frames) by what the labels say a frame shows; a press of {LIGHT_PRESS_MM} mm or less is light. At a light press a punch's rim or a plate's edge shades a line as a tendon does.\n\n| kind of frame |"
        );
        for r in &sets {
            md.push_str(&format!(" `{}` |", r.set));
        }
        md.push_str(&format!("\n|---|{}\n", "---|".repeat(sets.len())));
        for (k, kind) in KINDS.iter().enumerate() {
            if sets.iter().all(|r| r.kinds[k].frames == 0) {
                continue;
            }
            md.push_str(&format!("| {kind} |"));
            for r in &sets {
                let row = &r.kinds[k];
                match row.frames {
                    0 => md.push_str(" - |"),
                    n => md.push_str(&format!(" {:.3} ({n}) |", row.correct as f64 / n as f64)),
                }
            }
            md.push('\n');
        }
        md.push('\n');
        md
    }
}

/// The depth network's indentation over a whole frame, metres.
fn network_map(depth: &mut DepthEstimator, frame: &RgbImage) -> Result<IndentationMap> {
    let mm = depth.depth_mm(frame, None)?;
    let [w, h] = depth.artifact.model.input_size;
    let big = tactile_preprocess::enlarge_f32(&mm, (w, h), (frame.width(), frame.height()))
        .map_err(tactile_pipeline::Error::from)?;
    Ok(IndentationMap {
        width: frame.width(),
        height: frame.height(),
        indentation_m: big.iter().map(|v| v * 1e-3).collect(),
    })
}

/// The frames of a dataset, in row order.
fn frames_of(ds: &Dataset, max: usize) -> Result<Vec<RgbImage>> {
    (0..ds.len().min(max))
        .map(|i| Ok(ds.load_rgb(i)?))
        .collect()
}

/// `frames` with each pixel's channels changed by `f`.
fn recolour(
    frames: &[RgbImage],
    f: impl Fn(usize, usize, [u8; 3]) -> [u8; 3],
) -> Result<Vec<RgbImage>> {
    frames
        .iter()
        .map(|img| {
            let (w, h) = (img.width(), img.height());
            let mut out = Vec::with_capacity(w * h * 3);
            for (i, p) in img.as_slice().chunks_exact(3).enumerate() {
                out.extend(f(i % w, i / w, [p[0], p[1], p[2]]));
            }
            Ok(rgb_image(w, h, out)?)
        })
        .collect()
}

/// Measure everything on the page.
pub fn bench_own_sensor(b: &OwnSensorBench) -> Result<OwnSensorReport> {
    let times: Vec<(String, f64)> = match &b.times {
        Some(p) => {
            let v: serde_json::Map<String, serde_json::Value> =
                tactile_core::io::read_json_limited(p, 1 << 20)?;
            v.iter()
                .filter(|(k, _)| *k != "frames")
                .filter_map(|(k, v)| v.as_f64().map(|s| (k.clone(), s)))
                .collect()
        }
        None => vec![],
    };
    let frames = match &b.times {
        Some(p) => tactile_core::io::read_json_limited::<serde_json::Value>(p, 1 << 20)?
            .get("frames")
            .and_then(|v| v.as_u64()),
        None => None,
    };
    let m = &b.models;
    let mut nets = PalpationNetworks::load(m, b.runtime)?;
    // Every set is opened and checked to be visuo-tactile before any is
    // scored.
    let open = |set: &PathBuf| -> Result<Dataset> {
        let ds = Dataset::open(set)?;
        ds.expect_kind(tactile_core::dataset::DatasetKind::Visuotactile)?;
        Ok(ds)
    };
    let test = open(&b.test)?;
    let others = b
        .other_renders
        .iter()
        .map(open)
        .collect::<Result<Vec<_>>>()?;
    // A frame that cannot be decoded is named below: the reconstruction
    // reads every frame and stops at it.
    let test_scores = score_renders(&mut nets, &test)?;
    let other_renders = others
        .iter()
        .map(|ds| score_renders(&mut nets, ds))
        .collect::<Result<Vec<_>>>()?;
    let segmenter_rest = nets.segmenter.rest().is_some();
    let depth = &mut nets.depth;
    // The calibration's reconstruction on the same renders.
    let mut rec = Reconstructor::load(m, b.runtime, 0)?;
    let mut errs = Vec::with_capacity(test.len());
    for i in 0..test.len() {
        tactile_core::interrupt::check()?;
        let frame = test.load_rgb(i)?;
        let map = rec.reconstruct(&frame, &test.path_of(i, "file")?)?;
        let (_, _, truth) = test.load_depth_m(i)?;
        errs.push(mean(
            map.indentation_m
                .iter()
                .zip(&truth)
                .map(|(p, t)| ((p - t) as f64 * 1e3).abs()),
        ));
    }
    let reconstruction_mae_mm = mean(errs.into_iter());
    // The real ball presses.
    tactile_core::note!("the real ball presses in {}", b.ball.display());
    let presses = BallPresses::open(&b.ball)?;
    // On the grid a calibration with the defaults works on.
    let factor = CalibrationConfig::new().working_factor(&presses);
    let (_, prepared) = prepare_presses(&presses, factor, CircleSource::Auto)?;
    let mut pipeline = Pipeline::load(m, b.runtime, 1)?;
    let trained: Vec<String> = match &b.train {
        Some(t) => Dataset::open(t)?
            .manifest
            .extra
            .get("real_frames")
            .and_then(|r| r.get("used"))
            .and_then(|u| u.as_array())
            .map(|u| {
                u.iter()
                    .filter_map(|v| v.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default(),
        None => vec![],
    };
    let mut ball = Vec::with_capacity(prepared.len());
    for (i, p) in prepared.iter().enumerate() {
        let frame = presses.frame(i)?;
        let cap = p.cap(&presses);
        let r = pipeline.process(&p.file, &frame)?;
        let net = network_map(depth, &frame)?;
        let cal = rec.reconstruct(&frame, &presses.press_path(i))?;
        ball.push(BallRow {
            file: p.file.clone(),
            tendon: r.tendon,
            probability: r.score,
            foreign: r.out_of_distribution,
            in_training: trained.contains(&p.file),
            network: score_full(&net, &cap, &p.file),
            calibration: score_full(&cal, &cap, &p.file),
        });
    }
    // The pipeline's rate, and frames of this and other sensors.
    let own = frames_of(&test, 400)?;
    let t0 = std::time::Instant::now();
    for f in &own {
        pipeline.process("frame", f)?;
    }
    let pipeline_fps = own.len() as f64 / t0.elapsed().as_secs_f64().max(1e-9);
    let real: Vec<RgbImage> = (0..presses.presses.len())
        .map(|i| presses.frame(i))
        .collect::<tactile_gelsight::Result<_>>()?;
    let (w, h) = (own[0].width(), own[0].height());
    let virtual_frames = {
        use datasets_synth::{VisuotactileConfig, visuotactile};
        let vc = VisuotactileConfig {
            frames_per_sequence: 10,
            ..Default::default()
        };
        let mut v = Vec::new();
        for s in 0..6 {
            for f in 0..10 {
                let (_, fr) = visuotactile::sample(&vc, 990, s, f);
                v.push(rgb_image(fr.width, fr.height, fr.rgb)?);
            }
        }
        v
    };
    let stretched = virtual_frames
        .iter()
        .map(|f| {
            let r = tactile_preprocess::visuo::resize_rgb(f, w, h)
                .map_err(tactile_pipeline::Error::from)?;
            Ok(rgb_image(w, h, r.to_bytes())?)
        })
        .collect::<Result<Vec<_>>>()?;
    let sample: Vec<RgbImage> = own.iter().step_by(5).cloned().collect();
    let sets: Vec<(String, bool, Vec<RgbImage>)> = vec![
        ("held-out renders of this sensor".into(), true, own.clone()),
        (
            "the real ball presses (this sensor)".into(),
            true,
            real.clone(),
        ),
        (
            "virtual visuo-tactile sensor, 640x360".into(),
            false,
            virtual_frames,
        ),
        (
            format!("virtual visuo-tactile sensor stretched to {w}x{h}"),
            false,
            stretched,
        ),
        (
            "another unit: LEDs in another order (channels rotated)".into(),
            false,
            recolour(&sample, |_, _, [r, g, b]| [g, b, r])?,
        ),
        (
            "another unit: warmer light, falling off to one side".into(),
            false,
            recolour(&sample, |x, _, [r, g, b]| {
                let k = 1.1 - 0.5 * x as f32 / w as f32;
                [
                    (r as f32 * k * 1.25).min(255.0) as u8,
                    (g as f32 * k).min(255.0) as u8,
                    (b as f32 * k * 0.7).min(255.0) as u8,
                ]
            })?,
        ),
        (
            "another unit: a darker, flatter gel (half the contrast)".into(),
            false,
            recolour(&sample, |_, _, p| p.map(|v| (v as f32 * 0.5 + 40.0) as u8))?,
        ),
    ];
    let mut foreign = Vec::new();
    for (set, is_own, frames) in sets {
        let (mut flagged, mut tendon) = (0, 0);
        for f in &frames {
            tactile_core::interrupt::check()?;
            let r = pipeline.process("frame", f)?;
            flagged += usize::from(r.out_of_distribution);
            tendon += usize::from(r.tendon);
        }
        foreign.push(ForeignRow {
            set,
            own: is_own,
            frames: frames.len(),
            flagged,
            tendon,
        });
    }
    tactile_core::note!("the presses and renders as cameras and recorders compress them");
    let labels = (0..own.len())
        .map(|i| Ok(test.number(i, "tendon")? > 0.5))
        .collect::<Result<Vec<bool>>>()?;
    let recordings = recordings(
        &mut pipeline,
        &mut rec,
        (&presses, &prepared, &real),
        (&own, &labels),
    )?;
    let training =
        tactile_core::io::read_json::<serde_json::Value>(m.join("detector").join("training.json"))
            .ok();
    Ok(OwnSensorReport {
        times,
        frames,
        test: test_scores,
        other_renders,
        segmenter_rest,
        reconstruction_mae_mm,
        depth_prior: depth.artifact.prior.is_some(),
        depth_networks: match tactile_depth::DepthEnsembleArtifact::is_in(&m.join("depth")) {
            true => tactile_depth::DepthEnsembleArtifact::read(&m.join("depth"))?
                .members
                .len(),
            false => 1,
        },
        ball_presses: format!(
            "{} presses of {}",
            presses.presses.len(),
            presses.describe_balls()
        ),
        ball_summary: BallSummary::of_presses(&ball),
        ball,
        pipeline_fps,
        foreign,
        recordings,
        detector_augmented: training.as_ref().map(|v| !v["config"]["augment"].is_null()),
        detector_augmentation: training
            .and_then(|v| serde_json::from_value(v["config"]["augment"].clone()).ok())
            .map(|a: tactile_detect::augment::PhotometricAugment| a.describe()),
    })
}

/// How the sensor's frames are recorded on the page: as they are, as a USB
/// camera's Motion JPEG and a recorder's H.264 compress them, and with a
/// noisier camera's noise.
fn recording_ways() -> Vec<(String, Option<tactile_core::video::VideoCodec>)> {
    use tactile_core::video::VideoCodec::{H264Yuv420, MjpegYuv422};
    let mut ways = vec![("as stored (the frame files)".to_string(), None)];
    for q in [2, 5] {
        ways.push((
            format!("Motion JPEG as a USB camera sends it (FFmpeg `-q:v {q}`, 4:2:2)"),
            Some(MjpegYuv422 { q }),
        ));
    }
    for crf in [18, 23, 28] {
        let default = if crf == 23 { ", FFmpeg's default" } else { "" };
        ways.push((
            format!("H.264 as a recorder stores it (libx264 `-crf {crf}`{default}, 4:2:0)"),
            Some(H264Yuv420 { crf }),
        ));
    }
    ways
}

/// Gaussian noise of this many grey levels added to every channel of
/// every pixel: a cheap camera in dim light.
const CAMERA_NOISE_LEVELS: f64 = 4.0;

/// `frames` with [`CAMERA_NOISE_LEVELS`] of noise (seeded: the page is
/// the same each time).
fn noisy(frames: &[RgbImage]) -> Result<Vec<RgbImage>> {
    frames
        .iter()
        .enumerate()
        .map(|(i, img)| {
            let mut rng = tactile_core::rng::SampleRng::new(7, 0, i as u64);
            let px = tactile_preprocess::perturb::add_noise(
                img.as_slice(),
                CAMERA_NOISE_LEVELS,
                &mut rng,
            );
            Ok(rgb_image(img.width(), img.height(), px)?)
        })
        .collect()
}

/// The real frames (the rest frame, then every press: `(presses, their
/// prepared circles, their frames)`) and held-out renders `(frames, tendon
/// labels)` recorded each way of [`recording_ways`] and with a noisier
/// camera: what the pipeline reports on them.
fn recordings(
    pipeline: &mut Pipeline,
    rec: &mut Reconstructor,
    (presses, prepared, press_frames): (
        &BallPresses,
        &[tactile_gelsight::training::PreparedPress],
        &[RgbImage],
    ),
    (renders, labels): (&[RgbImage], &[bool]),
) -> Result<Vec<RecordingRow>> {
    let mut real = vec![presses.background.clone()];
    real.extend_from_slice(press_frames);
    let mut ways: Vec<(String, Vec<RgbImage>, Vec<RgbImage>)> = Vec::new();
    // Without FFmpeg the codecs' rows are left out (the page says so).
    let ffmpeg = tactile_core::video::ffmpeg_available();
    for (name, codec) in recording_ways()
        .into_iter()
        .filter(|(_, c)| ffmpeg || c.is_none())
    {
        let through = |frames: &[RgbImage]| -> Result<Vec<RgbImage>> {
            match codec {
                None => Ok(frames.to_vec()),
                Some(c) => Ok(tactile_core::video::round_trip(
                    &frames.iter().collect::<Vec<_>>(),
                    c,
                )?),
            }
        };
        ways.push((name, through(&real)?, through(renders)?));
    }
    ways.push((
        format!("camera noise: {CAMERA_NOISE_LEVELS} grey levels per pixel (Gaussian)"),
        noisy(&real)?,
        noisy(renders)?,
    ));
    let mut rows = Vec::new();
    let mut recorded_area: Vec<f64> = Vec::new();
    for (recording, real, renders) in ways {
        tactile_core::interrupt::check()?;
        let (mut real_tendon, mut real_probability) = (0, 0f32);
        for f in &real {
            let r = pipeline.process("frame", f)?;
            real_tendon += usize::from(r.tendon);
            real_probability = real_probability.max(r.score);
        }
        let (mut shape, mut far, mut areas) = (Vec::new(), Vec::new(), Vec::new());
        for (i, p) in prepared.iter().enumerate() {
            let map = rec.reconstruct(&real[i + 1], &presses.press_path(i))?;
            let score = score_full(&map, &p.cap(presses), &p.file);
            shape.push(score.shape_mae_mm);
            far.push(score.far_field_mm);
            areas.push(map.contact_area_mm2(rec.mm_per_px()) as f64);
        }
        if recorded_area.is_empty() {
            recorded_area = areas.clone();
        }
        let mut ratios: Vec<f64> = areas
            .iter()
            .zip(&recorded_area)
            .map(|(a, b)| a / b.max(1e-9))
            .collect();
        ratios.sort_by(f64::total_cmp);
        let correct = renders
            .iter()
            .zip(labels)
            .map(|(f, &t)| Ok(pipeline.process("frame", f)?.tendon == t))
            .collect::<Result<Vec<bool>>>()?;
        rows.push(RecordingRow {
            recording,
            real_frames: real.len(),
            real_tendon,
            real_probability,
            calibration_mm: (mean(shape.into_iter()), mean(far.into_iter())),
            contact_area_ratio: ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN),
            renders: correct.len(),
            render_accuracy: correct.iter().filter(|&&c| c).count() as f64
                / correct.len().max(1) as f64,
        });
    }
    Ok(rows)
}

impl OwnSensorReport {
    /// The page (its numbers as JSON beside it).
    pub fn write(&self, b: &OwnSensorBench, command: &str, out: &Path) -> Result<String> {
        let _page = crate::output::lock_page(out)?;
        let mut md = String::new();
        md.push_str("# Your own sensor: from ball presses to a trained palpation pipeline\n\n");
        md.push_str(&format!(
            "Generated by `{command}` after `bash scripts/own-sensor.sh` (which runs the loop below and then this). Machine: {}; {} runtime.\n\n",
            tactile_core::bench::Machine::detect().describe(),
            b.runtime
        ));
        md.push_str("A real GelSight-like sensor (`");
        md.push_str(&b.ball.display().to_string());
        md.push_str("`: ");
        md.push_str(&self.ball_presses);
        md.push_str(") is calibrated (`tactile calibrate ball`: the sensor model that reconstructs its skin, and its render model: colour change by slope and place, and the gel's spread around a contact, both fitted on the presses). Its own palpation videos are then rendered through that calibration over its own background (`tactile synth gelsight`: tendons of 1.5-3.5 mm on straight and curved lines pressed 0.05-1.5 mm at any angle and offset; spheres, punches and plate edges pressed 0.05-2.5 mm as negatives; frames without contact; exposure, noise, blur, optics and gel varied per video), with exact masks, directions and indentation maps, and paper B's three models are trained on them with the toolkit's trainers and exported to ONNX. ");
        if self.depth_prior {
            md.push_str("The depth network does not read the frame alone: it takes the calibration's own reconstruction of the frame as a fourth channel and learns a correction to it (`tactile train depth --prior-calibration`), so on real frames it starts from what the calibration sees there (given the calibration of another sensor than the one the frames were rendered from, it says so before training). ");
        }
        if self.depth_networks > 1 {
            md.push_str(&format!("`depth/` holds {} such networks trained alike with other seeds, answering as one (`tactile train ensemble`: the mean of their maps, one graph in every runtime): runs of one recipe differ most on frames unlike the renders, by 2.4x on another simulator's, and the mean depends on no single draw ([each network alone](own-sensor-depth-seeds.md)). ", self.depth_networks));
        }
        if self.segmenter_rest {
            md.push_str("The segmenter keeps the sensor's rest frame (`tactile train segmenter --rest`): it reads a tendon's direction from the window's shading against it, so the gel's own texture (scratches, streaks of its paint) does not pull the angle. ");
        }
        md.push_str("The folder `");
        md.push_str(&b.models.display().to_string());
        md.push_str("` then holds the calibration with `detector/`, `segmenter/` and `depth/` beside it, and `tactile run --models` on it runs the whole pipeline on that sensor's frames, its depth in indentation.\n\n## The loop, step by step\n\n| step | seconds |\n|---|---|\n");
        for (k, s) in &self.times {
            md.push_str(&format!("| {k} | {s:.0} |\n"));
        }
        let total: f64 = self.times.iter().map(|t| t.1).sum();
        md.push_str(&format!(
            "| **total** | **{total:.0}** ({:.1} min) |\n\n",
            total / 60.0
        ));
        if let Some(n) = self.frames {
            md.push_str(&format!("{n} frames were rendered for training.\n\n"));
        }
        let t = &self.test;
        let d = &t.detector.all;
        md.push_str(&format!(
            "## On renders no training used\n\n`{}`: {} frames ({} with a tendon).\n\n| model | measure | value |\n|---|---|---|\n| detector | accuracy | {:.4} |\n| detector | precision / recall | {:.4} / {:.4} |\n| detector | onset and release frames: accuracy | {:.4} |\n",
            b.test.display(),
            d.frames,
            d.true_pos + d.false_neg,
            d.accuracy,
            d.precision,
            d.recall,
            t.detector.onset_release.accuracy
        ));
        for p in &t.segmenter.paths {
            md.push_str(&format!(
                "| segmenter, {} ({} frames) | IoU / direction median / p90 / coverage | {:.3} / {:.2} deg / {:.2} deg / {:.1} % |\n",
                p.path,
                p.frames,
                p.mean_iou,
                p.direction.median_deg,
                p.direction.p90_deg,
                100.0 * p.direction.coverage
            ));
        }
        md.push_str(&format!(
            "| depth network | indentation MAE over the frame / over the tendon | {:.4} mm / {} |\n| depth network{} | ms per frame (the network alone, in batches of {}, on the runtime above) | {:.2} |\n| calibration's reconstruction (photometric, Poisson) | indentation MAE over the frame | {:.4} mm |\n| pipeline | frames/s over these frames (decoding excluded) | {:.1} |\n\n",
            t.depth.mae_mm,
            t.depth
                .mae_tendon_mm
                .map_or("-".into(), |v| format!("{v:.4} mm")),
            match self.depth_networks {
                1 => String::new(),
                n => format!(" ({n} averaged)"),
            },
            tactile_depth::eval::EVAL_BATCH,
            t.depth_ms,
            self.reconstruction_mae_mm,
            self.pipeline_fps
        ));
        md.push_str(&self.other_renders_section());
        md.push_str(&self.kinds_section());
        md.push_str(&self.ball_section());
        md.push_str("## Frames of other sensors\n\nThe detector's input profile (its training frames' statistics) flags frames that are not this sensor's; they get no tendon, direction or depth, nor the calibration's indentation (the gate is asked before the reconstruction). It also keeps its training frames' camera mode: trained on a colour sensor's frames, it flags a grey one (the camera switched to a mono mode, a bag of `mono8` Images); trained on a mono camera's, it flags colour ones. `tactile reconstruct`, `Reconstructor.reconstruct` and `tactile.calibrate.reconstruct`, which reconstruct what they are given, ask the same profile and name such frames in a warning. The 32 real presses score 0.9-2.7 against its threshold of 6.7; a 331-pin TacTip frame and a 127-pin one scaled to 640x480 and tinted (`ffmpeg -i F -vf scale=640:480,format=rgb24,colorchannelmixer=rr=1:gg=0.9:bb=0.8`, and `rr=0.9:gg=1:bb=1.1` for the 127-pin one) score 66.6 and 73.3 (`tactile run --models models/gelsight-r15 --data D --out r.jsonl`, the records' `input_score`). Besides the frame's global statistics it keeps the training frames' colour layout (each channel's level on a 16 x 12 grid, relative to the channel's mean): another unit of the same design differs there, in where each colour is bright (the residual) or in how strongly (the contrast), even when its global statistics match. Other units are stood in for by this sensor's held-out renders with another LED order, another light, or a flatter gel. `tactile train detector` fits the profile on its training frames; `tactile train profile` refits it on a detector trained before. Before a detector is trained, the calibration alone compares each frame with its rest frame (median colour change once exposure is matched, above 0.20 named): the real presses stay below 0.03, its renders below 0.04 (and below 0.07 under spheres of 15-40 mm pressing half the gel or more), TacTip frames on its canvas score 0.84 and 0.90; the other units below are not told that way (they stay below 0.17; the flatter gel, its exposure matched, below 0.05). `docs/hard-cases.md` has the commands. A frame the calibration cannot read at all (another size than its frames', or grey) is foreign too, with or without the detector, its record's `unreadable` saying why; `tactile reconstruct` refuses a folder holding such frames before it reconstructs any.\n\n| frames | own sensor | frames | flagged | tendon reported |\n|---|---|---|---|---|\n");
        for r in &self.foreign {
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} |\n",
                r.set,
                if r.own { "yes" } else { "no" },
                r.frames,
                r.flagged,
                r.tendon
            ));
        }
        md.push_str(&self.recordings_section());
        // Pictures: real presses beside the same presses rendered through
        // the calibration, and held-out renders with their labels.
        let (press_path, press_png) = crate::output::picture_beside(out, "presses");
        let (renders_path, renders_png) = crate::output::picture_beside(out, "renders");
        press_figure(b, &press_path)?;
        datasets_synth::preview::contact_sheet(&b.test, &renders_path, 12)?;
        md.push_str(&format!(
            "\n## Pictures\n\nReal ball presses (top) and the same presses rendered through the calibration (bottom: the ball at the annotated circle, pressed as the gel's fit says; no noise):\n\n![presses]({press_png})\n\nHeld-out renders with their labels (mask in red, direction as an arrow):\n\n![renders]({renders_png})\n"
        ));
        crate::output::markdown_and_json(out, &md, self)?;
        Ok(md)
    }
}

/// Three real presses above the same presses rendered through the
/// calibration in `b.models`, at half size.
fn press_figure(b: &OwnSensorBench, path: &Path) -> Result<()> {
    let presses = BallPresses::open(&b.ball)?;
    let unit = datasets_synth::calibrated::CalibratedSensor::load(&b.models)?;
    let picked: Vec<usize> = (0..presses.presses.len().min(3)).collect();
    use tactile_gelsight::render_model::{BallPress, render_presses};
    let pressed: Vec<BallPress> = picked
        .iter()
        .filter_map(|&i| Some(BallPress::of(&presses, i, presses.presses[i].annotated?)))
        .collect();
    if pressed.len() != picked.len() {
        return Ok(());
    }
    let rendered = render_presses(&unit.model, &presses.background, &pressed);
    let (w, h) = presses.size();
    let (hw, hh) = (w / 2, h / 2);
    let mut out = vec![255u8; 3 * hw * 2 * hh * 3];
    let width = 3 * hw;
    for (k, &i) in picked.iter().enumerate() {
        let real = presses.frame(i)?;
        let rows = [Some(real.as_slice().to_vec()), rendered[k].clone()];
        for (r, img) in rows.iter().enumerate() {
            let Some(img) = img else { continue };
            for y in 0..hh {
                for x in 0..hw {
                    let s = ((2 * y) * w + 2 * x) * 3;
                    let d = ((r * hh + y) * width + k * hw + x) * 3;
                    out[d..d + 3].copy_from_slice(&img[s..s + 3]);
                }
            }
        }
    }
    Ok(tactile_core::image_io::save_rgb_png(
        path,
        width,
        2 * hh,
        &out,
    )?)
}
