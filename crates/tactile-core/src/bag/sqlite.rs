//! rosbag2's SQLite storage (`.db3`, what `ros2 bag record` writes by
//! default on Humble and earlier), read through SQLite itself (`rusqlite`,
//! read-only): its `topics` table gives the channels, its `messages` table
//! the messages in log-time order, as rosbag2's own reader gives them. Each
//! message's bytes are CDR, read as an MCAP bag's are.
//!
//! The messages are read a page at a time by their (timestamp, id), so a
//! bag of any size is held a page of ids at a time, and a message's bytes
//! are copied out only when it is on the topic read (its length checked
//! against [`super::MAX_RECORD_BYTES`] first).

use std::collections::{BTreeMap, VecDeque};
use std::path::Path;

use rusqlite::{Connection, OpenFlags, params};

use super::{ChannelInfo, TopicTally, bag_error};
use crate::{Error, Result};

/// The first bytes of every SQLite database file.
pub(super) const SQLITE_MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// Message ids read per query.
const PAGE: i64 = 256;

/// Most topics one file may declare (each becomes a channel numbered as an
/// MCAP channel is, in 16 bits).
const MAX_TOPICS: usize = u16::MAX as usize;

/// The error of a file that is not a readable rosbag2 SQLite bag.
fn sqlite_error(path: &Path, what: impl std::fmt::Display) -> Error {
    bag_error(
        path,
        None,
        None,
        format!("not a readable ROS 2 bag in SQLite storage: {what}"),
    )
}

/// A message's place in the pass: its id, channel, log time and length.
struct Listed {
    id: i64,
    channel: u16,
    timestamp: i64,
    len: i64,
}

/// One `.db3` file being read.
pub(super) struct SqliteFile {
    db: Connection,
    /// Topic ids as channel numbers.
    channels: BTreeMap<i64, u16>,
    /// The (timestamp, id) of the last message listed: the pass goes on
    /// after it.
    after: (i64, i64),
    /// Messages listed, not yet given.
    listed: VecDeque<Listed>,
    /// The pass has listed every message.
    done: bool,
    /// SQLite found the file damaged (a recording cut short).
    damaged: bool,
}

/// True for SQLite's word that the file is damaged or cut short.
fn is_damage(e: &rusqlite::Error) -> bool {
    use rusqlite::ErrorCode::{DatabaseCorrupt, NotADatabase, SystemIoFailure};
    matches!(
        e.sqlite_error_code(),
        Some(DatabaseCorrupt | NotADatabase | SystemIoFailure)
    )
}

impl SqliteFile {
    /// Open `path` read-only, with its topics as channels (numbered from
    /// 1, in their ids' order).
    pub(super) fn open(path: &Path) -> Result<(Self, BTreeMap<u16, ChannelInfo>)> {
        let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
        let db = match written_whole(path) {
            // Nothing beside it to read: opened as a file that cannot
            // change, so SQLite adds no `-shm` or `-wal` to the folder.
            Some(uri) => Connection::open_with_flags(uri, flags | OpenFlags::SQLITE_OPEN_URI),
            None => Connection::open_with_flags(path, flags),
        }
        .map_err(|e| sqlite_error(path, e))?;
        // A table or column rosbag2 writes that is not there is named
        // with what rosbag2 keeps where.
        let schema_error = |e: rusqlite::Error| match &e {
            rusqlite::Error::SqliteFailure(_, Some(why)) if why.starts_with("no such") => {
                sqlite_error(
                    path,
                    format!(
                        "{e} (rosbag2 keeps its topics in a table `topics` with the columns id, \
                         name, type and serialization_format, and its messages in `messages` \
                         with id, topic_id, timestamp and data)"
                    ),
                )
            }
            _ => sqlite_error(path, e),
        };
        let topics = read_topics(&db).map_err(schema_error)?;
        if topics.len() > MAX_TOPICS {
            return Err(sqlite_error(path, format!("more than {MAX_TOPICS} topics")));
        }
        let mut channels = BTreeMap::new();
        let mut infos = BTreeMap::new();
        for (n, (id, info)) in topics.into_iter().enumerate() {
            let channel = (n + 1) as u16;
            channels.insert(id, channel);
            infos.insert(channel, info);
        }
        // The messages table is read as rosbag2 writes it, or named.
        db.prepare("SELECT id, topic_id, timestamp, length(data) FROM messages LIMIT 0")
            .map_err(schema_error)?;
        Ok((
            Self {
                db,
                channels,
                after: (i64::MIN, i64::MIN),
                listed: VecDeque::new(),
                done: false,
                damaged: false,
            },
            infos,
        ))
    }

    /// True once SQLite found the file damaged: the pass ends there, as a
    /// recording cut short (the recorder killed, the power lost) leaves it.
    pub(super) fn damaged(&self) -> bool {
        self.damaged
    }

    /// The next message: its channel, log time and bytes (the bytes only
    /// when `wanted` says its channel is, else empty); `None` after the
    /// last.
    pub(super) fn next(
        &mut self,
        path: &Path,
        wanted: impl Fn(u16) -> bool,
    ) -> Result<Option<(u16, u64, Vec<u8>)>> {
        if self.listed.is_empty() && !self.done {
            self.list_page(path)?;
        }
        let Some(m) = self.listed.pop_front() else {
            return Ok(None);
        };
        let log_time = u64::try_from(m.timestamp).map_err(|_| {
            sqlite_error(
                path,
                format!(
                    "message id {} has a negative timestamp {}",
                    m.id, m.timestamp
                ),
            )
        })?;
        if !wanted(m.channel) {
            return Ok(Some((m.channel, log_time, Vec::new())));
        }
        if m.len > super::MAX_RECORD_BYTES as i64 {
            return Err(sqlite_error(
                path,
                format!(
                    "message id {} holds {} bytes, more than the {} a message may",
                    m.id,
                    m.len,
                    super::MAX_RECORD_BYTES
                ),
            ));
        }
        let data: Vec<u8> = self
            .db
            .query_row("SELECT data FROM messages WHERE id = ?1", [m.id], |r| {
                r.get(0)
            })
            .map_err(|e| {
                self.damaged |= is_damage(&e);
                let why = match e {
                    rusqlite::Error::InvalidColumnType(_, _, kind) => {
                        format!("its data is {kind}, not the bytes of a message")
                    }
                    e => e.to_string(),
                };
                sqlite_error(path, format!("message id {}: {why}", m.id))
            })?;
        Ok(Some((m.channel, log_time, data)))
    }

    /// The next page of messages in (timestamp, id) order.
    fn list_page(&mut self, path: &Path) -> Result<()> {
        crate::interrupt::check()?;
        let page = self.page_after(self.after);
        let page = page.map_err(|e| {
            self.damaged |= is_damage(&e);
            sqlite_error(path, e)
        })?;
        self.done = page.len() < PAGE as usize;
        for (id, topic, timestamp, len) in page {
            self.after = (timestamp, id);
            let Some(&channel) = self.channels.get(&topic) else {
                return Err(sqlite_error(
                    path,
                    format!("message id {id} is on topic id {topic}, which `topics` does not list"),
                ));
            };
            self.listed.push_back(Listed {
                id,
                channel,
                timestamp,
                len: len.unwrap_or(0),
            });
        }
        Ok(())
    }

    /// The id, topic id, timestamp and length of the [`PAGE`] messages
    /// after `(timestamp, id)`.
    #[allow(clippy::type_complexity)]
    fn page_after(
        &self,
        (t, id): (i64, i64),
    ) -> rusqlite::Result<Vec<(i64, i64, i64, Option<i64>)>> {
        let mut q = self.db.prepare(
            "SELECT id, topic_id, timestamp, length(data) FROM messages \
             WHERE timestamp >= ?1 AND (timestamp > ?1 OR id > ?2) \
             ORDER BY timestamp, id LIMIT ?3",
        )?;
        let rows = q.query_map(params![t, id, PAGE], |r| {
            Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))
        })?;
        rows.collect()
    }
}

/// The topics table: each topic's id, and its name, type and encoding.
fn read_topics(db: &Connection) -> rusqlite::Result<Vec<(i64, ChannelInfo)>> {
    let mut q =
        db.prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")?;
    let rows = q.query_map([], |r| {
        Ok((
            r.get::<_, i64>(0)?,
            ChannelInfo {
                topic: r.get(1)?,
                message_type: r.get(2)?,
                encoding: r.get(3)?,
            },
        ))
    })?;
    // One more than may be kept, so a file of too many is told.
    rows.take(MAX_TOPICS + 1).collect()
}

/// Each topic of the file at `path` with its message count and first and
/// last log times, counted by SQLite without reading a message's bytes.
pub(super) fn tallies(path: &Path) -> Result<BTreeMap<String, TopicTally>> {
    let (file, infos) = SqliteFile::open(path)?;
    let mut tallies: BTreeMap<String, TopicTally> = infos
        .values()
        .map(|c| (c.topic.clone(), TopicTally::new(c.message_type.clone())))
        .collect();
    let mut q = file
        .db
        .prepare(
            "SELECT topic_id, count(*), min(timestamp), max(timestamp) FROM messages \
             GROUP BY topic_id",
        )
        .map_err(|e| sqlite_error(path, e))?;
    let rows = q
        .query_map([], |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, i64>(1)?,
                r.get::<_, i64>(2)?,
                r.get::<_, i64>(3)?,
            ))
        })
        .map_err(|e| sqlite_error(path, e))?;
    for row in rows {
        let (topic, count, first, last) = row.map_err(|e| sqlite_error(path, e))?;
        let info = file
            .channels
            .get(&topic)
            .and_then(|c| infos.get(c))
            .ok_or_else(|| {
                sqlite_error(
                    path,
                    format!("messages on topic id {topic}, which `topics` does not list"),
                )
            })?;
        let time = |t: i64| u64::try_from(t).unwrap_or(0);
        if let Some(t) = tallies.get_mut(&info.topic) {
            t.add(count.max(0) as u64, time(first), time(last));
        }
    }
    Ok(tallies)
}

/// The `file:` URI that opens `path` immutable, when it is in WAL mode
/// (rosbag2's `resilient` preset) with no `-wal` file beside it: its
/// writer closed it, so all of it is in the file. SQLite would otherwise
/// add a `-shm` and a `-wal` beside it to read it, and leave them; a file
/// in the usual rollback mode is read without either. `None` for any
/// other file, opened as it is (a WAL file with its `-wal`, a recording
/// under way or cut short, is read with it, as SQLite reads it).
fn written_whole(path: &Path) -> Option<String> {
    let mut head = [0u8; 20];
    let mut f = crate::io::open_regular(path).ok()?;
    let n = crate::video::read_full(&mut f, &mut head).ok()?;
    // Bytes 18 and 19 of the header: 2 for WAL mode.
    let wal_mode = n == 20 && head[18] == 2 && head[19] == 2;
    let mut wal = path.as_os_str().to_owned();
    wal.push("-wal");
    if !wal_mode || Path::new(&wal).exists() {
        return None;
    }
    let abs = std::path::absolute(path).ok()?;
    let text = abs.to_str()?;
    // A path's `%`, `?` and `#` would be read as the URI's own.
    let escaped = text
        .replace('%', "%25")
        .replace('?', "%3f")
        .replace('#', "%23");
    Some(format!("file:{escaped}?immutable=1"))
}

/// True for a file that starts as an SQLite database does.
pub(super) fn is_sqlite(path: &Path) -> bool {
    let mut head = [0u8; 16];
    crate::io::open_regular(path)
        .ok()
        .and_then(|mut f| crate::video::read_full(&mut f, &mut head).ok())
        .is_some_and(|n| n == 16 && &head == SQLITE_MAGIC)
}
