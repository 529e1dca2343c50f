//! Visuo-tactile frames with their depth maps (and tendon masks) at the
//! network's input size.

use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;
use tactile_core::Error;
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::rng::SampleRng;
use tactile_core::source::UndecodableFrames;
use tactile_core::spec::DepthMaps;
use tactile_core::spec::visuotactile as spec;
use tactile_preprocess::visuo::{ChannelStats, FloatImage, resize_grey};

use std::path::Path;

use tactile_burn::Runtime;
use tactile_detect::augment::PhotometricAugment;

use crate::prepare::FourthChannel;
use crate::prior::PriorSource;
use crate::{DepthNetConfig, DepthScale, Result};

/// One sample at the input size.
pub struct DepthSample {
    /// `H x W x 3` bytes.
    pub rgb: Vec<u8>,
    /// Camera-to-skin distance, millimetres, `H x W`.
    pub depth_mm: Vec<f32>,
    /// Tendon pixels.
    pub mask: Vec<bool>,
    /// The frame's `tendon` label.
    pub tendon: bool,
    /// The peak press of the frame, mm (for reporting the extremes).
    pub press_mm: Option<f64>,
    /// The calibration's reconstruction, mm, `H x W` (a network with a
    /// prior).
    pub prior_mm: Option<Vec<f32>>,
}

/// Samples of a dataset, with the sensing window at the input size.
pub struct DepthSet {
    /// Input width.
    pub width: usize,
    /// Input height.
    pub height: usize,
    /// The frames, in row order.
    pub samples: Vec<DepthSample>,
    /// Pixels where the skin is seen and scored: the ellipse inscribed in
    /// the frame for the virtual sensor's distances, every pixel for a
    /// calibrated sensor's indentation.
    pub window: Vec<bool>,
    /// What the depth maps hold.
    pub depth_maps: DepthMaps,
}

/// The skin at rest (`sensors.md`): camera-to-skin distance
/// `d0(r) = 15 + 3 (r / r_max)^2` mm, `r` from the frame centre and `r_max`
/// the half-diagonal, sampled on a `w x h` map that covers a frame of
/// aspect `frame_aspect` (width / height; a map may be stretched to the
/// network's input).
pub fn rest_dome_mm(w: usize, h: usize, frame_aspect: f64) -> Vec<f32> {
    let a = if frame_aspect.is_finite() && frame_aspect > 0.0 {
        frame_aspect
    } else {
        1.0
    };
    let r_max2 = (a / 2.0).powi(2) + 0.25;
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        let dv = (y as f64 + 0.5) / h as f64 - 0.5;
        for x in 0..w {
            let du = ((x as f64 + 0.5) / w as f64 - 0.5) * a;
            out.push(spec::rest_depth_mm((du * du + dv * dv) / r_max2) as f32);
        }
    }
    out
}

/// How far the skin is pushed towards the camera, mm, of a `w x h` map
/// holding `maps` of a frame of aspect `frame_aspect`: a distance map less
/// its rest dome (what shows the tendon in a picture, where the depth
/// itself is mostly the dome's bowl), an indentation map as it is.
pub fn push_mm(
    depth_mm: &[f32],
    maps: DepthMaps,
    (w, h): (usize, usize),
    frame_aspect: f64,
) -> Vec<f32> {
    match maps {
        DepthMaps::Distance => displacement_mm(depth_mm, w, h, frame_aspect),
        DepthMaps::Indentation => depth_mm.to_vec(),
    }
}

/// How far the skin is pushed towards the camera from its rest dome, mm
/// (positive: a ridge or a press), for a `w x h` depth map in mm of a frame
/// of aspect `frame_aspect`: what shows the tendon in a picture, where the
/// depth itself is mostly the dome's bowl.
pub fn displacement_mm(depth_mm: &[f32], w: usize, h: usize, frame_aspect: f64) -> Vec<f32> {
    rest_dome_mm(w, h, frame_aspect)
        .iter()
        .zip(depth_mm)
        .map(|(rest, d)| rest - d)
        .collect()
}

/// Read a depth map (metres on disk) and resize it to `w x h` in mm; any
/// NaN, infinity, wrong dtype or shape is an error naming the file (and the
/// pixel).
pub fn load_depth_mm(path: &std::path::Path, w: usize, h: usize) -> Result<Vec<f32>> {
    let (dw, dh, m) = tactile_core::npy::read_depth_npy(path)?;
    depth_m_to_mm(&m, (dw, dh), w, h).map_err(|e| Error::dataset(path, None, e.to_string()).into())
}

/// A depth map in metres, `dw x dh`, as millimetres at `w x h`.
pub fn depth_m_to_mm(
    m: &[f32],
    (dw, dh): (usize, usize),
    w: usize,
    h: usize,
) -> tactile_preprocess::Result<Vec<f32>> {
    let mm: Vec<f32> = m.iter().map(|v| v * 1000.0).collect();
    tactile_preprocess::resize_area_f32(&mm, (dw, dh), w, h)
}

impl DepthSet {
    /// Load `rows` of a visuo-tactile dataset at `w x h`, each frame's
    /// reconstruction through the calibration in `prior` too when given
    /// (on burn's Flex device, one reconstructor per worker).
    pub fn from_dataset(
        ds: &Dataset,
        rows: &[usize],
        size: [usize; 2],
        prior: Option<&Path>,
    ) -> Result<Self> {
        Self::from_rows(ds, rows, size, prior, None)
    }

    /// [`Self::from_dataset`], a frame that cannot be decoded past its
    /// header left out and counted in `skipped` instead of stopping it.
    pub fn from_dataset_skipping(
        ds: &Dataset,
        rows: &[usize],
        size: [usize; 2],
        prior: Option<&Path>,
        skipped: &mut UndecodableFrames,
    ) -> Result<Self> {
        Self::from_rows(ds, rows, size, prior, Some(skipped))
    }

    /// [`Self::from_dataset`], skipping undecodable frames into `skipped`
    /// when given.
    fn from_rows(
        ds: &Dataset,
        rows: &[usize],
        size: [usize; 2],
        prior: Option<&Path>,
        skipped: Option<&mut UndecodableFrames>,
    ) -> Result<Self> {
        let progress = Self::start_loading(ds, rows.len(), prior)?;
        ds.check_frame_headers(rows)?;
        let set = Self::load_rows(ds, rows, size, prior, &progress, skipped)?;
        progress.finish_and_clear();
        Ok(set)
    }

    /// A training and a validation set of `ds` (`train` and `val` rows),
    /// loaded as [`DepthSet::from_dataset`] loads one, with every frame's
    /// header of both read once before the first frame is decoded: a bad
    /// validation frame is named before the (slow) training frames load.
    pub fn from_splits(
        ds: &Dataset,
        train: &[usize],
        val: &[usize],
        size: [usize; 2],
        prior: Option<&Path>,
    ) -> Result<(Self, Self)> {
        let progress = Self::start_loading(ds, train.len() + val.len(), prior)?;
        ds.check_frame_headers(&[train, val].concat())?;
        let train_set = Self::load_rows(ds, train, size, prior, &progress, None)?;
        let val_set = Self::load_rows(ds, val, size, prior, &progress, None)?;
        progress.finish_and_clear();
        Ok((train_set, val_set))
    }

    /// Every row of `ds` loaded as [`DepthSet::from_dataset`] does, a
    /// chunk of `chunk_rows` rows at a time, each chunk handed to `each` in
    /// order: a dataset of any length in bounded memory. A frame that
    /// cannot be decoded past its header (its pixel data cut short) is left
    /// out of its chunk and counted ([`UndecodableFrames`], the rule of
    /// every reader of frames): the warning naming the first is returned;
    /// when no frame can be decoded the pass fails with the refusal.
    pub fn for_each_chunk(
        ds: &Dataset,
        size: [usize; 2],
        prior: Option<&Path>,
        chunk_rows: usize,
        mut each: impl FnMut(DepthSet) -> Result<()>,
    ) -> Result<Option<String>> {
        let progress = Self::start_loading(ds, ds.len(), prior)?;
        let rows: Vec<usize> = ds.every_row();
        ds.check_frame_headers(&rows)?;
        let mut skipped = UndecodableFrames::new(rows.len());
        let mut given = 0;
        for chunk in rows.chunks(chunk_rows.max(1)) {
            let set = Self::load_rows(ds, chunk, size, prior, &progress, Some(&mut skipped))?;
            // A chunk whose every frame was skipped gives no batch to run.
            if !set.is_empty() {
                given += set.len();
                each(set)?;
            }
        }
        progress.finish_and_clear();
        let warning = skipped.warning();
        skipped.finish(given)?;
        Ok(warning)
    }

    /// Check what every row needs before any is read (the kind of dataset,
    /// the calibration), and the progress bar of `rows` rows.
    fn start_loading(
        ds: &Dataset,
        rows: usize,
        prior: Option<&Path>,
    ) -> Result<tactile_core::progress::ProgressBar> {
        ds.expect_kind(DatasetKind::Visuotactile)?;
        if let Some(dir) = prior {
            // Loaded once here so a bad calibration is named before any work.
            PriorSource::load(dir, Runtime::BurnFlex, 1)?;
            tactile_core::note!(
                "reconstructing {rows} frames through the calibration in {}",
                dir.display()
            );
        }
        Ok(tactile_core::progress::progress_bar(
            rows as u64,
            "loading frames",
        ))
    }

    /// `rows` of `ds` at `w x h`, counted on `progress`; with `skipped`, a
    /// frame that cannot be decoded past its header is counted there and
    /// left out instead of stopping the load.
    fn load_rows(
        ds: &Dataset,
        rows: &[usize],
        [w, h]: [usize; 2],
        prior: Option<&Path>,
        progress: &tactile_core::progress::ProgressBar,
        mut skipped: Option<&mut UndecodableFrames>,
    ) -> Result<Self> {
        // Outer: a frame decoded whose sample cannot be made; inner: a
        // frame that cannot be read, kept apart so it may be skipped.
        type Read = Result<tactile_core::Result<DepthSample>>;
        let read: Vec<Read> = rows
            .par_iter()
            .with_min_len(32)
            .map_init(
                || prior.map(|d| PriorSource::load(d, Runtime::BurnFlex, 1)),
                |source, &i| -> Read {
                    let frame = match ds.load_rgb(i) {
                        Ok(frame) => frame,
                        Err(e) => {
                            progress.inc(1);
                            return Ok(Err(e));
                        }
                    };
                    let prior_mm = match source {
                        Some(Ok(p)) => Some(p.prior_mm(&frame, &ds.path_of(i, "file")?, [w, h])?),
                        Some(Err(e)) => {
                            return Err(tactile_core::Error::Invalid(e.to_string()).into());
                        }
                        None => None,
                    };
                    progress.inc(1);
                    let rgb = crate::prepare::frame_bytes(&frame, [w, h]).map_err(|e| {
                        tactile_core::Error::image(
                            ds.path_of(i, "file").unwrap_or_default(),
                            e.to_string(),
                        )
                    })?;
                    let (dw, dh, m) = ds.load_depth_m(i)?;
                    let depth_mm = depth_m_to_mm(&m, (dw, dh), w, h).map_err(|e| {
                        Error::dataset(
                            ds.path_of(i, "depth").unwrap_or_default(),
                            None,
                            e.to_string(),
                        )
                    })?;
                    let m = ds.load_mask(i)?;
                    let mask = resize_grey(&m, w, h)
                        .map_err(|e| e.in_file(ds.path_of(i, "mask").unwrap_or_default()))?
                        .data
                        .iter()
                        .map(|&v| v >= 0.5)
                        .collect();
                    Ok(Ok(DepthSample {
                        rgb,
                        depth_mm,
                        mask,
                        tendon: ds.number_opt(i, "tendon")? == Some(1.0),
                        press_mm: ds.number_opt(i, "press_mm")?,
                        prior_mm,
                    }))
                },
            )
            .collect();
        // In row order, so the first frame refused is the first named.
        let mut samples = Vec::with_capacity(read.len());
        for r in read {
            samples.extend(UndecodableFrames::decoded_or_stop(
                skipped.as_deref_mut(),
                r?,
            )?);
        }
        Ok(Self {
            width: w,
            height: h,
            samples,
            window: ds.manifest.depth_maps().window(w, h),
            depth_maps: ds.manifest.depth_maps(),
        })
    }

    /// Frames held.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// True when it holds no frame.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Frame `i` as a float image in [0, 1].
    pub fn image(&self, i: usize) -> FloatImage {
        FloatImage::from_bytes(self.width, self.height, 3, &self.samples[i].rgb)
    }

    /// Normalised `C x H x W` inputs of the frames at `idx` for a
    /// network of `model` ([`DepthNetConfig::network_input`]: RGB, plus
    /// the mask or the prior in `scale`'s model units when it takes one),
    /// end to end.
    pub fn inputs(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        model: &DepthNetConfig,
        scale: &DepthScale,
    ) -> Result<Vec<f32>> {
        self.inputs_of(idx, stats, model, scale, None)
    }

    /// [`Self::inputs`], each frame's colour channels changed by `augment`
    /// when given (drawn from its seed, round and the frame's index); the
    /// fourth channel stays as the frame was recorded.
    fn inputs_of(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        model: &DepthNetConfig,
        scale: &DepthScale,
        augment: Option<(&PhotometricAugment, (u64, u64))>,
    ) -> Result<Vec<f32>> {
        let c = model.in_channels;
        let mut x = Vec::with_capacity(idx.len() * c * self.width * self.height);
        for &i in idx {
            let s = &self.samples[i];
            let fourth = match (model.takes_prior(), model.takes_mask(), &s.prior_mm) {
                (true, _, Some(p)) => FourthChannel::Prior(p, *scale),
                (true, _, None) => {
                    return Err(crate::Error::PriorRequired {
                        size: [self.width, self.height],
                    });
                }
                (false, true, _) => FourthChannel::Mask(&s.mask),
                _ => FourthChannel::Nothing,
            };
            let mut img = self.image(i);
            if let Some((a, (seed, round))) = augment {
                a.apply(&mut img, &mut SampleRng::new(seed, round, i as u64));
            }
            x.extend(model.network_input(&img, stats, fourth)?);
        }
        Ok(x)
    }

    /// Inputs `[N, C, H, W]` ([`Self::inputs`]) and targets `[N, 1, H,
    /// W]` in model units.
    pub fn batch(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        scale: &DepthScale,
        model: &DepthNetConfig,
        device: &Device,
    ) -> Result<(Tensor<4>, Tensor<4>)> {
        self.batch_of(idx, stats, scale, model, None, device)
    }

    /// [`Self::batch`] with the frames' colour channels changed by
    /// `augment`, drawn from its `(seed, round)` (the round: the epoch);
    /// the prior or mask channel and the targets as recorded.
    pub fn augmented_batch(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        scale: &DepthScale,
        model: &DepthNetConfig,
        augment: (&PhotometricAugment, (u64, u64)),
        device: &Device,
    ) -> Result<(Tensor<4>, Tensor<4>)> {
        self.batch_of(idx, stats, scale, model, Some(augment), device)
    }

    fn batch_of(
        &self,
        idx: &[usize],
        stats: &ChannelStats,
        scale: &DepthScale,
        model: &DepthNetConfig,
        augment: Option<(&PhotometricAugment, (u64, u64))>,
        device: &Device,
    ) -> Result<(Tensor<4>, Tensor<4>)> {
        let (w, h) = (self.width, self.height);
        let c = model.in_channels;
        let x = self.inputs_of(idx, stats, model, scale, augment)?;
        let mut y = Vec::with_capacity(idx.len() * w * h);
        for &i in idx {
            y.extend(self.samples[i].depth_mm.iter().map(|&d| scale.to_model(d)));
        }
        Ok((
            Tensor::from_data(TensorData::new(x, [idx.len(), c, h, w]), device),
            Tensor::from_data(TensorData::new(y, [idx.len(), 1, h, w]), device),
        ))
    }
}
