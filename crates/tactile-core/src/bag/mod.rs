//! ROS 2 bags in: the image topics of an MCAP file (`ros2 bag record`'s
//! default storage since Iron) read as frames, each with its header stamp,
//! without ROS installed. The container is read by the `mcap` crate and the
//! messages by a CDR deserialiser (`cdr-encoding`); nothing of either
//! format is written by hand here. `sensor_msgs/msg/Image` (rgb8, bgr8,
//! rgba8, bgra8, mono8, mono16 and the other encodings of
//! [`messages::IMAGE_ENCODINGS`]) and `sensor_msgs/msg/CompressedImage`
//! (JPEG, PNG) are understood, and so are the `foxglove.RawImage` and
//! `foxglove.CompressedImage` of MCAP files the Foxglove SDK records (in
//! protobuf, or in JSON as Foxglove's JSON schemas have them; either
//! decoded by the `foxglove` crate's types), and video topics
//! (`foxglove.CompressedVideo`, ROS 2's `foxglove_msgs` one,
//! `ffmpeg_image_transport`'s and `h264_image_transport`'s packets: H.264,
//! H.265, VP9 and AV1, decoded by FFmpeg
//! in `video`); anything else is refused naming the topic and the
//! message.
//!
//! A bag is given as `ros2 bag record` leaves it (a folder holding
//! `metadata.yaml` and one or more `.mcap` files, split ones read in the
//! order of their numbers) or as one `.mcap` file. rosbag2's zstd
//! compression of whole files (`.mcap.zstd`) and of single messages is
//! undone by the `zstd` crate. rosbag2's SQLite storage (`.db3`, the
//! default of ROS 2 Humble and earlier) is read through SQLite in
//! `sqlite`, its messages the same CDR. ROS 1 bags are refused with the
//! command that converts them.
//!
//! The file is read a record at a time through `mcap`'s sans-I/O reader
//! (bounded memory whatever the bag's size); schemas and channels are kept
//! as they appear, and each message of the chosen topic becomes a frame.
//! Listing a bag's topics reads each file's index (summary and message
//! indexes) instead, when it has a whole one.

pub mod messages;
mod sqlite;
mod video;

pub use video::{LiveFrame, LiveVideo};

use std::collections::{BTreeMap, VecDeque};
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::image_io::RgbImage;
use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::{Error, Result};
use messages::{
    COMPRESSED_IMAGE_TYPE, CompressedImage, FFMPEG_PACKET_TYPE, FOXGLOVE_COMPRESSED_IMAGE_TYPE,
    FOXGLOVE_COMPRESSED_VIDEO_TYPE, FOXGLOVE_RAW_IMAGE_TYPE, H264_PACKET_TYPE, Header, IMAGE_TYPE,
    Image, ROS_COMPRESSED_VIDEO_TYPE, from_cdr,
};

fn bag_error(
    path: &Path,
    topic: Option<&str>,
    index: Option<u64>,
    message: impl ToString,
) -> Error {
    Error::Bag {
        path: path.to_path_buf(),
        topic: topic.map(str::to_string),
        index,
        message: message.to_string(),
    }
}

fn container_error(path: &Path, message: impl ToString) -> Error {
    bag_error(
        path,
        None,
        None,
        format!("not a readable MCAP bag: {}", message.to_string()),
    )
}

/// Largest record read (a compressed chunk or one message): a raw 8K RGBA
/// frame with room to spare. A longer record is refused before it is
/// buffered.
pub const MAX_RECORD_BYTES: usize = 256 << 20;

/// One image topic of a bag.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BagTopic {
    /// Its name (`/gelsight/image_raw`).
    pub topic: String,
    /// Its message type (`sensor_msgs/msg/Image`).
    pub message_type: String,
    /// Messages on it.
    pub count: u64,
    /// Messages per second between its first and last log times.
    pub rate_hz: f64,
}

/// One frame of a bag.
pub struct BagFrame {
    /// The pixels.
    pub image: RgbImage,
    /// The message's header stamp, nanoseconds since the epoch; its log
    /// time when the header carries none (0, as a publisher that does not
    /// stamp leaves it), so frames keep their times.
    pub stamp_ns: i64,
    /// When the recorder logged it, nanoseconds since the epoch.
    pub log_time_ns: u64,
    /// Its index on its topic (0-based).
    pub index: u64,
}

#[derive(Clone)]
struct ChannelInfo {
    topic: String,
    message_type: String,
    encoding: String,
}

/// Records of a bag, one after another, file after file of a split bag.
struct Records {
    /// The file being read.
    path: PathBuf,
    /// The files still to read.
    rest: VecDeque<PathBuf>,
    /// The file being read, as its storage reads it.
    storage: Storage,
    /// The current file's schemas and channels (their ids are per file).
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, ChannelInfo>,
    /// Every topic met so far, in any file, with its message type.
    topics: BTreeMap<String, String>,
    /// Files that ended without their end (no footer or end magic, or
    /// in the middle of a record): recordings cut short, read up to their
    /// last complete record.
    cut_short: Vec<PathBuf>,
    /// Messages met so far, in any file.
    messages: u64,
}

/// One storage file being read: an MCAP file record by record, or
/// rosbag2's SQLite storage message by message.
enum Storage {
    Mcap {
        file: Box<dyn Read + Send>,
        reader: Box<LinearReader>,
    },
    Sqlite(sqlite::SqliteFile),
}

/// What [`Records::next`] found.
enum Item {
    Message {
        channel: u16,
        log_time: u64,
        data: Vec<u8>,
    },
    Other,
}

/// The start of every zstd frame (RFC 8878), which plain CDR (`00 01`)
/// never begins with.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];

/// One storage file: an MCAP file's bytes, decompressed when rosbag2
/// compressed the whole file (`.mcap.zstd`); or an SQLite database, with
/// its topics as channels.
fn open_storage(path: &Path) -> Result<(Storage, BTreeMap<u16, ChannelInfo>)> {
    if sqlite::is_sqlite(path) || has_suffix(path, ".db3") {
        let (db, channels) = sqlite::SqliteFile::open(path)?;
        return Ok((Storage::Sqlite(db), channels));
    }
    let file = crate::io::open_regular(path)?;
    let file: Box<dyn Read + Send> = match has_suffix(path, ".zstd") {
        false => Box::new(file),
        true => Box::new(zstd::stream::read::Decoder::new(file).map_err(|e| Error::io(path, e))?),
    };
    let storage = Storage::Mcap {
        file,
        reader: Box::new(new_reader()),
    };
    Ok((storage, BTreeMap::new()))
}

fn new_reader() -> LinearReader {
    LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES),
    )
}

impl Records {
    fn open(path: &Path) -> Result<Self> {
        Self::from_files(storage_files(path)?)
    }

    /// The records of `files`, one after another (at least one file).
    fn from_files(files: Vec<PathBuf>) -> Result<Self> {
        let mut rest: VecDeque<PathBuf> = files.into();
        let Some(first) = rest.pop_front() else {
            return Err(Error::Bag {
                path: PathBuf::new(),
                topic: None,
                index: None,
                message: "a bag without storage files".into(),
            });
        };
        let (storage, channels) = open_storage(&first)?;
        let mut records = Self {
            storage,
            path: first,
            rest,
            schemas: BTreeMap::new(),
            channels,
            topics: BTreeMap::new(),
            cut_short: Vec::new(),
            messages: 0,
        };
        records.note_topics();
        Ok(records)
    }

    /// Add the topics of the file's channels known when it opens (an
    /// SQLite file's; an MCAP file's come with its Channel records).
    fn note_topics(&mut self) {
        for c in self.channels.values() {
            self.topics
                .entry(c.topic.clone())
                .or_insert_with(|| c.message_type.clone());
        }
    }

    /// On to the next file of a split bag; false after the last.
    fn next_file(&mut self) -> Result<bool> {
        let Some(next) = self.rest.pop_front() else {
            return Ok(false);
        };
        let (storage, channels) = open_storage(&next)?;
        self.storage = storage;
        self.path = next;
        self.schemas.clear();
        self.channels = channels;
        self.note_topics();
        Ok(true)
    }

    fn container(&self, message: impl ToString) -> Error {
        container_error(&self.path, message)
    }

    /// The next record, `None` at the end of the file. A message's bytes
    /// are copied out only when it is on `topic` (others are skipped in
    /// place: listing a bag copies nothing).
    fn next(&mut self, topic: Option<&str>) -> Result<Option<Item>> {
        loop {
            let (file, reader) = match &mut self.storage {
                Storage::Sqlite(db) => {
                    let channels = &self.channels;
                    let wanted = |channel: u16| {
                        channels
                            .get(&channel)
                            .is_some_and(|c| topic == Some(c.topic.as_str()))
                    };
                    let next = match db.next(&self.path, wanted) {
                        // Damage after messages were read: the end of a
                        // recording cut short, as an MCAP file's.
                        Err(_) if db.damaged() && self.messages > 0 => {
                            self.cut_short.push(self.path.clone());
                            None
                        }
                        next => next?,
                    };
                    match next {
                        Some((channel, log_time, data)) => {
                            self.messages += 1;
                            return Ok(Some(Item::Message {
                                channel,
                                log_time,
                                data,
                            }));
                        }
                        None if self.next_file()? => continue,
                        None => return Ok(None),
                    }
                }
                Storage::Mcap { file, reader } => (file, reader),
            };
            let Some(event) = reader.next_event() else {
                if self.next_file()? {
                    continue;
                }
                return Ok(None);
            };
            let event = match event {
                Ok(e) => e,
                // The file ends without its footer, the end of a recording
                // cut short (the recorder killed, the power lost): every
                // complete record before it was read, as Foxglove and
                // `mcap recover` read such a file.
                Err(mcap::McapError::UnexpectedEof) => {
                    // Cut before its first message: nothing to read.
                    if self.messages == 0 {
                        return Err(self.container(
                            "it ends before its first complete message (a recording cut short before anything was recorded, or not an MCAP file written whole)",
                        ));
                    }
                    self.cut_short.push(self.path.clone());
                    if self.next_file()? {
                        continue;
                    }
                    return Ok(None);
                }
                Err(e) => return Err(container_error(&self.path, e)),
            };
            match event {
                LinearReadEvent::ReadRequest(need) => {
                    let buf = reader.insert(need);
                    let n = file.read(buf).map_err(|e| match e.kind() {
                        // A damaged `.mcap.zstd`: its decompressor's reason.
                        std::io::ErrorKind::InvalidData | std::io::ErrorKind::Other => {
                            container_error(&self.path, e)
                        }
                        _ => Error::io(&self.path, e),
                    })?;
                    reader.notify_read(n);
                }
                LinearReadEvent::Record { opcode, data } => {
                    let record = mcap::parse_record(opcode, data)
                        .map_err(|e| container_error(&self.path, e))?;
                    return Ok(Some(match record {
                        Record::Schema { header, .. } => {
                            self.schemas.insert(header.id, header.name);
                            Item::Other
                        }
                        Record::Channel(c) => {
                            let message_type = match (self.schemas.get(&c.schema_id), c.schema_id) {
                                (Some(name), _) => name.clone(),
                                (None, 0) => String::new(),
                                (None, id) => {
                                    return Err(self.container(format!(
                                        "channel {} ({}) names schema {id}, which no record defines",
                                        c.id, c.topic
                                    )));
                                }
                            };
                            self.topics
                                .entry(c.topic.clone())
                                .or_insert_with(|| message_type.clone());
                            self.channels.insert(
                                c.id,
                                ChannelInfo {
                                    topic: c.topic,
                                    message_type,
                                    encoding: c.message_encoding,
                                },
                            );
                            Item::Other
                        }
                        Record::Message { header, data } => {
                            self.messages += 1;
                            let wanted = topic.is_some_and(|t| {
                                self.channels
                                    .get(&header.channel_id)
                                    .is_some_and(|c| c.topic == t)
                            });
                            Item::Message {
                                channel: header.channel_id,
                                log_time: header.log_time,
                                data: if wanted {
                                    data.into_owned()
                                } else {
                                    Vec::new()
                                },
                            }
                        }
                        _ => Item::Other,
                    }));
                }
            }
        }
    }
}

/// ROS 1's image types, as `mcap convert` writes a ROS 1 bag's topics to
/// MCAP (encoding `ros1`): listed, and refused with the command that
/// converts the bag to ROS 2 messages.
const ROS1_IMAGE_TYPES: [&str; 2] = ["sensor_msgs/Image", "sensor_msgs/CompressedImage"];

/// True for the image message types a bag's frames may be: ROS 2's
/// Image and CompressedImage, the Foxglove SDK's RawImage,
/// CompressedImage and CompressedVideo, the last also as ROS 2's
/// `foxglove_msgs`, `ffmpeg_image_transport`'s and `h264_image_transport`'s
/// packets (and ROS 1's images, listed to be refused with advice).
pub fn is_image_type(t: &str) -> bool {
    [
        IMAGE_TYPE,
        COMPRESSED_IMAGE_TYPE,
        FOXGLOVE_RAW_IMAGE_TYPE,
        FOXGLOVE_COMPRESSED_IMAGE_TYPE,
    ]
    .contains(&t)
        || video::is_video_type(t)
        || ROS1_IMAGE_TYPES.contains(&t)
}

/// The message encodings an image type is read in: ROS 2's CDR, or, for
/// Foxglove's schemas, the protobuf the Foxglove SDK writes them in and
/// the JSON of Foxglove's JSON schemas (bytes in base64), as a recorder
/// logging plain dictionaries or a JSON WebSocket stream writes them.
fn expected_encodings(message_type: &str) -> &'static [&'static str] {
    match message_type {
        FOXGLOVE_RAW_IMAGE_TYPE
        | FOXGLOVE_COMPRESSED_IMAGE_TYPE
        | FOXGLOVE_COMPRESSED_VIDEO_TYPE => &["protobuf", "json"],
        _ => &["cdr"],
    }
}

/// A message of a Foxglove schema in its channel's encoding: protobuf, or
/// JSON through the `foxglove` crate's serde (bytes in base64).
fn foxglove_message<M>(topic: &TopicMessages, m: &TopicMessage) -> Result<M>
where
    M: foxglove::Decode + serde::de::DeserializeOwned,
{
    let decoded = match m.json {
        true => serde_json::from_slice(&m.data).map_err(|e| format!("{e} (in its JSON)")),
        false => M::decode(m.data.as_slice()).map_err(|e| e.to_string()),
    };
    decoded.map_err(|e| {
        topic.message_error(
            m.index,
            format!("not a valid {} message: {e}", m.message_type),
        )
    })
}

/// A Foxglove timestamp in nanoseconds since the epoch (0 when absent).
fn foxglove_stamp(t: Option<foxglove::messages::Timestamp>) -> i64 {
    t.map_or(0, |t| i64::try_from(t.total_nanos()).unwrap_or(i64::MAX))
}

fn has_suffix(p: &Path, suffix: &str) -> bool {
    p.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.to_ascii_lowercase().ends_with(suffix))
}

/// True for a path named like an MCAP file (`.mcap`): a bag read, or
/// results written as one.
pub fn is_bag_file(p: &Path) -> bool {
    has_suffix(p, ".mcap")
}

/// True for a bag file read: an MCAP file, one rosbag2 compressed whole
/// (`.mcap.zstd`), or rosbag2's SQLite storage (`.db3`). Outputs are
/// never written compressed or in SQLite.
pub fn is_bag_input_file(p: &Path) -> bool {
    is_bag_file(p) || has_suffix(p, ".mcap.zstd") || has_suffix(p, ".db3")
}

/// True for a ROS 2 bag folder as `ros2 bag record` leaves it: a folder
/// whose `metadata.yaml` is rosbag2's (its `rosbag2_bagfile_information`
/// key in the first 64 KiB), so a folder of frames with a `metadata.yaml`
/// of another tool stays a folder of frames.
pub fn is_bag_folder(p: &Path) -> bool {
    let meta = p.join("metadata.yaml");
    if !p.is_dir() || !meta.is_file() {
        return false;
    }
    const KEY: &[u8] = b"rosbag2_bagfile_information";
    let mut head = Vec::new();
    File::open(&meta)
        .and_then(|f| f.take(64 << 10).read_to_end(&mut head))
        .is_ok_and(|_| head.windows(KEY.len()).any(|w| w == KEY))
}

/// Most storage files one bag folder may hold.
const MAX_BAG_FILES: usize = 100_000;

/// The error refusing `path`, `what` (a bag this toolkit does not read),
/// with the command that converts `src` to MCAP without ROS.
fn foreign_bag_error(path: &Path, what: &str, src: &Path) -> Error {
    bag_error(
        path,
        None,
        None,
        format!(
            "{what}; this toolkit reads ROS 2 bags in MCAP storage: convert it to MCAP without ROS: {}",
            convert_command(&src.display().to_string())
        ),
    )
}

/// The commands that convert the bag `src` (a ROS 1 bag) to a ROS 2 bag
/// in MCAP storage without ROS.
fn convert_command(src: &str) -> String {
    format!(
        "`pip install rosbags`, then `rosbags-convert --src {src} --dst NEW_FOLDER --dst-storage mcap`"
    )
}

/// The error of an SQLite bag file rosbag2 compressed whole.
fn db3_zstd_error(path: &Path) -> Error {
    bag_error(
        path,
        None,
        None,
        "an SQLite bag file rosbag2 compressed whole, which SQLite cannot read in place: \
         decompress it first (`zstd -d FILE`, beside it), then give the .db3 or its folder",
    )
}

/// A file told by its first bytes to be a bag this toolkit does not read
/// (a ROS 1 `.bag`: the error saying how to convert it), or a bag it reads
/// under another name (an SQLite database not named `.db3`: the error
/// saying how it is read). `None` for any other file.
pub fn other_bag_format(path: &Path) -> Option<Error> {
    let mut head = [0u8; 16];
    let mut file = crate::io::open_regular(path).ok()?;
    let n = crate::video::read_full(&mut file, &mut head).ok()?;
    let head = &head[..n];
    if has_suffix(path, ".db3.zstd") {
        Some(db3_zstd_error(path))
    } else if head == sqlite::SQLITE_MAGIC && !has_suffix(path, ".db3") {
        Some(bag_error(
            path,
            None,
            None,
            "an SQLite database: a ROS 2 bag in SQLite storage is read as rosbag2 names it \
             (a .db3 file, or its bag folder)",
        ))
    } else if head.starts_with(b"#ROSBAG V") {
        Some(foreign_bag_error(path, "a ROS 1 bag", path))
    } else {
        None
    }
}

/// When `path` is one `.mcap` of a bag folder holding several: the warning
/// that only it is read (a split of the recording, not all of it).
pub fn split_read_alone(path: &Path) -> Option<String> {
    if path.is_dir() {
        return None;
    }
    let folder = path.parent().filter(|d| is_bag_folder(d))?;
    let n = storage_files(folder).ok()?.len();
    (n > 1).then(|| {
        format!(
            "warning: {} is one of the {n} files of the bag folder {}; only it is read (give the folder to read the whole recording)",
            path.display(),
            folder.display()
        )
    })
}

/// The files of the bag at `path`, in the order they are read: the file
/// itself, or a bag folder's `.mcap` (and `.mcap.zstd`) files in the order
/// of the numbers in their names (`rec_0`, `rec_1`, …, `rec_10`), as
/// rosbag2 splits a recording.
fn storage_files(path: &Path) -> Result<Vec<PathBuf>> {
    if !path.is_dir() {
        crate::io::expect_regular(path)?;
        if let Some(e) = other_bag_format(path) {
            return Err(e);
        }
        return Ok(vec![path.to_path_buf()]);
    }
    if !is_bag_folder(path) {
        return Err(bag_error(
            path,
            None,
            None,
            "a folder without the metadata.yaml of a ROS 2 bag folder (rosbag2_bagfile_information); a topic is read from a ROS 2 bag: give its folder or one .mcap or .db3 file",
        ));
    }
    let entries: Vec<PathBuf> = std::fs::read_dir(path)
        .map_err(|e| Error::io(path, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| !crate::source::is_hidden_file(p))
        .take(MAX_BAG_FILES + 1)
        .collect();
    if entries.len() > MAX_BAG_FILES {
        return Err(bag_error(
            path,
            None,
            None,
            format!("more than {MAX_BAG_FILES} files; a bag folder holds at most that many"),
        ));
    }
    if let Some(z) = entries.iter().find(|p| has_suffix(p, ".db3.zstd")) {
        return Err(db3_zstd_error(z));
    }
    let mut files: Vec<PathBuf> = entries
        .into_iter()
        .filter(|p| is_bag_input_file(p))
        .collect();
    if files.is_empty() {
        return Err(bag_error(
            path,
            None,
            None,
            "a ROS 2 bag folder (it holds metadata.yaml) without an .mcap or .db3 file",
        ));
    }
    for f in &files {
        crate::dataset::expect_entry_inside(path, f)?;
    }
    alphanumeric_sort::sort_path_slice(&mut files);
    Ok(files)
}

/// A topic of one storage file or a whole bag: its message type, message
/// count and first and last log times.
#[derive(Debug, Clone, PartialEq)]
struct TopicTally {
    message_type: String,
    count: u64,
    first: u64,
    last: u64,
}

impl TopicTally {
    fn new(message_type: String) -> Self {
        Self {
            message_type,
            count: 0,
            first: u64::MAX,
            last: 0,
        }
    }

    fn add(&mut self, count: u64, first: u64, last: u64) {
        if count > 0 {
            self.count += count;
            self.first = self.first.min(first);
            self.last = self.last.max(last);
        }
    }
}

type Tallies = BTreeMap<String, TopicTally>;

/// Most bytes of summary and message indexes read from one file to list
/// its topics; a larger index is passed over for a scan of the file.
const MAX_INDEX_BYTES: u64 = 64 << 20;

/// Reads of an MCAP file's index, bounded in total by [`MAX_INDEX_BYTES`].
struct IndexFile {
    file: File,
    size: u64,
    read: u64,
}

impl IndexFile {
    /// Count `n` more bytes against the budget; `None` past it.
    fn charge(&mut self, n: u64) -> Option<()> {
        self.read = self.read.checked_add(n)?;
        (self.read <= MAX_INDEX_BYTES).then_some(())
    }

    /// `n` bytes at `offset`; `None` past the file's end or the budget.
    fn read_at(&mut self, offset: u64, n: u64) -> Option<Vec<u8>> {
        use std::io::{Seek, SeekFrom};
        if offset.checked_add(n)? > self.size {
            return None;
        }
        self.charge(n)?;
        self.file.seek(SeekFrom::Start(offset)).ok()?;
        let mut buf = vec![0; usize::try_from(n).ok()?];
        self.file.read_exact(&mut buf).ok()?;
        Some(buf)
    }
}

/// The topics of one `.mcap` file from its summary and message indexes,
/// without reading its messages: a few reads at its end and one per chunk
/// and channel. `None` when the file has no complete index to trust (no
/// summary, as a recording cut short leaves it; no statistics or message
/// indexes; indexes that disagree with its statistics; a compressed
/// file), and it is scanned instead.
fn indexed_tallies(path: &Path) -> Option<Tallies> {
    use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
    use std::io::Seek;
    // A pipe or device named .mcap is never opened (it would block); the
    // scan refuses it by name.
    if !is_bag_file(path) {
        return None;
    }
    let file = crate::io::open_regular(path).ok()?;
    let size = file.metadata().ok()?.len();
    let mut index = IndexFile {
        file,
        size,
        read: 0,
    };
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(MAX_RECORD_BYTES),
    );
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(n) => {
                index.charge(n as u64)?;
                let got = index.file.read(reader.insert(n)).ok()?;
                reader.notify_read(got);
            }
            SummaryReadEvent::SeekRequest(to) => {
                reader.notify_seeked(index.file.seek(to).ok()?);
            }
        }
    }
    let summary = reader.finish()?;
    let stats = summary.stats.as_ref()?;
    let mut tallies = Tallies::new();
    let mut by_channel: BTreeMap<u16, &str> = BTreeMap::new();
    for (id, c) in &summary.channels {
        let message_type = c
            .schema
            .as_ref()
            .map(|s| s.name.clone())
            .unwrap_or_default();
        tallies
            .entry(c.topic.clone())
            .or_insert_with(|| TopicTally::new(message_type));
        by_channel.insert(*id, &c.topic);
    }
    let mut indexed = 0u64;
    for chunk in &summary.chunk_indexes {
        crate::interrupt::check().ok()?;
        for (&channel, &offset) in &chunk.message_index_offsets {
            // A Message Index record: opcode, length, then its body.
            let head = index.read_at(offset, 9)?;
            let len = u64::from_le_bytes(head[1..9].try_into().ok()?);
            if head[0] != mcap::records::op::MESSAGE_INDEX || len > MAX_RECORD_BYTES as u64 {
                return None;
            }
            let body = index.read_at(offset + 9, len)?;
            let Ok(Record::MessageIndex(m)) = mcap::parse_record(head[0], &body) else {
                return None;
            };
            let topic = by_channel
                .get(&channel)
                .filter(|_| m.channel_id == channel)?;
            let times = m.records.iter().map(|e| e.log_time);
            let (first, last) = (times.clone().min()?, times.max()?);
            indexed += m.records.len() as u64;
            tallies
                .get_mut(*topic)?
                .add(m.records.len() as u64, first, last);
        }
    }
    // Every message indexed, or the file is read through instead.
    (indexed == stats.message_count).then_some(tallies)
}

/// The warning that `file` ended without its footer, `what` of it was
/// read, and the rest is lost.
fn cut_short_warning(file: &Path, what: &str) -> String {
    let how = match sqlite::is_sqlite(file) {
        true => "is damaged past some of its messages (SQLite: database disk image is malformed)",
        false => "ends without its MCAP footer",
    };
    format!(
        "warning: {} {how}, as a recording cut short leaves it (the recorder killed or the power lost): {what}, what it held after them is lost",
        file.display()
    )
}

/// The topics of one storage file, read through record by record, after
/// `messages_before` messages of the bag's earlier files (a file cut short
/// before its first message is an error only when it is all there is),
/// and whether it was cut short.
fn scanned_tallies(path: &Path, messages_before: u64) -> Result<(Tallies, bool)> {
    let mut records = Records::from_files(vec![path.to_path_buf()])?;
    records.messages = messages_before;
    let mut tallies = Tallies::new();
    while let Some(item) = records.next(None)? {
        crate::interrupt::check()?;
        if let Item::Message {
            channel, log_time, ..
        } = item
            && let Some(c) = records.channels.get(&channel)
        {
            tallies
                .entry(c.topic.clone())
                .or_insert_with(|| TopicTally::new(c.message_type.clone()))
                .add(1, log_time, log_time);
        }
    }
    for (topic, message_type) in records.topics {
        tallies
            .entry(topic)
            .or_insert_with(|| TopicTally::new(message_type));
    }
    Ok((tallies, !records.cut_short.is_empty()))
}

/// A bag's image topics, and what a user should know of them.
#[derive(Debug, Clone, PartialEq)]
pub struct BagListing {
    /// Its image topics, in name order.
    pub topics: Vec<BagTopic>,
    /// Its files cut short (recordings stopped without closing), whose
    /// messages are counted up to their last complete record.
    pub warnings: Vec<String>,
}

/// Every image topic of the bag at `path` with its message count and rate,
/// in name order (see [`list_image_topics`]).
pub fn image_topics(path: &Path) -> Result<Vec<BagTopic>> {
    Ok(list_image_topics(path)?.topics)
}

/// Every image topic of the bag at `path` with its message count and rate,
/// in name order, and warnings of files cut short. Each file's topics come
/// from its index when it has a whole one (so listing a bag of gigabytes
/// reads kilobytes), else from a pass over it.
pub fn list_image_topics(path: &Path) -> Result<BagListing> {
    let mut bag = Tallies::new();
    let mut warnings = Vec::new();
    for file in storage_files(path)? {
        // An SQLite file is counted by SQLite, or, when it is damaged
        // (a recording cut short), read through up to the damage.
        let indexed = match sqlite::is_sqlite(&file) {
            true => sqlite::tallies(&file).ok(),
            false => indexed_tallies(&file),
        };
        let tallies = match indexed {
            Some(t) => t,
            None => {
                let (t, cut) = scanned_tallies(&file, bag.values().map(|t| t.count).sum())?;
                if cut {
                    let what = "its messages up to the last complete record are counted";
                    warnings.push(cut_short_warning(&file, what));
                }
                t
            }
        };
        for (topic, t) in tallies {
            bag.entry(topic)
                .or_insert_with(|| TopicTally::new(t.message_type.clone()))
                .add(t.count, t.first, t.last);
        }
    }
    let topics = bag
        .into_iter()
        .filter(|(_, t)| is_image_type(&t.message_type))
        .map(|(topic, t)| {
            let span = t.last.saturating_sub(t.first) as f64 * 1e-9;
            BagTopic {
                topic,
                rate_hz: match t.count > 1 && span > 0.0 {
                    true => (t.count - 1) as f64 / span,
                    false => 0.0,
                },
                message_type: t.message_type,
                count: t.count,
            }
        })
        .collect();
    Ok(BagListing { topics, warnings })
}

/// The one image topic to read from a bag when none is named: the only
/// one it has, else an error listing them.
pub fn only_image_topic(path: &Path) -> Result<String> {
    let topics = image_topics(path)?;
    match topics.as_slice() {
        [one] => Ok(one.topic.clone()),
        [] => Err(bag_error(
            path,
            None,
            None,
            "has no image topic (sensor_msgs/msg/Image or CompressedImage, foxglove.RawImage or CompressedImage)",
        )),
        many => Err(bag_error(
            path,
            None,
            None,
            format!(
                "has {} image topics; name one with --topic (topic= in Python): {}",
                many.len(),
                many.iter()
                    .map(|t| t.topic.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )),
    }
}

/// The messages of one topic of a bag, each checked as its channel
/// appears: a topic of another message type or encoding is refused by
/// name; one that never appears is refused at the end of the file.
pub(crate) struct TopicMessages {
    records: Records,
    topic: String,
    /// Messages given so far.
    given: u64,
}

/// One message of the topic read, undone of rosbag2's compression.
pub(crate) struct TopicMessage {
    /// Its message type.
    pub message_type: String,
    /// True when it is in JSON (a Foxglove schema's), not the type's
    /// binary encoding.
    pub json: bool,
    /// When the recorder logged it, nanoseconds since the epoch.
    pub log_time: u64,
    /// Its bytes, in the type's encoding.
    pub data: Vec<u8>,
    /// Its index on its topic (0-based).
    pub index: u64,
}

impl TopicMessages {
    /// The error of the topic read.
    pub(crate) fn topic_error(&self, message: impl ToString) -> Error {
        bag_error(&self.records.path, Some(&self.topic), None, message)
    }

    /// The error of the topic's message `index`.
    pub(crate) fn message_error(&self, index: u64, message: impl ToString) -> Error {
        bag_error(&self.records.path, Some(&self.topic), Some(index), message)
    }

    /// The next message on the topic, `None` after the last.
    pub(crate) fn next(&mut self) -> Result<Option<TopicMessage>> {
        loop {
            let Some(item) = self.records.next(Some(&self.topic))? else {
                if self.given == 0 {
                    // Nothing to run on: a topic not in the bag, or one
                    // declared (a recorder subscribed) with no message.
                    let names: Vec<&str> = self
                        .records
                        .topics
                        .iter()
                        .filter(|(n, t)| is_image_type(t) && **n != self.topic)
                        .map(|(n, _)| n.as_str())
                        .collect();
                    let others = match names.is_empty() {
                        true => "none".to_string(),
                        false => names.join(", "),
                    };
                    return Err(self.topic_error(
                        match self.records.topics.contains_key(&self.topic) {
                            false => format!("not in the bag; its image topics: {others}"),
                            true => format!(
                                "has no messages{}: its channel is declared, but nothing was logged on it; the bag's other image topics: {others}",
                                match self.records.cut_short.is_empty() {
                                    true => "",
                                    false => " before the recording was cut short",
                                }
                            ),
                        },
                    ));
                }
                return Ok(None);
            };
            let Item::Message {
                channel,
                log_time,
                data,
            } = item
            else {
                continue;
            };
            let Some(c) = self.records.channels.get(&channel).cloned() else {
                return Err(self.records.container(format!(
                    "a message on channel {channel}, which no record defines"
                )));
            };
            if c.topic != self.topic {
                continue;
            }
            if !is_image_type(&c.message_type) {
                return Err(self.topic_error(format!(
                    "carries {}, not {IMAGE_TYPE}, {COMPRESSED_IMAGE_TYPE}, {FOXGLOVE_RAW_IMAGE_TYPE}, {FOXGLOVE_COMPRESSED_IMAGE_TYPE}, {FOXGLOVE_COMPRESSED_VIDEO_TYPE}, {ROS_COMPRESSED_VIDEO_TYPE}, {FFMPEG_PACKET_TYPE} or {H264_PACKET_TYPE}",
                    if c.message_type.is_empty() {
                        "messages without a schema"
                    } else {
                        &c.message_type
                    }
                )));
            }
            if c.encoding == "ros1" || ROS1_IMAGE_TYPES.contains(&c.message_type.as_str()) {
                return Err(self.topic_error(format!(
                    "carries ROS 1 messages ({} in encoding {:?}), as `mcap convert` writes a ROS 1 bag; this toolkit reads ROS 2 messages: convert the original ROS 1 bag without ROS: {}",
                    c.message_type,
                    c.encoding,
                    convert_command("BAG")
                )));
            }
            let encodings = expected_encodings(&c.message_type);
            if !encodings.contains(&c.encoding.as_str()) {
                return Err(self.topic_error(format!(
                    "{} in message encoding {:?}; it is read in {}",
                    c.message_type,
                    c.encoding,
                    match encodings {
                        ["cdr"] => "cdr (ROS 2's)",
                        _ => "protobuf, as the Foxglove SDK writes it, or json",
                    }
                )));
            }
            let index = self.given;
            // rosbag2's message compression: each ROS 2 message's bytes
            // zstd'd.
            let data = match c.encoding == "cdr" && data.starts_with(&ZSTD_MAGIC) {
                true => unzstd(&data).map_err(|e| self.message_error(index, e))?,
                false => data,
            };
            self.given += 1;
            return Ok(Some(TopicMessage {
                json: c.encoding == "json",
                message_type: c.message_type,
                log_time,
                data,
                index,
            }));
        }
    }
}

/// The frames of one image topic of a bag, in the order they were logged.
pub struct BagImages {
    /// The topic's messages; held by the video decoder while it runs.
    messages: Option<TopicMessages>,
    /// The decoder of a video topic, started at its first message.
    video: Option<video::VideoFrames>,
    topic: String,
    /// Frames given so far.
    frames: u64,
}

impl BagImages {
    /// Read the frames of `topic` in the bag at `path`. The topic is
    /// checked as its channel appears: a topic of another message type or
    /// encoding is refused by name; one that never appears is refused at
    /// the end of the file.
    pub fn open(path: &Path, topic: &str) -> Result<Self> {
        Ok(Self {
            messages: Some(TopicMessages {
                records: Records::open(path)?,
                topic: topic.to_string(),
                given: 0,
            }),
            video: None,
            topic: topic.to_string(),
            frames: 0,
        })
    }

    /// The topic read.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// What a user should know of the frames read so far: each file that
    /// ended without its footer (a recording cut short), of which the
    /// complete records were read and the rest is lost; of a video topic,
    /// the messages before its first keyframe, which cannot be decoded.
    pub fn warnings(&self) -> Vec<String> {
        let read = format!(
            "its frames up to the last complete record were read ({} on {} in all)",
            self.frames, self.topic
        );
        let messages = self
            .messages
            .as_ref()
            .or_else(|| self.video.as_ref().and_then(|v| v.messages()));
        let mut warnings: Vec<String> = messages
            .iter()
            .flat_map(|m| m.records.cut_short.iter())
            .map(|f| cut_short_warning(f, &read))
            .collect();
        if let Some(v) = &self.video {
            warnings.extend(v.warnings());
        }
        warnings
    }

    /// The next frame, `None` after the last.
    pub fn next_frame(&mut self) -> Result<Option<BagFrame>> {
        let frame = match (&mut self.video, &mut self.messages) {
            (Some(v), _) => v.next_frame()?,
            (None, Some(messages)) => {
                let Some(m) = messages.next()? else {
                    return Ok(None);
                };
                // A compressed image topic whose first message is video
                // is read as a video topic.
                let video = video::is_video_type(&m.message_type)
                    || (self.frames == 0 && video::carries_video(messages, &m)?);
                if video {
                    let Some(messages) = self.messages.take() else {
                        return Ok(None);
                    };
                    let v = self.video.insert(video::VideoFrames::start(messages, m)?);
                    v.next_frame()?
                } else {
                    let (image, stamp_ns) = decode_image(messages, &m)?;
                    Some(BagFrame {
                        image,
                        stamp_ns: stamp_or_log_time(stamp_ns, m.log_time),
                        log_time_ns: m.log_time,
                        index: m.index,
                    })
                }
            }
            (None, None) => None,
        };
        self.frames += u64::from(frame.is_some());
        Ok(frame)
    }
}

/// A message's stamp, or its log time when the publisher left it 0, so
/// frames keep their times.
fn stamp_or_log_time(stamp_ns: i64, log_time: u64) -> i64 {
    match stamp_ns {
        0 => i64::try_from(log_time).unwrap_or(i64::MAX),
        t => t,
    }
}

/// One message of an image type (in its encoding): its frame and stamp
/// (0 when it carries none).
fn decode_image(topic: &TopicMessages, m: &TopicMessage) -> Result<(RgbImage, i64)> {
    let (message_type, data) = (m.message_type.as_str(), m.data.as_slice());
    let bad = |e: String| topic.message_error(m.index, e);
    Ok(match message_type {
        IMAGE_TYPE => {
            let m: Image<'_> = from_cdr(data).map_err(bad)?;
            (m.to_rgb().map_err(bad)?, m.header.stamp.nanos())
        }
        COMPRESSED_IMAGE_TYPE => {
            let m: CompressedImage<'_> = from_cdr(data).map_err(bad)?;
            (m.to_rgb().map_err(bad)?, m.header.stamp.nanos())
        }
        FOXGLOVE_RAW_IMAGE_TYPE => {
            let m: foxglove::messages::RawImage = foxglove_message(topic, m)?;
            // The same pixel encodings as a ROS 2 Image; Foxglove's
            // 16-bit ones are little-endian.
            let image = Image {
                header: Header::default(),
                height: m.height,
                width: m.width,
                encoding: m.encoding,
                is_bigendian: 0,
                step: m.step,
                data: &m.data,
            };
            (image.to_rgb().map_err(bad)?, foxglove_stamp(m.timestamp))
        }
        _ => {
            let m: foxglove::messages::CompressedImage = foxglove_message(topic, m)?;
            let image = CompressedImage {
                header: Header::default(),
                format: m.format,
                data: &m.data,
            };
            (image.to_rgb().map_err(bad)?, foxglove_stamp(m.timestamp))
        }
    })
}

/// A message rosbag2 compressed on its own, decompressed; refused past
/// [`MAX_RECORD_BYTES`] before more is held.
fn unzstd(data: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let d = zstd::stream::read::Decoder::new(data)
        .map_err(|e| format!("not a readable zstd-compressed message: {e}"))?;
    let mut out = Vec::new();
    d.take(MAX_RECORD_BYTES as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("not a readable zstd-compressed message: {e}"))?;
    if out.len() > MAX_RECORD_BYTES {
        return Err(format!(
            "a zstd-compressed message of more than {MAX_RECORD_BYTES} bytes"
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn a_compressed_message_is_bounded_and_a_damaged_one_named() {
        let small = zstd::encode_all(&b"\x00\x01\x00\x00hello"[..], 1).unwrap();
        assert!(small.starts_with(&ZSTD_MAGIC));
        assert_eq!(unzstd(&small).unwrap(), b"\x00\x01\x00\x00hello");
        // A bomb: a few kilobytes that would be 300 MB; refused once past
        // the record limit, not held whole.
        let bomb = zstd::encode_all(std::io::repeat(0).take(300 << 20), 1).unwrap();
        assert!(bomb.len() < 1 << 20);
        let e = unzstd(&bomb).unwrap_err();
        assert!(e.contains("more than 268435456 bytes"), "{e}");
        let mut damaged = small.clone();
        damaged.truncate(small.len() - 3);
        let e = unzstd(&damaged).unwrap_err();
        assert!(e.contains("not a readable zstd-compressed message"), "{e}");
    }

    /// A bag written with `options`: 40 messages on `/a` (Image, every
    /// 10 ms), 7 on `/b` (CompressedImage, every 50 ms, from 1 s) and 5 on
    /// `/log` (another type), interleaved; messages carry filler bytes.
    fn indexed_bag(options: mcap::WriteOptions) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        let mut w = options.create(&mut out).unwrap();
        let channel = |w: &mut mcap::Writer<_>, schema: &str, topic: &str| {
            let s = w.add_schema(schema, "ros2msg", b"").unwrap();
            w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap()
        };
        let a = channel(&mut w, IMAGE_TYPE, "/a");
        let b = channel(&mut w, COMPRESSED_IMAGE_TYPE, "/b");
        let log = channel(&mut w, "rcl_interfaces/msg/Log", "/log");
        let mut events: Vec<(u64, u16)> = (0..40).map(|i| (i * 10_000_000, a)).collect();
        events.extend((0..7).map(|i| (1_000_000_000 + i * 50_000_000, b)));
        events.extend((0..5).map(|i| (i * 3_000_000 + 5, log)));
        events.sort();
        for (i, (t, c)) in events.into_iter().enumerate() {
            let h = mcap::records::MessageHeader {
                channel_id: c,
                sequence: i as u32,
                log_time: t,
                publish_time: t,
            };
            w.write_to_known_channel(&h, &[i as u8; 700]).unwrap();
        }
        w.finish().unwrap();
        drop(w);
        out.into_inner()
    }

    #[test]
    fn a_bag_is_listed_from_its_index_as_a_pass_over_it_lists_it() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("x.mcap");
        let write = |o: mcap::WriteOptions| {
            let b = indexed_bag(o);
            std::fs::write(&f, &b).unwrap();
            b
        };
        // Chunks of a few messages each (so each topic spans several),
        // compressed or not: the index gives what a pass gives.
        for compression in [None, Some(mcap::Compression::Zstd)] {
            let options = mcap::WriteOptions::new()
                .compression(compression)
                .chunk_size(Some(3000));
            let bag = write(options);
            let indexed = indexed_tallies(&f).expect("an indexed bag");
            assert_eq!(indexed, scanned_tallies(&f, 0).unwrap().0);
            assert_eq!(indexed["/a"].count, 40);
            assert_eq!(
                (indexed["/b"].first, indexed["/b"].last),
                (1_000_000_000, 1_300_000_000)
            );
            let listed = image_topics(&f).unwrap();
            assert_eq!(listed.len(), 2);
            assert!((listed[0].rate_hz - 100.0).abs() < 1e-9, "{listed:?}");
            assert!((listed[1].rate_hz - 20.0).abs() < 1e-9, "{listed:?}");
            // The messages themselves are not read: with a chunk in the
            // middle damaged, the listing is the same (reading its frames
            // would name the damage).
            let summary = mcap::Summary::read(&bag).unwrap().unwrap();
            let chunk = &summary.chunk_indexes[summary.chunk_indexes.len() / 2];
            let (start, len) = (
                chunk.chunk_start_offset as usize,
                chunk.chunk_length as usize,
            );
            let mut damaged = bag.clone();
            damaged[start + 60..start + len].fill(0xAB);
            std::fs::write(&f, &damaged).unwrap();
            assert_eq!(image_topics(&f).unwrap(), listed);
            assert!(scanned_tallies(&f, 0).is_err());
        }
        // Bags without a whole index are read through, with the same
        // result: no message indexes, no statistics, no chunks, no
        // summary (a recording cut short).
        for options in [
            mcap::WriteOptions::new().emit_message_indexes(false),
            mcap::WriteOptions::new().emit_statistics(false),
            mcap::WriteOptions::new().use_chunks(false),
            mcap::WriteOptions::new().emit_summary_records(false),
        ] {
            let bag = write(options);
            assert!(indexed_tallies(&f).is_none());
            let listed = image_topics(&f).unwrap();
            assert_eq!(listed.iter().map(|t| t.count).collect::<Vec<_>>(), [40, 7]);
            let cut = &bag[..bag.len() - 40];
            std::fs::write(&f, cut).unwrap();
            assert!(indexed_tallies(&f).is_none());
        }
        // Cut before its first message (the magic and header only): an
        // error, alone; the last split of a bag folder, nothing to add.
        let bag = write(mcap::WriteOptions::new());
        std::fs::write(&f, &bag[..30]).unwrap();
        for e in [image_topics(&f).unwrap_err(), first_frame_error(&f, "/a")] {
            assert!(
                e.to_string().contains(
                    "x.mcap: not a readable MCAP bag: it ends before its first complete message"
                ),
                "{e}"
            );
        }
        let folder = dir.path().join("rec");
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(
            folder.join("metadata.yaml"),
            "rosbag2_bagfile_information:\n",
        )
        .unwrap();
        std::fs::write(folder.join("rec_0.mcap"), &bag).unwrap();
        std::fs::write(folder.join("rec_1.mcap"), &bag[..30]).unwrap();
        let listed = image_topics(&folder).unwrap();
        assert_eq!(listed.iter().map(|t| t.count).collect::<Vec<_>>(), [40, 7]);
    }

    /// An MCAP file of JSON messages: per topic, its schema's name and
    /// messages, logged a second apart from `t0`.
    fn json_bag(path: &Path, topics: &[(&str, &str, Vec<serde_json::Value>)], t0: u32) {
        let mut out = std::io::Cursor::new(Vec::new());
        let mut writer = mcap::Writer::new(&mut out).unwrap();
        for (topic, schema, messages) in topics {
            let s = writer.add_schema(schema, "jsonschema", b"{}").unwrap();
            let c = writer
                .add_channel(s, topic, "json", &BTreeMap::new())
                .unwrap();
            for (i, message) in (0..).zip(messages) {
                let h = mcap::records::MessageHeader {
                    channel_id: c,
                    sequence: i,
                    log_time: u64::from(t0 + i) * 1_000_000_000,
                    publish_time: 0,
                };
                let data = serde_json::to_vec(message).unwrap();
                writer.write_to_known_channel(&h, &data).unwrap();
            }
        }
        writer.finish().unwrap();
        drop(writer);
        std::fs::write(path, out.into_inner()).unwrap();
    }

    /// The error of the first frame of `topic`.
    fn first_frame_error(path: &Path, topic: &str) -> Error {
        BagImages::open(path, topic)
            .unwrap()
            .next_frame()
            .err()
            .unwrap()
    }

    /// A `w x h` RGB test frame and its PNG.
    fn frame_and_png(w: u32, h: u32, seed: u32) -> (Vec<u8>, Vec<u8>) {
        let px: Vec<u8> = (0..w * h * 3).map(|i| (i * seed % 251) as u8).collect();
        let mut png = Vec::new();
        image::RgbImage::from_raw(w, h, px.clone())
            .unwrap()
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        (px, png)
    }

    #[test]
    fn foxglove_images_in_json_are_read() {
        // Foxglove's JSON schemas, as a recorder logging plain JSON
        // writes them: bytes in base64, stamps as {sec, nsec}, fields the
        // schema does not name ignored.
        use base64::Engine;
        let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("json.mcap");
        let (w, h) = (6u32, 4u32);
        let (px, png) = frame_and_png(w, h, 11);
        let t0 = 1_700_000_000u32;
        let raw = |i: u32| {
            serde_json::json!({
                "timestamp": {"sec": t0 + i, "nsec": 250_000_000},
                "frame_id": "cam",
                "width": w,
                "height": h,
                "encoding": "rgb8",
                "step": w * 3,
                "data": b64(&px),
                "note": "ignored",
            })
        };
        let compressed =
            |_: u32| serde_json::json!({"frame_id": "cam", "data": b64(&png), "format": "png"});
        let topics = [
            ("/raw", FOXGLOVE_RAW_IMAGE_TYPE, vec![raw(0), raw(1)]),
            (
                "/png",
                FOXGLOVE_COMPRESSED_IMAGE_TYPE,
                vec![compressed(0), compressed(1)],
            ),
        ];
        json_bag(&path, &topics, t0);
        for (topic, _, _) in &topics {
            let mut r = BagImages::open(&path, topic).unwrap();
            for i in 0..2 {
                let f = r.next_frame().unwrap().unwrap();
                assert_eq!(f.image.as_slice(), px.as_slice(), "{topic} {i}");
                // Its timestamp, else (the PNG's) its log time.
                let nsec = if *topic == "/raw" { 250_000_000 } else { 0 };
                assert_eq!(f.stamp_ns, (t0 + i) as i64 * 1_000_000_000 + nsec);
            }
            assert!(r.next_frame().unwrap().is_none());
        }
        // Data that is not base64: refused naming the message.
        let mut bad = raw(0);
        bad["data"] = "not base64!".into();
        json_bag(&path, &[("/raw", FOXGLOVE_RAW_IMAGE_TYPE, vec![bad])], t0);
        let e = first_frame_error(&path, "/raw").to_string();
        assert!(
            e.contains(
                "json.mcap: topic /raw, message 0: not a valid foxglove.RawImage message: Invalid"
            ),
            "{e}"
        );
    }

    #[test]
    fn frames_the_foxglove_sdk_records_are_read() {
        use foxglove::messages::{CompressedImage as FoxCompressed, RawImage, Timestamp};
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sdk.mcap");
        let (w, h) = (16u32, 8u32);
        let (px, png) = frame_and_png(w, h, 7);
        // Recorded as a Foxglove SDK user records: a context, its MCAP
        // writer, a typed channel per topic. The BGR frame's rows padded.
        let t0 = 1_700_000_000u32;
        let ctx = foxglove::Context::new();
        let writer = ctx.mcap_writer().create_new_buffered_file(&path).unwrap();
        let raw = ctx.channel_builder("/cam/raw").build::<RawImage>();
        let jpeg = ctx.channel_builder("/cam/png").build::<FoxCompressed>();
        let bgr: Vec<u8> = px
            .chunks(w as usize * 3)
            .flat_map(|row| {
                let mut r: Vec<u8> = row.chunks(3).flat_map(|p| [p[2], p[1], p[0]]).collect();
                r.extend([0; 4]);
                r
            })
            .collect();
        for i in 0..3u32 {
            let stamp = Timestamp::new(t0 + i, 0);
            raw.log_with_time(
                &RawImage {
                    timestamp: Some(stamp),
                    frame_id: "cam".into(),
                    width: w,
                    height: h,
                    encoding: "bgr8".into(),
                    step: w * 3 + 4,
                    data: bgr.clone().into(),
                },
                stamp,
            );
            jpeg.log_with_time(
                &FoxCompressed {
                    timestamp: None,
                    frame_id: "cam".into(),
                    data: png.clone().into(),
                    format: "png".into(),
                },
                stamp,
            );
        }
        writer.close().unwrap();
        let topics = image_topics(&path).unwrap();
        let listed: Vec<_> = topics
            .iter()
            .map(|t| (t.topic.as_str(), t.message_type.as_str(), t.count))
            .collect();
        assert_eq!(
            listed,
            [
                ("/cam/png", FOXGLOVE_COMPRESSED_IMAGE_TYPE, 3),
                ("/cam/raw", FOXGLOVE_RAW_IMAGE_TYPE, 3)
            ]
        );
        for topic in ["/cam/raw", "/cam/png"] {
            let mut r = BagImages::open(&path, topic).unwrap();
            for i in 0..3 {
                let f = r.next_frame().unwrap().unwrap();
                assert_eq!(f.image.as_slice(), px.as_slice(), "{topic} {i}");
                // The message's timestamp; its log time when it has none.
                assert_eq!(f.stamp_ns, (t0 + i) as i64 * 1_000_000_000, "{topic} {i}");
            }
            assert!(r.next_frame().unwrap().is_none());
        }
        // Neither protobuf nor JSON, or not a valid message: refused by
        // name.
        let bad = dir.path().join("bad.mcap");
        let mut out = std::io::Cursor::new(Vec::new());
        let mut w = mcap::Writer::new(&mut out).unwrap();
        let s = w
            .add_schema(FOXGLOVE_RAW_IMAGE_TYPE, "protobuf", b"")
            .unwrap();
        let flat = w
            .add_channel(s, "/flatbuffer", "flatbuffer", &BTreeMap::new())
            .unwrap();
        let json = w.add_channel(s, "/json", "json", &BTreeMap::new()).unwrap();
        let garbage = w
            .add_channel(s, "/garbage", "protobuf", &BTreeMap::new())
            .unwrap();
        for (channel, data) in [
            (flat, &b"{}"[..]),
            (json, &b"{\"width\": 2}"[..]),
            (garbage, &[0xff; 12][..]),
        ] {
            let h = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: 0,
                log_time: 1,
                publish_time: 1,
            };
            w.write_to_known_channel(&h, data).unwrap();
        }
        w.finish().unwrap();
        drop(w);
        std::fs::write(&bad, out.into_inner()).unwrap();
        for (topic, want) in [
            (
                "/flatbuffer",
                "topic /flatbuffer: foxglove.RawImage in message encoding \"flatbuffer\"; it is read in protobuf, as the Foxglove SDK writes it, or json",
            ),
            (
                "/json",
                "topic /json, message 0: not a valid foxglove.RawImage message: missing field `frame_id`",
            ),
            (
                "/garbage",
                "topic /garbage, message 0: not a valid foxglove.RawImage message",
            ),
        ] {
            let e = first_frame_error(&bad, topic);
            assert!(e.to_string().contains(want), "{e}");
        }
    }

    #[test]
    fn ros1_messages_in_mcap_are_listed_and_refused_with_the_command_that_converts_them() {
        // As `mcap convert recording.bag recording.mcap` writes a ROS 1
        // bag: ros1msg schemas, ros1 messages.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("converted.mcap");
        let mut out = std::io::Cursor::new(Vec::new());
        let mut w = mcap::Writer::new(&mut out).unwrap();
        let s = w.add_schema("sensor_msgs/Image", "ros1msg", b"").unwrap();
        let c = w.add_channel(s, "/cam", "ros1", &BTreeMap::new()).unwrap();
        let h = mcap::records::MessageHeader {
            channel_id: c,
            sequence: 0,
            log_time: 1,
            publish_time: 1,
        };
        w.write_to_known_channel(&h, &[0; 40]).unwrap();
        w.finish().unwrap();
        drop(w);
        std::fs::write(&path, out.into_inner()).unwrap();
        assert_eq!(only_image_topic(&path).unwrap(), "/cam");
        let e = first_frame_error(&path, "/cam").to_string();
        assert!(
            e.contains(
                "topic /cam: carries ROS 1 messages (sensor_msgs/Image in encoding \"ros1\")"
            ) && e.contains("rosbags-convert --src BAG --dst NEW_FOLDER --dst-storage mcap"),
            "{e}"
        );
    }

    #[test]
    fn other_bag_formats_are_told_by_their_first_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("x.mcap");
        std::fs::write(&f, b"SQLite format 3\0...").unwrap();
        let e = other_bag_format(&f).unwrap().to_string();
        assert!(
            e.contains(
                "an SQLite database: a ROS 2 bag in SQLite storage is read as rosbag2 names it"
            ),
            "{e}"
        );
        let db3 = dir.path().join("x.db3");
        std::fs::write(&db3, b"SQLite format 3\0...").unwrap();
        assert!(other_bag_format(&db3).is_none(), "read as a bag");
        std::fs::write(&f, b"#ROSBAG V2.0\n").unwrap();
        let e = other_bag_format(&f).unwrap().to_string();
        assert!(
            e.contains("a ROS 1 bag") && e.contains(&format!("--src {}", f.display())),
            "{e}"
        );
        std::fs::write(&f, b"\x89MCAP0\r\n").unwrap();
        assert!(other_bag_format(&f).is_none());
        std::fs::write(&f, b"").unwrap();
        assert!(other_bag_format(&f).is_none());
    }
}
