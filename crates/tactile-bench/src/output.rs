//! Writing a bench's results: the Markdown table, its plot and its rows as
//! JSON, side by side. A page's files are written together under its
//! folder's lock ([`lock_page`]), so two runs writing one page leave the
//! files of one of them, never a mix.

use std::path::{Path, PathBuf};
use std::time::Duration;

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

/// How long a page's writer waits for another run writing in the same
/// folder: a page is written in seconds, so past this the folder is held
/// by something longer (a model trained into it).
pub const PAGE_PATIENCE: Duration = Duration::from_secs(120);

/// Before a bench runs: its page `out`, its rows (`NAME.json`) and its
/// plot (`NAME.png`) can be written, none is a file of the input
/// `datasets` or of a model (a page `m/pose.md` would put its rows over
/// `m/pose.json`), and the page is none of the others (`--out x.json`
/// would write the page over its own rows), nor in the folder of a model
/// being trained (whose lock the page would wait for, then lose its
/// measurements).
pub fn check_page(out: &Path, datasets: &[&tactile_core::dataset::Dataset]) -> Result<()> {
    let dir = tactile_core::io::folder_of(out);
    if dir.join(tactile_burn::artifact::INCOMPLETE_FILE).is_file() {
        // Held by a training (busy), or not lockable at all (said as is).
        match tactile_core::io::FolderLock::of_existing(dir) {
            Err(tactile_core::Error::Busy { .. }) => {
                return Err(tactile_core::Error::Invalid(format!(
                    "{}: a model is being trained in this folder, which a page's files wait for until the training ends; give the page another folder",
                    dir.display()
                ))
                .into());
            }
            Err(e) => return Err(e.into()),
            Ok(_) => {}
        }
    }
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if matches!(ext, "json" | "png") {
        return Err(tactile_core::Error::Invalid(format!(
            "{}: a page is Markdown, with its rows (NAME.json) and plots (NAME.png) beside it under its own name, so it cannot be named .{ext}; give NAME.md",
            out.display()
        ))
        .into());
    }
    for f in [
        out.to_path_buf(),
        out.with_extension("json"),
        out.with_extension("png"),
    ] {
        tactile_core::dataset::check_output_file(&f, datasets)?;
    }
    Ok(())
}

/// A study that may write a page: `out` checked against the dataset at
/// `data` before `run` ([`check_page`]: its rows and plot beside it too),
/// then written by `write`. The one sequence of `tactile compare|sweep|
/// robustness --out` and Python's `tactile.study.NAME(..., out=)`.
pub fn with_page<R>(
    data: &Path,
    out: Option<&Path>,
    run: impl FnOnce() -> Result<R>,
    write: impl FnOnce(&R, &Path) -> Result<()>,
) -> Result<R> {
    if let Some(out) = out {
        let ds = tactile_core::dataset::Dataset::open(data)?;
        check_page(out, &[&ds])?;
    }
    let r = run()?;
    if let Some(out) = out {
        write(&r, out)?;
    }
    Ok(r)
}

/// The folder of a page locked while its files are written, and a second
/// Ctrl-C held off until they all are.
pub struct PageLock {
    // Dropped in this order: the lock, then the hold (which may end the
    // process, releasing the lock anyway).
    _folder: tactile_core::io::FolderLock,
    _hold: tactile_core::interrupt::Hold,
}

/// Lock the folder of the page `out` while its files are written: a second
/// run writing a page there waits (up to [`PAGE_PATIENCE`]) until the first
/// has written all of its files, then writes all of its own. Once locked, a
/// second Ctrl-C ends the run only after the page's files are all written
/// (the first only asks the run to stop), so they always come from one run.
pub fn lock_page(out: &Path) -> Result<PageLock> {
    let dir = tactile_core::io::folder_of(out);
    tactile_core::io::create_dir_all(dir)?;
    let folder = tactile_core::io::FolderLock::wait(dir, PAGE_PATIENCE)?;
    Ok(PageLock {
        _folder: folder,
        _hold: tactile_core::interrupt::hold(),
    })
}

/// Draws a picture to the path it is given.
type Draw = Box<dyn Fn(&Path) -> Result<()> + Send + Sync>;

/// A picture of a page, drawn when the page is written (under its lock),
/// not while the bench runs.
pub struct Picture {
    path: PathBuf,
    draw: Draw,
}

impl Picture {
    /// The picture `path`, drawn by `draw(path)`.
    pub fn new(path: PathBuf, draw: impl Fn(&Path) -> Result<()> + Send + Sync + 'static) -> Self {
        Self {
            path,
            draw: Box::new(draw),
        }
    }

    /// A line plot ([`line_plot`]) of `series`, linear axes.
    pub fn lines(
        path: PathBuf,
        title: &str,
        x_label: &str,
        y_label: &str,
        series: Vec<Series>,
    ) -> Self {
        let [title, x_label, y_label] = [title, x_label, y_label].map(String::from);
        Self::new(path, move |path| {
            Ok(line_plot(path, &title, &x_label, &y_label, &series, false)?)
        })
    }

    fn draw(&self) -> Result<()> {
        (self.draw)(&self.path)
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
    /// Further pictures the Markdown links, drawn with the page.
    pub pictures: Vec<Picture>,
    /// Markdown after the plot's link.
    pub after_plot: String,
}

impl<M: Serialize> Table<M> {
    /// Write the table, its plot (`NAME.png`), its further pictures and
    /// its rows (`NAME.json`), all under the page's lock; returns the
    /// Markdown with the image linked.
    pub fn write(&self, out: &Path) -> Result<String> {
        let _page = lock_page(out)?;
        for p in &self.pictures {
            p.draw()?;
        }
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
        let md = format!(
            "{}\n![{}]({name})\n{}",
            self.markdown, self.title, self.after_plot
        );
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
/// (`out` with the extension `json`), each atomically, under the page's lock.
pub fn write_markdown_and_json<T: Serialize>(out: &Path, markdown: &str, rows: &T) -> Result<()> {
    let _page = lock_page(out)?;
    markdown_and_json(out, markdown, rows)
}

/// [`write_markdown_and_json`] for a writer that holds the page's lock.
pub(crate) fn markdown_and_json<T: Serialize>(out: &Path, markdown: &str, rows: &T) -> Result<()> {
    tactile_core::io::write_atomic(out, markdown.as_bytes())?;
    tactile_core::io::write_json_atomic(out.with_extension("json"), rows)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A page is refused, before the bench runs, in the folder of a model
    /// being trained (marked and locked); an interrupted training's folder
    /// (marked, not locked) takes it.
    #[test]
    fn a_page_is_refused_in_the_folder_of_a_model_being_trained() {
        let tmp = tempfile::tempdir().unwrap();
        let page = tmp.path().join("page.md");
        let training = tactile_burn::artifact::Unfinished::begin(tmp.path()).unwrap();
        let e = check_page(&page, &[]).err().unwrap().to_string();
        assert!(e.contains("a model is being trained in this folder"), "{e}");
        drop(training);
        assert!(
            tmp.path()
                .join(tactile_burn::artifact::INCOMPLETE_FILE)
                .is_file()
        );
        check_page(&page, &[]).unwrap();
    }

    /// Another run writing a page in the folder holds its lock: this run's
    /// page files (Markdown, JSON and pictures) wait, then appear together.
    #[test]
    fn a_page_waits_for_another_run_writing_in_its_folder_then_writes_all_its_files() {
        let tmp = tempfile::tempdir().unwrap();
        let other = tactile_core::io::FolderLock::acquire(tmp.path()).unwrap();
        let page = tmp.path().join("page.md");
        let table = Table::<u32> {
            markdown: "| model |\n|---|\n".into(),
            title: "error against latency".into(),
            y_label: "error".into(),
            series: vec![Series {
                name: "onnxruntime".into(),
                points: vec![(1.0, 0.5), (2.0, 0.25)],
            }],
            rows: Vec::new(),
            pictures: vec![Picture::new(tmp.path().join("page-extra.png"), |p| {
                Ok(tactile_core::io::write_atomic(p, b"picture")?)
            })],
            after_plot: "after".into(),
        };
        let other_page = tmp.path().join("other.md");
        let (md, plain) = std::thread::scope(|s| {
            let table_run = s.spawn(|| table.write(&page));
            let plain_run = s.spawn(|| write_markdown_and_json(&other_page, "plain", &[1, 2]));
            std::thread::sleep(Duration::from_millis(400));
            let written: Vec<_> = std::fs::read_dir(tmp.path())
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            assert!(
                written.is_empty(),
                "written while another run held the folder: {written:?}"
            );
            drop(other);
            (table_run.join().unwrap(), plain_run.join().unwrap())
        });
        let md = md.unwrap();
        plain.unwrap();
        assert!(
            md.ends_with("![error against latency](page.png)\nafter"),
            "{md}"
        );
        assert_eq!(std::fs::read_to_string(&page).unwrap(), md);
        for f in [
            "page.png",
            "page.json",
            "page-extra.png",
            "other.md",
            "other.json",
        ] {
            assert!(tmp.path().join(f).is_file(), "{f} not written");
        }
    }
}
