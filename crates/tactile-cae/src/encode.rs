//! Encoding pin images to feature vectors, and feature CSV files.

use std::path::Path;

use burn::tensor::Device;
use tactile_core::{Error, Result};

use crate::data::PinSet;
use crate::model::CaeEncoder;

/// Features of every image, `[N][F]`, computed in batches.
pub fn encode_all(
    encoder: &CaeEncoder,
    data: &PinSet,
    batch: usize,
    device: &Device,
) -> Result<Vec<Vec<f32>>> {
    let idx: Vec<usize> = (0..data.len()).collect();
    let mut out = Vec::with_capacity(data.len());
    for chunk in idx.chunks(batch.max(1)) {
        let f = encoder.forward(data.batch(chunk, device));
        let [n, k] = f.dims();
        let v: Vec<f32> = f
            .into_data()
            .try_to_vec::<f32>()
            .map_err(|e| Error::Invalid(format!("cannot read features: {e:?}")))?;
        out.extend((0..n).map(|i| v[i * k..(i + 1) * k].to_vec()));
    }
    Ok(out)
}

/// Write `file,f0,f1,...` rows atomically (the layout of the authors' golden features).
pub fn write_features_csv(
    path: impl AsRef<Path>,
    files: &[String],
    features: &[Vec<f32>],
) -> Result<()> {
    let k = features.first().map_or(0, Vec::len);
    tactile_core::io::write_atomic_with(path, |w| {
        let mut csv = csv::Writer::from_writer(w);
        let mut header = vec!["file".to_string()];
        header.extend((0..k).map(|i| format!("f{i}")));
        csv.write_record(&header)?;
        for (f, v) in files.iter().zip(features) {
            let mut row = vec![f.clone()];
            row.extend(v.iter().map(|x| format!("{x:.6}")));
            csv.write_record(&row)?;
        }
        csv.flush()
    })
}

/// Read a feature CSV: `file` column, then every column named `f<i>`.
pub fn read_features_csv(path: impl AsRef<Path>) -> Result<(Vec<String>, Vec<Vec<f32>>)> {
    let path = path.as_ref();
    let mut r =
        csv::Reader::from_path(path).map_err(|e| Error::dataset(path, None, e.to_string()))?;
    let header = r
        .headers()
        .map_err(|e| Error::dataset(path, Some(1), e.to_string()))?
        .clone();
    let file_col = header
        .iter()
        .position(|h| h == "file")
        .ok_or_else(|| Error::dataset(path, Some(1), "no 'file' column"))?;
    let cols: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with('f') && h[1..].parse::<usize>().is_ok())
        .map(|(i, _)| i)
        .collect();
    if cols.is_empty() {
        return Err(Error::dataset(
            path,
            Some(1),
            "no feature columns f0, f1, ...",
        ));
    }
    let (mut files, mut feats) = (Vec::new(), Vec::new());
    for (i, rec) in r.records().enumerate() {
        let line = i + 2;
        let rec = rec.map_err(|e| Error::dataset(path, Some(line), e.to_string()))?;
        files.push(rec.get(file_col).unwrap_or_default().to_string());
        let v = cols
            .iter()
            .map(|&c| {
                let s = rec.get(c).unwrap_or_default();
                s.parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        Error::dataset(
                            path,
                            Some(line),
                            format!("column '{}': '{s}' is not a finite number", &header[c]),
                        )
                    })
            })
            .collect::<Result<Vec<f32>>>()?;
        feats.push(v);
    }
    Ok((files, feats))
}
