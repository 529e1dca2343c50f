//! Depth maps as NumPy `.npy` files (float32, metres, H x W), via ndarray-npy.

use std::path::Path;

use crate::{Error, Result};
use ndarray::Array2;
use ndarray_npy::WriteNpyExt;

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

/// Largest depth map read, in pixels (8K UHD).
pub const MAX_DEPTH_PIXELS: usize = 7680 * 4320;

/// Depths outside this range, metres, are no camera-to-skin distance.
pub const PLAUSIBLE_DEPTH_M: std::ops::Range<f32> = 0.0..1.0;

/// Bytes before an `.npy` header: the magic string, the version and the
/// header's length (2 bytes in version 1, 4 in versions 2 and 3).
fn header_end(bytes: &[u8]) -> Option<usize> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return None;
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        _ => return None,
    };
    start.checked_add(len).filter(|&end| end <= bytes.len())
}

/// A big-endian 2-D float32 or float64 map of `bytes` (a whole `.npy`
/// file whose header [`header_end`] found inside it), byte-swapped, as
/// `(width, height, values)`: `None` when it is no such map. Its header's
/// shape is checked against the 8K limit and the bytes there are before
/// anything is allocated for it.
fn read_byte_swapped(
    bytes: &[u8],
) -> std::result::Result<Option<(usize, usize, Vec<f32>)>, String> {
    use ndarray_npy::ReadNpyExt;
    use ndarray_npy::npy::header::Header;
    let Some(data) = header_end(bytes).map(|end| bytes.len() - end) else {
        return Ok(None);
    };
    let Ok(header) = Header::from_reader(&mut &bytes[..]) else {
        return Ok(None);
    };
    // The dtype as Python writes it, `'>f4'`.
    let descr = header.type_descriptor.to_string();
    let value_bytes = match descr.trim_matches(['\'', '"']) {
        ">f4" => 4,
        ">f8" => 8,
        _ => return Ok(None),
    };
    let [h, w] = header.shape[..] else {
        return Ok(None);
    };
    check_depth_size(w, h)?;
    if w * h * value_bytes != data {
        return Err(format!(
            "its header says {w}x{h} values of {value_bytes} bytes, and {data} bytes follow it"
        ));
    }
    let read = |e: ndarray_npy::ReadNpyError| format!("cannot read its {descr} values: {e}");
    Ok(Some(if value_bytes == 4 {
        let a = Array2::<f32>::read_npy(bytes).map_err(read)?;
        (w, h, a.iter().copied().collect())
    } else {
        let a = Array2::<f64>::read_npy(bytes).map_err(read)?;
        (w, h, a.iter().map(|&x| x as f32).collect())
    }))
}

/// A depth map's size: non-empty and at most 8K.
fn check_depth_size(w: usize, h: usize) -> std::result::Result<(), String> {
    match w == 0 || h == 0 || w.saturating_mul(h) > MAX_DEPTH_PIXELS {
        true => Err(format!(
            "{w}x{h} depth map: must be non-empty and at most 8K ({MAX_DEPTH_PIXELS} pixels)"
        )),
        false => Ok(()),
    }
}

/// Plausible indentation of a calibrated sensor's skin, metres: a little
/// below rest (the gel's own noise) to 2 cm in.
pub const PLAUSIBLE_INDENTATION_M: std::ops::RangeInclusive<f32> = -0.005..=0.02;

/// Read a depth map: `(width, height, metres)`; names the file on any
/// problem: not a 2-D float32 array (a float64 one, as `numpy.save` writes
/// a map computed in double precision, is read to float32; either, stored
/// big-endian, is byte-swapped), larger than
/// 8K, a header that claims more than the file holds, a value that is not
/// a finite distance between 0 and 1 m (the pixel is named). Every size is checked before anything
/// is allocated for it.
pub fn read_depth_npy(path: impl AsRef<Path>) -> Result<(usize, usize, Vec<f32>)> {
    read_depth_npy_of(path, crate::spec::DepthMaps::Distance)
}

/// [`read_depth_npy`] of a map holding `maps`: distances as there, or a
/// calibrated sensor's indentation, each value within
/// [`PLAUSIBLE_INDENTATION_M`].
pub fn read_depth_npy_of(
    path: impl AsRef<Path>,
    maps: crate::spec::DepthMaps,
) -> Result<(usize, usize, Vec<f32>)> {
    use ndarray::ArrayView2;
    use ndarray_npy::ViewNpyExt;
    let path = path.as_ref();
    crate::io::expect_regular(path)?;
    let bad = |m: String| Error::dataset(path, None, m);
    let size = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    // A float64 map of 8K, the largest read.
    let limit = (MAX_DEPTH_PIXELS * 8 + (1 << 20)) as u64;
    if size > limit {
        return Err(bad(format!(
            "{size} bytes: larger than any 8K depth map ({limit} bytes at most)"
        )));
    }
    // Read into 4-byte-aligned storage so the floats can be viewed in place.
    let mut words = vec![0u32; (size as usize).div_ceil(4)];
    {
        use std::io::Read;
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
        std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut bytes[..size as usize]))
            .map_err(|e| Error::io(path, e))?;
    }
    let bytes = &bytemuck::cast_slice::<u32, u8>(&words)[..size as usize];
    if header_end(bytes).is_none() {
        return Err(bad("not an .npy file, or its header is cut short".into()));
    }
    // Views, not reads: nothing is allocated for the header's shape, which
    // the view checks against the bytes there are.
    let (w, h, v) = match ArrayView2::<f32>::view_npy(bytes) {
        Ok(a) => {
            let (h, w) = a.dim();
            check_depth_size(w, h).map_err(bad)?;
            (w, h, a.iter().copied().collect::<Vec<f32>>())
        }
        Err(e32) => match ArrayView2::<f64>::view_npy(bytes) {
            Ok(a) => {
                let (h, w) = a.dim();
                check_depth_size(w, h).map_err(bad)?;
                // A distance beyond f32's range becomes infinite, which the
                // value checks below refuse.
                (w, h, a.iter().map(|&x| x as f32).collect())
            }
            // Views take the machine's byte order alone: a big-endian map
            // (`dtype='>f4'`) is read, byte-swapped, once its header is
            // found to fit the bytes there are.
            Err(_) => match read_byte_swapped(bytes).map_err(bad)? {
                Some(read) => read,
                None => {
                    return Err(bad(format!(
                        "not a 2-D float32 (or float64) .npy depth map: {e32}"
                    )));
                }
            },
        },
    };
    if maps == crate::spec::DepthMaps::Indentation {
        if let Some(i) = v.iter().position(|x| !PLAUSIBLE_INDENTATION_M.contains(x)) {
            return Err(bad(format!(
                "indentation at pixel ({}, {}) is {} m: expected a finite value from {} to {} m",
                i % w,
                i / w,
                v[i],
                PLAUSIBLE_INDENTATION_M.start(),
                PLAUSIBLE_INDENTATION_M.end()
            )));
        }
        return Ok((w, h, v));
    }
    if let Some(i) = v
        .iter()
        .position(|x| !PLAUSIBLE_DEPTH_M.contains(x) || *x == 0.0)
    {
        return Err(bad(format!(
            "depth at pixel ({}, {}) is {} m: not a camera-to-skin distance (expected more than 0 and less than 1 m)",
            i % w,
            i / w,
            v[i]
        )));
    }
    Ok((w, h, v))
}
