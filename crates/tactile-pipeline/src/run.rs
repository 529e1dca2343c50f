//! The palpation pipeline over a source of frames: records streamed to the
//! caller as they are made, an optional hysteresis per sequence, overlays,
//! and a summary of speed, latency and decisions kept in bounded memory.

use std::path::{Path, PathBuf};

use serde::Serialize;
use tactile_burn::Runtime;
use tactile_core::metrics::Reservoir;

use crate::Result;
use crate::hysteresis::Hysteresis;
use crate::overlay::FrameViews;
use crate::palpation::{FrameRecord, Pipeline};
use tactile_core::image_io::RgbImage;
use tactile_core::source::{FrameSource, SourceKind};

/// How a run goes.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Two-threshold filter on the detector per sequence: `(on, off)`.
    pub hysteresis: Option<(f32, f32)>,
    /// Write an overlay PNG per tendon frame (and a calibrated sensor's
    /// indentation picture per frame) into this folder.
    pub render: Option<PathBuf>,
}

/// Most pipelines one run loads (each a copy of the models, run on a
/// thread of its own).
pub const MAX_PIPELINES: usize = 64;

/// Whether a run may process frames on `pipelines` copies of the models
/// at once: 1 to [`MAX_PIPELINES`]; more than one only for a recorded
/// source (a live one's frames arrive one at a time, and waiting for
/// several would add their interval to every frame's latency) and without
/// a hysteresis (which decides each frame after the one before it).
pub fn check_pipelines(
    pipelines: usize,
    hysteresis: Option<(f32, f32)>,
    source: SourceKind,
) -> Result<()> {
    let refuse = |why: String| Err(tactile_core::Error::Invalid(why).into());
    if !(1..=MAX_PIPELINES).contains(&pipelines) {
        return refuse(format!(
            "pipelines: must be 1 to {MAX_PIPELINES}, got {pipelines}"
        ));
    }
    if pipelines > 1 && hysteresis.is_some() {
        return refuse(format!(
            "pipelines {pipelines} with a hysteresis: the hysteresis decides each frame after the \
             one before it, so its frames go through one pipeline: leave pipelines at 1, or the \
             hysteresis out"
        ));
    }
    if pipelines > 1 && source.is_live() {
        return refuse(format!(
            "pipelines {pipelines} on a live source (a {}): its frames arrive one at a time, \
             and waiting for {pipelines} of them would add their interval to every frame's \
             latency: leave pipelines at 1 for a camera, a stream or standard input",
            match source {
                SourceKind::Camera => "camera",
                SourceKind::Stream => "network stream",
                _ => "stream on standard input",
            }
        ));
    }
    Ok(())
}

/// Median and 95th percentile, ms.
pub type Spread = [f64; 2];

/// Per-stage times over the frames that ran each stage.
#[derive(Debug, Clone, Serialize)]
pub struct StageTimes {
    /// Bringing a large frame to the working resolution (every frame).
    pub prepare: Option<Spread>,
    /// The detector (every frame).
    pub detect: Option<Spread>,
    /// Segmenter and direction (tendon frames).
    pub segment: Option<Spread>,
    /// Depth (tendon frames).
    pub depth: Option<Spread>,
    /// Every frame, whole.
    pub frame: Option<Spread>,
    /// Tendon frames, whole.
    pub tendon_frame: Option<Spread>,
    /// A calibrated sensor's reconstruction (every frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reconstruct: Option<Spread>,
}

/// A calibrated sensor's skin over a run.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct ContactSummary {
    /// Frames with any skin pushed in past the contact threshold.
    pub frames_in_contact: usize,
    /// The deepest indentation over the run, mm.
    pub peak_mm: f32,
}

/// Frames a calibrated sensor cannot read, over a run (another size than
/// its calibration's, grey for a sensor calibrated in colour): each is
/// foreign to the sensor (no tendon, no indentation), and the first is
/// named with why, so the camera's mode can be checked.
#[derive(Debug, Clone, Serialize)]
pub struct UnreadableFrames {
    /// How many frames.
    pub frames: usize,
    /// Why the first could not be read, naming it.
    pub first: String,
}

/// What a run did, how fast and how well.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// What the frames came from.
    pub source: SourceKind,
    /// Frames processed.
    pub frames: usize,
    /// Whether decoding overlapped the models.
    pub overlapped_decoding: bool,
    /// Frames missing from a numbered folder.
    pub missing_frames: u64,
    /// A folder's or dataset's frames skipped because they could not be
    /// decoded behind a whole header (cut short), named by a warning.
    pub undecodable_frames: u64,
    /// Live frames dropped because processing fell behind (the oldest
    /// waiting ones); 0 for recorded sources, which drop nothing.
    pub dropped_frames: u64,
    /// Where the networks ran.
    pub runtime: Runtime,
    /// onnxruntime intra-op threads.
    pub threads: usize,
    /// Copies of the models that processed frames at once, each on a
    /// thread of its own.
    pub pipelines: usize,
    /// Frames per second, decoding included.
    pub fps: f64,
    /// Frames the detector gated out (0 without paper B's models).
    pub gated_out: usize,
    /// Frames flagged as another sensor's (unreadable by a calibrated
    /// sensor, input statistics far from the detector's training frames,
    /// or a calibration alone's rest frame unlike them): answered with no
    /// tendon and no indentation. Counts `unreadable`'s frames too.
    pub out_of_distribution: usize,
    /// Frames the calibrated sensor could not read, when there were any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unreadable: Option<UnreadableFrames>,
    /// How the pipeline told frames of another sensor
    /// ([`Pipeline::foreign_by`]), for the warnings.
    #[serde(skip)]
    pub foreign_by: &'static str,
    /// Frames that went through every stage.
    pub tendon_frames: usize,
    /// Whether the folder has paper B's models (a calibration alone
    /// reconstructs only: no tendon decisions are made).
    pub palpation: bool,
    /// A calibrated sensor: frames with skin in contact, and the deepest
    /// indentation over the run, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSummary>,
    /// Accuracy of the decisions against the labels, when there are labels.
    pub detector_accuracy: Option<f64>,
    /// Changes of decision within sequences.
    pub decision_changes: usize,
    /// Accuracy of the detector's threshold alone.
    pub detector_accuracy_threshold_only: Option<f64>,
    /// Changes of the threshold's decision within sequences.
    pub decision_changes_threshold_only: usize,
    /// Changes of the label within sequences.
    pub label_changes: usize,
    /// The hysteresis `[on, off]`, when used.
    pub hysteresis: Option<[f32; 2]>,
    /// Median and p95 per stage.
    pub stages_ms: StageTimes,
    /// Live sources: median and p95 from a frame's arrival to its record.
    pub latency_ms: Option<Spread>,
    /// The process's peak resident memory, MB (Linux).
    pub peak_rss_mb: Option<f64>,
}

impl RunSummary {
    /// The summary in a few lines for a person.
    pub fn describe(&self) -> Vec<String> {
        let stage =
            |v: Option<Spread>| v.map_or("-".into(), |[m, p]| format!("{m:.2} / {p:.2} ms"));
        let source = serde_json::to_value(self.source).ok();
        let mut lines = vec![];
        let name = source.as_ref().and_then(|v| v.as_str()).unwrap_or("source");
        let runtime = match self.pipelines {
            1 => self.runtime.to_string(),
            n => format!("{} on {n} pipelines", self.runtime),
        };
        if self.palpation {
            // Frames the calibration cannot read cost no detector pass.
            let unread = self.unreadable.as_ref().map_or(0, |u| u.frames);
            lines.push(format!(
                "{} frames from a {name} ({:.1} frames/s, {}, decoding included); {} without a tendon cost one detector pass{}",
                self.frames,
                self.fps,
                runtime,
                self.gated_out.saturating_sub(unread),
                match unread {
                    0 => String::new(),
                    n => format!(", {n} unreadable none"),
                }
            ));
            lines.push(format!(
                "median / p95 per stage: prepare {}, detect {}, segment + direction {}, depth {}, whole frame {}",
                stage(self.stages_ms.prepare),
                stage(self.stages_ms.detect),
                stage(self.stages_ms.segment),
                stage(self.stages_ms.depth),
                stage(self.stages_ms.frame)
            ));
        } else {
            lines.push(format!(
                "{} frames from a {name} ({:.1} frames/s, {}, decoding included); a calibrated sensor without palpation models: indentation only",
                self.frames, self.fps, runtime
            ));
            lines.push(format!(
                "median / p95: whole frame {}",
                stage(self.stages_ms.frame)
            ));
        }
        if let Some(c) = self.contact {
            lines.push(format!(
                "calibrated sensor: reconstruction {} per frame; {} of {} frames in contact (past {} mm), deepest {:.3} mm",
                stage(self.stages_ms.reconstruct),
                c.frames_in_contact,
                self.frames,
                tactile_core::spec::calibrated::CONTACT_MIN_INDENTATION_MM,
                c.peak_mm
            ));
        }
        lines.extend(self.warnings());
        if self.source.is_live() {
            lines.push(format!(
                "live: {} frame(s) dropped while the models were busy; arrival to record {}",
                self.dropped_frames,
                stage(self.latency_ms)
            ));
        }
        if let Some(acc) = self.detector_accuracy {
            lines.push(format!(
                "tendon decisions: accuracy {acc:.4} with {} changes within sequences ({} changes in the labels); the detector's threshold alone: {:.4}, {} changes",
                self.decision_changes,
                self.label_changes,
                self.detector_accuracy_threshold_only.unwrap_or(f64::NAN),
                self.decision_changes_threshold_only
            ));
        }
        lines
    }

    /// The run's warnings, each a line starting `warning: `: frames the
    /// calibrated sensor cannot read, and frames that do not look like the
    /// sensor's. [`Self::describe`] holds them; the Python
    /// package raises them as `UserWarning`s.
    pub fn warnings(&self) -> Vec<String> {
        let mut warnings = vec![];
        let left_out = match (self.palpation, self.contact.is_some()) {
            (false, _) => "indentation",
            (true, true) => "tendon, direction, depth or indentation",
            (true, false) => "tendon, direction or depth",
        };
        let mut unlike_frames = self.out_of_distribution;
        if let Some(u) = &self.unreadable {
            warnings.push(format!(
                "warning: {} of {} frames cannot be read by this calibrated sensor (blank, or frames of another sensor or camera mode): they got no {left_out}. The first: {}",
                u.frames, self.frames, u.first
            ));
            unlike_frames = unlike_frames.saturating_sub(u.frames);
        }
        if unlike_frames > 0 {
            warnings.push(format!(
                "warning: {} of {} frames do not look like this sensor's ({}): they got no {left_out}",
                unlike_frames, self.frames, self.foreign_by
            ));
        }
        warnings
    }
}

/// Where records go as JSON Lines: standard output (flushed per record;
/// a reader that has gone stops the run quietly) or a file that appears
/// when [`JsonLines::finish`] is called.
pub enum JsonLines {
    /// Standard output.
    Stdout,
    /// A file, written atomically.
    File(tactile_core::io::AtomicFile),
}

impl JsonLines {
    /// `-` for standard output, else a file.
    pub fn create(out: &Path) -> Result<Self> {
        Ok(match out == Path::new("-") {
            true => JsonLines::Stdout,
            false => JsonLines::File(tactile_core::io::AtomicFile::create(out)?),
        })
    }

    /// Write one record; [`Flow::Stop`] when standard output was closed.
    pub fn write<T: serde::Serialize>(&mut self, rec: &T) -> Result<Flow> {
        let line = serde_json::to_string(rec).map_err(|e| {
            tactile_core::Error::Invalid(format!("cannot write a record as JSON: {e}"))
        })?;
        match self {
            JsonLines::File(f) => f.write_line(&line)?,
            JsonLines::Stdout => {
                use std::io::Write as _;
                let mut out = std::io::stdout().lock();
                if let Err(e) = writeln!(out, "{line}").and_then(|_| out.flush()) {
                    if e.kind() == std::io::ErrorKind::BrokenPipe {
                        return Ok(Flow::Stop);
                    }
                    return Err(tactile_core::Error::io("<stdout>", e).into());
                }
            }
        }
        Ok(Flow::Continue)
    }

    /// Move a file into place.
    pub fn finish(self) -> Result<()> {
        if let JsonLines::File(f) = self {
            f.commit()?;
        }
        Ok(())
    }
}

/// What the consumer of records wants next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Go on with the next frame.
    Continue,
    /// Stop the run here (e.g. the reader of the records has gone).
    Stop,
}

/// Accuracy and decision changes, counted as records arrive.
#[derive(Default)]
struct Decisions {
    labelled: usize,
    correct: usize,
    changes: usize,
}

impl Decisions {
    fn add(&mut self, decision: bool, label: Option<bool>, prev: Option<bool>) {
        if let Some(t) = label {
            self.labelled += 1;
            self.correct += usize::from(decision == t);
        }
        self.changes += usize::from(prev.is_some_and(|p| p != decision));
    }

    fn accuracy(&self) -> Option<f64> {
        (self.labelled > 0).then(|| self.correct as f64 / self.labelled as f64)
    }
}

/// Run `pipeline` over every frame of `source`, handing each record to
/// `sink` as soon as it is made (memory stays bounded however long the
/// source). Overlays of tendon frames go to `options.render` as
/// `NAME-overlay.png` (a calibrated sensor's frames as
/// `NAME-indentation.png`), staged and moved in when the run ends; a
/// render folder that already holds files is refused before any frame.
///
/// Several `pipelines` (copies of the same models, [`check_pipelines`])
/// take the frames of a recorded source a few at a time, one frame each on
/// a thread of its own; records still reach `sink` in the source's order.
pub fn run(
    pipelines: &mut [Pipeline],
    source: &mut FrameSource,
    options: &RunOptions,
    sink: &mut dyn FnMut(&RunItem<'_>) -> Result<Flow>,
) -> Result<RunSummary> {
    check_pipelines(pipelines.len(), options.hysteresis, source.kind())?;
    // Overlays go to a staging folder first: an error or an interrupt
    // leaves no half set of them. The folder must be new (absent or
    // empty), as `reconstruct --render` asks: another run's overlays of the
    // same names are never written over, and two runs never mix theirs.
    let render = match &options.render {
        Some(dir) => {
            tactile_core::io::ensure_writable_dir(dir)?;
            Some(tactile_core::io::StagedDir::fresh(dir)?)
        }
        None => None,
    };
    let mut stems = crate::overlay::PictureStems::default();
    let mut filter = options
        .hysteresis
        .map(|(on, off)| Hysteresis::new(on, off))
        .transpose()?;
    // A stream's length is unknown: its bar counts without a total.
    let known = source.known_frames().unwrap_or(0);
    let pb = tactile_core::progress::progress_bar(known, "run");
    let t0 = std::time::Instant::now();
    let mut times: [Reservoir; 8] = Default::default();
    let mut contact = ContactSummary::default();
    let (mut frames, mut gated, mut ood) = (0usize, 0usize, 0usize);
    let mut unreadable = None;
    let (mut final_d, mut raw_d, mut labels) = (
        Decisions::default(),
        Decisions::default(),
        Decisions::default(),
    );
    // The previous frame's sequence and decisions, for changes within one.
    let mut prev: Option<(Option<String>, bool, bool, Option<bool>)> = None;
    let mut batch = Vec::with_capacity(pipelines.len());
    // Once the source has ended it is not asked again.
    let mut ended = false;
    'frames: loop {
        while !ended && batch.len() < pipelines.len() {
            match source.next_frame()? {
                Some(f) => batch.push(f),
                None => ended = true,
            }
        }
        if batch.is_empty() {
            break;
        }
        // One pipeline: its hysteresis, reset where a sequence begins.
        if let Some(h) = filter.as_mut()
            && prev.as_ref().is_none_or(|p| p.0 != batch[0].sequence)
        {
            h.reset();
        }
        let made = process_batch(pipelines, &batch, filter.as_mut())?;
        for (frame, (mut rec, views)) in batch.drain(..).zip(made) {
            let same_sequence = prev.as_ref().is_some_and(|p| p.0 == frame.sequence);
            if let Some(why) = &rec.unreadable {
                unreadable
                    .get_or_insert_with(|| UnreadableFrames {
                        frames: 0,
                        first: why.clone(),
                    })
                    .frames += 1;
            }
            rec.latency_ms = frame.arrived.map(|t| 1e3 * t.elapsed().as_secs_f64());
            rec.stamp_ns = frame.stamp_ns;
            if let (Some(staged), Some(v)) = (&render, &views) {
                let stem = stems.next(&frame.name);
                v.save_pngs(staged.path(), &stem, &frame.image)?;
            }
            if let Some(peak) = rec.indentation_peak_mm {
                contact.peak_mm = contact.peak_mm.max(peak);
                contact.frames_in_contact += usize::from(rec.contact_area_mm2.unwrap_or(0.0) > 0.0);
            }
            let p = prev.as_ref().filter(|_| same_sequence);
            final_d.add(rec.tendon, frame.tendon, p.map(|p| p.1));
            raw_d.add(rec.tendon_raw, frame.tendon, p.map(|p| p.2));
            if let Some(t) = frame.tendon {
                labels.add(t, None, p.and_then(|p| p.3));
            }
            for (r, v) in times.iter_mut().zip([
                Some(rec.ms_prepare),
                Some(rec.ms_detect),
                rec.ms_segment,
                rec.ms_depth,
                Some(rec.ms_total),
                rec.tendon.then_some(rec.ms_total),
                rec.latency_ms,
                rec.ms_reconstruct,
            ]) {
                if let Some(v) = v {
                    r.push(v);
                }
            }
            frames += 1;
            gated += usize::from(!rec.tendon);
            ood += usize::from(rec.out_of_distribution);
            if rec.out_of_distribution {
                // A live run (a camera in another mode) shows it at once on
                // the bar, not only in the summary when it ends.
                pb.set_message(match &unreadable {
                    Some(u) => format!(
                        "{ood} foreign, {} unreadable: {}",
                        u.frames,
                        tactile_core::printable(&u.first)
                    ),
                    None => format!("{ood} foreign"),
                });
            }
            prev = Some((
                frame.sequence.clone(),
                rec.tendon,
                rec.tendon_raw,
                frame.tendon,
            ));
            pb.inc(1);
            let item = RunItem {
                record: &rec,
                views: views.as_ref(),
                frame: &frame.image,
            };
            if sink(&item)? == Flow::Stop {
                break 'frames;
            }
        }
    }
    pb.finish_and_clear();
    if let Some(staged) = render {
        staged.commit(false)?;
    }
    let wall = t0.elapsed().as_secs_f64();
    let [
        prepare,
        detect,
        segment,
        depth,
        frame,
        tendon_frame,
        latency,
        reconstruct,
    ] = times.map(|r| r.median_p95());
    let pipeline = &pipelines[0];
    let palpation = pipeline.palpation.is_some();
    Ok(RunSummary {
        source: source.kind(),
        frames,
        overlapped_decoding: source.overlapped(),
        missing_frames: source.list().map_or(0, |l| l.missing_frames().count),
        undecodable_frames: source.undecodable(),
        dropped_frames: source.dropped(),
        runtime: pipeline.runtime,
        threads: pipeline.threads,
        pipelines: pipelines.len(),
        fps: frames as f64 / wall.max(1e-9),
        // Without paper B's models no detector ran to gate a frame out
        // (and no frame has a tendon: every record stays tendon-free).
        gated_out: if palpation { gated } else { 0 },
        out_of_distribution: ood,
        unreadable,
        foreign_by: pipeline.foreign_by(),
        tendon_frames: frames - gated,
        palpation,
        contact: pipeline.sensor.is_some().then_some(contact),
        detector_accuracy: final_d.accuracy(),
        decision_changes: final_d.changes,
        detector_accuracy_threshold_only: raw_d.accuracy(),
        decision_changes_threshold_only: raw_d.changes,
        label_changes: labels.changes,
        hysteresis: options.hysteresis.map(|(on, off)| [on, off]),
        stages_ms: StageTimes {
            prepare,
            detect,
            segment,
            depth,
            frame,
            tendon_frame,
            reconstruct,
        },
        latency_ms: latency,
        peak_rss_mb: tactile_core::metrics::peak_rss_mb(),
    })
}

/// Each frame of `batch` through a pipeline of its own (the first with
/// `filter`, which a batch of more than one never has), in parallel when
/// there are several; the results in the batch's order, or the first
/// frame's error.
fn process_batch(
    pipelines: &mut [Pipeline],
    batch: &[tactile_core::source::Frame],
    filter: Option<&mut Hysteresis>,
) -> Result<Vec<(FrameRecord, Option<FrameViews>)>> {
    if let ([pipeline, ..], [frame]) = (&mut *pipelines, batch) {
        return Ok(vec![pipeline.process_filtered(
            &frame.name,
            &frame.image,
            filter,
        )?]);
    }
    std::thread::scope(|scope| {
        let running: Vec<_> = pipelines
            .iter_mut()
            .zip(batch)
            .map(|(p, f)| scope.spawn(move || p.process_filtered(&f.name, &f.image, None)))
            .collect();
        running
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(tactile_core::Error::Invalid(
                        "a pipeline's thread failed: the run stops here".into(),
                    )
                    .into())
                })
            })
            .collect()
    })
}

/// What [`run`] hands its sink per frame: the record, what the models saw
/// (tendon frames, a calibrated sensor's frames) and the frame itself, so a
/// sink can write images (MCAP results, a live view) as well as records.
pub struct RunItem<'a> {
    /// The frame's record.
    pub record: &'a FrameRecord,
    /// The window, mask, depth and indentation, when the frame had them.
    pub views: Option<&'a FrameViews>,
    /// The frame as it came.
    pub frame: &'a RgbImage,
}

/// Run over `source` keeping every record: for tests, reports and short
/// recorded sources.
pub fn run_collect(
    pipeline: &mut Pipeline,
    source: &mut FrameSource,
    options: &RunOptions,
) -> Result<RunOutcome> {
    let mut records = Vec::new();
    let summary = run(
        std::slice::from_mut(pipeline),
        source,
        options,
        &mut |item| {
            records.push(item.record.clone());
            Ok(Flow::Continue)
        },
    )?;
    Ok(RunOutcome { records, summary })
}

/// Every frame's record and the summary.
pub struct RunOutcome {
    /// One record per frame, in order.
    pub records: Vec<FrameRecord>,
    /// Speed and decisions.
    pub summary: RunSummary,
}

#[cfg(test)]
mod tests {
    use super::{SourceKind, check_pipelines};

    #[test]
    fn several_pipelines_only_on_a_recorded_source_without_a_hysteresis() {
        for kind in [SourceKind::Dataset, SourceKind::Video, SourceKind::Bag] {
            check_pipelines(1, None, kind).unwrap();
            check_pipelines(64, None, kind).unwrap();
        }
        check_pipelines(1, Some((0.6, 0.3)), SourceKind::Camera).unwrap();
        let refused = |n, h, kind| check_pipelines(n, h, kind).unwrap_err().to_string();
        assert!(refused(0, None, SourceKind::Folder).contains("must be 1 to 64, got 0"));
        assert!(refused(65, None, SourceKind::Folder).contains("must be 1 to 64, got 65"));
        assert!(refused(2, Some((0.6, 0.3)), SourceKind::Folder).contains("with a hysteresis"));
        let live = refused(2, None, SourceKind::Camera);
        assert!(live.contains("on a live source (a camera)"), "{live}");
        let live = refused(2, None, SourceKind::Stdin);
        assert!(live.contains("(a stream on standard input)"), "{live}");
    }
}
