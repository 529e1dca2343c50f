//! Paths a dataset's `labels.csv` names, kept inside the dataset folder.
//!
//! A path is refused when it is absolute, goes up with `..`, or passes
//! through a symbolic link whose target leaves the folder. Every test is
//! made on the path and on links inside the folder only: nothing outside
//! is ever looked at, so the answer never tells whether an outside file
//! exists.

use std::path::{Component, Path, PathBuf};

use crate::io::MAX_LINKS;

/// Why a path is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Escape {
    /// An absolute path (or one with a drive or root).
    Absolute,
    /// A `..` component.
    Parent,
    /// A symbolic link whose target is outside the folder.
    Link,
    /// Links that point at each other (more than [`MAX_LINKS`]).
    Loop,
    /// An empty path.
    Empty,
}

impl Escape {
    /// The reason, in words.
    pub fn describe(self) -> &'static str {
        match self {
            Escape::Absolute => "is absolute: files must be named relative to the dataset folder",
            Escape::Parent => "goes up with '..': files must stay inside the dataset folder",
            Escape::Link => {
                "passes through a symbolic link that leaves the dataset folder (to keep the \
                 frames on another disk, move the whole dataset folder there and link to it)"
            }
            Escape::Loop => "passes through too many symbolic links",
            Escape::Empty => "is empty",
        }
    }
}

/// `a` with `.` removed and `..` applied, without touching the disk.
fn lexical(a: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in a.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// `rel` (as written in `labels.csv`) resolved inside `root`, which must be
/// an absolute, canonical folder path.
pub fn resolve_inside(root: &Path, rel: impl AsRef<Path>) -> Result<PathBuf, Escape> {
    let rel = rel.as_ref();
    if rel.as_os_str().to_string_lossy().trim().is_empty() {
        return Err(Escape::Empty);
    }
    let mut parts = Vec::new();
    for c in rel.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => return Err(Escape::Absolute),
            Component::ParentDir => return Err(Escape::Parent),
            Component::CurDir => {}
            Component::Normal(p) => parts.push(p.to_os_string()),
        }
    }
    let mut links = 0;
    let mut pending: Vec<std::ffi::OsString> = parts.into_iter().rev().collect();
    let mut at = root.to_path_buf();
    while let Some(part) = pending.pop() {
        let next = at.join(&part);
        let is_link = std::fs::symlink_metadata(&next).is_ok_and(|m| m.file_type().is_symlink());
        if !is_link {
            at = next;
            continue;
        }
        links += 1;
        if links > MAX_LINKS {
            return Err(Escape::Loop);
        }
        let target = std::fs::read_link(&next).map_err(|_| Escape::Link)?;
        let target = lexical(&at.join(target));
        let inside = target.strip_prefix(root).map_err(|_| Escape::Link)?;
        // Walk the target from the root again: its own parts may be links.
        pending.extend(
            inside
                .components()
                .filter_map(|c| match c {
                    Component::Normal(p) => Some(p.to_os_string()),
                    _ => None,
                })
                .collect::<Vec<_>>()
                .into_iter()
                .rev(),
        );
        at = root.to_path_buf();
    }
    Ok(at)
}

/// What to add to "'`rel`' does not exist" when `rel` was written on
/// Windows (`frames\a.png`, as `os.path.join` writes it there): here a
/// backslash is part of a file name, not a folder separator. Empty for
/// any other path.
pub fn backslash_hint(rel: &str) -> String {
    match rel.contains('\\') {
        true => format!(
            " (a backslash is no folder separator here: write '{}')",
            rel.replace('\\', "/")
        ),
        false => String::new(),
    }
}

/// Refuse `entry`, a file listed in the folder `dir` (a folder of frames,
/// of presses), when it is a symbolic link whose target leaves `dir`: the
/// folder a user names bounds what is read, as a dataset's does.
pub fn expect_entry_inside(dir: &Path, entry: &Path) -> crate::Result<()> {
    let is_link = std::fs::symlink_metadata(entry).is_ok_and(|m| m.file_type().is_symlink());
    if !is_link {
        return Ok(());
    }
    let refuse = |why: &str| crate::Error::image(entry, why.to_string());
    let root = dir.canonicalize().map_err(|e| crate::Error::io(dir, e))?;
    let name = entry
        .strip_prefix(dir)
        .map_err(|_| refuse("is not in the folder being read"))?;
    match resolve_inside(&root, name) {
        Ok(_) => Ok(()),
        Err(Escape::Loop) => Err(refuse("passes through too many symbolic links")),
        Err(_) => Err(refuse(
            "is a symbolic link that leaves the folder; refusing to read outside it (copy the file into the folder)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_that_leave_are_refused_without_looking_outside() {
        let d = tempfile::tempdir().unwrap();
        let root = d.path().canonicalize().unwrap().join("ds");
        std::fs::create_dir_all(root.join("frames/sub")).unwrap();
        std::fs::write(root.join("frames/a.png"), b"x").unwrap();
        std::fs::write(d.path().join("secret.png"), b"x").unwrap();
        let ok = |r: &str| resolve_inside(&root, r);
        assert_eq!(ok("frames/a.png").unwrap(), root.join("frames/a.png"));
        assert_eq!(ok("./frames/a.png").unwrap(), root.join("frames/a.png"));
        assert_eq!(ok("../secret.png"), Err(Escape::Parent));
        assert_eq!(ok("frames/../../secret.png"), Err(Escape::Parent));
        assert_eq!(ok("/etc/passwd"), Err(Escape::Absolute));
        assert_eq!(ok(""), Err(Escape::Empty));
        #[cfg(unix)]
        {
            use std::os::unix::fs::symlink;
            // Links out, existing or not: the same answer.
            symlink(d.path().join("secret.png"), root.join("frames/out.png")).unwrap();
            symlink("/definitely/not/here.png", root.join("frames/gone.png")).unwrap();
            symlink("../../secret.png", root.join("frames/up.png")).unwrap();
            symlink(d.path(), root.join("frames/dir")).unwrap();
            for r in [
                "frames/out.png",
                "frames/gone.png",
                "frames/up.png",
                "frames/dir/secret.png",
            ] {
                assert_eq!(ok(r), Err(Escape::Link), "{r}");
            }
            // Links that stay inside are followed.
            symlink("a.png", root.join("frames/alias.png")).unwrap();
            symlink("..", root.join("frames/sub/back")).unwrap();
            assert_eq!(ok("frames/alias.png").unwrap(), root.join("frames/a.png"));
            assert_eq!(
                ok("frames/sub/back/a.png").unwrap(),
                root.join("frames/a.png")
            );
            // A loop ends.
            symlink("loop2", root.join("frames/loop1")).unwrap();
            symlink("loop1", root.join("frames/loop2")).unwrap();
            assert_eq!(ok("frames/loop1"), Err(Escape::Loop));
            // A folder's entries: links out refused by name, links in kept.
            let dir = root.join("frames");
            assert!(expect_entry_inside(&dir, &dir.join("a.png")).is_ok());
            assert!(expect_entry_inside(&dir, &dir.join("alias.png")).is_ok());
            for name in ["out.png", "gone.png", "up.png"] {
                let e = expect_entry_inside(&dir, &dir.join(name)).unwrap_err();
                let msg = e.to_string();
                assert!(
                    msg.contains(name) && msg.contains("leaves the folder"),
                    "{msg}"
                );
            }
        }
    }
}
