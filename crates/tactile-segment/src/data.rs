//! Tendon frames as segmenter windows: the frame and its mask scaled and
//! cut to the square window, optionally as rotated copies (paper B's
//! augmentation).

use crate::Result;
use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::source::UndecodableFrames;
use tactile_preprocess::visuo::{ChannelStats, FloatImage, SquareWindow, resize_grey, resize_rgb};

use crate::prepare::cut_frame;

/// One window: 8-bit `S x S x 3` pixels, its 0/1 mask and where it came from.
#[derive(Debug, Clone)]
pub struct Window {
    /// Dataset row it was cut from.
    pub row: usize,
    /// Rotation applied, degrees.
    pub rotation_deg: f64,
    /// `S x S x 3` bytes.
    pub pixels: Vec<u8>,
    /// `S x S` tendon flags.
    pub mask: Vec<bool>,
    /// Its row's `direction_deg` label, when present.
    pub direction_deg: Option<f64>,
    /// Its row's `path` label, when present.
    pub path: Option<String>,
}

/// Windows of a dataset's frames with their labels.
pub struct SegmentSet {
    /// The window every frame was cut with.
    pub window: SquareWindow,
    /// The windows, `copies` per row, in row order.
    pub windows: Vec<Window>,
}

/// `copies` seeded angles, one in each of `copies` equal parts of 360
/// degrees (paper B); one copy means no rotation.
pub fn rotation_angles(copies: usize, seed: u64, row: usize) -> Vec<f64> {
    if copies <= 1 {
        return vec![0.0];
    }
    // SplitMix64 of (seed, row): reproducible and independent per frame.
    let mut s = seed ^ (row as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let part = 360.0 / copies as f64;
    (0..copies).map(|k| part * (k as f64 + next())).collect()
}

impl SegmentSet {
    /// Windows of `rows` (each `copies` times, rotated; masks required).
    pub fn from_dataset(
        ds: &Dataset,
        rows: &[usize],
        window: SquareWindow,
        copies: usize,
        seed: u64,
    ) -> Result<Self> {
        Self::from_rows(ds, rows, window, copies, seed, None)
    }

    /// [`Self::from_dataset`], a frame that cannot be decoded past its
    /// header (its pixel data cut short) left out and counted in `skipped`
    /// instead of stopping it: the frames a scoring reads.
    pub fn from_dataset_skipping(
        ds: &Dataset,
        rows: &[usize],
        window: SquareWindow,
        copies: usize,
        seed: u64,
        skipped: &mut UndecodableFrames,
    ) -> Result<Self> {
        Self::from_rows(ds, rows, window, copies, seed, Some(skipped))
    }

    /// [`Self::from_dataset`], skipping undecodable frames into `skipped`
    /// when given.
    fn from_rows(
        ds: &Dataset,
        rows: &[usize],
        window: SquareWindow,
        copies: usize,
        seed: u64,
        mut skipped: Option<&mut UndecodableFrames>,
    ) -> Result<Self> {
        ds.expect_kind(DatasetKind::Visuotactile)?;
        let (sw, sh) = window.scaled_size(ds.manifest.width as usize, ds.manifest.height as usize);
        // Outer: a frame decoded whose windows cannot be cut; inner: a
        // frame that cannot be read, kept apart so it may be skipped.
        type Read = Result<tactile_core::Result<Vec<Window>>>;
        let read: Vec<Read> = rows
            .par_iter()
            .map(|&row| -> Read {
                let frame = match ds.load_rgb(row) {
                    Ok(frame) => frame,
                    Err(e) => return Ok(Err(e)),
                };
                let frame = resize_rgb(&frame, sw, sh)
                    .map_err(|e| e.in_file(ds.path_of(row, "file").unwrap_or_default()))?;
                let m = ds.load_mask(row)?;
                let mask = resize_grey(&m, sw, sh)
                    .map_err(|e| e.in_file(ds.path_of(row, "mask").unwrap_or_default()))?;
                let direction_deg = ds.number_opt(row, "direction_deg")?;
                let path = ds.text_opt(row, "path").map(str::to_string);
                Ok(Ok(rotation_angles(copies, seed, row)
                    .into_iter()
                    .map(|deg| {
                        let (pixels, m) = cut_frame(&frame, Some(&mask), window, deg);
                        Window {
                            row,
                            rotation_deg: deg,
                            pixels,
                            mask: m.unwrap_or_default(),
                            direction_deg,
                            path: path.clone(),
                        }
                    })
                    .collect()))
            })
            .collect();
        // In row order, so the first frame refused is the first named.
        let mut windows = Vec::with_capacity(read.len() * copies);
        for r in read {
            let cut = UndecodableFrames::decoded_or_stop(skipped.as_deref_mut(), r?)?;
            windows.extend(cut.into_iter().flatten());
        }
        Ok(Self { window, windows })
    }

    /// Windows held.
    pub fn len(&self) -> usize {
        self.windows.len()
    }

    /// True when there is no window.
    pub fn is_empty(&self) -> bool {
        self.windows.is_empty()
    }

    /// The window's pixels as a float image in [0, 1].
    pub fn image(&self, i: usize) -> FloatImage {
        let s = self.window.side;
        FloatImage::from_bytes(s, s, 3, &self.windows[i].pixels)
    }

    /// Normalised `[N, 3, S, S]` inputs and `[N, 1, S, S]` masks.
    pub fn batch(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        device: &Device,
    ) -> Result<(Tensor<4>, Tensor<4>)> {
        let s = self.window.side;
        let mut x = Vec::with_capacity(idx.len() * 3 * s * s);
        let mut y = Vec::with_capacity(idx.len() * s * s);
        for &i in idx {
            x.extend(stats.to_chw(&self.image(i))?);
            y.extend(self.windows[i].mask.iter().map(|&m| m as u8 as f32));
        }
        Ok((
            Tensor::from_data(TensorData::new(x, [idx.len(), 3, s, s]), device),
            Tensor::from_data(TensorData::new(y, [idx.len(), 1, s, s]), device),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_fall_one_per_equal_part_and_repeat_per_seed() {
        let a = rotation_angles(4, 7, 12);
        assert_eq!(a.len(), 4);
        for (k, d) in a.iter().enumerate() {
            assert!(
                (90.0 * k as f64..90.0 * (k + 1) as f64).contains(d),
                "{a:?}"
            );
        }
        assert_eq!(a, rotation_angles(4, 7, 12));
        assert_ne!(a, rotation_angles(4, 8, 12));
        assert_eq!(rotation_angles(1, 7, 12), vec![0.0]);
    }
}
