//! The native part of the Python package `tactile` (distribution
//! `tactile-rs`): thin bindings over the library. Each class or function
//! parses its Python arguments, releases the interpreter lock, calls the
//! same library code as the `tactile` command line, and turns the result
//! into numpy arrays, dicts or Python exceptions. The typed Python API,
//! with its docstrings and stubs, is in `python/tactile/`.

mod args;
mod calibrate;
mod dataset;
mod encoder;
mod errors;
mod eval;
mod export;
mod frame;
mod image;
mod json;
mod pickling;
mod pipeline;
mod pose;
mod predict;
mod robot;
mod run;
mod source;
mod study;
mod synth;
mod train;
mod work;

use pyo3::prelude::*;

/// tactile-rs native module: see the `tactile` package.
#[pymodule]
fn _tactile(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MAX_FRAME_SIDE", frame::MAX_SIDE)?;
    m.add("MAX_BATCH", frame::MAX_BATCH)?;
    m.add("MAX_ARRAY_BYTES", synth::MAX_ARRAY_BYTES)?;
    m.add_class::<pipeline::PyPipeline>()?;
    m.add_class::<pipeline::FrameResult>()?;
    m.add_class::<encoder::PyTactipEncoder>()?;
    m.add_class::<pose::PyPoseEstimator>()?;
    m.add_function(wrap_pyfunction!(predict::predict, m)?)?;
    m.add_function(wrap_pyfunction!(export::export, m)?)?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_class::<calibrate::PyReconstructor>()?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate_ball, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::reconstruct_frames, m)?)?;
    m.add_class::<dataset::PyDataset>()?;
    m.add_class::<source::PyFrameSource>()?;
    m.add_class::<source::PyFrame>()?;
    m.add_function(wrap_pyfunction!(pickling::frame_result, m)?)?;
    m.add_function(wrap_pyfunction!(pickling::frame, m)?)?;
    m.add_class::<source::PyVideoDecoder>()?;
    m.add_function(wrap_pyfunction!(source::frames, m)?)?;
    m.add_function(wrap_pyfunction!(source::bag_topics, m)?)?;
    m.add_function(wrap_pyfunction!(source::ros_image_to_rgb, m)?)?;
    m.add_class::<robot::PyMcapWriter>()?;
    m.add_class::<robot::PyLiveView>()?;
    m.add_function(wrap_pyfunction!(image::read_rgb, m)?)?;
    m.add_function(wrap_pyfunction!(image::read_grey, m)?)?;
    m.add_function(wrap_pyfunction!(synth::synth_tactip, m)?)?;
    m.add_function(wrap_pyfunction!(synth::synth_visuotactile, m)?)?;
    m.add_function(wrap_pyfunction!(synth::synth_gelsight, m)?)?;
    m.add_function(wrap_pyfunction!(synth::synth_ideal_detector, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_cae, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_detector, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_pose, m)?)?;
    m.add_function(wrap_pyfunction!(train::options, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_segmenter, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_depth, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_head_py, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_regressor_py, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_profile, m)?)?;
    m.add_function(wrap_pyfunction!(train::train_align, m)?)?;
    m.add_function(wrap_pyfunction!(eval::eval_detector, m)?)?;
    m.add_function(wrap_pyfunction!(eval::eval_segmenter, m)?)?;
    m.add_function(wrap_pyfunction!(eval::eval_depth, m)?)?;
    m.add_function(wrap_pyfunction!(eval::eval_tactip, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_compare, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_robustness, m)?)?;
    Ok(())
}
