//! Atomic file output: every file is written to a temporary file in the
//! target folder and renamed into place, so an interrupted or failed write
//! never leaves a half-written output behind.

use std::io::Write;
use std::path::Path;

use crate::{Error, Result};

/// Write `bytes` to `path` atomically (its folder is created if needed).
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Write to `path` atomically through a writer callback.
pub fn write_atomic_with<F>(path: impl AsRef<Path>, write: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let path = path.as_ref();
    let mut tmp = temp_beside(path)?;
    {
        let mut buf = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut buf).map_err(|e| Error::io(path, e))?;
        buf.flush().map_err(|e| Error::io(path, e))?;
    }
    persist_temp(tmp, path)
}

/// Where an output named `path` is written: `path` itself when nothing or
/// a regular file is there; the file a symbolic link there names (so the
/// link stays and the file it points at is replaced, as a shell's `>`
/// does). Anything else is refused, naming it: a pipe, a device (such as
/// `/dev/stdout`, a link to one) or a socket would be replaced by the
/// renamed temporary file, not written into.
pub fn output_path(path: &Path) -> Result<std::path::PathBuf> {
    // `--out -` means standard output to the commands that stream there
    // (they never ask here); to any other it would be a file named `-`.
    if path == Path::new("-") {
        return Err(Error::Invalid(
            "-: this output cannot go to standard output; give a file name (`predict` and `run` stream their records there with `--out -`)".into(),
        ));
    }
    if path.as_os_str().is_empty() {
        return Err(Error::Invalid(format!(
            "{}: give a file name for this output",
            crate::error::shown(path)
        )));
    }
    let target = through_links(path)?;
    match std::fs::metadata(&target) {
        // Nothing there yet (or a link to nothing yet: the file it names).
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(target),
        Err(e) => Err(Error::io(path, e)),
        Ok(m) if m.is_file() => Ok(target),
        Ok(m) if m.is_dir() => Err(Error::Invalid(format!(
            "{}: is a folder; give a file name for this output",
            path.display()
        ))),
        Ok(_) => Err(Error::Invalid(format!(
            "{}: is a pipe, a device or a socket, not a file: an output is written beside its place and renamed into it, which would replace it; give a file name (commands that stream to standard output take `--out -`)",
            path.display()
        ))),
    }
}

/// Entries of a folder looked at to tell whether it holds a model
/// ([`refuse_model_file`]); a model folder holds a handful.
const MAX_MODEL_FOLDER_ENTRIES: usize = 10_000;

/// The rest frame a calibrated sensor's model folder holds and loads
/// (`tactile_gelsight::artifact::BACKGROUND_FILE` is this), which outputs never replace.
pub const MODEL_BACKGROUND_FILE: &str = "background.png";

/// Refuse an output `out` (written at `target`, [`output_path`]) that
/// would replace a file a model is loaded from: weights (`*.bpk`) anywhere,
/// and a config or notes (`*.json`) or a calibrated sensor's rest frame
/// ([`MODEL_BACKGROUND_FILE`]) in a folder that holds a model
/// ([`model_configs`]: a `NAME.json` with its `NAME.bpk`, or an
/// `ensemble.json`). `predict --out m/pose.json` would otherwise
/// write estimates over the model's config, a bench page
/// `m/pose.md` its rows over it (`m/pose.json`), and a page
/// `m/background.md` its plot over the sensor's rest frame. Its other
/// files (curves, plots, exports) and new files may be written.
pub fn refuse_model_file(out: &Path, target: &Path) -> Result<()> {
    let ext = target.extension().and_then(|e| e.to_str()).unwrap_or("");
    let background = target.file_name() == Some(std::ffi::OsStr::new(MODEL_BACKGROUND_FILE));
    if !(matches!(ext, "json" | "bpk") || background) || !target.is_file() {
        return Ok(());
    }
    let dir = folder_of(target);
    if ext == "bpk" || !model_configs(dir).is_empty() {
        return Err(Error::Invalid(format!(
            "{}: is a file of the model in {} (its config, notes, weights or rest frame); writing this output over it would break the model, so nothing was done: give another file name",
            out.display(),
            dir.display()
        )));
    }
    Ok(())
}

/// The configs of the models the folder `dir` holds: each `NAME.json` with
/// its weights `NAME.bpk` beside it, and an `ensemble.json` (sorted; empty
/// for a folder that holds no model, or none at all).
pub fn model_configs(dir: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut configs: Vec<String> = entries
        .take(MAX_MODEL_FOLDER_ENTRIES)
        .flatten()
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|name| {
            name == "ensemble.json"
                || name
                    .strip_suffix(".json")
                    .is_some_and(|stem| dir.join(format!("{stem}.bpk")).is_file())
        })
        .collect();
    configs.sort();
    configs
}

/// Before a model whose config is `config` (`detector.json`) is trained
/// into the folder `dir`: refuse a folder that holds a model of another
/// kind ([`model_configs`]), whose notes and curves the run would replace,
/// leaving two models in one folder. A model of the same kind is trained
/// again, as asked.
pub fn refuse_other_model(dir: &Path, config: &str) -> Result<()> {
    let others: Vec<String> = model_configs(dir)
        .into_iter()
        .filter(|c| c != config)
        .collect();
    if others.is_empty() {
        return Ok(());
    }
    Err(Error::Invalid(format!(
        "{}: holds another model ({}); training a model with {config} into it would replace that model's notes and curves and leave two models in one folder, so nothing was done: give another output folder",
        dir.display(),
        others.join(", ")
    )))
}

/// Symbolic links followed in one path before it counts as a loop (as
/// Linux's own limit): for outputs here and for a dataset's files
/// ([`crate::dataset::resolve_inside`]).
pub const MAX_LINKS: usize = 40;

/// The path that `path` names once its symbolic links are followed (each
/// relative one from its own folder), the last link's target even when
/// nothing is there yet; `path` itself when it is no link. An output
/// renamed into place lands there, replacing no link.
pub fn through_links(path: &Path) -> Result<std::path::PathBuf> {
    let mut here = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&here) {
            Ok(m) if m.file_type().is_symlink() => {
                let named = std::fs::read_link(&here).map_err(|e| Error::io(path, e))?;
                // An absolute target replaces the folder it is joined to.
                here = here.parent().unwrap_or(Path::new("")).join(named);
            }
            _ => return Ok(here),
        }
    }
    Err(Error::Invalid(format!(
        "{}: too many levels of symbolic links",
        path.display()
    )))
}

/// A temporary file in the folder of `path`'s [`output_path`] (created if
/// needed) that [`persist_temp`] moves there; dropped before that, it
/// leaves nothing.
pub fn temp_beside(path: impl AsRef<Path>) -> Result<tempfile::NamedTempFile> {
    let target = output_path(path.as_ref())?;
    let path = target.as_path();
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(path, e))?;
    tempfile::Builder::new()
        .prefix(".tactile-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| Error::io(path, e))
}

/// Move a finished [`temp_beside`] file to `path` (its [`output_path`],
/// looked at again: nothing but a file is ever replaced).
pub fn persist_temp(tmp: tempfile::NamedTempFile, path: impl AsRef<Path>) -> Result<()> {
    let target = output_path(path.as_ref())?;
    let path = target.as_path();
    // Temporary files are private (0600); a finished output is an ordinary file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| Error::io(path, e))?;
    }
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// A file written bit by bit (records of a long run) that appears at its
/// path only when [`AtomicFile::commit`] is called; dropped before that,
/// it leaves nothing.
pub struct AtomicFile {
    path: std::path::PathBuf,
    out: std::io::BufWriter<tempfile::NamedTempFile>,
}

impl AtomicFile {
    /// Start writing what will become `path` (its folder is created).
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        Ok(Self {
            path: path.to_path_buf(),
            out: std::io::BufWriter::new(temp_beside(path)?),
        })
    }

    /// Where the finished file goes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Write one line.
    pub fn write_line(&mut self, line: &str) -> Result<()> {
        writeln!(self.out, "{line}").map_err(|e| Error::io(&self.path, e))
    }

    /// Move the finished file into place.
    pub fn commit(self) -> Result<()> {
        let path = self.path;
        let tmp = self
            .out
            .into_inner()
            .map_err(|e| Error::io(&path, e.into_error()))?;
        persist_temp(tmp, &path)
    }
}

/// Write `value` as pretty JSON to `path` atomically.
pub fn write_json_atomic<T: serde::Serialize>(path: impl AsRef<Path>, value: &T) -> Result<()> {
    let path = path.as_ref();
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Invalid(format!("{}: cannot serialise JSON: {e}", path.display())))?;
    write_atomic(path, text.as_bytes())
}

/// Largest JSON file [`read_json`] reads: far above any manifest, config
/// or model description, far below what would exhaust memory (a sparse
/// file can claim terabytes).
pub const MAX_JSON_BYTES: u64 = 64 << 20;

/// `dir` is a folder (`what`: "dataset folder", "model folder"): a path
/// that does not exist is [`Error::not_found`], a file (or a pipe) is a
/// folder of the wrong kind ("not a model folder (a file)").
pub fn expect_folder(dir: &Path, what: &str) -> Result<()> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(m) if m.is_file() => Err(Error::wrong_kind(dir, what, "a file")),
        Ok(_) => Err(Error::wrong_kind(dir, what, "a pipe, a device or a socket")),
        Err(_) => Err(Error::not_found(dir, what)),
    }
}

/// Read and parse a JSON file of at most [`MAX_JSON_BYTES`], naming the
/// file on error.
pub fn read_json<T: serde::de::DeserializeOwned>(path: impl AsRef<Path>) -> Result<T> {
    read_json_limited(path, MAX_JSON_BYTES)
}

/// Largest weights file read (burn records, safetensors): a network of
/// 100 million float32 parameters, the most any model folder may hold, is
/// 400 MB.
pub const MAX_WEIGHTS_BYTES: u64 = 1 << 30;

/// Refuse `path` when it holds more than `max_bytes`, naming it; checked
/// on its size, before anything is read.
pub fn check_file_size(path: &Path, max_bytes: u64) -> Result<()> {
    let len = expect_regular(path)?.len();
    if len > max_bytes {
        return Err(too_large(path, len, max_bytes));
    }
    Ok(())
}

fn too_large(path: &Path, len: u64, max_bytes: u64) -> Error {
    Error::Invalid(format!(
        "{}: {len} bytes is too large (at most {max_bytes})",
        path.display()
    ))
}

/// Refuse anything but a regular file (after links), naming it, before it
/// is opened: opening a pipe blocks until something writes to it, and a
/// device never ends, so a `labels.csv`, a config or a weights file that is
/// one would hang the reader instead of failing. Its metadata, for its size.
pub fn expect_regular(path: &Path) -> Result<std::fs::Metadata> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::NotRegularFile {
            path: path.to_path_buf(),
        });
    }
    Ok(meta)
}

/// `path` opened for reading once [`expect_regular`] passes it: the one
/// way the toolkit opens a file a user or a model folder names.
pub fn open_regular(path: &Path) -> Result<std::fs::File> {
    expect_regular(path)?;
    std::fs::File::open(path).map_err(|e| Error::io(path, e))
}

/// The bytes of `path`, a file of at most `max_bytes`, naming the file
/// when it is larger. The size is checked before the file is read, and the
/// read stops past the limit, so a file that grows while it is read is
/// bounded too; a pipe or a device is refused unopened ([`open_regular`]).
pub fn read_limited(path: impl AsRef<Path>, max_bytes: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    let path = path.as_ref();
    let file = open_regular(path)?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    if len > max_bytes {
        return Err(too_large(path, len, max_bytes));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(max_bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(path, bytes.len() as u64, max_bytes));
    }
    Ok(bytes)
}

/// The UTF-8 text of `path`, a file of at most [`MAX_JSON_BYTES`]
/// ([`read_limited`]), naming it when it is not text.
pub fn read_text(path: impl AsRef<Path>) -> Result<String> {
    let path = path.as_ref();
    String::from_utf8(read_limited(path, MAX_JSON_BYTES)?).map_err(|e| {
        Error::dataset(
            path,
            None,
            format!("not UTF-8 text: {e}{}", utf16_hint(e.as_bytes())),
        )
    })
}

/// [`read_json`] of a file of at most `max_bytes` ([`read_limited`]).
pub fn read_json_limited<T: serde::de::DeserializeOwned>(
    path: impl AsRef<Path>,
    max_bytes: u64,
) -> Result<T> {
    let path = path.as_ref();
    let bytes = read_limited(path, max_bytes)?;
    serde_json::from_slice(without_byte_order_mark(&bytes))
        .map_err(|e| Error::dataset(path, Some(e.line()), format!("{e}{}", utf16_hint(&bytes))))
}

/// Text without its leading UTF-8 byte order mark, as Windows' Notepad
/// and Excel ("CSV UTF-8") save one: serde_json refuses it as a value (the
/// CSV reader passes over it by itself).
pub fn without_byte_order_mark(text: &[u8]) -> &[u8] {
    text.strip_prefix(b"\xef\xbb\xbf").unwrap_or(text)
}

/// What to add to the error about a file whose text begins with `start`,
/// when that is a UTF-16 byte order mark (Excel's "Unicode Text",
/// Notepad's "UTF-16"): how to save it as UTF-8. Empty otherwise.
pub fn utf16_hint(start: &[u8]) -> &'static str {
    match start.get(..2) {
        Some([0xff, 0xfe] | [0xfe, 0xff]) => {
            " (it is UTF-16 text, as Excel's \"Unicode Text\" saves it: save it as \"CSV UTF-8\", or JSON as UTF-8)"
        }
        _ => "",
    }
}

/// Create a folder (and parents), naming it on error.
pub fn create_dir_all(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    std::fs::create_dir_all(path).map_err(|e| Error::io(path, e))
}

/// Prove a file can be written in `dir` (a temporary file, removed at
/// once), so a command fails before its work, naming the folder, instead
/// of after it. A folder that does not exist yet is not created: its
/// nearest existing ancestor is probed instead, so a failed command leaves
/// no empty folder behind.
pub fn ensure_writable_dir(dir: impl AsRef<Path>) -> Result<()> {
    let dir = dir.as_ref();
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let probe = dir
        .ancestors()
        .find(|a| a.is_dir() || a.as_os_str().is_empty())
        .map(|a| {
            if a.as_os_str().is_empty() {
                Path::new(".")
            } else {
                a
            }
        })
        .unwrap_or(Path::new("."));
    let refuse = |why: String| {
        Error::Invalid(format!(
            "{}: cannot write in this folder ({why})",
            dir.display()
        ))
    };
    if dir.exists() && !dir.is_dir() {
        return Err(refuse(
            "it is a file, a pipe or a device, not a folder".into(),
        ));
    }
    tempfile::Builder::new()
        .prefix(".tactile-probe-")
        .tempfile_in(probe)
        .map(drop)
        .map_err(|e| refuse(e.kind().to_string()))
}

/// Every warning of a scoring the front ends show, each starting
/// "warning: ": what reading the frames found (`frame_warnings`, already
/// so worded), then that the model trained on them (`fitted`, the words
/// alone).
pub fn scoring_warnings(frame_warnings: &[String], fitted: &Option<String>) -> Vec<String> {
    let fitted = fitted.iter().map(|w| format!("warning: {w}"));
    frame_warnings.iter().cloned().chain(fitted).collect()
}

/// A result record as both front ends print it: `model` and `data`, then
/// every field of the library's `result` (serialised as it is, never picked
/// field by field, so a new score reaches the command line and Python at
/// once).
pub fn scored_record(
    model: &Path,
    data: &Path,
    result: &impl serde::Serialize,
) -> Result<serde_json::Value> {
    let mut v = serde_json::json!({ "model": model, "data": data });
    let r = serde_json::to_value(result).map_err(|e| Error::Invalid(e.to_string()))?;
    match (v.as_object_mut(), r) {
        (Some(m), serde_json::Value::Object(r)) => m.extend(r),
        (Some(m), other) => {
            m.insert("result".into(), other);
        }
        _ => {}
    }
    Ok(v)
}

/// The folder the file `path` is in: its parent, or "." for a bare name
/// (whose parent is the empty path) and for a root.
pub fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// [`ensure_writable_dir`] for the folder an output file will go into.
pub fn ensure_writable_parent(file: impl AsRef<Path>) -> Result<()> {
    ensure_writable_dir(folder_of(file.as_ref()))
}

/// A folder locked for one run writing into it (`flock` on the folder): a
/// second run into the same folder is refused, or waits, instead of mixing
/// its files with the first's. The system releases it when the process
/// ends, however it ends, so a killed run never blocks the next.
pub struct FolderLock {
    _held: std::fs::File,
}

impl FolderLock {
    /// Lock the folder `dir`; refused ([`Error::Busy`]) while another run
    /// holds it.
    pub fn acquire(dir: &Path) -> Result<Self> {
        Self::wait(dir, std::time::Duration::ZERO)
    }

    /// [`Self::acquire`] of `dir`, created first if needed: the folder a
    /// run is about to write a model into.
    pub fn creating(dir: &Path) -> Result<Self> {
        create_dir_all(dir)?;
        Self::acquire(dir)
    }

    /// [`Self::acquire`] of `dir` when it is a folder, before its configs
    /// are read and rewritten; `None` when it is not, so the reader that
    /// follows names what is there instead.
    pub fn of_existing(dir: &Path) -> Result<Option<Self>> {
        dir.is_dir().then(|| Self::acquire(dir)).transpose()
    }

    /// Lock `dir`, waiting up to `patience` while another run holds it
    /// ([`Error::Busy`] after that; [`Error::Interrupted`] on Ctrl-C): for
    /// writes that take a moment, such as the files of one page, which a
    /// second run should follow rather than be refused.
    pub fn wait(dir: &Path, patience: std::time::Duration) -> Result<Self> {
        let lock = open_folder(dir)?;
        let start = std::time::Instant::now();
        loop {
            match lock.try_lock() {
                Ok(()) => return Ok(Self { _held: lock }),
                Err(std::fs::TryLockError::WouldBlock) if start.elapsed() < patience => {
                    crate::interrupt::check()?;
                    std::thread::sleep(std::time::Duration::from_millis(50));
                }
                Err(std::fs::TryLockError::WouldBlock) => {
                    return Err(Error::Busy {
                        path: dir.to_path_buf(),
                    });
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(dir, e)),
            }
        }
    }
}

/// `dir` opened to be locked: refused unless it is a folder, so a pipe
/// there is named, never waited on.
fn open_folder(dir: &Path) -> Result<std::fs::File> {
    expect_folder(dir, "folder to write into")?;
    std::fs::File::open(dir).map_err(|e| Error::io(dir, e))
}

/// Refuse an output folder that already holds files (another run's
/// results, or anything else): a run that writes a new folder checks it
/// before any work, and [`StagedDir::fresh`] again when it stages.
pub fn refuse_folder_with_files(target: &Path) -> Result<()> {
    if std::fs::read_dir(target).is_ok_and(|mut d| d.next().is_some()) {
        return Err(Error::Invalid(format!(
            "{}: already holds files (left alone); choose a new folder",
            target.display()
        )));
    }
    Ok(())
}

/// A folder written in full before it appears. Files go into a hidden
/// staging folder beside the target (`.NAME.partial-PID-XXXX`), unique to
/// the run, so concurrent runs never mix; [`StagedDir::commit`] renames it
/// into place. Dropped without a commit (an error, an interrupt), it is
/// removed; one left by a killed process is removed by the next run.
pub struct StagedDir {
    staging: tempfile::TempDir,
    target: std::path::PathBuf,
    /// The target held something when the run began (so a refusal to
    /// overwrite it is not another run's doing).
    existed: bool,
}

fn process_alive(pid: u32) -> bool {
    !cfg!(target_os = "linux") || Path::new(&format!("/proc/{pid}")).exists()
}

impl StagedDir {
    /// A staging folder for `target` (whose parent is created if needed).
    pub fn new(target: impl AsRef<Path>) -> Result<Self> {
        // Through a link, the folder it names (the link stays).
        let named = target.as_ref();
        if named.as_os_str().is_empty() {
            return Err(Error::Invalid(format!(
                "{}: give a folder for this output",
                crate::error::shown(named)
            )));
        }
        let target = through_links(named)?;
        if std::fs::metadata(&target).is_ok_and(|m| !m.is_dir()) {
            return Err(Error::Invalid(format!(
                "{}: is a file, a pipe or a device, not a folder; give a folder for this output",
                named.display()
            )));
        }
        let name = target
            .file_name()
            .ok_or_else(|| Error::Invalid(format!("{}: not a folder name", target.display())))?
            .to_string_lossy()
            .into_owned();
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => std::path::PathBuf::from("."),
        };
        create_dir_all(&parent)?;
        let prefix = format!(".{name}.partial-");
        // Staging folders of runs that were killed.
        if let Ok(entries) = std::fs::read_dir(&parent) {
            for e in entries.flatten() {
                let file = e.file_name().to_string_lossy().into_owned();
                let pid = file
                    .strip_prefix(&prefix)
                    .and_then(|rest| rest.split('-').next())
                    .and_then(|p| p.parse::<u32>().ok());
                if let Some(pid) = pid
                    && !process_alive(pid)
                {
                    let _ = std::fs::remove_dir_all(e.path());
                }
            }
        }
        let staging = tempfile::Builder::new()
            .prefix(&format!("{prefix}{}-", std::process::id()))
            .tempdir_in(&parent)
            .map_err(|e| Error::io(&parent, e))?;
        let existed = std::fs::read_dir(&target).is_ok_and(|mut d| d.next().is_some());
        Ok(Self {
            staging,
            target,
            existed,
        })
    }

    /// [`StagedDir::new`] for a target that must be new (absent or empty):
    /// one that already holds files is refused at once, before any work,
    /// and left alone.
    pub fn fresh(target: impl AsRef<Path>) -> Result<Self> {
        let target = target.as_ref();
        refuse_folder_with_files(target)?;
        Self::new(target)
    }

    /// Where to write.
    pub fn path(&self) -> &Path {
        self.staging.path()
    }

    /// Move the staging folder into place. With `replace`, an existing
    /// target is swapped out first and removed after; without, a target
    /// that exists and is not empty (another run's result) is left alone
    /// and this run fails.
    pub fn commit(self, replace: bool) -> Result<std::path::PathBuf> {
        let staging = self.staging.keep();
        let (target, existed) = (self.target, self.existed);
        let fail = |e: std::io::Error, staging: &Path| {
            let _ = std::fs::remove_dir_all(staging);
            Error::io(&target, e)
        };
        if replace && target.exists() {
            let old = tempfile::Builder::new()
                .prefix(".tactile-old-")
                .tempdir_in(staging.parent().unwrap_or(Path::new(".")))
                .map_err(|e| fail(e, &staging))?
                .keep();
            let aside = old.join("x");
            std::fs::rename(&target, &aside).map_err(|e| fail(e, &staging))?;
            std::fs::rename(&staging, &target).map_err(|e| fail(e, &staging))?;
            let _ = std::fs::remove_dir_all(&old);
        } else {
            std::fs::rename(&staging, &target).map_err(|e| {
                if target.is_dir() {
                    let _ = std::fs::remove_dir_all(&staging);
                    let why = match existed {
                        true => "the folder already exists and is left alone (choose a new one)",
                        false => "another run wrote this folder meanwhile",
                    };
                    Error::Invalid(format!(
                        "{}: {why}; this run's output was discarded",
                        target.display()
                    ))
                } else {
                    fail(e, &staging)
                }
            })?;
        }
        Ok(target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_path_is_said_to_be_one() {
        // An input: named as an empty path, not a message starting ": ".
        let e = crate::dataset::Dataset::open(Path::new("")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "'' (an empty path): dataset folder does not exist"
        );
        let e = read_limited(Path::new(""), 10).unwrap_err().to_string();
        assert!(e.starts_with("'' (an empty path): "), "{e}");
        // An output is refused before anything is written for it.
        let e = output_path(Path::new("")).unwrap_err().to_string();
        assert_eq!(e, "'' (an empty path): give a file name for this output");
        assert!(temp_beside("").is_err());
        let e = StagedDir::new("").err().map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some("'' (an empty path): give a folder for this output")
        );
    }

    #[test]
    fn outputs_never_replace_what_a_model_is_loaded_from() {
        let tmp = tempfile::tempdir().unwrap();
        let write = |p: &Path| std::fs::write(p, b"{}").unwrap();
        let (net, ens, plain) = (
            tmp.path().join("net"),
            tmp.path().join("ens"),
            tmp.path().join("results"),
        );
        for d in [&net, &ens, &ens.join("member-0"), &plain] {
            std::fs::create_dir_all(d).unwrap();
        }
        for f in [
            "pose.json",
            "pose.bpk",
            "training.json",
            "curves.csv",
            "background.png",
        ] {
            write(&net.join(f));
        }
        write(&ens.join("ensemble.json"));
        write(&plain.join("background.png"));
        write(&ens.join("member-0/pose.json"));
        write(&ens.join("member-0/pose.bpk"));
        write(&plain.join("scores.json"));
        let check = |p: std::path::PathBuf| refuse_model_file(&p, &output_path(&p).unwrap());
        for refused in [
            net.join("pose.json"),
            net.join("pose.bpk"),
            net.join("training.json"),
            net.join("background.png"),
            ens.join("ensemble.json"),
            ens.join("member-0/pose.json"),
        ] {
            let e = check(refused.clone()).err().unwrap().to_string();
            assert!(e.contains("is a file of the model in"), "{e}");
        }
        // A link to a model's config is the config.
        std::os::unix::fs::symlink(net.join("pose.json"), tmp.path().join("link.json")).unwrap();
        assert!(check(tmp.path().join("link.json")).is_err());
        // A model of another kind is not trained into a model's folder; one
        // of the same kind is trained again.
        let other = |d: &Path, config: &str| refuse_other_model(d, config).is_err();
        assert_eq!(model_configs(&net), ["pose.json"]);
        assert!(other(&net, "detector.json") && !other(&net, "pose.json"));
        assert!(other(&ens, "pose.json"), "an ensemble's folder");
        assert!(!other(&plain, "pose.json") && !other(&tmp.path().join("new"), "pose.json"));
        for allowed in [
            net.join("curves.csv"),
            net.join("estimates.json"),
            plain.join("scores.json"),
            plain.join("background.png"),
        ] {
            check(allowed.clone()).unwrap_or_else(|e| panic!("{}: {e}", allowed.display()));
        }
    }

    #[test]
    fn a_held_folder_is_refused_at_once_or_after_the_wait_and_a_pipe_is_never_waited_on() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("model");
        let held = FolderLock::creating(&dir).unwrap();
        let busy = |r: Result<FolderLock>| matches!(r, Err(Error::Busy { .. }));
        assert!(busy(FolderLock::acquire(&dir)));
        let start = std::time::Instant::now();
        assert!(busy(FolderLock::wait(
            &dir,
            std::time::Duration::from_millis(200)
        )));
        assert!(start.elapsed() >= std::time::Duration::from_millis(200));
        let waiting = std::thread::spawn({
            let dir = dir.clone();
            move || FolderLock::wait(&dir, std::time::Duration::from_secs(60)).map(drop)
        });
        std::thread::sleep(std::time::Duration::from_millis(100));
        drop(held);
        waiting.join().unwrap().unwrap();
        let pipe = tmp.path().join("pipe");
        let made = std::process::Command::new("mkfifo").arg(&pipe).status();
        if made.is_ok_and(|s| s.success()) {
            for r in [
                FolderLock::acquire(&pipe),
                FolderLock::wait(&pipe, std::time::Duration::from_secs(60)),
            ] {
                let e = r.err().unwrap();
                assert!(matches!(e, Error::WrongKind { .. }), "{e}");
                assert!(
                    e.to_string().contains("a pipe, a device or a socket"),
                    "{e}"
                );
            }
        }
    }

    #[test]
    fn outputs_replace_files_write_through_links_and_refuse_pipes_and_devices() {
        use std::os::unix::fs::FileTypeExt;
        let tmp = tempfile::tempdir().unwrap();
        let p = |n: &str| tmp.path().join(n);
        let fifo = |q: &Path| {
            let made = std::process::Command::new("mkfifo")
                .arg(q)
                .status()
                .unwrap();
            assert!(made.success());
        };
        let is_link = |n: &str| {
            std::fs::symlink_metadata(p(n))
                .unwrap()
                .file_type()
                .is_symlink()
        };
        std::fs::write(p("old.csv"), "old").unwrap();
        std::os::unix::fs::symlink("old.csv", p("link.csv")).unwrap();
        std::os::unix::fs::symlink("sub/new.csv", p("dangling.csv")).unwrap();
        fifo(&p("pipe"));
        std::os::unix::fs::symlink(p("pipe"), p("to-pipe")).unwrap();
        std::os::unix::fs::symlink("/dev/null", p("to-null")).unwrap();
        // A file is replaced; through a link, the file it names (the link stays).
        write_atomic(p("link.csv"), b"new").unwrap();
        assert!(is_link("link.csv"));
        assert_eq!(std::fs::read(p("old.csv")).unwrap(), b"new");
        write_atomic(p("dangling.csv"), b"made").unwrap();
        assert_eq!(std::fs::read(p("sub/new.csv")).unwrap(), b"made");
        assert!(is_link("dangling.csv"));
        // A pipe, a link to one or to a device is refused and stays as it was.
        for q in ["pipe", "to-pipe", "to-null"] {
            let e = write_atomic(p(q), b"x").unwrap_err().to_string();
            assert!(
                e.contains(q) && e.contains("is a pipe, a device or a socket"),
                "{e}"
            );
            assert!(AtomicFile::create(p(q)).is_err(), "{q}");
        }
        assert!(std::fs::metadata(p("pipe")).unwrap().file_type().is_fifo());
        assert!(is_link("to-null"));
        assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
        let e = write_atomic(tmp.path(), b"x").unwrap_err().to_string();
        assert!(e.contains("is a folder"), "{e}");
        // A folder output through a link fills the folder it names.
        std::fs::create_dir(p("empty")).unwrap();
        std::os::unix::fs::symlink("empty", p("to-empty")).unwrap();
        let staged = StagedDir::fresh(p("to-empty")).unwrap();
        std::fs::write(staged.path().join("f"), "a").unwrap();
        staged.commit(false).unwrap();
        assert_eq!(std::fs::read(p("empty/f")).unwrap(), b"a");
        assert!(is_link("to-empty"));
        let e = StagedDir::new(p("pipe")).err().unwrap().to_string();
        assert!(e.contains("not a folder"), "{e}");
        // Nothing temporary is left beside them.
        let left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".tactile-"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    #[test]
    fn a_folder_is_told_from_a_file_and_from_nothing() {
        let dir = tempfile::tempdir().unwrap();
        assert!(expect_folder(dir.path(), "model folder").is_ok());
        let f = dir.path().join("labels.txt");
        std::fs::write(&f, "x").unwrap();
        let e = expect_folder(&f, "dataset folder").unwrap_err();
        assert!(!e.is_not_found());
        assert!(
            e.to_string()
                .contains("labels.txt: not a dataset folder (a file)"),
            "{e}"
        );
        let e = expect_folder(&dir.path().join("nowhere"), "model folder").unwrap_err();
        assert!(
            e.is_not_found()
                && e.to_string()
                    .contains("nowhere: model folder does not exist")
        );
    }

    #[test]
    fn json_files_are_bounded_before_they_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.json");
        std::fs::File::create(&p).unwrap().set_len(1 << 40).unwrap();
        let e = read_json::<serde_json::Value>(&p).unwrap_err().to_string();
        assert!(e.contains("big.json") && e.contains("too large"), "{e}");
        std::fs::write(&p, "[1, 2, 3]").unwrap();
        assert_eq!(read_json::<Vec<u8>>(&p).unwrap(), vec![1, 2, 3]);
        assert!(read_json_limited::<Vec<u8>>(&p, 4).is_err());
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let n = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(n, 1, "temporary files left behind");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(
                mode, 0o644,
                "outputs must be readable by others, got {mode:o}"
            );
        }
    }

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        let r = write_atomic_with(&p, |_| Err(std::io::Error::other("boom")));
        assert!(r.unwrap_err().to_string().contains("out.txt"));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn staged_folders_appear_whole_and_never_mix() {
        let d = tempfile::tempdir().unwrap();
        let target = d.path().join("out");
        let a = StagedDir::new(&target).unwrap();
        let b = StagedDir::new(&target).unwrap();
        assert_ne!(a.path(), b.path());
        std::fs::write(a.path().join("f"), b"a").unwrap();
        std::fs::write(b.path().join("f"), b"b").unwrap();
        assert!(!target.exists());
        a.commit(false).unwrap();
        let e = b.commit(false).unwrap_err().to_string();
        assert!(e.contains("another run"), "{e}");
        assert_eq!(std::fs::read(target.join("f")).unwrap(), b"a");
        // A folder that held something before the run is named as such.
        let late = StagedDir::new(&target).unwrap();
        let e = late.commit(false).unwrap_err().to_string();
        assert!(e.contains("already exists"), "{e}");
        assert_eq!(std::fs::read(target.join("f")).unwrap(), b"a");
        // Replacing swaps the whole folder.
        let c = StagedDir::new(&target).unwrap();
        std::fs::write(c.path().join("g"), b"c").unwrap();
        c.commit(true).unwrap();
        assert!(!target.join("f").exists() && target.join("g").exists());
        // Dropped without a commit: nothing is left beside the target.
        drop(StagedDir::new(&target).unwrap());
        let names: Vec<String> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec!["out".to_string()]);
        // A stale staging folder of a dead process is removed.
        std::fs::create_dir(d.path().join(".out.partial-999999999-abc")).unwrap();
        drop(StagedDir::new(&target).unwrap());
        assert!(!d.path().join(".out.partial-999999999-abc").exists());
    }

    #[test]
    fn unwritable_folder_names_the_file() {
        let r = write_atomic("/proc/definitely/not/here.txt", b"x");
        assert!(r.unwrap_err().to_string().contains("here.txt"));
    }
}
