//! The ideal detector of a rendered frame: how precisely the frame itself
//! tells its ridge's height `A`, whatever network reads it.
//!
//! A frame shows a tendon when `A >= 0.03 mm`. An observer that knew
//! everything about the frame except `A` (the tendon's path and width, the
//! press, the exposure, the noise level) could measure `A` no better than
//! the Cramér–Rao bound
//! `sigma_A = 1 / sqrt(sum over pixels and channels of (dI/dA)^2 / s^2)`,
//! with `I` the noiseless 8-bit value (shaded, exposed, with glare, blurred;
//! clipped pixels carry nothing) and `s^2` the sensor noise's variance plus
//! the 8-bit rounding's 1/12. Its chance of labelling the frame right is
//! `Phi(|A - 0.03| / sigma_A)`; when the tendon is out of view or the skin
//! untouched it knows the answer. Averaged over a set this bounds any
//! detector's accuracy from above: a real detector must also find the
//! tendon, and a renderer other than the reference one moves the shading.

use std::path::Path;

use rayon::prelude::*;
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::{Error, Result};

use super::camera::{Camera, sub};
use super::render::{glare_plane, light_vectors, shade};
use super::{
    BLUR_PX, HOUSING_RGB, MASK_FLOOR_MM, MASK_FRACTION, SENSOR_SPEC, SequenceScene,
    TENDON_MIN_AMPLITUDE_MM, VisuotactileConfig, frame_setup, surface,
};
use crate::raster::{Border, gaussian_blur};

/// Step of the central difference in `A`, mm (the shading is smooth in
/// `A`; the result does not move between 1e-5 and 1e-3).
const STEP_MM: f64 = 1e-4;
/// The 8-bit rounding's variance, levels squared.
const ROUNDING_VARIANCE: f64 = 1.0 / 12.0;
/// Most sequences a dataset's `sequence` column may name.
const MAX_SEQUENCES: f64 = 1e9;

/// What the ideal detector makes of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameBound {
    /// The ridge height `A`, mm.
    pub ridge_mm: f64,
    /// The smallest standard deviation of any unbiased measurement of `A`
    /// from this frame, mm (infinite when the frame holds no ridge to see).
    pub sigma_mm: f64,
    /// The centre line comes close enough to the window for a ridge at
    /// the threshold to be labelled (a mask at `A = 0.03` is not empty).
    pub in_view: bool,
    /// The ideal detector's chance of labelling the frame right.
    pub p_correct: f64,
}

/// The ideal detector on frame `frame` of sequence `sequence` of the
/// dataset `config` and `seed` describe (reference renderer's optics).
pub fn frame_bound(
    config: &VisuotactileConfig,
    seed: u64,
    sequence: u64,
    frame: usize,
) -> FrameBound {
    let (cam, scene, press_mm, mut rng) = frame_setup(config, seed, sequence, frame);
    let (exposure, noise_sigma) = super::render::camera_draws(config, &mut rng);
    let amp = scene.ridge_amplitude_mm(press_mm);
    let planes = SlopePlanes::new(&cam, &scene, press_mm, exposure);
    let mut information = 0.0f64;
    for (vals, slopes) in planes.value.iter().zip(&planes.slope) {
        for (&x, &d) in vals.iter().zip(slopes) {
            let level = x as f64 * 255.0;
            // A clipped pixel does not move with `A`.
            if level > 0.5 && level < 254.5 {
                information += (d as f64 * 255.0).powi(2);
            }
        }
    }
    information /= noise_sigma * noise_sigma + ROUNDING_VARIANCE;
    let sigma_mm = if information > 0.0 {
        1.0 / information.sqrt()
    } else {
        f64::INFINITY
    };
    let in_view = planes.peak_shape > MASK_FRACTION.max(MASK_FLOOR_MM / TENDON_MIN_AMPLITUDE_MM);
    let p_correct = if press_mm <= 0.0 || !in_view {
        1.0
    } else {
        let z = (amp - TENDON_MIN_AMPLITUDE_MM).abs() / sigma_mm;
        0.5 * libm::erfc(-z / std::f64::consts::SQRT_2)
    };
    FrameBound {
        ridge_mm: amp,
        sigma_mm,
        in_view,
        p_correct,
    }
}

/// A frame's noiseless camera planes and their slope in `A`, after the
/// blur, in [0, 1] channel units (per mm for the slope).
struct SlopePlanes {
    /// Noiseless value per channel.
    value: Vec<Vec<f32>>,
    /// d value / dA per channel, per mm.
    slope: Vec<Vec<f32>>,
    /// Largest ridge profile `exp(-s^2 / 2 w^2)` over the window.
    peak_shape: f64,
}

impl SlopePlanes {
    fn new(cam: &Camera, scene: &SequenceScene, press_mm: f64, exposure: f64) -> Self {
        let width_mm = scene.ridge_width_mm();
        let lights = light_vectors();
        let (w, h) = (cam.width, cam.height);
        let glare = glare_plane(cam);
        let mut value = vec![vec![0.0f32; w * h]; 3];
        let mut slope = vec![vec![0.0f32; w * h]; 3];
        let mut peak_shape = 0.0f64;
        for v in 0..h {
            for u in 0..w {
                let (uf, vf) = (u as f64, v as f64);
                let i = v * w + u;
                if !cam.in_window(uf, vf) {
                    for (c, plane) in value.iter_mut().enumerate() {
                        plane[i] = (HOUSING_RGB[c] / 255.0) as f32;
                    }
                    continue;
                }
                // The ridge per mm of `A` and its gradient.
                let (dx, dy) = sub(cam.to_mm(uf, vf), scene.line.nearest(cam.to_mm(uf, vf)));
                let shape = libm::exp(-(dx * dx + dy * dy) / (2.0 * width_mm * width_mm));
                peak_shape = peak_shape.max(shape);
                let (sx, sy) = (
                    -shape * dx / (width_mm * width_mm),
                    -shape * dy / (width_mm * width_mm),
                );
                let at = surface(cam, scene, press_mm, uf, vf);
                let (gx, gy) = (at.gx, at.gy);
                let base = shade(-gx, -gy, &lights);
                let up = shade(-(gx + STEP_MM * sx), -(gy + STEP_MM * sy), &lights);
                let down = shade(-(gx - STEP_MM * sx), -(gy - STEP_MM * sy), &lights);
                for c in 0..3 {
                    value[c][i] = (base[c] * exposure) as f32 + glare[i];
                    slope[c][i] = ((up[c] - down[c]) / (2.0 * STEP_MM) * exposure) as f32;
                }
            }
        }
        for plane in value.iter_mut().chain(slope.iter_mut()) {
            gaussian_blur(plane, w, h, BLUR_PX, Border::Clamp);
        }
        Self {
            value,
            slope,
            peak_shape,
        }
    }
}

/// One frame of a dataset as the ideal detector sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetFrameBound {
    /// The frame's file, as `labels.csv` names it.
    pub file: String,
    /// The `tendon` label.
    pub tendon: bool,
    /// The ideal detector on it.
    pub bound: FrameBound,
}

/// The ideal detector on every frame of a virtual visuo-tactile dataset
/// written by this generator: the scenes are drawn again from the
/// manifest's configuration and seed and each row's `sequence` and
/// `frame_index`; a row whose `ridge_mm` disagrees with the scene drawn
/// again is refused (another generator or version wrote it). With `out`,
/// the per-frame CSV is written there ([`write_bounds_csv`]), checked
/// before any work never to be one of the dataset's own files.
pub fn dataset_bounds(
    root: &Path,
    out: Option<&Path>,
    progress: bool,
) -> Result<Vec<DatasetFrameBound>> {
    let ds = Dataset::open(root)?;
    if let Some(out) = out {
        tactile_core::dataset::check_output_file(out, &[&ds])?;
        tactile_core::dataset::refuse_misnamed_results(
            out,
            tactile_core::dataset::ResultsFormat::Csv,
        )?;
    }
    let bounds = bounds_of(&ds, progress)?;
    if let Some(out) = out {
        write_bounds_csv(&bounds, out)?;
    }
    Ok(bounds)
}

fn bounds_of(ds: &Dataset, progress: bool) -> Result<Vec<DatasetFrameBound>> {
    let root = ds.root.as_path();
    ds.expect_kind(DatasetKind::Visuotactile)?;
    let manifest_path = root.join("manifest.json");
    let refuse = |why: String| Error::dataset(&manifest_path, None, why);
    let m = &ds.manifest;
    let name = |g: &str| g.split(' ').next().unwrap_or_default().to_string();
    if name(&m.generator) != name(crate::write::GENERATOR) || m.sensor_spec != SENSOR_SPEC {
        return Err(refuse(format!(
            "the ideal detector needs a virtual visuo-tactile dataset written by datasets-synth \
             (this one is '{}' by '{}')",
            m.sensor_spec, m.generator
        )));
    }
    let seed = m
        .seed
        .ok_or_else(|| refuse("no 'seed': the scenes cannot be drawn again".into()))?;
    let config: VisuotactileConfig = m
        .extra
        .get("config")
        .cloned()
        .ok_or_else(|| refuse("no 'config': the scenes cannot be drawn again".into()))
        .and_then(|c| serde_json::from_value(c).map_err(|e| refuse(format!("'config': {e}"))))?;
    config.validate().map_err(|e| refuse(e.to_string()))?;
    let labels = ds.labels_path();
    let mut rows = Vec::with_capacity(ds.len());
    for i in 0..ds.len() {
        let line = ds.rows[i].line;
        let at = |column: &str, max: f64| -> Result<f64> {
            let v = ds.number(i, column)?;
            if v < 0.0 || v >= max || v.fract() != 0.0 {
                return Err(Error::dataset(
                    &labels,
                    Some(line),
                    format!("column '{column}': {v} is not a whole number below {max}"),
                ));
            }
            Ok(v)
        };
        let sequence = at("sequence", MAX_SEQUENCES)? as u64;
        // `validate` bounds frames_per_sequence by MAX_FRAMES_PER_SEQUENCE.
        let frame = at("frame_index", config.frames_per_sequence as f64)? as usize;
        let ridge = ds.number_opt(i, "ridge_mm")?;
        rows.push((i, line, sequence, frame, ridge));
    }
    let pb = tactile_core::progress::progress_bar_if(rows.len() as u64, "ideal detector", progress);
    let out = rows
        .par_iter()
        .map(|&(i, line, sequence, frame, ridge)| {
            tactile_core::interrupt::check()?;
            let bound = frame_bound(&config, seed, sequence, frame);
            pb.inc(1);
            if let Some(a) = ridge
                && (a - bound.ridge_mm).abs() > 1e-4
            {
                return Err(Error::dataset(
                    &labels,
                    Some(line),
                    format!(
                        "ridge_mm {a} but the scene drawn again from the manifest gives {:.5}: \
                         not written by this version of datasets-synth",
                        bound.ridge_mm
                    ),
                ));
            }
            Ok(DatasetFrameBound {
                file: ds.text(i, "file")?.to_string(),
                tendon: ds.number(i, "tendon")? > 0.5,
                bound,
            })
        })
        .collect::<Result<Vec<_>>>();
    pb.finish_and_clear();
    out
}

/// A set's ideal detector in a line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdealSummary {
    /// Frames.
    pub frames: usize,
    /// The ideal detector's expected accuracy (its mean chance of being
    /// right): no detector can expect more on this set.
    pub accuracy: f64,
    /// Frames it labels right with a chance under 0.99: the frames no
    /// detector can be sure of.
    pub uncertain: usize,
    /// Median of the bound over frames with a tendon in view under
    /// contact, mm (NaN when there is none).
    pub median_sigma_mm: f64,
}

/// Summarise the ideal detector on a set.
pub fn summarise(bounds: &[DatasetFrameBound]) -> IdealSummary {
    let frames = bounds.len();
    let accuracy = bounds.iter().map(|b| b.bound.p_correct).sum::<f64>() / frames.max(1) as f64;
    let uncertain = bounds.iter().filter(|b| b.bound.p_correct < 0.99).count();
    let sigmas: Vec<f64> = bounds
        .iter()
        .filter(|b| b.bound.in_view && b.bound.ridge_mm > 0.0)
        .map(|b| b.bound.sigma_mm)
        .collect();
    let median_sigma_mm = if sigmas.is_empty() {
        f64::NAN
    } else {
        tactile_core::metrics::median(&sigmas)
    };
    IdealSummary {
        frames,
        accuracy,
        uncertain,
        median_sigma_mm,
    }
}

/// Write the per-frame bounds as CSV (`file,tendon,ridge_mm,
/// ridge_sigma_mm,in_view,ideal_p_correct`), atomically.
pub fn write_bounds_csv(bounds: &[DatasetFrameBound], out: &Path) -> Result<()> {
    tactile_core::io::write_atomic_with(out, |w| {
        let mut csv = csv::Writer::from_writer(w);
        csv.write_record([
            "file",
            "tendon",
            "ridge_mm",
            "ridge_sigma_mm",
            "in_view",
            "ideal_p_correct",
        ])?;
        for b in bounds {
            csv.write_record([
                b.file.clone(),
                u8::from(b.tendon).to_string(),
                format!("{:.5}", b.bound.ridge_mm),
                format!("{:.3e}", b.bound.sigma_mm),
                u8::from(b.bound.in_view).to_string(),
                format!("{:.6}", b.bound.p_correct),
            ])?;
        }
        csv.flush()
    })
}

#[cfg(test)]
mod tests {
    use super::super::render::{camera_draws, render};
    use super::*;
    use crate::rng::{Range, SampleRng};
    use crate::write::{WriteOptions, write_visuotactile};

    /// Light presses on the narrowest, deepest tendon, in view, at a
    /// fixed noise and exposure, 320 x 180.
    fn light() -> VisuotactileConfig {
        VisuotactileConfig {
            width: 320,
            height: 180,
            tendon_radius_mm: Range::fixed(1.5),
            burial_mm: Range::fixed(4.0),
            press_mm: Range::fixed(0.3),
            out_of_view_fraction: 0.0,
            exposure_jitter: Range::fixed(0.0),
            noise_sigma: Range::fixed(3.0),
            ..VisuotactileConfig::default()
        }
    }

    /// `A` measured by the matched filter (the slope planes) from the
    /// difference of two frames, mm.
    fn project(planes: &SlopePlanes, a: &[u8], b: &[u8]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for c in 0..3 {
            for (i, (&x, &d)) in planes.value[c].iter().zip(&planes.slope[c]).enumerate() {
                let level = x as f64 * 255.0;
                if level > 0.5 && level < 254.5 {
                    let d = d as f64 * 255.0;
                    num += d * (a[i * 3 + c] as f64 - b[i * 3 + c] as f64);
                    den += d * d;
                }
            }
        }
        num / den
    }

    #[test]
    fn the_slope_planes_are_the_renderers_change_with_the_ridge_height() {
        let config = light();
        let (cam, scene, press, mut rng) = frame_setup(&config, 7, 0, 15);
        let (exposure, _) = camera_draws(&config, &mut rng);
        let planes = SlopePlanes::new(&cam, &scene, press, exposure);
        // A higher ridge of the same width: radius up, burial down.
        let mut higher = scene.clone();
        higher.tendon_radius_mm += 0.5;
        higher.burial_mm -= 1.0;
        assert!((higher.ridge_width_mm() - scene.ridge_width_mm()).abs() < 1e-12);
        let gain = higher.ridge_amplitude_mm(press) - scene.ridge_amplitude_mm(press);
        // The same noise in both frames: it cancels, and dithers the
        // 8-bit rounding that would bias a noiseless difference.
        let rng = || SampleRng::new(1, 1, 1);
        let a = render(&config, &higher, press, &mut rng());
        let b = render(&config, &scene, press, &mut rng());
        let measured = project(&planes, &a.rgb, &b.rgb);
        assert!(
            (measured / gain - 1.0).abs() < 0.05,
            "the renderer's ridge grew {gain:.5} mm, the slope planes read {measured:.5}"
        );
    }

    #[test]
    fn the_bound_is_the_spread_of_a_matched_filter_on_rendered_frames() {
        let config = light();
        let bound = frame_bound(&config, 7, 0, 15);
        assert!(bound.in_view && bound.ridge_mm > 0.0 && bound.sigma_mm.is_finite());
        let (cam, scene, press, mut rng) = frame_setup(&config, 7, 0, 15);
        let (exposure, _) = camera_draws(&config, &mut rng);
        let planes = SlopePlanes::new(&cam, &scene, press, exposure);
        let quiet = VisuotactileConfig {
            noise_sigma: Range::fixed(0.0),
            ..light()
        };
        let clean = render(&quiet, &scene, press, &mut SampleRng::new(1, 1, 1));
        let n = 40;
        let measured: Vec<f64> = (0..n)
            .map(|k| {
                let noisy = render(&config, &scene, press, &mut SampleRng::new(100 + k, 5, 0));
                project(&planes, &noisy.rgb, &clean.rgb)
            })
            .collect();
        let mean = measured.iter().sum::<f64>() / n as f64;
        let spread =
            (measured.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        // 40 draws give the spread to about 11 %.
        assert!(
            (spread / bound.sigma_mm - 1.0).abs() < 0.3,
            "matched filter spread {spread:.6} mm, bound {:.6} mm",
            bound.sigma_mm
        );
        // More noise, a wider bound, by the noise's ratio.
        let noisier = frame_bound(
            &VisuotactileConfig {
                noise_sigma: Range::fixed(6.0),
                ..light()
            },
            7,
            0,
            15,
        );
        let ratio = ((36.0 + ROUNDING_VARIANCE) / (9.0 + ROUNDING_VARIANCE)).sqrt();
        assert!((noisier.sigma_mm / bound.sigma_mm / ratio - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_dataset_is_bounded_frame_by_frame_and_a_foreign_row_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("set");
        let config = VisuotactileConfig {
            frames_per_sequence: 6,
            ..light()
        };
        write_visuotactile(&config, 12, 5, &out, WriteOptions::default()).unwrap();
        let bounds = dataset_bounds(&out, None, false).unwrap();
        assert_eq!(bounds.len(), 12);
        for (i, b) in bounds.iter().enumerate() {
            assert_eq!(b.bound, frame_bound(&config, 5, (i / 6) as u64, i % 6));
            assert!((0.5..=1.0).contains(&b.bound.p_correct));
        }
        // A ridge height this generator did not draw.
        let labels = out.join("labels.csv");
        let text = std::fs::read_to_string(&labels).unwrap();
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let last = lines[3].rfind(',').unwrap();
        lines[3] = format!("{},0.5", &lines[3][..last]);
        std::fs::write(&labels, lines.join("\n") + "\n").unwrap();
        let err = dataset_bounds(&out, None, false).unwrap_err().to_string();
        assert!(
            err.contains("labels.csv") && err.contains("ridge_mm") && err.contains('4'),
            "{err}"
        );
    }
}
