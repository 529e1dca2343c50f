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
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(path, e))?;
    let mut tmp = tempfile::Builder::new()
        .prefix(".tactile-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(|e| Error::io(path, e))?;
    {
        let mut buf = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut buf).map_err(|e| Error::io(path, e))?;
        buf.flush().map_err(|e| Error::io(path, e))?;
    }
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

/// Write `value` as pretty JSON to `path` atomically.
pub fn write_json_atomic<T: serde::Serialize>(path: impl AsRef<Path>, value: &T) -> Result<()> {
    let path = path.as_ref();
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Invalid(format!("{}: cannot serialise JSON: {e}", path.display())))?;
    write_atomic(path, text.as_bytes())
}

/// Read and parse a JSON file, naming the file on error.
pub fn read_json<T: serde::de::DeserializeOwned>(path: impl AsRef<Path>) -> Result<T> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| Error::dataset(path, Some(e.line()), e.to_string()))
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
        return Err(refuse("it is a file".into()));
    }
    tempfile::Builder::new()
        .prefix(".tactile-probe-")
        .tempfile_in(probe)
        .map(drop)
        .map_err(|e| refuse(e.kind().to_string()))
}

/// [`ensure_writable_dir`] for the folder an output file will go into.
pub fn ensure_writable_parent(file: impl AsRef<Path>) -> Result<()> {
    ensure_writable_dir(file.as_ref().parent().unwrap_or(Path::new(".")))
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn unwritable_folder_names_the_file() {
        let r = write_atomic("/proc/definitely/not/here.txt", b"x");
        assert!(r.unwrap_err().to_string().contains("here.txt"));
    }
}
