//! `tactile.study`: paper A's studies of an encoder, as `tactile compare`,
//! `tactile sweep` and `tactile robustness` run them: each returns its page
//! (`markdown`) with its rows, and with `out=` writes the page (and its
//! rows and plots beside it) as the command's `--out` does.

use std::path::Path;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use tactile_bench::compare::{Compare, CompareResult};
use tactile_bench::robustness::{Robustness, RobustnessResult};
use tactile_bench::sweep::{Sweep, SweepResult};

use crate::args::{PathArg, PathList};
use crate::errors::PyResultExt;
use crate::work::interruptible;

/// A study run off the interpreter (Ctrl-C stops it), its page `out`
/// checked before and written after as the command does
/// ([`tactile_bench::output::with_page`]).
fn study<R: Send>(
    py: Python<'_>,
    (data, out): (&Path, Option<&Path>),
    run: impl FnOnce() -> tactile_bench::Result<R> + Send,
    write: impl FnOnce(&R, &Path) -> tactile_bench::Result<()> + Send,
) -> PyResult<R> {
    interruptible(py, || {
        tactile_bench::output::with_page(data, out, run, write).py()
    })
}

/// Feature sets (the encoder's, PCA, raw pixels, pin tracking) against
/// estimators on one split; `options` are
/// [`tactile_bench::compare::CompareOptions`]'.
#[pyfunction]
#[pyo3(signature = (encoder, data, *, out=None, **options))]
pub(crate) fn study_compare<'py>(
    py: Python<'py>,
    encoder: PathArg,
    data: PathArg,
    out: Option<PathArg>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(encoder, data, out);
    let c = Compare {
        encoder,
        data,
        options: crate::json::options(py, options)?,
    };
    let r = study(
        py,
        (&c.data, out.as_deref()),
        || tactile_bench::compare::compare(&c),
        CompareResult::write,
    )?;
    for w in &r.warnings {
        crate::errors::user_warning(py, w)?;
    }
    let mut v = r.rows();
    v["markdown"] = r.markdown.into();
    crate::json::to_py(py, &v)
}

/// Paper A's feature-count search: each encoder's reconstruction error,
/// shape accuracy and speed; `options` are
/// [`tactile_bench::sweep::SweepOptions`]'.
#[pyfunction]
#[pyo3(signature = (encoders, data, *, out=None, **options))]
pub(crate) fn study_sweep<'py>(
    py: Python<'py>,
    encoders: PathList,
    data: PathArg,
    out: Option<PathArg>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(encoders, data, out);
    if encoders.is_empty() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "encoders: give at least one encoder folder",
        ));
    }
    let s = Sweep {
        encoders,
        data,
        options: crate::json::options(py, options)?,
    };
    let r = study(
        py,
        (&s.data, out.as_deref()),
        || tactile_bench::sweep::sweep(&s),
        SweepResult::write,
    )?;
    crate::json::to_py(py, &r)
}

/// Every estimator's errors on clean frames and on copies with more
/// noise, an illumination gradient, a light blob or a rotation; `options`
/// are [`tactile_bench::robustness::RobustnessOptions`]'.
#[pyfunction]
#[pyo3(signature = (encoder, data, *, out=None, **options))]
pub(crate) fn study_robustness<'py>(
    py: Python<'py>,
    encoder: PathArg,
    data: PathArg,
    out: Option<PathArg>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    crate::args::keywords!(encoder, data, out);
    let r = Robustness {
        encoder,
        data,
        options: crate::json::options(py, options)?,
    };
    let result = study(
        py,
        (&r.data, out.as_deref()),
        || tactile_bench::robustness::robustness(&r),
        RobustnessResult::write,
    )?;
    for w in &result.warnings {
        crate::errors::user_warning(py, w)?;
    }
    crate::json::to_py(py, &result)
}
