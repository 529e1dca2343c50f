//! ROS 2 bags in: the image topics of an MCAP file (`ros2 bag record`'s
//! default storage since Iron) read as frames, each with its header stamp,
//! without ROS installed. The container is read by the `mcap` crate and the
//! messages by a CDR deserialiser (`cdr-encoding`); nothing of either
//! format is written by hand here. `sensor_msgs/msg/Image` (rgb8, bgr8,
//! rgba8, bgra8, mono8, mono16) and `sensor_msgs/msg/CompressedImage`
//! (JPEG, PNG) are understood; anything else is refused naming the topic
//! and the message.
//!
//! The file is read a record at a time through `mcap`'s sans-I/O reader
//! (bounded memory whatever the bag's size); schemas and channels are kept
//! as they appear, and each message of the chosen topic becomes a frame.

pub mod messages;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::image_io::RgbImage;
use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::{Error, Result};
use messages::{COMPRESSED_IMAGE_TYPE, CompressedImage, IMAGE_TYPE, Image, from_cdr};

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
    /// The message's header stamp, nanoseconds since the epoch.
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

/// Records of a bag, one after another.
struct Records {
    path: PathBuf,
    file: File,
    reader: LinearReader,
    schemas: BTreeMap<u16, String>,
    channels: BTreeMap<u16, ChannelInfo>,
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

impl Records {
    fn open(path: &Path) -> Result<Self> {
        crate::image_io::expect_regular_file(path)?;
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let options = LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
        Ok(Self {
            path: path.to_path_buf(),
            file,
            reader: LinearReader::new_with_options(options),
            schemas: BTreeMap::new(),
            channels: BTreeMap::new(),
        })
    }

    fn container(&self, message: impl ToString) -> Error {
        container_error(&self.path, message)
    }

    /// The next record, `None` at the end of the file. A message's bytes
    /// are copied out only when it is on `topic` (others are skipped in
    /// place: listing a bag copies nothing).
    fn next(&mut self, topic: Option<&str>) -> Result<Option<Item>> {
        loop {
            let Some(event) = self.reader.next_event() else {
                return Ok(None);
            };
            match event.map_err(|e| container_error(&self.path, e))? {
                LinearReadEvent::ReadRequest(need) => {
                    let buf = self.reader.insert(need);
                    let n = self.file.read(buf).map_err(|e| Error::io(&self.path, e))?;
                    self.reader.notify_read(n);
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

/// True for the two image message types a bag's frames may be.
pub fn is_image_type(t: &str) -> bool {
    t == IMAGE_TYPE || t == COMPRESSED_IMAGE_TYPE
}

/// True for a path named like an MCAP file (`.mcap`).
pub fn is_bag_file(p: &Path) -> bool {
    p.extension()
        .and_then(|x| x.to_str())
        .is_some_and(|x| x.eq_ignore_ascii_case("mcap"))
}

/// Every image topic of the bag at `path` with its message count and rate
/// (one pass over the file), in name order.
pub fn image_topics(path: &Path) -> Result<Vec<BagTopic>> {
    let mut records = Records::open(path)?;
    // Per channel: count, first and last log time.
    let mut seen: BTreeMap<u16, (u64, u64, u64)> = BTreeMap::new();
    while let Some(item) = records.next(None)? {
        crate::interrupt::check()?;
        if let Item::Message {
            channel, log_time, ..
        } = item
        {
            let e = seen.entry(channel).or_insert((0, log_time, log_time));
            e.0 += 1;
            e.1 = e.1.min(log_time);
            e.2 = e.2.max(log_time);
        }
    }
    let mut topics: BTreeMap<String, BagTopic> = BTreeMap::new();
    for (id, c) in &records.channels {
        if !is_image_type(&c.message_type) {
            continue;
        }
        let (count, first, last) = seen.get(id).copied().unwrap_or((0, 0, 0));
        let t = topics.entry(c.topic.clone()).or_insert(BagTopic {
            topic: c.topic.clone(),
            message_type: c.message_type.clone(),
            count: 0,
            rate_hz: 0.0,
        });
        t.count += count;
        let span = last.saturating_sub(first) as f64 * 1e-9;
        if count > 1 && span > 0.0 {
            t.rate_hz = (count - 1) as f64 / span;
        }
    }
    Ok(topics.into_values().collect())
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
            "has no sensor_msgs/msg/Image or CompressedImage topic",
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

/// The frames of one image topic of a bag, in the order they were logged.
pub struct BagImages {
    records: Records,
    topic: String,
    index: u64,
}

impl BagImages {
    /// Read the frames of `topic` in the bag at `path`. The topic is
    /// checked as its channel appears: a topic of another message type or
    /// encoding is refused by name; one that never appears is refused at
    /// the end of the file.
    pub fn open(path: &Path, topic: &str) -> Result<Self> {
        Ok(Self {
            records: Records::open(path)?,
            topic: topic.to_string(),
            index: 0,
        })
    }

    /// The topic read.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    fn topic_error(&self, message: impl ToString) -> Error {
        bag_error(&self.records.path, Some(&self.topic), None, message)
    }

    fn message_error(&self, message: impl ToString) -> Error {
        bag_error(
            &self.records.path,
            Some(&self.topic),
            Some(self.index),
            message,
        )
    }

    /// The next frame, `None` after the last.
    pub fn next_frame(&mut self) -> Result<Option<BagFrame>> {
        loop {
            let Some(item) = self.records.next(Some(&self.topic))? else {
                if self.index == 0
                    && !self
                        .records
                        .channels
                        .values()
                        .any(|c| c.topic == self.topic)
                {
                    let mut names: Vec<&str> = self
                        .records
                        .channels
                        .values()
                        .filter(|c| is_image_type(&c.message_type))
                        .map(|c| c.topic.as_str())
                        .collect();
                    names.sort_unstable();
                    names.dedup();
                    return Err(self.topic_error(format!(
                        "not in the bag; its image topics: {}",
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join(", ")
                        }
                    )));
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
                    "carries {}, not {IMAGE_TYPE} or {COMPRESSED_IMAGE_TYPE}",
                    if c.message_type.is_empty() {
                        "messages without a schema"
                    } else {
                        &c.message_type
                    }
                )));
            }
            if c.encoding != "cdr" {
                return Err(self.topic_error(format!(
                    "message encoding {:?}, not ROS 2's cdr",
                    c.encoding
                )));
            }
            let (image, stamp) = if c.message_type == IMAGE_TYPE {
                let m: Image<'_> = from_cdr(&data).map_err(|e| self.message_error(e))?;
                (
                    m.to_rgb().map_err(|e| self.message_error(e))?,
                    m.header.stamp,
                )
            } else {
                let m: CompressedImage<'_> = from_cdr(&data).map_err(|e| self.message_error(e))?;
                (
                    m.to_rgb().map_err(|e| self.message_error(e))?,
                    m.header.stamp,
                )
            };
            let frame = BagFrame {
                image,
                stamp_ns: stamp.nanos(),
                log_time_ns: log_time,
                index: self.index,
            };
            self.index += 1;
            return Ok(Some(frame));
        }
    }
}
