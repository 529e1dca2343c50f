#![allow(clippy::unwrap_used)]
//! Hostile bags, many of them: a valid bag (chunked and compressed, and
//! plain; ROS 2 Image and CompressedImage and Foxglove RawImage topics)
//! with its bytes flipped, cut, or its length fields set huge, is
//! read through every image topic. Each read ends in frames or an error
//! naming the file; none panics or allocates what a header claims. So is
//! an SQLite bag (`.db3`) with its bytes set, cut or zeroed. (The
//! libFuzzer target `fuzz/fuzz_targets/bag.rs` explores further.)

use std::collections::BTreeMap;
use std::path::Path;

use tactile_core::bag::messages::{CompressedImage, Header, Image, Time, to_cdr};
use tactile_core::bag::{BagImages, image_topics};
use tactile_core::rng::SampleRng;

/// One message's frame as an Image and as a PNG CompressedImage, in CDR.
type ImageAndPng = (Vec<u8>, Vec<u8>);

/// The test frame's pixels (16x8 rgb8), and for each of the three
/// messages `i` (stamped 10 + i s and i ns) the CDR of its Image and of
/// its PNG CompressedImage.
fn frames_and_cdr() -> (Vec<u8>, Vec<ImageAndPng>) {
    let px: Vec<u8> = (0..16 * 8 * 3).map(|i| (i * 7 % 251) as u8).collect();
    let mut png = Vec::new();
    image::RgbImage::from_raw(16, 8, px.clone())
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let messages = (0..3u32)
        .map(|i| {
            let header = Header {
                stamp: Time {
                    sec: 10 + i as i32,
                    nanosec: i,
                },
                frame_id: "cam".into(),
            };
            let img = Image {
                header: header.clone(),
                height: 8,
                width: 16,
                encoding: "rgb8".into(),
                is_bigendian: 0,
                step: 48,
                data: &px,
            };
            let c = CompressedImage {
                header,
                format: "png".into(),
                data: &png,
            };
            (to_cdr(&img).unwrap(), to_cdr(&c).unwrap())
        })
        .collect();
    (px, messages)
}

fn bag_bytes(chunked: bool) -> Vec<u8> {
    let (px, messages) = frames_and_cdr();
    let mut out = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::WriteOptions::new()
            .use_chunks(chunked)
            .create(&mut out)
            .unwrap();
        let s_img = w
            .add_schema("sensor_msgs/msg/Image", "ros2msg", b"")
            .unwrap();
        let s_cmp = w
            .add_schema("sensor_msgs/msg/CompressedImage", "ros2msg", b"")
            .unwrap();
        let raw = w
            .add_channel(s_img, "/raw", "cdr", &BTreeMap::new())
            .unwrap();
        let cmp = w
            .add_channel(s_cmp, "/png", "cdr", &BTreeMap::new())
            .unwrap();
        // As the Foxglove SDK records a raw frame: protobuf.
        let s_fox = w.add_schema("foxglove.RawImage", "protobuf", b"").unwrap();
        let fox = w
            .add_channel(s_fox, "/fox", "protobuf", &BTreeMap::new())
            .unwrap();
        for (i, (img, png)) in (0u32..).zip(messages) {
            let f = foxglove::messages::RawImage {
                timestamp: Some(foxglove::messages::Timestamp::new(10 + i, i)),
                frame_id: "cam".into(),
                width: 16,
                height: 8,
                encoding: "rgb8".into(),
                step: 48,
                data: px.clone().into(),
            };
            let mut fox_bytes = Vec::new();
            foxglove::Encode::encode(&f, &mut fox_bytes).unwrap();
            for (channel, data) in [(raw, img), (cmp, png), (fox, fox_bytes)] {
                let h = mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence: i,
                    log_time: u64::from(i),
                    publish_time: u64::from(i),
                };
                w.write_to_known_channel(&h, &data).unwrap();
            }
        }
        w.finish().unwrap();
    }
    out.into_inner()
}

/// Read every image topic of the bag at `path`; errors must name it.
fn read_all(path: &Path) -> usize {
    let name = path.display().to_string();
    let check = |e: tactile_core::Error| {
        let m = e.to_string();
        assert!(
            m.contains(&name),
            "an error that does not name the bag: {m}"
        );
    };
    let topics = match image_topics(path) {
        Ok(t) => t,
        Err(e) => {
            check(e);
            return 0;
        }
    };
    let mut frames = 0;
    for t in topics {
        let mut r = match BagImages::open(path, &t.topic) {
            Ok(r) => r,
            Err(e) => {
                check(e);
                continue;
            }
        };
        loop {
            match r.next_frame() {
                Ok(Some(f)) => {
                    assert!(f.image.width() * f.image.height() <= 33_177_600);
                    frames += 1;
                }
                Ok(None) => break,
                Err(e) => {
                    check(e);
                    break;
                }
            }
        }
    }
    frames
}

#[test]
fn mutated_bags_give_frames_or_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mutated.mcap");
    for chunked in [true, false] {
        let good = bag_bytes(chunked);
        std::fs::write(&path, &good).unwrap();
        assert_eq!(read_all(&path), 9, "the unmutated bag (chunked {chunked})");
        let mut rng = SampleRng::new(35, u64::from(chunked), 0);
        let mut pick = |n: usize| ((rng.uniform() * n as f64) as usize).min(n - 1);
        for round in 0..1500 {
            let mut b = good.clone();
            match round % 4 {
                // A few random bytes.
                0 | 1 => {
                    for _ in 0..1 + pick(4) {
                        let i = pick(b.len());
                        b[i] = pick(256) as u8;
                    }
                }
                // Cut anywhere.
                2 => b.truncate(pick(b.len())),
                // A length field (any 8 aligned bytes) set huge.
                _ => {
                    let i = pick(b.len() - 8);
                    let v = [u64::MAX, 1 << 40, 1 << 31, 0xFFFF_FFFF][pick(4)];
                    b[i..i + 8].copy_from_slice(&v.to_le_bytes());
                }
            }
            std::fs::write(&path, &b).unwrap();
            read_all(&path);
        }
    }
}

/// The same frames in rosbag2's SQLite storage: `/raw` Images and `/png`
/// CompressedImages, as `ros2 bag record` writes a `.db3` on Humble.
fn sqlite_bag_bytes(dir: &Path) -> Vec<u8> {
    let path = dir.join("good.db3");
    let db = rusqlite::Connection::open(&path).unwrap();
    db.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
             serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
             timestamp INTEGER NOT NULL, data BLOB NOT NULL);
         CREATE INDEX timestamp_idx ON messages (timestamp ASC);
         INSERT INTO topics VALUES (1, '/raw', 'sensor_msgs/msg/Image', 'cdr', '');
         INSERT INTO topics VALUES (2, '/png', 'sensor_msgs/msg/CompressedImage', 'cdr', '');",
    )
    .unwrap();
    let (_, messages) = frames_and_cdr();
    for (i, (img, png)) in (0u32..).zip(messages) {
        for (topic, data) in [(1, img), (2, png)] {
            db.execute(
                "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
                rusqlite::params![topic, i64::from(i), data],
            )
            .unwrap();
        }
    }
    drop(db);
    std::fs::read(&path).unwrap()
}

#[test]
fn mutated_sqlite_bags_give_frames_or_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let good = sqlite_bag_bytes(dir.path());
    let path = dir.path().join("mutated.db3");
    std::fs::write(&path, &good).unwrap();
    assert_eq!(read_all(&path), 6, "the unmutated bag");
    let mut rng = SampleRng::new(36, 0, 0);
    let mut pick = |n: usize| ((rng.uniform() * n as f64) as usize).min(n - 1);
    let rounds = std::env::var("TACTILE_FUZZ_RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(600);
    for round in 0..rounds {
        let mut b = good.clone();
        match round % 4 {
            // A few random bytes, half of them in the header and schema
            // (the first page).
            0 | 1 => {
                for _ in 0..1 + pick(4) {
                    let within = match pick(2) {
                        0 => b.len().min(4096),
                        _ => b.len(),
                    };
                    let i = pick(within);
                    b[i] = pick(256) as u8;
                }
            }
            // Cut anywhere.
            2 => b.truncate(pick(b.len())),
            // A run of zeros, as damage leaves a page.
            _ => {
                let i = pick(b.len());
                let end = (i + 1 + pick(4096)).min(b.len());
                b[i..end].fill(0);
            }
        }
        std::fs::write(&path, &b).unwrap();
        read_all(&path);
    }
    // Nothing was written beside the bag.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 2, "good.db3 and mutated.db3 alone");
}
