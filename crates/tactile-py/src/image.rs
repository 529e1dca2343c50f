//! Reading frames with the library's own decoder, so a Python program
//! sees exactly the pixels `tactile run` and `tactile encode` see.

use numpy::IntoPyArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::args::PathArg;
use crate::errors::PyResultExt;

/// An RGB image as an `(H, W, 3)` uint8 numpy array, its pixels moved,
/// not copied: how every RGB frame reaches Python.
pub(crate) fn rgb_array(
    py: Python<'_>,
    img: tactile_core::image_io::RgbImage,
) -> PyResult<Bound<'_, PyAny>> {
    let (w, h) = (img.width(), img.height());
    Ok(ndarray::Array3::from_shape_vec((h, w, 3), img.into_vec())
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
}

/// A frame file (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM, 8 bits per
/// channel) as `(H, W, 3)` uint8 RGB (grey is expanded).
#[pyfunction]
pub(crate) fn read_rgb(py: Python<'_>, path: PathArg) -> PyResult<Bound<'_, PyAny>> {
    crate::args::keywords!(path);
    let img = py
        .detach(move || tactile_core::image_io::load_rgb(&path))
        .py()?;
    rgb_array(py, img)
}

/// A frame file (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM, 8 bits per
/// channel) as `(H, W)` uint8 grey (RGB converted with OpenCV's weights).
#[pyfunction]
pub(crate) fn read_grey(py: Python<'_>, path: PathArg) -> PyResult<Bound<'_, PyAny>> {
    crate::args::keywords!(path);
    let img = py
        .detach(move || tactile_core::image_io::load_grey(&path))
        .py()?;
    let (w, h) = (img.width(), img.height());
    Ok(ndarray::Array2::from_shape_vec((h, w), img.into_vec())
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
}
