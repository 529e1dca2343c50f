//! Writing a bench's results: the Markdown table, its plot and its rows as
//! JSON, side by side.

use std::path::Path;

use serde::Serialize;
use tactile_core::plot::{Series, line_plot};

use crate::Result;
use crate::latency::RuntimeMs;

/// One model's row for the JSON beside a table: its error metrics and the
/// median milliseconds per runtime.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow<M> {
    /// The model folder's name.
    pub model: String,
    /// Its errors.
    pub metrics: M,
    /// Its latency per runtime.
    pub ms: RuntimeMs,
}

impl<M> BenchRow<M> {
    /// The row of the model in `dir`.
    pub fn new(dir: &Path, metrics: M, ms: RuntimeMs) -> Self {
        Self {
            model: folder_name(dir),
            metrics,
            ms,
        }
    }
}

/// The last component of `dir`.
pub fn folder_name(dir: &Path) -> String {
    dir.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
}

/// Add one point per runtime (x = ms, y = `error`) to the per-runtime series.
pub fn add_points(series: &mut Vec<Series>, ms: &RuntimeMs, error: f64) {
    for (name, v) in ms.named() {
        let Some(v) = v else { continue };
        match series.iter_mut().find(|s| s.name == name) {
            Some(s) => s.points.push((v, error)),
            None => series.push(Series {
                name: name.to_string(),
                points: vec![(v, error)],
            }),
        }
    }
}

/// A bench's table with its plot: written as `out`, `out.png` and `out.json`.
pub struct Table<M> {
    /// The Markdown, without the image link.
    pub markdown: String,
    /// Plot title.
    pub title: String,
    /// Its y axis.
    pub y_label: String,
    /// Error against latency, per runtime.
    pub series: Vec<Series>,
    /// The rows.
    pub rows: Vec<BenchRow<M>>,
}

impl<M: Serialize> Table<M> {
    /// Write the table, its plot (`NAME.png`) and its rows (`NAME.json`);
    /// returns the Markdown with the image linked.
    pub fn write(&self, out: &Path) -> Result<String> {
        tactile_core::io::write_json_atomic(out.with_extension("json"), &self.rows)?;
        let png = out.with_extension("png");
        line_plot(
            &png,
            &self.title,
            "latency, batch 1 (ms)",
            &self.y_label,
            &self.series,
            false,
        )?;
        let name = png.file_name().unwrap_or_default().to_string_lossy();
        let md = format!("{}\n![{}]({name})\n", self.markdown, self.title);
        tactile_core::io::write_atomic(out, md.as_bytes())?;
        Ok(md)
    }
}

/// The header line of a model bench: machine, threads, method, data.
pub fn header(what: &str, data: &Path, runs: usize) -> String {
    let threads = crate::latency::threads();
    format!(
        "Machine: {}. Threads: burn devices use rayon over {threads} cores; onnxruntime {threads} intra-op threads. \
         Latency: median of {runs} runs at batch 1, inference only (loading and resizing excluded). \
         {what} on {} (held out: never used in training or in any choice).\n\n",
        tactile_core::bench::Machine::detect().describe(),
        data.display()
    )
}

/// A picture of the page `out` written beside it: its path and the name the
/// page links it by (`NAME-suffix.png` for the page `NAME.md`).
pub fn picture_beside(out: &Path, suffix: &str) -> (std::path::PathBuf, String) {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let name = format!("{stem}-{suffix}.png");
    (out.parent().unwrap_or(Path::new(".")).join(&name), name)
}

/// Write a bench's Markdown to `out` and its rows as JSON beside it
/// (`out` with the extension `json`), each atomically.
pub fn write_markdown_and_json<T: Serialize>(out: &Path, markdown: &str, rows: &T) -> Result<()> {
    tactile_core::io::write_atomic(out, markdown.as_bytes())?;
    tactile_core::io::write_json_atomic(out.with_extension("json"), rows)?;
    Ok(())
}
