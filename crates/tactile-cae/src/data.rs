//! From a dataset folder to pin-image tensors.

use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::source::UndecodableFrames;
use tactile_preprocess::profile::InputProfile;
use tactile_preprocess::{PinImage, PreprocessConfig, is_flat_frame, preprocess};

use crate::Result;

/// Pin images of a TacTip dataset, in `labels.csv` order.
pub struct PinSet {
    /// Each frame's `file` label.
    pub files: Vec<String>,
    /// Each frame's row in its dataset (empty for pin images of no
    /// dataset): a pass that skips an undecodable frame says which rows
    /// its results are of, for scoring them against their labels.
    pub rows: Vec<usize>,
    /// Each frame's pin image.
    pub images: Vec<PinImage>,
    /// The `file` labels of frames one grey level throughout their crop
    /// ([`tactile_preprocess::is_flat_frame`]: no pins to read), for a
    /// warning.
    pub flat: Vec<String>,
}

/// A frame whose pin image lies outside its model's pin profile
/// ([`PinSet::foreign`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ForeignFrame {
    /// Its `file` label (or a stream frame's label).
    pub file: String,
    /// Its score ([`InputProfile::score_pins`]).
    pub score: f32,
}

impl ForeignFrame {
    /// Those of `pins` (one per frame, through the model's first
    /// preprocessing) that score above `profile`'s threshold, in order,
    /// scored in parallel; a frame is named by `label` of its place, and
    /// those `skip` says (flat frames, told apart by their own warning)
    /// are not scored.
    pub fn among(
        profile: &InputProfile,
        pins: &[PinImage],
        skip: impl Fn(usize) -> bool + Sync,
        label: impl Fn(usize) -> String,
    ) -> Vec<Self> {
        let scores: Vec<Option<f32>> = pins
            .par_iter()
            .enumerate()
            .map(|(i, p)| (!skip(i)).then(|| profile.score_pins(p)))
            .collect();
        scores
            .into_iter()
            .enumerate()
            .filter_map(|(i, s)| {
                s.filter(|&s| s > profile.threshold).map(|score| Self {
                    file: label(i),
                    score,
                })
            })
            .collect()
    }
}

/// Rows of a dataset preprocessed at a time when only their estimates are
/// kept (inference over a whole dataset): 1,024 pin images of 128 px are
/// 64 MiB, where a million rows at once would be 64 GiB.
pub const DATASET_CHUNK: usize = 1024;

/// What a chunked pass over a dataset does with a frame that cannot be
/// decoded past its header ([`PinSet::for_each_chunk_with`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Undecodable {
    /// Stop, naming it: a pass whose outputs are matched to the labels row
    /// by row (scoring, training).
    Stop,
    /// Leave it out with a warning: a pass whose outputs are kept by file
    /// (estimates, features).
    Skip,
}

impl PinSet {
    /// Preprocess every frame of `ds` (in parallel).
    pub fn from_dataset(ds: &Dataset, cfg: &PreprocessConfig) -> Result<Self> {
        Self::from_rows(ds, &ds.every_row(), cfg)
    }

    /// Preprocess the frames of `rows` of `ds` (in parallel, in order),
    /// their headers checked first ([`Dataset::check_frame_headers`]).
    pub fn from_rows(ds: &Dataset, rows: &[usize], cfg: &PreprocessConfig) -> Result<Self> {
        ds.check_frame_headers(rows)?;
        let mut sets = Self::from_rows_each(ds, rows, std::slice::from_ref(cfg))?;
        Ok(sets.remove(0))
    }

    /// [`Self::from_rows`] once per preprocessing of `cfgs` (a multi-scale
    /// model's), each frame read and decoded once.
    pub fn from_rows_each(
        ds: &Dataset,
        rows: &[usize],
        cfgs: &[PreprocessConfig],
    ) -> Result<Vec<Self>> {
        Self::from_rows_each_or_skip(ds, rows, cfgs, None)
    }

    /// [`Self::from_rows_each`]; with `undecodable`, a frame that cannot be
    /// decoded past its header is counted there and left out of the sets
    /// ([`UndecodableFrames::decoded`]) instead of stopping the pass.
    fn from_rows_each_or_skip(
        ds: &Dataset,
        rows: &[usize],
        cfgs: &[PreprocessConfig],
        mut undecodable: Option<&mut UndecodableFrames>,
    ) -> Result<Vec<Self>> {
        ds.expect_kind(DatasetKind::Tactip)?;
        let files: Vec<String> = rows
            .iter()
            .map(|&i| ds.text(i, "file").map(str::to_string))
            .collect::<tactile_core::Result<_>>()?;
        // Outer: a frame decoded that cannot be preprocessed; inner: a
        // frame that cannot be read, kept apart so it may be skipped.
        type Read = Result<tactile_core::Result<(Vec<PinImage>, bool)>>;
        let per_frame: Vec<Read> = rows
            .par_iter()
            .map(|&i| {
                let frame = match ds.load_grey(i, "file") {
                    Ok(frame) => frame,
                    Err(e) => return Ok(Err(e)),
                };
                let path = ds.path_of(i, "file")?;
                let flat = cfgs.first().is_some_and(|c| is_flat_frame(&frame, c));
                let pins = cfgs
                    .iter()
                    .map(|cfg| {
                        preprocess(&frame, cfg).map_err(|e| crate::Error::from(e.in_file(&path)))
                    })
                    .collect::<Result<Vec<_>>>()?;
                Ok(Ok((pins, flat)))
            })
            .collect();
        let mut sets: Vec<Self> = cfgs
            .iter()
            .map(|_| Self {
                files: Vec::with_capacity(rows.len()),
                rows: Vec::with_capacity(rows.len()),
                images: Vec::with_capacity(rows.len()),
                flat: Vec::new(),
            })
            .collect();
        // In row order, so the first frame refused is the first named.
        for ((file, &row), read) in files.into_iter().zip(rows).zip(per_frame) {
            let Some((pins, flat)) =
                UndecodableFrames::decoded_or_stop(undecodable.as_deref_mut(), read?)?
            else {
                continue;
            };
            for (set, pin) in sets.iter_mut().zip(pins) {
                set.images.push(pin);
                set.files.push(file.clone());
                set.rows.push(row);
                if flat {
                    set.flat.push(file.clone());
                }
            }
        }
        Ok(sets)
    }

    /// Every row of `ds` preprocessed once per preprocessing of `cfgs`, a
    /// chunk of `chunk_rows` rows ([`DATASET_CHUNK`] for inference) at a
    /// time, each chunk's sets handed to `each` in order: a dataset of any
    /// length in bounded memory.
    pub fn for_each_chunk<E: From<crate::Error>>(
        ds: &Dataset,
        cfgs: &[PreprocessConfig],
        chunk_rows: usize,
        each: impl FnMut(Vec<Self>) -> std::result::Result<(), E>,
    ) -> std::result::Result<(), E> {
        let rows: Vec<usize> = ds.every_row();
        Self::for_each_chunk_of(ds, &rows, cfgs, chunk_rows, each)
    }

    /// [`Self::for_each_chunk`] over the rows `rows` of `ds` alone.
    pub fn for_each_chunk_of<E: From<crate::Error>>(
        ds: &Dataset,
        rows: &[usize],
        cfgs: &[PreprocessConfig],
        chunk_rows: usize,
        each: impl FnMut(Vec<Self>) -> std::result::Result<(), E>,
    ) -> std::result::Result<(), E> {
        Self::chunks(ds, rows, cfgs, chunk_rows, None, each).map(|_| ())
    }

    /// [`Self::for_each_chunk`] with `undecodable` saying what becomes of
    /// a frame that cannot be decoded past its whole header (its pixel data
    /// cut short). With [`Undecodable::Skip`] it is left out of its chunk
    /// and counted, so the other frames keep their results, as `tactile run`
    /// keeps a folder's: the warning that names the first and counts them
    /// is returned ([`UndecodableFrames::warning`]), and a pass that decodes
    /// no frame fails with the refusal. With [`Undecodable::Stop`] it stops
    /// the pass, as any other error (a file gone, a frame that cannot be
    /// preprocessed) does either way.
    pub fn for_each_chunk_with<E: From<crate::Error>>(
        ds: &Dataset,
        cfgs: &[PreprocessConfig],
        chunk_rows: usize,
        undecodable: Undecodable,
        each: impl FnMut(Vec<Self>) -> std::result::Result<(), E>,
    ) -> std::result::Result<Option<String>, E> {
        let rows: Vec<usize> = ds.every_row();
        if undecodable == Undecodable::Stop {
            return Self::chunks(ds, &rows, cfgs, chunk_rows, None, each).map(|_| None);
        }
        let mut skipped = UndecodableFrames::new(rows.len());
        let given = Self::chunks(ds, &rows, cfgs, chunk_rows, Some(&mut skipped), each)?;
        // Taken before `finish`, which hands the first refusal to the error
        // when no frame was decoded.
        let warning = skipped.warning();
        skipped.finish(given).map_err(crate::Error::from)?;
        Ok(warning)
    }

    /// The chunked pass, skipping undecodable frames into `undecodable`:
    /// the frames given to `each`.
    fn chunks<E: From<crate::Error>>(
        ds: &Dataset,
        rows: &[usize],
        cfgs: &[PreprocessConfig],
        chunk_rows: usize,
        mut undecodable: Option<&mut UndecodableFrames>,
        mut each: impl FnMut(Vec<Self>) -> std::result::Result<(), E>,
    ) -> std::result::Result<usize, E> {
        ds.expect_kind(DatasetKind::Tactip)
            .map_err(crate::Error::from)?;
        ds.check_frame_headers(rows).map_err(crate::Error::from)?;
        let chunk_rows = chunk_rows.max(1);
        // On a terminal, a pass of more than one chunk shows its progress
        // (`predict`, `encode` or `evaluate` over thousands of frames).
        let bar = tactile_core::progress::progress_bar_if(
            rows.len() as u64,
            "frames",
            rows.len() > chunk_rows,
        );
        let mut given = 0;
        for chunk in rows.chunks(chunk_rows) {
            let sets = Self::from_rows_each_or_skip(ds, chunk, cfgs, undecodable.as_deref_mut())?;
            let n = sets.first().map_or(0, Self::len);
            // A chunk whose every frame was skipped gives no batch to run.
            if n > 0 {
                given += n;
                each(sets)?;
            }
            bar.inc(chunk.len() as u64);
        }
        bar.finish_and_clear();
        Ok(given)
    }

    /// Whether each image's frame is flat ([`Self::flat`]), in order.
    pub fn flat_mask(&self) -> Vec<bool> {
        let flat: std::collections::HashSet<&str> = self.flat.iter().map(String::as_str).collect();
        self.files
            .iter()
            .map(|f| flat.contains(f.as_str()))
            .collect()
    }

    /// The frames whose pin images lie outside `profile` (a model's
    /// training pin profile, [`InputProfile::fit_pins`]), in order: a
    /// frame of another sensor, at another scale, or of no pins. Flat
    /// frames are left to their own warning ([`Self::flat`]).
    pub fn foreign(&self, profile: &InputProfile) -> Vec<ForeignFrame> {
        let flat = self.flat_mask();
        ForeignFrame::among(
            profile,
            &self.images,
            |i| flat[i],
            |i| self.files[i].clone(),
        )
    }

    /// Pin images alone (perturbed or live frames), without file names.
    pub fn from_images(images: Vec<PinImage>) -> Self {
        Self {
            files: Vec::new(),
            rows: Vec::new(),
            images,
            flat: Vec::new(),
        }
    }

    /// Number of images.
    pub fn len(&self) -> usize {
        self.images.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }

    /// A `[N, 1, S, S]` batch of the images at `idx`.
    pub fn batch(&self, idx: &[usize], device: &Device) -> Tensor<4> {
        batch_tensor(idx.iter().map(|&i| &self.images[i]), device)
    }
}

/// Stack pin images into a `[N, 1, S, S]` tensor.
pub fn batch_tensor<'a>(images: impl Iterator<Item = &'a PinImage>, device: &Device) -> Tensor<4> {
    let mut data = Vec::new();
    let mut n = 0;
    let mut side = 0;
    for img in images {
        side = img.side;
        data.extend_from_slice(&img.pixels);
        n += 1;
    }
    Tensor::from_data(TensorData::new(data, [n, 1, side, side]), device)
}
