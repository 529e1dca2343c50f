//! A trained encoder at work: frames to pin images to feature vectors, on
//! any runtime, in batches. The commands, the Python package, the benches
//! and paper A's perception all encode through [`TactipEncoder`].

use std::path::Path;

use tactile_burn::{Network, Runtime};
use tactile_core::dataset::Dataset;
use tactile_core::image_io::GreyImage;
use tactile_preprocess::PinImage;
use tactile_preprocess::profile::InputProfile;

use crate::artifact::CaeArtifact;
use crate::data::{DATASET_CHUNK, PinSet, Undecodable};
use crate::{Error, Result};

/// Pin images per network call.
pub const ENCODE_BATCH: usize = 256;

/// A loaded encoder with its preprocessing.
pub struct TactipEncoder {
    /// Architecture and preprocessing.
    pub artifact: CaeArtifact,
    net: Box<dyn Network>,
}

impl TactipEncoder {
    /// Load the model in `dir` onto `runtime` (`threads` intra-op threads
    /// for onnxruntime).
    pub fn load(dir: impl AsRef<Path>, runtime: Runtime, threads: usize) -> Result<Self> {
        let (artifact, net) =
            tactile_onnx::load_network::<CaeArtifact>(dir.as_ref(), runtime, threads)?;
        Ok(Self { artifact, net })
    }

    /// An encoder from a config and a network already built.
    pub fn from_network(artifact: CaeArtifact, net: Box<dyn Network>) -> Self {
        Self { artifact, net }
    }

    /// Features per frame.
    pub fn feature_count(&self) -> usize {
        self.artifact.model.feature_count()
    }

    /// Where it runs.
    pub fn runtime(&self) -> Runtime {
        self.net.runtime()
    }

    /// A raw greyscale frame as the pin image this encoder reads.
    pub fn preprocess(&self, frame: &GreyImage) -> Result<PinImage> {
        Ok(tactile_preprocess::preprocess(
            frame,
            &self.artifact.preprocess,
        )?)
    }

    /// Features of pin images, `[N][F]`, in batches of [`ENCODE_BATCH`].
    pub fn encode(&mut self, pins: &[PinImage]) -> Result<Vec<Vec<f32>>> {
        let side = self.artifact.model.input_px;
        let k = self.feature_count();
        let mut out = Vec::with_capacity(pins.len());
        for chunk in pins.chunks(ENCODE_BATCH) {
            let mut x = Vec::with_capacity(chunk.len() * side * side);
            for p in chunk {
                if p.side != side {
                    return Err(tactile_core::Error::shape(
                        "pin image",
                        format!("{side}x{side}"),
                        format!("{0}x{0}", p.side),
                    )
                    .into());
                }
                x.extend_from_slice(&p.pixels);
            }
            let v = self.net.run([chunk.len(), 1, side, side], x)?;
            out.extend(v.chunks(k).map(<[f32]>::to_vec));
        }
        Ok(out)
    }

    /// Preprocess and encode every frame of a TacTip dataset, a chunk at a
    /// time ([`PinSet::for_each_chunk`]): each row's `file` label and
    /// features. A frame that cannot be decoded stops it: its features
    /// are kept row by row against the labels.
    pub fn encode_dataset(&mut self, ds: &Dataset) -> Result<(Vec<String>, Vec<Vec<f32>>)> {
        // Only the features are wanted: no frame is scored against the
        // encoder's pin profile.
        let e = self.encode_rows(ds, None, Undecodable::Stop)?;
        Ok((e.files, e.features))
    }

    /// [`Self::encode_dataset`], also giving the `file` labels of frames
    /// one grey level throughout their crop ([`PinSet::flat`]) and of
    /// frames unlike its training frames ([`PinSet::foreign`]); a frame
    /// that cannot be decoded past its header is left out and named in
    /// [`EncodedDataset::undecodable`], so the others keep their features
    /// ([`PinSet::for_each_chunk_with`]).
    pub fn encode_dataset_flagging(&mut self, ds: &Dataset) -> Result<EncodedDataset> {
        let profile = self.artifact.input_profile.clone();
        self.encode_rows(ds, profile.as_ref(), Undecodable::Skip)
    }

    /// Every row of `ds` encoded, its frames outside `profile` listed, its
    /// undecodable frames stopping the pass or skipped as `undecodable` says.
    fn encode_rows(
        &mut self,
        ds: &Dataset,
        profile: Option<&InputProfile>,
        undecodable: Undecodable,
    ) -> Result<EncodedDataset> {
        let cfg = self.artifact.preprocess.clone();
        let mut e = EncodedDataset {
            files: Vec::with_capacity(ds.len()),
            rows: Vec::with_capacity(ds.len()),
            features: Vec::with_capacity(ds.len()),
            flat: Vec::new(),
            foreign: Vec::new(),
            undecodable: None,
        };
        let cfgs = std::slice::from_ref(&cfg);
        let each = |mut sets: Vec<PinSet>| {
            let set = sets.swap_remove(0);
            e.features.extend(self.encode(&set.images)?);
            if let Some(p) = profile {
                e.foreign.extend(set.foreign(p));
            }
            e.files.extend(set.files);
            e.rows.extend(set.rows);
            e.flat.extend(set.flat);
            Ok::<(), Error>(())
        };
        // `each` holds `e` until the pass ends.
        let skipped = PinSet::for_each_chunk_with(ds, cfgs, DATASET_CHUNK, undecodable, each)?;
        e.undecodable = skipped;
        Ok(e)
    }
}

/// A dataset's features ([`TactipEncoder::encode_dataset_flagging`]).
pub struct EncodedDataset {
    /// Each row's `file` label (an undecodable frame's row left out).
    pub files: Vec<String>,
    /// Each of those rows' place in the dataset ([`PinSet::rows`]), for
    /// scoring the features against their labels.
    pub rows: Vec<usize>,
    /// Each row's features.
    pub features: Vec<Vec<f32>>,
    /// The `file` labels of frames one grey level throughout their crop.
    pub flat: Vec<String>,
    /// The frames unlike the encoder's training frames
    /// ([`PinSet::foreign`]; none when it has no pin profile).
    pub foreign: Vec<crate::data::ForeignFrame>,
    /// The warning naming the first frame that could not be decoded past
    /// its header and counting them, when any was left out.
    pub undecodable: Option<String>,
}

/// Write `file,f0,f1,...` rows atomically (the layout of the authors'
/// golden features). Each value is the shortest decimal that reads back as
/// the same `f32`, so features survive the file bit for bit.
pub fn write_features_csv(
    path: impl AsRef<Path>,
    files: &[String],
    features: &[Vec<f32>],
) -> Result<()> {
    let k = features.first().map_or(0, Vec::len);
    Ok(tactile_core::io::write_atomic_with(path, |w| {
        let mut csv = csv::Writer::from_writer(w);
        let mut header = vec!["file".to_string()];
        header.extend((0..k).map(|i| format!("f{i}")));
        csv.write_record(&header)?;
        for (f, v) in files.iter().zip(features) {
            let mut row = vec![f.clone()];
            row.extend(v.iter().map(|x| x.to_string()));
            csv.write_record(&row)?;
        }
        csv.flush()
    })?)
}

/// Read a feature CSV: `file` column, then every column named `f<i>`.
pub fn read_features_csv(path: impl AsRef<Path>) -> Result<(Vec<String>, Vec<Vec<f32>>)> {
    use tactile_core::Error as E;
    let path = path.as_ref();
    let file = tactile_core::io::open_regular(path)?;
    let mut r = tactile_core::csv_lines::reader(&csv::ReaderBuilder::new(), file);
    let header = r
        .headers()
        .map_err(|e| E::dataset(path, Some(1), e.to_string()))?
        .clone();
    let file_col = header.iter().position(|h| h == "file").ok_or_else(|| {
        let hint = tactile_core::csv_lines::separator_hint(header.iter());
        E::dataset(path, Some(1), format!("no 'file' column{hint}"))
    })?;
    let cols: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with('f') && h[1..].parse::<usize>().is_ok())
        .map(|(i, _)| i)
        .collect();
    if cols.is_empty() {
        return Err(E::dataset(path, Some(1), "no feature columns f0, f1, ...").into());
    }
    let (mut files, mut feats) = (Vec::new(), Vec::new());
    for item in tactile_core::csv_lines::records(&mut r) {
        let (line, rec) = item.map_err(|(line, why)| E::dataset(path, Some(line), why))?;
        files.push(rec.get(file_col).unwrap_or_default().to_string());
        let v = cols
            .iter()
            .map(|&c| {
                let s = rec.get(c).unwrap_or_default();
                s.parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        E::dataset(
                            path,
                            Some(line),
                            format!("column '{}': '{s}' is not a finite number", &header[c]),
                        )
                    })
            })
            .collect::<tactile_core::Result<Vec<f32>>>()?;
        feats.push(v);
    }
    Ok((files, feats))
}

/// The rows of a feature CSV in the order of `ds`'s rows, matched by
/// `file`; a frame without a row is an error naming it and its line.
pub fn features_for_dataset(csv: &Path, ds: &Dataset) -> Result<Vec<Vec<f32>>> {
    let (files, feats) = read_features_csv(csv)?;
    let by_file: std::collections::HashMap<&str, &Vec<f32>> =
        files.iter().map(String::as_str).zip(&feats).collect();
    (0..ds.len())
        .map(|i| {
            let file = ds.text(i, "file")?;
            by_file.get(file).map(|v| (*v).clone()).ok_or_else(|| {
                Error::Core(tactile_core::Error::dataset(
                    csv,
                    None,
                    format!(
                        "no feature row for '{file}' (labels.csv line {})",
                        ds.rows[i].line
                    ),
                ))
            })
        })
        .collect()
}
