//! NumPy `.npz` archives (zips of `.npy` arrays), as `numpy.savez` and
//! `savez_compressed` write them: gs_sdk's `label.npz` and Taxim's
//! `dataPack.npz`. Every array's header is read within a limit and its
//! shape and type checked before its values are allocated; the zip and
//! the `.npy` format are read by the `zip` and `ndarray-npy` crates.

use std::io::{Read, Seek};

use ndarray_npy::npy::header::Header;

/// Largest `.npy` header read, bytes (NumPy pads its headers to 64 bytes;
/// one of 4 GB could be claimed).
const MAX_HEADER_BYTES: usize = 64 << 10;

/// An open `.npz` archive. Errors are the reason alone: the caller names
/// the file and the array.
pub(crate) struct Npz<R> {
    archive: zip::ZipArchive<R>,
}

/// The `.npy` entry of the array `name`.
fn entry_name(name: &str) -> String {
    format!("{name}.npy")
}

impl<R: Read + Seek> Npz<R> {
    /// The archive in `reader`.
    pub(crate) fn new(reader: R) -> Result<Self, String> {
        let archive = zip::ZipArchive::new(reader)
            .map_err(|e| format!("not a NumPy .npz archive (a zip of .npy arrays): {e}"))?;
        Ok(Self { archive })
    }

    /// Whether the archive holds the array `name`.
    pub(crate) fn has(&self, name: &str) -> bool {
        self.archive.index_for_name(&entry_name(name)).is_some()
    }

    /// The `count` numbers (any integer or float dtype) of the array
    /// `name`, its entry at most `max_bytes`; `missing` says what it is
    /// for when the archive lacks it.
    pub(crate) fn numbers(
        &mut self,
        name: &str,
        count: usize,
        max_bytes: u64,
        missing: &str,
    ) -> Result<Vec<f64>, String> {
        let mut entry =
            (self.archive.by_name(&entry_name(name))).map_err(|_| missing.to_string())?;
        if entry.size() > max_bytes {
            return Err(format!(
                "{} bytes: far more than {count} numbers ({max_bytes} bytes at most)",
                entry.size()
            ));
        }
        let mut bytes = Vec::new();
        (&mut entry)
            .take(max_bytes + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| format!("cannot read it: {e}"))?;
        if bytes.len() as u64 > max_bytes {
            return Err(format!(
                "far more than {count} numbers ({max_bytes} bytes at most)"
            ));
        }
        let header = read_header(&mut &bytes[..])?;
        let found = element_count(&header.shape);
        if found != Some(count) {
            let found = found.map_or("more".to_string(), |n| n.to_string());
            return Err(format!(
                "holds {found} numbers (shape {:?}), not {count}",
                header.shape
            ));
        }
        let values = read_as::<f64>(&bytes, |v| *v)
            .or_else(|| read_as::<f32>(&bytes, |v| f64::from(*v)))
            .or_else(|| read_as::<i64>(&bytes, |v| *v as f64))
            .or_else(|| read_as::<i32>(&bytes, |v| f64::from(*v)))
            .or_else(|| read_as::<u64>(&bytes, |v| *v as f64))
            .or_else(|| read_as::<u32>(&bytes, |v| f64::from(*v)))
            .or_else(|| read_as::<i16>(&bytes, |v| f64::from(*v)))
            .or_else(|| read_as::<u16>(&bytes, |v| f64::from(*v)))
            .or_else(|| read_as::<u8>(&bytes, |v| f64::from(*v)));
        values.ok_or_else(|| {
            format!(
                "its dtype {} is no number this reads (floats or integers)",
                header.type_descriptor
            )
        })
    }

    /// The shape of the `uint8` array `name` (C order), checked by
    /// `check` before any value is read, and `read` given a reader of its
    /// values, row-major; `missing` says what it is where the archive
    /// lacks it.
    pub(crate) fn with_bytes<T>(
        &mut self,
        name: &str,
        missing: &str,
        check: impl FnOnce(&[usize]) -> Result<(), String>,
        read: impl FnOnce(&[usize], &mut dyn Read) -> Result<T, String>,
    ) -> Result<T, String> {
        let mut entry =
            (self.archive.by_name(&entry_name(name))).map_err(|_| missing.to_string())?;
        let header = read_header(&mut entry)?;
        let descr = header.type_descriptor.to_string();
        if !matches!(descr.as_str(), "'|u1'" | "'<u1'" | "'>u1'") {
            return Err(format!(
                "its dtype is {descr}, not uint8 (8-bit pixels, as OpenCV reads an image)"
            ));
        }
        if header.layout.is_fortran() {
            return Err(
                "is saved in Fortran order: save it in C order (numpy.ascontiguousarray)".into(),
            );
        }
        check(&header.shape)?;
        let values = read(&header.shape, &mut entry)?;
        // Read to its end, so the zip's checksum of it is compared: a
        // stored array damaged on disk would otherwise be read as pixels.
        match entry.read(&mut [0u8; 1]) {
            Ok(0) => Ok(values),
            Ok(_) => Err(format!(
                "holds more bytes than its shape {:?} says: not one .npy array",
                header.shape
            )),
            Err(e) => Err(format!(
                "is damaged ({e}): its bytes do not match the archive's checksum of them"
            )),
        }
    }

    /// The strings of the array `name` when it holds `count` of them as
    /// NumPy keeps text (`<U`: UTF-32; `|S`: bytes), the entry at most
    /// `max_bytes`; `None` where it holds anything else (Python objects
    /// are pickled, and pickles are not read).
    pub(crate) fn strings(
        &mut self,
        name: &str,
        count: usize,
        max_bytes: u64,
    ) -> Option<Vec<String>> {
        let entry = self.archive.by_name(&entry_name(name)).ok()?;
        if entry.size() > max_bytes {
            return None;
        }
        let mut bytes = Vec::new();
        entry.take(max_bytes + 1).read_to_end(&mut bytes).ok()?;
        let mut rest = &bytes[..];
        let header = read_header(&mut rest).ok()?;
        if element_count(&header.shape) != Some(count) || header.layout.is_fortran() {
            return None;
        }
        let descr = header.type_descriptor.to_string();
        let descr = descr.trim_matches('\'');
        let (kind, width) = descr.split_at_checked(2)?;
        let width: usize = width.parse().ok()?;
        let unit = match kind {
            "<U" | ">U" => 4,
            "|S" => 1,
            _ => return None,
        };
        let size = width.checked_mul(unit)?;
        if size == 0 || rest.len() != size.checked_mul(count)? {
            return None;
        }
        let text = |item: &[u8]| -> Option<String> {
            let s: String = match unit {
                4 => (item.chunks_exact(4))
                    .map(|c| {
                        let b = [c[0], c[1], c[2], c[3]];
                        let v = match kind {
                            "<U" => u32::from_le_bytes(b),
                            _ => u32::from_be_bytes(b),
                        };
                        char::from_u32(v)
                    })
                    .collect::<Option<String>>()?,
                _ => String::from_utf8_lossy(item).into_owned(),
            };
            Some(s.trim_end_matches('\0').to_string())
        };
        rest.chunks_exact(size).map(text).collect()
    }
}

/// The product of `shape`, unless it overflows.
pub(crate) fn element_count(shape: &[usize]) -> Option<usize> {
    shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d))
}

/// A `.npy` header from `reader`, its length checked before it is read.
fn read_header(reader: &mut dyn Read) -> Result<Header, String> {
    const MAGIC: &[u8] = b"\x93NUMPY";
    let not_npy = |e: std::io::Error| format!("not a .npy array: {e}");
    let mut start = [0u8; 8];
    reader.read_exact(&mut start).map_err(not_npy)?;
    if &start[..6] != MAGIC {
        return Err("not a .npy array (no NumPy magic string)".into());
    }
    // Version 1 gives the header's length in 2 bytes, 2 and 3 in 4.
    let wide = start[6] >= 2;
    let mut len_bytes = vec![0u8; if wide { 4 } else { 2 }];
    reader.read_exact(&mut len_bytes).map_err(not_npy)?;
    let len = match wide {
        true => {
            u32::from_le_bytes([len_bytes[0], len_bytes[1], len_bytes[2], len_bytes[3]]) as usize
        }
        false => u16::from_le_bytes([len_bytes[0], len_bytes[1]]) as usize,
    };
    if len > MAX_HEADER_BYTES {
        return Err(format!(
            "its .npy header claims {len} bytes ({MAX_HEADER_BYTES} at most)"
        ));
    }
    let mut all = Vec::with_capacity(start.len() + len_bytes.len() + len);
    all.extend_from_slice(&start);
    all.extend_from_slice(&len_bytes);
    let at = all.len();
    all.resize(at + len, 0);
    reader.read_exact(&mut all[at..]).map_err(not_npy)?;
    Header::from_reader(&mut &all[..]).map_err(|e| format!("not a .npy array: {e}"))
}

/// The numbers of a `.npy` array of `T`, if it is one.
fn read_as<T: ndarray_npy::ReadableElement>(bytes: &[u8], to: fn(&T) -> f64) -> Option<Vec<f64>> {
    use ndarray_npy::ReadNpyExt;
    let a = ndarray::ArrayD::<T>::read_npy(bytes).ok()?;
    Some(a.iter().map(to).collect())
}
