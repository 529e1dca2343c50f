//! `tactile.synth`: the virtual sensors of `sensors.md`, as arrays in
//! memory or written as a dataset.

use datasets_synth::{
    CalibratedConfig, CalibratedSensor, TactipConfig, TactipLabels, VisuotactileConfig,
    WriteOptions, calibrated, tactip, visuotactile,
};
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::args::{Given, PathArg, Whole, optional};
use crate::errors::PyResultExt;

/// Most bytes of arrays one call may return (a bigger set is written to
/// disk with `out=`).
pub(crate) const MAX_ARRAY_BYTES: usize = 4 << 30;

fn check_in_memory(count: usize, bytes_per_frame: usize) -> PyResult<()> {
    datasets_synth::check_count(count).py()?;
    let bytes = count.saturating_mul(bytes_per_frame);
    if bytes > MAX_ARRAY_BYTES {
        return Err(PyValueError::new_err(format!(
            "count: {count} frames would take {:.1} GB in memory (limit {} GB); write them to disk with out=...",
            bytes as f64 / 1e9,
            MAX_ARRAY_BYTES >> 30
        )));
    }
    Ok(())
}

/// `count=` or `sequences=`: at least 1 (how many a dataset may hold is
/// the generator's check).
fn how_many(arg: Option<&Whole>, name: &str) -> PyResult<Option<usize>> {
    optional(arg, name, 1, usize::MAX)
}

/// `seed=`: any whole number a `u64` holds.
fn seed(arg: &Whole) -> PyResult<u64> {
    arg.within("seed", 0, u64::MAX)
}

fn write_options(force: bool, progress: bool) -> WriteOptions {
    WriteOptions { force, progress }
}

fn column<'py>(py: Python<'py>, v: Vec<Option<f64>>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
}

/// A dict of a palpation video's frames as arrays: `frames (N, H, W, 3)
/// uint8` RGB, `masks (N, H, W) bool` (the tendon's pixels, as a dataset's
/// reader reads its mask PNG) and the per-pixel map as `depth_key (N, H,
/// W) float32`, of frames of `(w, h)` pixels.
fn video_arrays<'py, 'a>(
    py: Python<'py>,
    (w, h): (usize, usize),
    frames: impl ExactSizeIterator<Item = (&'a [u8], &'a [u8], &'a [f32])>,
    depth_key: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let count = frames.len();
    let mut rgb = Vec::with_capacity(count * w * h * 3);
    let mut mask = Vec::with_capacity(count * w * h);
    let mut depth = Vec::with_capacity(count * w * h);
    for (frame_rgb, frame_mask, frame_depth) in frames {
        rgb.extend_from_slice(frame_rgb);
        mask.extend(
            frame_mask
                .iter()
                .map(|&v| v >= tactile_core::image_io::MASK_TENDON_MIN),
        );
        depth.extend_from_slice(frame_depth);
    }
    let shape_err = |e: ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let d = PyDict::new(py);
    d.set_item(
        "frames",
        ndarray::Array4::from_shape_vec((count, h, w, 3), rgb)
            .map_err(shape_err)?
            .into_pyarray(py),
    )?;
    d.set_item(
        "masks",
        ndarray::Array3::from_shape_vec((count, h, w), mask)
            .map_err(shape_err)?
            .into_pyarray(py),
    )?;
    d.set_item(
        depth_key,
        ndarray::Array3::from_shape_vec((count, h, w), depth)
            .map_err(shape_err)?
            .into_pyarray(py),
    )?;
    Ok(d)
}

/// Virtual TacTip frames: written to `out` (returns the folder), or
/// returned as `(frames (N, 300, 300) uint8, labels dict)`.
#[pyfunction]
#[pyo3(signature = (count, seed, out, force, progress, **options))]
pub(crate) fn synth_tactip(
    py: Python<'_>,
    count: Whole,
    seed: Whole,
    out: Option<PathArg>,
    force: Given<bool>,
    progress: Given<bool>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    crate::args::keywords!(out, force, progress);
    let count = count.within("count", 1, usize::MAX)?;
    let seed = self::seed(&seed)?;
    let cfg: TactipConfig = crate::json::options(py, options)?;
    cfg.validate().py()?;
    if let Some(out) = out {
        let path = crate::work::interruptible(py, || {
            datasets_synth::write_tactip(&cfg, count, seed, &out, write_options(force, progress))
                .py()
        })?;
        return Ok(path.into_pyobject(py)?.into_any().unbind());
    }
    let n = tactip::FRAME_PX;
    check_in_memory(count, n * n)?;
    let samples: Vec<(Vec<u8>, TactipLabels)> = crate::work::interruptible(py, || {
        datasets_synth::render_frames(count, progress, |i| {
            let (scene, frame) = tactip::sample(&cfg, seed, i as u64);
            let labels = TactipLabels::of(&scene, &frame);
            Ok((frame.pixels, labels))
        })
        .py()
    })?;
    let (pixels, labels): (Vec<Vec<u8>>, Vec<TactipLabels>) = samples.into_iter().unzip();
    let frames = ndarray::Array3::from_shape_vec((count, n, n), pixels.concat())
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item("shape", PyList::new(py, labels.iter().map(|l| l.shape))?)?;
    d.set_item("x_mm", column(py, labels.iter().map(|l| l.x_mm).collect()))?;
    d.set_item("y_mm", column(py, labels.iter().map(|l| l.y_mm).collect()))?;
    d.set_item(
        "theta_deg",
        column(py, labels.iter().map(|l| l.theta_deg).collect()),
    )?;
    d.set_item(
        "depth_mm",
        column(py, labels.iter().map(|l| Some(l.depth_mm)).collect()),
    )?;
    d.set_item(
        "force_n",
        column(py, labels.iter().map(|l| Some(l.force_n)).collect()),
    )?;
    d.set_item(
        "radius_mm",
        column(py, labels.iter().map(|l| l.radius_mm).collect()),
    )?;
    Ok((frames.into_pyarray(py), d)
        .into_pyobject(py)?
        .into_any()
        .unbind())
}

/// Virtual visuo-tactile palpation videos: written to `out` (returns the
/// folder), or returned as a dict of `frames (N, H, W, 3) uint8`,
/// `masks (N, H, W) bool`, `depth_m (N, H, W) float32` and the labels.
#[pyfunction]
#[pyo3(signature = (count, sequences, seed, out, force, progress, **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn synth_visuotactile(
    py: Python<'_>,
    count: Option<Whole>,
    sequences: Option<Whole>,
    seed: Whole,
    out: Option<PathArg>,
    force: Given<bool>,
    progress: Given<bool>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    crate::args::keywords!(out, force, progress);
    let count = how_many(count.as_ref(), "count")?;
    let sequences = how_many(sequences.as_ref(), "sequences")?;
    let seed = self::seed(&seed)?;
    let cfg: VisuotactileConfig = crate::json::options(py, options)?;
    cfg.validate().py()?;
    let count = cfg.frame_count(count, sequences).py()?;
    if let Some(out) = out {
        let path = crate::work::interruptible(py, || {
            datasets_synth::write_visuotactile(
                &cfg,
                count,
                seed,
                &out,
                write_options(force, progress),
            )
            .py()
        })?;
        return Ok(path.into_pyobject(py)?.into_any().unbind());
    }
    let (w, h) = (cfg.width as usize, cfg.height as usize);
    check_in_memory(count, w * h * (3 + 1 + 4))?;
    struct Sample {
        frame: visuotactile::VisuotactileFrame,
        path: &'static str,
        sequence: usize,
        index: usize,
        tendon_radius_mm: f64,
        burial_mm: f64,
    }
    let samples: Vec<Sample> = crate::work::interruptible(py, || {
        datasets_synth::render_frames(count, progress, |i| {
            let (sequence, index) = datasets_synth::visuotactile_position(&cfg, i);
            let (scene, frame) = visuotactile::sample(&cfg, seed, sequence as u64, index);
            Ok(Sample {
                frame,
                path: scene.path.name(),
                sequence,
                index,
                tendon_radius_mm: scene.tendon_radius_mm,
                burial_mm: scene.burial_mm,
            })
        })
        .py()
    })?;
    let d = video_arrays(
        py,
        (w, h),
        samples
            .iter()
            .map(|s| (&s.frame.rgb[..], &s.frame.mask[..], &s.frame.depth_m[..])),
        "depth_m",
    )?;
    let f = |g: &dyn Fn(&Sample) -> f64| -> Vec<f64> { samples.iter().map(g).collect() };
    d.set_item(
        "tendon",
        PyArray1::from_vec(py, samples.iter().map(|s| s.frame.tendon).collect()),
    )?;
    d.set_item(
        "direction_deg",
        column(py, samples.iter().map(|s| s.frame.direction_deg).collect()),
    )?;
    d.set_item("path", PyList::new(py, samples.iter().map(|s| s.path))?)?;
    d.set_item("press_mm", PyArray1::from_vec(py, f(&|s| s.frame.press_mm)))?;
    d.set_item(
        "sequence",
        PyArray1::from_vec(py, samples.iter().map(|s| s.sequence as i64).collect()),
    )?;
    d.set_item(
        "frame_index",
        PyArray1::from_vec(py, samples.iter().map(|s| s.index as i64).collect()),
    )?;
    d.set_item(
        "tendon_radius_mm",
        PyArray1::from_vec(py, f(&|s| s.tendon_radius_mm)),
    )?;
    d.set_item("burial_mm", PyArray1::from_vec(py, f(&|s| s.burial_mm)))?;
    d.set_item("ridge_mm", PyArray1::from_vec(py, f(&|s| s.frame.ridge_mm)))?;
    Ok(d.into_any().unbind())
}

/// A calibrated sensor's palpation videos: written to `out` (returns the
/// folder), or returned as a dict of `frames (N, H, W, 3) uint8`,
/// `masks (N, H, W) bool`, `indentation_m (N, H, W) float32` and the labels.
#[pyfunction]
#[pyo3(signature = (sensor, count, sequences, seed, out, force, progress, **options))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn synth_gelsight(
    py: Python<'_>,
    sensor: PathArg,
    count: Option<Whole>,
    sequences: Option<Whole>,
    seed: Whole,
    out: Option<PathArg>,
    force: Given<bool>,
    progress: Given<bool>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    crate::args::keywords!(sensor, out, force, progress);
    let count = how_many(count.as_ref(), "count")?;
    let sequences = how_many(sequences.as_ref(), "sequences")?;
    let seed = self::seed(&seed)?;
    let cfg: CalibratedConfig = crate::json::options(py, options)?;
    if let Some(out) = out {
        let (path, _) = crate::work::interruptible(py, || {
            let options = write_options(force, progress);
            tactile_gelsight::negatives::write_sensor_videos(
                &sensor,
                &cfg,
                (count, sequences),
                seed,
                &out,
                options,
            )
            .py()
        })?;
        return Ok(path.into_pyobject(py)?.into_any().unbind());
    }
    cfg.validate().py()?;
    let count = cfg.frame_count(count, sequences).py()?;
    let unit = py.detach(|| CalibratedSensor::load(&sensor)).py()?;
    if cfg.real_presses.is_some() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "real_presses joins real frames to a set written to a folder: give out=",
        ));
    }
    let (w, h) = (unit.width(), unit.height());
    check_in_memory(count, w * h * (3 + 1 + 4))?;
    let samples: Vec<(calibrated::CalibratedFrame, &'static str)> =
        crate::work::interruptible(py, || {
            datasets_synth::render_frames(count, progress, |i| {
                let (sequence, index) = datasets_synth::calibrated_position(&cfg, i);
                let (scene, frame) = calibrated::sample(&unit, &cfg, seed, sequence as u64, index);
                Ok((frame, scene.contact.name()))
            })
            .py()
        })?;
    let d = video_arrays(
        py,
        (w, h),
        samples
            .iter()
            .map(|(f, _)| (&f.rgb[..], &f.mask[..], &f.indentation_m[..])),
        "indentation_m",
    )?;
    d.set_item(
        "tendon",
        PyArray1::from_vec(py, samples.iter().map(|s| s.0.tendon).collect()),
    )?;
    d.set_item(
        "direction_deg",
        column(py, samples.iter().map(|s| s.0.direction_deg).collect()),
    )?;
    d.set_item("path", PyList::new(py, samples.iter().map(|s| s.1))?)?;
    d.set_item(
        "press_mm",
        PyArray1::from_vec(py, samples.iter().map(|s| s.0.press_mm).collect()),
    )?;
    d.set_item(
        "ridge_mm",
        PyArray1::from_vec(py, samples.iter().map(|s| s.0.ridge_mm).collect()),
    )?;
    d.set_item(
        "peak_mm",
        PyArray1::from_vec(py, samples.iter().map(|s| s.0.peak_mm).collect()),
    )?;
    let position = |i| datasets_synth::calibrated_position(&cfg, i);
    d.set_item(
        "sequence",
        PyArray1::from_vec(py, (0..count).map(|i| position(i).0 as i64).collect()),
    )?;
    d.set_item(
        "frame_index",
        PyArray1::from_vec(py, (0..count).map(|i| position(i).1 as i64).collect()),
    )?;
    Ok(d.into_any().unbind())
}

/// The ideal detector of a virtual visuo-tactile dataset
/// (`tactile synth ideal-detector`): per-frame arrays and the summary.
#[pyfunction]
#[pyo3(signature = (data, out, progress))]
pub(crate) fn synth_ideal_detector(
    py: Python<'_>,
    data: PathArg,
    out: Option<PathArg>,
    progress: Given<bool>,
) -> PyResult<Py<PyAny>> {
    crate::args::keywords!(data, out, progress);
    let bounds = crate::work::interruptible(py, || {
        visuotactile::dataset_bounds(&data, out.as_deref(), progress).py()
    })?;
    let s = visuotactile::summarise(&bounds);
    let d = PyDict::new(py);
    d.set_item("frames", s.frames)?;
    d.set_item("accuracy", s.accuracy)?;
    d.set_item("uncertain", s.uncertain)?;
    d.set_item("median_sigma_mm", s.median_sigma_mm)?;
    let f = |g: &dyn Fn(&visuotactile::DatasetFrameBound) -> f64| -> Vec<f64> {
        bounds.iter().map(g).collect()
    };
    d.set_item(
        "file",
        PyList::new(py, bounds.iter().map(|b| b.file.as_str()))?,
    )?;
    d.set_item(
        "tendon",
        PyArray1::from_vec(py, bounds.iter().map(|b| b.tendon).collect()),
    )?;
    d.set_item("ridge_mm", PyArray1::from_vec(py, f(&|b| b.bound.ridge_mm)))?;
    d.set_item(
        "ridge_sigma_mm",
        PyArray1::from_vec(py, f(&|b| b.bound.sigma_mm)),
    )?;
    d.set_item(
        "in_view",
        PyArray1::from_vec(py, bounds.iter().map(|b| b.bound.in_view).collect()),
    )?;
    d.set_item(
        "ideal_p_correct",
        PyArray1::from_vec(py, f(&|b| b.bound.p_correct)),
    )?;
    Ok(d.into_any().unbind())
}
