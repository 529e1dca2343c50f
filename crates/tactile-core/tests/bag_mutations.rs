#![allow(clippy::unwrap_used)]
//! Hostile bags, many of them: a valid bag (chunked and compressed, and
//! plain; ROS 2 Image and CompressedImage and Foxglove RawImage topics)
//! with its bytes flipped, cut, or its length fields set huge, is
//! read through every image topic. Each read ends in frames or an error
//! naming the file; none panics or allocates what a header claims. (The
//! libFuzzer target `fuzz/fuzz_targets/bag.rs` explores further.)

use std::collections::BTreeMap;
use std::path::Path;

use tactile_core::bag::messages::{CompressedImage, Header, Image, Time, to_cdr};
use tactile_core::bag::{BagImages, image_topics};
use tactile_core::rng::SampleRng;

fn bag_bytes(chunked: bool) -> Vec<u8> {
    let px: Vec<u8> = (0..16 * 8 * 3).map(|i| (i * 7 % 251) as u8).collect();
    let mut png = Vec::new();
    image::RgbImage::from_raw(16, 8, px.clone())
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
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
        for i in 0..3u32 {
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
            for (channel, data) in [
                (raw, to_cdr(&img).unwrap()),
                (cmp, to_cdr(&c).unwrap()),
                (fox, fox_bytes),
            ] {
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
