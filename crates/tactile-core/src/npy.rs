//! Depth maps as NumPy `.npy` files (float32, metres, H x W), via ndarray-npy.

use std::path::Path;

use crate::{Error, Result};
use ndarray::Array2;
use ndarray_npy::{ReadNpyExt, WriteNpyExt};

/// Write a depth map atomically; refuses non-finite values.
pub fn write_depth_npy(
    path: impl AsRef<Path>,
    width: usize,
    height: usize,
    depth_m: &[f32],
) -> Result<()> {
    let path = path.as_ref();
    if let Some(i) = depth_m.iter().position(|v| !v.is_finite()) {
        return Err(Error::Invalid(format!(
            "{}: depth at pixel ({}, {}) is not finite",
            path.display(),
            i % width.max(1),
            i / width.max(1)
        )));
    }
    let a = Array2::from_shape_vec((height, width), depth_m.to_vec())
        .map_err(|e| Error::shape("depth map", format!("{height}x{width}"), e.to_string()))?;
    crate::io::write_atomic_with(path, |w| a.write_npy(w).map_err(std::io::Error::other))
}

/// Read a depth map: `(width, height, metres)`; names the file on any problem
/// (not float32, not 2-D, a NaN or infinity).
pub fn read_depth_npy(path: impl AsRef<Path>) -> Result<(usize, usize, Vec<f32>)> {
    let path = path.as_ref();
    let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let a = Array2::<f32>::read_npy(std::io::BufReader::new(f)).map_err(|e| {
        Error::dataset(path, None, format!("not a 2-D float32 .npy depth map: {e}"))
    })?;
    let (h, w) = a.dim();
    let v: Vec<f32> = a.iter().copied().collect();
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(Error::dataset(
            path,
            None,
            format!(
                "depth at pixel ({}, {}) is {}",
                i % w.max(1),
                i / w.max(1),
                v[i]
            ),
        ));
    }
    Ok((w, h, v))
}
