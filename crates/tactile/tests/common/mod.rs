//! Helpers shared by the command-line test files.
#![allow(dead_code, clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use tactile_core::bag::messages::{Header, Image, Time, to_cdr};

/// A ROS 2 bag being written (MCAP, `cdr` messages) with one
/// `sensor_msgs/msg/Image` topic, as a camera driver records it.
pub struct ImageBag {
    /// The writer, for messages of other topics.
    pub writer: mcap::Writer<BufWriter<File>>,
    channel: u16,
    frame_id: String,
    sequence: u32,
}

impl ImageBag {
    /// A bag at `path` with Images on `topic`, their headers' `frame_id`
    /// `frame_id`.
    pub fn create(path: &Path, topic: &str, frame_id: &str) -> Self {
        Self::create_after(path, &[], topic, frame_id)
    }

    /// As [`ImageBag::create`], with channels for `others` (schema
    /// `std_msgs/msg/String`) defined first, so the image channel's id is
    /// `others.len() + 1` (channel ids are the file's own).
    pub fn create_after(path: &Path, others: &[&str], topic: &str, frame_id: &str) -> Self {
        let mut writer = mcap::Writer::new(BufWriter::new(File::create(path).unwrap())).unwrap();
        if !others.is_empty() {
            let s = writer
                .add_schema("std_msgs/msg/String", "ros2msg", b"")
                .unwrap();
            for t in others {
                writer.add_channel(s, t, "cdr", &BTreeMap::new()).unwrap();
            }
        }
        let schema = writer
            .add_schema("sensor_msgs/msg/Image", "ros2msg", b"")
            .unwrap();
        let channel = writer
            .add_channel(schema, topic, "cdr", &BTreeMap::new())
            .unwrap();
        Self {
            writer,
            channel,
            frame_id: frame_id.into(),
            sequence: 0,
        }
    }

    /// One Image stamped (and logged) at `stamp_ns`: `data` holds
    /// `height` rows of `width` pixels of `channels` bytes in `encoding`.
    pub fn write(&mut self, stamp_ns: i64, size: (u32, u32, u32), encoding: &str, data: &[u8]) {
        self.write_logged(stamp_ns, stamp_ns as u64, size, encoding, data);
    }

    /// As [`ImageBag::write`], its header stamped `stamp_ns` and the
    /// message logged at `log_time_ns`.
    pub fn write_logged(
        &mut self,
        stamp_ns: i64,
        log_time_ns: u64,
        (width, height, channels): (u32, u32, u32),
        encoding: &str,
        data: &[u8],
    ) {
        let msg = Image {
            header: Header {
                stamp: Time::from_nanos(stamp_ns),
                frame_id: self.frame_id.clone(),
            },
            height,
            width,
            encoding: encoding.into(),
            is_bigendian: 0,
            step: width * channels,
            data,
        };
        let header = mcap::records::MessageHeader {
            channel_id: self.channel,
            sequence: self.sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        self.sequence += 1;
        self.writer
            .write_to_known_channel(&header, &to_cdr(&msg).unwrap())
            .unwrap();
    }

    /// Close the bag (its summary and footer written).
    pub fn finish(mut self) {
        self.writer.finish().unwrap();
    }
}
