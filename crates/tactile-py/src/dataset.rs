//! `tactile.Dataset`: a dataset folder of the documented layout, its
//! labels as arrays and its frames, masks and depth maps read on access.

use std::path::PathBuf;

use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::{PyIndexError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySlice};
use tactile_core::dataset::{Dataset, DatasetKind};
use tactile_core::import::{ImportOptions, import_dataset};

use crate::args::{Given, PathArg, Whole};
use crate::errors::PyResultExt;
use crate::work::interruptible;

/// A dataset folder (`manifest.json`, `labels.csv`, frames and, for
/// visuo-tactile data, masks and depth maps), checked when opened. Labels
/// are read at once; images only when asked for (`ds[i]`, `ds.frame(i)`).
#[pyclass(module = "tactile", name = "Dataset", frozen)]
pub struct PyDataset {
    ds: Dataset,
}

impl PyDataset {
    /// Row `i`, counted from the end when negative, as a list's index:
    /// past either end (however far) an `IndexError`, not an integer a
    /// `TypeError`.
    fn index(&self, i: &Whole) -> PyResult<usize> {
        let n = self.ds.len() as i128;
        let out_of_range = |shown: &dyn std::fmt::Display| {
            PyIndexError::new_err(format!(
                "index {shown} out of range for a dataset of {n} frames"
            ))
        };
        match i {
            Whole::Int(i) => {
                let j = if *i < 0 { i + n } else { *i };
                if !(0..n).contains(&j) {
                    return Err(out_of_range(i));
                }
                Ok(j as usize)
            }
            Whole::Huge(text) => Err(out_of_range(text)),
            Whole::Not(t) => Err(PyTypeError::new_err(format!(
                "dataset indices must be integers or slices, not {t}"
            ))),
        }
    }

    fn has(&self, column: &str) -> bool {
        self.ds.columns.iter().any(|c| c == column)
    }
}

fn array2<T: numpy::Element>(
    py: Python<'_>,
    h: usize,
    w: usize,
    data: Vec<T>,
) -> PyResult<Bound<'_, PyAny>> {
    Ok(ndarray::Array2::from_shape_vec((h, w), data)
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
}

#[pymethods]
impl PyDataset {
    /// Open and check the dataset folder `path`.
    #[new]
    fn new(py: Python<'_>, path: PathArg) -> PyResult<Self> {
        crate::args::keywords!(path);
        let ds = py.detach(move || Dataset::open(&path)).py()?;
        Ok(Self { ds })
    }

    /// `tactile dataset from-video`: the frames of `video` (a video file,
    /// a ROS 2 bag's image topic or a folder of frames) that `labels` (a
    /// CSV with a `frame` column) labels, written as a `kind` dataset
    /// ("tactip" or "visuotactile") into the new folder `out`, then opened.
    #[staticmethod]
    #[pyo3(
        signature = (video, labels, kind, out, *, topic=None, sensor=Given::of("real sensor"), force=Given::of(false)),
        text_signature = "(video, labels, kind, out, *, topic=None, sensor='real sensor', force=False)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn from_video(
        py: Python<'_>,
        video: PathArg,
        labels: PathArg,
        kind: Given<String>,
        out: PathArg,
        topic: Option<Given<String>>,
        sensor: Given<String>,
        force: Given<bool>,
    ) -> PyResult<Self> {
        crate::args::keywords!(video, labels, out, kind, topic, sensor, force);
        let kind = kind.parse::<DatasetKind>().py()?;
        let options = ImportOptions {
            frames: video,
            topic,
            labels,
            kind,
            out,
            sensor,
            force,
        };
        let summary = interruptible(py, || import_dataset(&options).py())?;
        for w in &summary.warnings {
            crate::errors::user_warning(py, w)?;
        }
        let ds = py.detach(move || Dataset::open(&summary.out)).py()?;
        Ok(Self { ds })
    }

    fn __len__(&self) -> usize {
        self.ds.len()
    }

    /// Pickled as its folder (made absolute), opened and checked again
    /// where it is unpickled: a worker process reads the frames itself.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, pyo3::types::PyType>, (PathBuf,))> {
        let root = std::path::absolute(&slf.get().ds.root)?;
        Ok((slf.get_type(), (root,)))
    }

    /// The folder.
    #[getter]
    fn path(&self) -> PathBuf {
        self.ds.root.clone()
    }

    /// The folder, so a dataset is an `os.PathLike`: every function that
    /// takes a dataset's path takes the dataset itself
    /// (`tactile.eval.tactip(model, ds)`), as the folder it was opened from.
    fn __fspath__(&self) -> std::ffi::OsString {
        self.ds.root.clone().into_os_string()
    }

    /// "tactip" or "visuotactile".
    #[getter]
    fn kind(&self) -> &'static str {
        self.ds.manifest.kind.name()
    }

    /// Frame width, pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.ds.manifest.width
    }

    /// Frame height, pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.ds.manifest.height
    }

    /// The columns of labels.csv, in order.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.ds.columns.clone()
    }

    /// manifest.json as a dict.
    #[getter]
    fn manifest<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::json::to_py(py, &self.ds.manifest)
    }

    /// Every column of labels.csv: numbers as float64 arrays (NaN where a
    /// cell is empty), anything else as a list of str (None where empty).
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for col in &self.ds.columns {
            let cells: Vec<Option<&str>> = (0..self.ds.len())
                .map(|i| self.ds.text_opt(i, col))
                .collect();
            let numbers: Option<Vec<f64>> = cells
                .iter()
                .map(|c| match c {
                    None => Some(f64::NAN),
                    Some(s) => s.parse::<f64>().ok(),
                })
                .collect();
            let numeric = numbers.filter(|_| cells.iter().any(Option::is_some));
            match numeric {
                Some(v) => out.set_item(col, PyArray1::from_vec(py, v))?,
                None => out.set_item(col, PyList::new(py, cells)?)?,
            }
        }
        Ok(out)
    }

    /// Frame `i`: `(H, W)` uint8 grey for TacTip data, `(H, W, 3)` uint8
    /// RGB for visuo-tactile data.
    fn frame<'py>(&self, py: Python<'py>, i: Whole) -> PyResult<Bound<'py, PyAny>> {
        let i = self.index(&i)?;
        let (w, h) = (
            self.ds.manifest.width as usize,
            self.ds.manifest.height as usize,
        );
        match self.ds.manifest.kind {
            DatasetKind::Tactip => {
                let img = py.detach(|| self.ds.load_grey(i, "file")).py()?;
                array2(py, h, w, img.into_vec())
            }
            DatasetKind::Visuotactile => {
                let img = py.detach(|| self.ds.load_rgb(i)).py()?;
                crate::image::rgb_array(py, img)
            }
        }
    }

    /// Tendon mask of frame `i`, `(H, W)` bool; None without a mask column
    /// or an empty cell (but for a row without a tendon, whose empty cell
    /// is an empty mask).
    fn mask<'py>(&self, py: Python<'py>, i: Whole) -> PyResult<Option<Bound<'py, PyAny>>> {
        let i = self.index(&i)?;
        if !self.has("mask") || !self.ds.has_mask(i).py()? {
            return Ok(None);
        }
        let img = py.detach(|| self.ds.load_mask(i)).py()?;
        let (w, h) = (img.width(), img.height());
        let bits = img
            .as_slice()
            .iter()
            .map(|&v| v >= tactile_core::image_io::MASK_TENDON_MIN)
            .collect();
        array2(py, h, w, bits).map(Some)
    }

    /// Depth map of frame `i`, `(H, W)` float32 metres; None without a
    /// depth column or an empty cell.
    fn depth_m<'py>(&self, py: Python<'py>, i: Whole) -> PyResult<Option<Bound<'py, PyAny>>> {
        let i = self.index(&i)?;
        if !self.has("depth") || self.ds.text_opt(i, "depth").is_none() {
            return Ok(None);
        }
        let (w, h, d) = py.detach(|| self.ds.load_depth_m(i)).py()?;
        array2(py, h, w, d).map(Some)
    }

    fn __repr__(&self) -> String {
        format!(
            "Dataset('{}', kind='{}', frames={}, size={}x{})",
            self.ds.root.display(),
            self.ds.manifest.kind.name(),
            self.ds.len(),
            self.ds.manifest.width,
            self.ds.manifest.height
        )
    }

    /// Sample `i` as a dict: `frame`, `mask` and `depth_m` where the
    /// dataset has them, and every other label of the row (numbers as
    /// float, empty cells as None; `file` and `depth` stay file names).
    /// A slice (`ds[:100]`, `ds[::10]`, `ds[-5:]`) gives the list of its
    /// samples, as a list's slice does.
    fn __getitem__<'py>(
        &self,
        py: Python<'py>,
        key: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let Ok(slice) = key.cast::<PySlice>() else {
            return Ok(self.sample(py, key.extract::<Whole>()?)?.into_any());
        };
        let len = isize::try_from(self.ds.len())
            .map_err(|_| PyValueError::new_err("a dataset too long to slice"))?;
        let at = slice.indices(len)?;
        let samples = PyList::empty(py);
        let mut i = at.start;
        for _ in 0..at.slicelength {
            samples.append(self.sample(py, Whole::Int(i as i128))?)?;
            i += at.step;
        }
        Ok(samples.into_any())
    }
}

impl PyDataset {
    /// Sample `i` ([`Self::__getitem__`]).
    fn sample<'py>(&self, py: Python<'py>, i: Whole) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        out.set_item("frame", self.frame(py, i.clone())?)?;
        if let Some(m) = self.mask(py, i.clone())? {
            out.set_item("mask", m)?;
        }
        if let Some(d) = self.depth_m(py, i.clone())? {
            out.set_item("depth_m", d)?;
        }
        let j = self.index(&i)?;
        for col in &self.ds.columns {
            // The mask array stands in for its file name.
            if out.contains(col)? {
                continue;
            }
            match self.ds.text_opt(j, col) {
                None => out.set_item(col, py.None())?,
                Some(s) => match s.parse::<f64>() {
                    Ok(v) if !matches!(col.as_str(), "file" | "mask" | "depth") => {
                        out.set_item(col, v)?
                    }
                    _ => out.set_item(col, s)?,
                },
            }
        }
        Ok(out)
    }
}
