//! Paper B's palpation pipeline, frame by frame: the detector runs on every
//! frame; only when it sees a tendon do the segmenter, its post-processing
//! (largest region, glare override, direction) and the depth network run.
//! A calibrated GelSight-like sensor's folder adds its skin's indentation
//! on every frame (or gives only that, when it holds no palpation models).
//! It composes the model wrappers; each prepares its own input the same
//! way on every runtime.

use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use tactile_burn::Runtime;
use tactile_core::image_io::RgbImage;
use tactile_depth::DepthEstimator;
use tactile_detect::TendonDetector;
use tactile_segment::TendonSegmenter;

use tactile_burn::Artifact;
use tactile_gelsight::prepare::WorkingImage;
use tactile_gelsight::reconstruct::{CheckBasis, SensorCheck};
use tactile_gelsight::{GelsightArtifact, Reconstructor};

use crate::hysteresis::Hysteresis;
use crate::overlay::{FrameViews, SensorView, TendonView};
use crate::{Error, Result};

/// What the pipeline made of one frame (one JSON Lines record).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameRecord {
    /// The frame's file name (a stream's or a bag's frame: its number).
    pub frame: String,
    /// A bag's frame: its message's header stamp, nanoseconds since the
    /// epoch (copied into the results written to MCAP).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stamp_ns: Option<i64>,
    /// The tendon decision (the detector's threshold, or the hysteresis).
    pub tendon: bool,
    /// Detector probability.
    pub score: f32,
    /// Direction of the tendon, degrees in [0, 180).
    pub direction_deg: Option<f64>,
    /// Major / minor eigenvalue of the kept region.
    pub anisotropy: Option<f64>,
    /// Why there is no direction on a tendon frame (empty, too small, isotropic).
    pub no_direction: Option<String>,
    /// Pixels of the kept region in the segmenter's window.
    pub mask_area_px: usize,
    /// Smallest camera-to-skin distance inside the sensing window, mm.
    pub depth_min_mm: Option<f32>,
    /// Mean camera-to-skin distance inside the sensing window, mm.
    pub depth_mean_mm: Option<f32>,
    /// Largest camera-to-skin distance inside the sensing window, mm.
    pub depth_max_mm: Option<f32>,
    /// What the depth fields hold: `indentation` for a calibrated
    /// sensor's depth network (then over the whole frame: how far the skin
    /// is pushed in), else the camera-to-skin distance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_maps: Option<tactile_core::spec::DepthMaps>,
    /// The detector's own threshold decision (before any hysteresis).
    pub tendon_raw: bool,
    /// How far the frame's input statistics lie from the training frames',
    /// in spreads (with a detector that has an input profile).
    #[serde(default)]
    pub input_score: Option<f32>,
    /// Far outside the training frames (another sensor, not a sensor
    /// frame): no tendon, direction or depth is given. A calibration alone
    /// says so of a frame unlike its rest frame, and gives no indentation.
    #[serde(default)]
    pub out_of_distribution: bool,
    /// The detector's gate that answered without the network (`blank`,
    /// `foreign`), if any: the same answer `tactile eval detector` scores
    /// (`foreign` too for a calibration alone's frame unlike its rest
    /// frame).
    #[serde(default)]
    pub gate: Option<tactile_detect::Gate>,
    /// Time to bring a large frame down to the working resolution, ms
    /// (0 for frames already near it).
    #[serde(default)]
    pub ms_prepare: f64,
    /// Live sources: from the frame's arrival to this record, ms (queueing
    /// included).
    #[serde(default)]
    pub latency_ms: Option<f64>,
    /// Time of the detector, ms.
    pub ms_detect: f64,
    /// Time of the segmenter and direction, ms (tendon frames).
    pub ms_segment: Option<f64>,
    /// Time of the depth network, ms (tendon frames).
    pub ms_depth: Option<f64>,
    /// Time of the whole frame, ms.
    pub ms_total: f64,
    /// A calibrated sensor: the skin's deepest indentation, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub indentation_peak_mm: Option<f32>,
    /// A calibrated sensor: the area where the skin is pushed in by more
    /// than [`tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM`], mm².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_area_mm2: Option<f32>,
    /// A calibrated sensor: time of its reconstruction, ms.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ms_reconstruct: Option<f64>,
    /// A calibrated sensor: why it cannot read this frame (another size
    /// than its calibration's, grey for a sensor calibrated in colour),
    /// naming it. The frame is then another sensor's or another camera
    /// mode's: `out_of_distribution`, `foreign`, and given nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unreadable: Option<String>,
}

impl FrameRecord {
    /// The record of frame `name` before any model has run: no tendon.
    pub fn empty(name: &str) -> Self {
        Self {
            frame: name.to_string(),
            stamp_ns: None,
            tendon: false,
            score: 0.0,
            direction_deg: None,
            anisotropy: None,
            no_direction: None,
            mask_area_px: 0,
            depth_min_mm: None,
            depth_mean_mm: None,
            depth_max_mm: None,
            depth_maps: None,
            tendon_raw: false,
            input_score: None,
            out_of_distribution: false,
            gate: None,
            ms_prepare: 0.0,
            latency_ms: None,
            ms_detect: 0.0,
            ms_segment: None,
            ms_depth: None,
            ms_total: 0.0,
            indentation_peak_mm: None,
            contact_area_mm2: None,
            ms_reconstruct: None,
            unreadable: None,
        }
    }
}

/// Paper B's three models on one runtime.
pub struct PalpationModels {
    /// Tendon or not.
    pub detector: TendonDetector,
    /// Where and which way.
    pub segmenter: TendonSegmenter,
    /// How deep the skin is.
    pub depth: DepthEstimator,
    window: Vec<bool>,
}

impl PalpationModels {
    /// Load `detector/`, `segmenter/` and `depth/` from `dir`.
    pub fn load(dir: &Path, runtime: Runtime, threads: usize) -> Result<Self> {
        let depth = DepthEstimator::load(dir.join("depth"), runtime, threads)?;
        if depth.artifact.with_mask {
            return Err(Error::Core(tactile_core::Error::model(
                dir.join("depth"),
                "the pipeline's depth model must take RGB only (mask-channel models are for evaluation)",
            )));
        }
        let [w, h] = depth.artifact.model.input_size;
        let window = depth.artifact.depth_maps.window(w, h);
        Ok(Self {
            detector: TendonDetector::load(dir.join("detector"), runtime, threads)?,
            segmenter: TendonSegmenter::load(dir.join("segmenter"), runtime, threads)?,
            depth,
            window,
        })
    }
}

/// A models folder run frame by frame: paper B's palpation models, a
/// calibrated GelSight-like sensor's reconstruction, or both.
pub struct Pipeline {
    /// Paper B's models (`detector/`, `segmenter/`, `depth/`); `None` for
    /// a folder that holds only a sensor calibration.
    pub palpation: Option<PalpationModels>,
    /// A calibrated GelSight-like sensor (`tactile calibrate ball` wrote
    /// the folder itself): the skin's indentation on every frame.
    pub sensor: Option<Reconstructor>,
    /// Where the networks run.
    pub runtime: Runtime,
    /// onnxruntime intra-op threads it was loaded with.
    pub threads: usize,
    /// Frames at least twice this tall are box-averaged once to about it
    /// before paper B's models ([`tactile_preprocess::visuo::working_frame`]).
    pub working_height: usize,
    /// A calibration run without palpation models: how it tells frames of
    /// another sensor (the detector's input profile when `detector/` can
    /// be read, else the rest frame); `None` with palpation models, whose
    /// gate does it.
    pub sensor_check: Option<SensorCheck<'static>>,
    /// What loading found that a user should know: palpation models
    /// beside a calibration that cannot all be read (one still being
    /// trained), so the calibration runs alone.
    pub warnings: Vec<String>,
}

impl Pipeline {
    /// Load the models folder `dir` onto `runtime` (`threads` intra-op
    /// threads for onnxruntime): `detector/`, `segmenter/` and `depth/`,
    /// and the sensor calibration when `dir` is one (`gelsight.json`).
    /// A folder with a calibration and no `detector/` reconstructs only.
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let dir = dir.as_ref();
        let calibrated = GelsightArtifact::is_in(dir);
        let models_folder = |d: &Path| {
            GelsightArtifact::is_in(d)
                || ["detector", "segmenter", "depth"]
                    .iter()
                    .any(|m| d.join(m).is_dir())
        };
        tactile_core::io::expect_folder(dir, "models folder")?;
        if !models_folder(dir) {
            return Err(tactile_core::Error::wrong_kind(
                dir,
                "models folder",
                format!(
                    "no detector/, segmenter/ and depth/, and no gelsight.json{}",
                    tactile_burn::artifact::folder_hint(
                        dir,
                        models_folder,
                        "one model, not a folder of them: pass the folder that holds detector/, segmenter/ and depth/ (or a calibrated sensor's)"
                    )
                ),
            )
            .into());
        }
        // Palpation models beside a calibration that cannot all be read
        // (`detector/` being trained, `segmenter/` and `depth/` not yet)
        // leave the calibration to run alone, saying so.
        let (palpation, unread) = match calibrated && !dir.join("detector").exists() {
            true => (None, None),
            false => match PalpationModels::load(dir, runtime, threads) {
                Ok(models) => (Some(models), None),
                Err(e) if calibrated => (None, Some(e.to_string())),
                Err(e) => return Err(e),
            },
        };
        let sensor = match calibrated {
            true => Some(Reconstructor::load(dir, runtime, threads)?),
            false => None,
        };
        let sensor_check =
            (calibrated && palpation.is_none()).then(|| crate::reconstruct::detector_profile(dir));
        let warnings = match (&unread, &sensor_check) {
            (Some(e), Some(check)) => vec![format!(
                "warning: {e}: the palpation models beside this calibration cannot all be read (still being trained?), so the calibration runs alone: the skin's indentation, no tendon; {}",
                match check {
                    Ok(Some(_)) =>
                        "frames of another sensor are told by the detector's input profile"
                            .to_string(),
                    Err(d) if d != e =>
                        format!("frames of another sensor are told by the rest frame ({d})"),
                    _ => "frames of another sensor are told by the rest frame".to_string(),
                }
            )],
            _ => vec![],
        };
        Ok(Self {
            palpation,
            sensor,
            runtime,
            threads,
            working_height: tactile_preprocess::visuo::WORKING_HEIGHT,
            sensor_check: sensor_check.map(|c| SensorCheck::or_rest_frame(c.ok().flatten())),
            warnings,
        })
    }

    /// A calibrated sensor's exposure-matched working image of `frame`
    /// (named `name`), or why it cannot read it: another size than its
    /// calibration's, blank, in BGR order, or grey for a sensor calibrated
    /// in colour ([`Reconstructor::working_frame`]'s refusals), as `Err`.
    /// [`Self::process`] gives such a frame nothing; without a calibration
    /// the networks take frames of any size, and this is `Ok(None)`.
    fn sensor_working(
        &self,
        name: &str,
        frame: &RgbImage,
    ) -> Result<std::result::Result<Option<WorkingImage>, String>> {
        let Some(sensor) = self.sensor.as_ref() else {
            return Ok(Ok(None));
        };
        match sensor.working_frame(frame, Path::new(name)) {
            Ok(working) => Ok(Ok(Some(working))),
            Err(e) if e.is_frame_refusal() => Ok(Err(e.to_string())),
            Err(e) => Err(e.into()),
        }
    }

    /// How this pipeline tells a frame of another sensor, in words for a
    /// run's summary.
    pub fn foreign_by(&self) -> &'static str {
        match self.sensor_check.as_ref().map(|c| &c.basis) {
            None => {
                "input statistics far from the training frames', or grey where they were in colour"
            }
            Some(CheckBasis::DetectorProfile { .. }) => {
                "colours unlike the frames its detector was trained on"
            }
            Some(CheckBasis::RestFrame) => {
                "colours changed over half the picture from its rest frame"
            }
        }
    }

    /// The tendon detector, if the folder has one.
    pub fn detector(&self) -> Option<&TendonDetector> {
        self.palpation.as_ref().map(|p| &p.detector)
    }

    /// The detector's probability threshold (`None` without a detector).
    pub fn threshold(&self) -> Option<f64> {
        self.detector().map(|d| d.artifact.threshold)
    }

    /// Run on one frame. Frames without a tendon cost one detector pass
    /// (and the sensor's reconstruction, when calibrated).
    pub fn process(&mut self, name: &str, frame: &RgbImage) -> Result<FrameRecord> {
        Ok(self.process_filtered(name, frame, None)?.0)
    }

    /// [`Self::process`], the tendon decision taken by a hysteresis filter
    /// over the sequence when one is given, also returning what the frame
    /// looked like (tendon frames, and every frame of a calibrated sensor).
    pub fn process_filtered(
        &mut self,
        name: &str,
        frame: &RgbImage,
        filter: Option<&mut Hysteresis>,
    ) -> Result<(FrameRecord, Option<FrameViews>)> {
        let t0 = Instant::now();
        let mut rec = FrameRecord::empty(name);
        let mut views = FrameViews::default();
        // A frame a calibrated sensor cannot read (another size, blank, in
        // BGR order, grey for a colour calibration) is another sensor's or
        // another camera mode's: foreign, with or without palpation
        // models, so one such frame does not stop a run. A sequence's
        // filter hears it as a score of 0, as it does the gate's foreign
        // frames. The working image the check made is the one reconstructed.
        let t_sensor = Instant::now();
        let sensor_working = match self.sensor_working(name, frame)? {
            Ok(working) => working,
            Err(why) => {
                if let Some(h) = filter {
                    h.update(0.0);
                }
                rec.unreadable = Some(why);
                rec.out_of_distribution = true;
                rec.gate = Some(tactile_detect::Gate::Foreign);
                rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
                return Ok((rec, None));
            }
        };
        let ms_sensor_prepare = 1e3 * t_sensor.elapsed().as_secs_f64();
        // With palpation models, the detector's gate is asked first: a
        // frame of another sensor (input statistics far from the
        // detector's training frames') gets no tendon, no direction, no
        // depth and no reconstruction.
        let mut gated = None;
        if let Some(models) = self.palpation.as_mut() {
            // One downsample of a large frame; every model reads the result.
            let t_prepare = Instant::now();
            let working = tactile_preprocess::visuo::working_frame(frame, self.working_height)?;
            rec.ms_prepare = 1e3 * t_prepare.elapsed().as_secs_f64();
            let t_detect = Instant::now();
            let img = models
                .detector
                .artifact
                .model
                .frame_image(working.as_ref().unwrap_or(frame))?;
            let gate = models.detector.gate(&img)?;
            let ms_gate = 1e3 * t_detect.elapsed().as_secs_f64();
            if self.sensor.is_some() && gate.0 == Some(tactile_detect::Gate::Foreign) {
                let a = models.detector.assess_gated(img, gate)?;
                // The sequence's filter still hears the frame (a score of
                // 0), as it does an uncalibrated pipeline's foreign frame.
                if let Some(h) = filter {
                    h.update(a.probability);
                }
                rec.score = a.probability;
                rec.input_score = a.input_score;
                rec.out_of_distribution = a.out_of_distribution;
                rec.gate = a.gate;
                rec.ms_detect = ms_gate;
                rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
                return Ok((rec, None));
            }
            gated = Some((working, img, gate, ms_gate));
        }
        // A calibrated sensor's skin, from the frame as it came (its
        // calibrated size and colour, checked above). A calibration alone
        // asks its check instead of the gate (the detector's profile or
        // the rest frame, as `tactile reconstruct` does): a frame unlike
        // the sensor's gets no indentation.
        if let (Some(sensor), Some(working)) = (self.sensor.as_mut(), sensor_working) {
            let t = Instant::now();
            if let Some(check) = self.sensor_check.as_mut()
                && check
                    .unlike(frame, &working, sensor.background())?
                    .is_some()
            {
                rec.out_of_distribution = true;
                rec.gate = Some(tactile_detect::Gate::Foreign);
                rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
                return Ok((rec, None));
            }
            let map = sensor.reconstruct_working(&working)?;
            // Shrinking and matching the frame (made by the check) counts
            // as the reconstruction's, as before.
            rec.ms_reconstruct = Some(ms_sensor_prepare + 1e3 * t.elapsed().as_secs_f64());
            rec.indentation_peak_mm = Some(map.peak_mm());
            rec.contact_area_mm2 = Some(map.contact_area_mm2(sensor.mm_per_px()));
            views.indentation = Some(SensorView {
                map,
                mm_per_px: sensor.mm_per_px(),
            });
        }
        let (Some(models), Some((working, img, gate, ms_gate))) = (self.palpation.as_mut(), gated)
        else {
            rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
            return Ok((rec, views.any().then_some(views)));
        };
        let frame = working.as_ref().unwrap_or(frame);
        let t_detect = Instant::now();
        let assessment = models.detector.assess_gated(img, gate)?;
        rec.score = assessment.probability;
        rec.tendon_raw = assessment.tendon;
        rec.tendon = match filter {
            Some(h) => h.update(rec.score),
            None => rec.tendon_raw,
        };
        rec.input_score = assessment.input_score;
        rec.out_of_distribution = assessment.out_of_distribution;
        rec.gate = assessment.gate;
        rec.ms_detect = ms_gate + 1e3 * t_detect.elapsed().as_secs_f64();
        if !rec.tendon {
            rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
            return Ok((rec, views.any().then_some(views)));
        }
        // Segment and point.
        let t1 = Instant::now();
        let seg = models.segmenter.segment(frame)?;
        let t = seg.tendon;
        rec.mask_area_px = t.region.area();
        let mut direction = None;
        match t.direction {
            Ok(d) => {
                rec.direction_deg = Some(d.angle_deg);
                rec.anisotropy = Some(d.anisotropy);
                direction = Some((d.angle_deg, d.point));
            }
            Err(why) => rec.no_direction = Some(format!("{why:?}")),
        }
        rec.ms_segment = Some(1e3 * t1.elapsed().as_secs_f64());
        // Depth.
        let t2 = Instant::now();
        // A depth network with a prior corrects the calibration's
        // reconstruction, made above on the frame as it came.
        let depth_mm = match &views.indentation {
            Some(v) if models.depth.artifact.model.takes_prior() => {
                models.depth.depth_mm_reconstructed(frame, &v.map)?
            }
            _ => models.depth.depth_mm(frame, None)?,
        };
        let mm: Vec<f32> = depth_mm
            .iter()
            .zip(&models.window)
            .filter(|(_, inside)| **inside)
            .map(|(&v, _)| v)
            .collect();
        rec.depth_min_mm = mm.iter().copied().reduce(f32::min);
        rec.depth_max_mm = mm.iter().copied().reduce(f32::max);
        rec.depth_mean_mm = Some(mm.iter().sum::<f32>() / mm.len().max(1) as f32);
        rec.depth_maps = Some(models.depth.artifact.depth_maps);
        rec.ms_depth = Some(1e3 * t2.elapsed().as_secs_f64());
        rec.ms_total = 1e3 * t0.elapsed().as_secs_f64();
        views.tendon = Some(TendonView {
            window: seg.window.data,
            side: models.segmenter.artifact.model.side,
            region: t.region.pixels,
            direction,
            depth_mm,
            depth_size: models.depth.artifact.model.input_size,
            depth_maps: models.depth.artifact.depth_maps,
            frame_aspect: frame.width() as f64 / frame.height().max(1) as f64,
        });
        Ok((rec, Some(views)))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_folder_that_is_no_models_folder_is_named_with_what_it_holds() {
        let tmp = tempfile::tempdir().unwrap();
        let refusal = |dir: &Path| match Pipeline::load(dir, Runtime::BurnFlex, 1) {
            Ok(_) => panic!("{} loaded", dir.display()),
            Err(e) => e.to_string(),
        };
        // One model of the set given instead of the set.
        let depth = tmp.path().join("models/depth");
        std::fs::create_dir_all(&depth).unwrap();
        std::fs::write(depth.join("depth.json"), "{}").unwrap();
        let e = refusal(&depth);
        assert!(
            e.contains("not a models folder")
                && e.contains("it holds depth.json: one model, not a folder of them"),
            "{e}"
        );
        // The folder above a models folder: it is named.
        let e = refusal(tmp.path());
        assert!(e.contains("the folder models in it is: pass it"), "{e}");
        let e = refusal(&tmp.path().join("nowhere"));
        assert!(e.contains("models folder does not exist"), "{e}");
        let e = refusal(&depth.join("depth.json"));
        assert!(
            e.contains("depth.json: not a models folder (a file)"),
            "{e}"
        );
    }
}
