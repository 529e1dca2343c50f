//! An MCAP file of ROS 2 messages being written: `ros2` profile, `ros2msg`
//! schemas, `cdr` channels, in a temporary file beside its place that is
//! moved there when finished (dropped unfinished, it leaves nothing).

use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::schemas::Schema;
use crate::{Error, Result};

pub(crate) struct McapFile {
    path: PathBuf,
    writer: mcap::Writer<BufWriter<tempfile::NamedTempFile>>,
    schemas: BTreeMap<String, u16>,
    sequence: u32,
}

impl McapFile {
    /// The writer's error for `path`: a failed write (a full disk, a lost
    /// drive) as the system's own error, an `OSError` in Python, whose
    /// message the MCAP crate's text ("I/O error from writing, or reading
    /// a compression stream") would hide.
    fn fail(path: &Path, e: mcap::McapError) -> Error {
        match e {
            mcap::McapError::Io(io) => tactile_core::Error::io(path, io).into(),
            other => Error::Write {
                path: path.to_path_buf(),
                message: other.to_string(),
            },
        }
    }

    /// Start the file that will be `path` (its folder is created).
    pub(crate) fn create(path: &Path) -> Result<Self> {
        let tmp = tactile_core::io::temp_beside(path)?;
        let writer = mcap::WriteOptions::new()
            .profile("ros2")
            .library(concat!("tactile-rs ", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(tmp))
            .map_err(|e| Self::fail(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            schemas: BTreeMap::new(),
            sequence: 0,
        })
    }

    /// Register a `cdr` channel on `topic` (its schema once per file).
    pub(crate) fn channel(&mut self, topic: &str, schema: &Schema) -> Result<u16> {
        let id = match self.schemas.get(schema.name) {
            Some(&id) => id,
            None => {
                let id = self
                    .writer
                    .add_schema(schema.name, "ros2msg", schema.text.as_bytes())
                    .map_err(|e| Self::fail(&self.path, e))?;
                self.schemas.insert(schema.name.to_string(), id);
                id
            }
        };
        self.writer
            .add_channel(id, topic, "cdr", &BTreeMap::new())
            .map_err(|e| Self::fail(&self.path, e))
    }

    /// One message, logged and published at `stamp_ns`.
    pub(crate) fn write(&mut self, channel: u16, stamp_ns: i64, data: &[u8]) -> Result<()> {
        let time = u64::try_from(stamp_ns).unwrap_or(0);
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: time,
            publish_time: time,
        };
        self.sequence = self.sequence.wrapping_add(1);
        self.writer
            .write_to_known_channel(&header, data)
            .map_err(|e| Self::fail(&self.path, e))
    }

    /// Close the file (its summary and index) and move it into place.
    pub(crate) fn finish(mut self) -> Result<PathBuf> {
        let path = self.path.clone();
        self.writer.finish().map_err(|e| Self::fail(&path, e))?;
        let tmp = self
            .writer
            .into_inner()
            .into_inner()
            .map_err(|e| tactile_core::Error::io(&path, e.into_error()))?;
        tactile_core::io::persist_temp(tmp, &path)?;
        Ok(path)
    }
}
