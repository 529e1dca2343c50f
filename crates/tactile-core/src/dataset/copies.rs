//! Whether a frame is one of a set of frame files: the same file, or a copy
//! of it (the same bytes under another name or in another folder). It tells
//! a trainer that a test set holds its training frames, and a bench or a
//! calibration that a model fitted the frames it is given. Names and sizes
//! alone would take another recording's frames for copies wherever frames
//! all have one size (uncompressed formats) and share a naming scheme.

use std::collections::{HashMap, HashSet};
use std::io::Read;
use std::path::{Path, PathBuf};

/// A set of frame files to find frames among. Files are read only when a
/// frame of their size is asked about, and each is digested once.
pub(crate) struct FrameCopies {
    files: HashSet<PathBuf>,
    by_size: HashMap<u64, Vec<PathBuf>>,
    digests: HashMap<PathBuf, Option<u64>>,
}

impl FrameCopies {
    /// The frames `files` (resolved paths).
    pub(crate) fn new(files: impl IntoIterator<Item = PathBuf>) -> Self {
        let files: HashSet<PathBuf> = files.into_iter().collect();
        let mut by_size: HashMap<u64, Vec<PathBuf>> = HashMap::new();
        for f in &files {
            if let Ok(m) = std::fs::metadata(f) {
                by_size.entry(m.len()).or_default().push(f.clone());
            }
        }
        Self {
            files,
            by_size,
            digests: HashMap::new(),
        }
    }

    /// Whether `frame` (a resolved path) is one of the files, or holds the
    /// bytes of one.
    pub(crate) fn holds(&mut self, frame: &Path) -> bool {
        if self.files.contains(frame) {
            return true;
        }
        let Some(candidates) = std::fs::metadata(frame)
            .ok()
            .and_then(|m| self.by_size.get(&m.len()))
        else {
            return false;
        };
        let Some(d) = digest(frame) else {
            return false;
        };
        let digests = &mut self.digests;
        candidates.iter().any(|c| {
            *digests.entry(c.clone()).or_insert_with(|| digest(c)) == Some(d)
                && same_bytes(c, frame)
        })
    }
}

/// A digest of a file's bytes, read in chunks (`None` when it cannot be
/// read): equal files have equal digests; [`same_bytes`] confirms a match.
fn digest(path: &Path) -> Option<u64> {
    use std::hash::Hasher;
    let mut file = crate::io::open_regular(path).ok()?;
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    let mut buf = vec![0u8; 64 * 1024];
    loop {
        match file.read(&mut buf).ok()? {
            0 => return Some(hasher.finish()),
            n => hasher.write(&buf[..n]),
        }
    }
}

/// Whether two files hold the same bytes, compared in chunks.
fn same_bytes(a: &Path, b: &Path) -> bool {
    let (Ok(mut a), Ok(mut b)) = (std::fs::File::open(a), std::fs::File::open(b)) else {
        return false;
    };
    let (mut x, mut y) = (vec![0u8; 64 * 1024], vec![0u8; 64 * 1024]);
    loop {
        let Ok(n) = a.read(&mut x) else { return false };
        if n == 0 {
            // Equal so far: the same only if `b` ends here too.
            return matches!(b.read(&mut y[..1]), Ok(0));
        }
        if b.read_exact(&mut y[..n]).is_err() || x[..n] != y[..n] {
            return false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_copy_under_another_name_is_found_and_a_frame_of_the_same_size_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, bytes: &[u8]| {
            let p = dir.path().join(name);
            std::fs::write(&p, bytes).unwrap();
            p
        };
        // Uncompressed frames of one size: another recording's frame has
        // the size of every frame here, and even the name of one.
        let a = write("a.pgm", &[1; 70_000]);
        let mut other = vec![1; 70_000];
        other[69_999] = 2;
        let b = write("b.pgm", &other);
        let copy = write("copy-of-a.pgm", &[1; 70_000]);
        let longer = write("longer.pgm", &[1; 70_001]);
        let mut set = FrameCopies::new([a.clone(), b.clone()]);
        assert!(set.holds(&a) && set.holds(&copy));
        let mut only_b = FrameCopies::new([b]);
        assert!(!only_b.holds(&a) && !only_b.holds(&copy) && !only_b.holds(&longer));
        assert!(!set.holds(&dir.path().join("missing.pgm")));
        assert!(!same_bytes(&a, &longer) && !same_bytes(&longer, &a));
    }
}
