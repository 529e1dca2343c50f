//! One frame's results as ROS 2 messages ([`FrameMessages`]) and an MCAP
//! file of them ([`McapResults`]).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use tactile_core::image_io::RgbImage;
use tactile_pipeline::FrameRecord;
use tactile_pipeline::overlay::FrameViews;

use crate::mcap_file::McapFile;
use crate::messages::{
    Color, Header, Image, ImageAnnotations, PalpationResult, Point2, PointsAnnotation,
    TextAnnotation, Time, to_cdr_with_capacity,
};
use crate::schemas::{self, Schema};
use crate::{Error, Result};

/// The camera frame every message names.
pub const FRAME_ID: &str = "tactile_sensor";

/// The channels results go to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Topic {
    /// The input frame, rgb8 (when asked).
    Image,
    /// The record.
    Result,
    /// The kept region in the segmenter's window, mono8.
    TendonMask,
    /// The depth network's map, 32FC1 mm.
    Depth,
    /// A calibrated sensor's indentation, 32FC1 mm.
    Indentation,
    /// The decision and direction drawn over the tendon mask.
    Annotations,
}

impl Topic {
    /// Every topic, in the order channels are registered.
    pub const ALL: [Topic; 6] = [
        Topic::Image,
        Topic::Result,
        Topic::TendonMask,
        Topic::Depth,
        Topic::Indentation,
        Topic::Annotations,
    ];

    /// The topics a run of `pipeline` can write ([`Topic::written`]). A
    /// file declares these and no other, so a reader never lists a topic
    /// the run could not fill.
    pub fn written_by(pipeline: &tactile_pipeline::Pipeline, with_frames: bool) -> Vec<Topic> {
        Topic::written(
            pipeline.palpation.is_some(),
            pipeline.sensor.is_some(),
            with_frames,
        )
    }

    /// The topics written by a pipeline with or without paper B's models
    /// (`palpation`: the tendon mask and depth map) and a calibrated
    /// `sensor` (the indentation), with the input frames or not: the record
    /// and its annotations always.
    pub fn written(palpation: bool, sensor: bool, with_frames: bool) -> Vec<Topic> {
        Topic::ALL
            .into_iter()
            .filter(|t| match t {
                Topic::Image => with_frames,
                Topic::TendonMask | Topic::Depth => palpation,
                Topic::Indentation => sensor,
                Topic::Result | Topic::Annotations => true,
            })
            .collect()
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Topic::Image => "/tactile/image",
            Topic::Result => "/tactile/result",
            Topic::TendonMask => "/tactile/tendon_mask",
            Topic::Depth => "/tactile/depth",
            Topic::Indentation => "/tactile/indentation",
            Topic::Annotations => "/tactile/annotations",
        }
    }

    /// Its message type and schema.
    pub fn schema(self) -> Schema {
        match self {
            Topic::Result => schemas::palpation_result(),
            Topic::Annotations => schemas::image_annotations(),
            _ => schemas::image(),
        }
    }
}

/// One frame's results, encoded: `(topic, CDR bytes)` in [`Topic::ALL`]
/// order, with the stamp they carry.
#[derive(Debug, Clone)]
pub struct FrameMessages {
    /// The input frame's stamp, nanoseconds since the epoch.
    pub stamp_ns: i64,
    /// The messages.
    pub messages: Vec<(Topic, Vec<u8>)>,
}

fn nan_or<T: Into<f64>>(v: Option<T>) -> f64 {
    v.map_or(f64::NAN, Into::into)
}

fn nan_or32(v: Option<f32>) -> f32 {
    v.unwrap_or(f32::NAN)
}

fn encode<T: serde::Serialize>(topic: Topic, msg: &T) -> Result<Vec<u8>> {
    encode_sized(topic, msg, 256)
}

fn encode_image(topic: Topic, msg: &Image<'_>) -> Result<Vec<u8>> {
    encode_sized(topic, msg, msg.data.len() + 256)
}

fn encode_sized<T: serde::Serialize>(topic: Topic, msg: &T, capacity: usize) -> Result<Vec<u8>> {
    to_cdr_with_capacity(msg, capacity).map_err(|message| Error::Encode {
        topic: topic.name().into(),
        message,
    })
}

fn image_msg<'a>(
    header: &Header,
    width: usize,
    height: usize,
    encoding: &str,
    data: &'a [u8],
) -> Image<'a> {
    Image {
        header: header.clone(),
        height: height as u32,
        width: width as u32,
        encoding: encoding.into(),
        is_bigendian: 0,
        step: (data.len() / height.max(1)) as u32,
        data,
    }
}

fn f32_bytes(values: &[f32], scale: f32) -> Vec<u8> {
    values
        .iter()
        .flat_map(|v| (v * scale).to_le_bytes())
        .collect()
}

/// `foxglove_msgs/PointsAnnotation`'s `LINE_LIST`.
const LINE_LIST: u8 = 4;
const RED: Color = Color {
    r: 0.95,
    g: 0.1,
    b: 0.1,
    a: 1.0,
};
const CLEAR: Color = Color {
    r: 0.0,
    g: 0.0,
    b: 0.0,
    a: 0.0,
};
const SHADE: Color = Color {
    r: 0.0,
    g: 0.0,
    b: 0.0,
    a: 0.6,
};
const WHITE: Color = Color {
    r: 1.0,
    g: 1.0,
    b: 1.0,
    a: 1.0,
};

impl FrameMessages {
    /// The messages of one frame: its record, what the models saw
    /// (`views`), and the input `frame` itself when given. The stamp is the
    /// record's (a bag's header stamp), else the time now.
    pub fn encode(
        record: &FrameRecord,
        views: Option<&FrameViews>,
        frame: Option<&RgbImage>,
    ) -> Result<Self> {
        let stamp_ns = checked_stamp(&record.frame, record.stamp_ns.unwrap_or_else(now_ns))?;
        let header = Header {
            stamp: Time::from_nanos(stamp_ns),
            frame_id: FRAME_ID.into(),
        };
        let mut messages = Vec::with_capacity(Topic::ALL.len());
        if let Some(img) = frame {
            let m = image_msg(&header, img.width(), img.height(), "rgb8", img.as_slice());
            messages.push((Topic::Image, encode_image(Topic::Image, &m)?));
        }
        let r = record;
        let result = PalpationResult {
            header: header.clone(),
            frame: r.frame.clone(),
            tendon: r.tendon,
            tendon_raw: r.tendon_raw,
            score: r.score,
            has_direction: r.direction_deg.is_some(),
            direction_deg: nan_or(r.direction_deg),
            anisotropy: nan_or(r.anisotropy),
            no_direction: r.no_direction.clone().unwrap_or_default(),
            mask_area_px: r.mask_area_px as u64,
            depth_min_mm: nan_or32(r.depth_min_mm),
            depth_mean_mm: nan_or32(r.depth_mean_mm),
            depth_max_mm: nan_or32(r.depth_max_mm),
            depth_maps: match (r.depth_maps, r.depth_mean_mm) {
                (Some(d), _) => d.name().to_string(),
                (None, Some(_)) => tactile_core::spec::DepthMaps::Distance.name().to_string(),
                (None, None) => String::new(),
            },
            indentation_peak_mm: nan_or32(r.indentation_peak_mm),
            contact_area_mm2: nan_or32(r.contact_area_mm2),
            out_of_distribution: r.out_of_distribution,
            gate: r.gate.map(|g| g.name().to_string()).unwrap_or_default(),
            input_score: nan_or32(r.input_score),
            ms_prepare: r.ms_prepare,
            ms_detect: r.ms_detect,
            ms_segment: nan_or(r.ms_segment),
            ms_depth: nan_or(r.ms_depth),
            ms_reconstruct: nan_or(r.ms_reconstruct),
            ms_total: r.ms_total,
        };
        messages.push((Topic::Result, encode(Topic::Result, &result)?));
        let tendon = views.and_then(|v| v.tendon.as_ref());
        if let Some(t) = tendon {
            let mask: Vec<u8> = t.region.iter().map(|&k| if k { 255 } else { 0 }).collect();
            let m = image_msg(&header, t.side, t.side, "mono8", &mask);
            messages.push((Topic::TendonMask, encode_image(Topic::TendonMask, &m)?));
            let [w, h] = t.depth_size;
            let depth = f32_bytes(&t.depth_mm, 1.0);
            let m = image_msg(&header, w, h, "32FC1", &depth);
            messages.push((Topic::Depth, encode_image(Topic::Depth, &m)?));
        }
        if let Some(s) = views.and_then(|v| v.indentation.as_ref()) {
            let bytes = f32_bytes(&s.map.indentation_m, 1e3);
            let m = image_msg(&header, s.map.width, s.map.height, "32FC1", &bytes);
            messages.push((Topic::Indentation, encode_image(Topic::Indentation, &m)?));
        }
        let mut annotations = ImageAnnotations::default();
        annotations.texts.push(TextAnnotation {
            timestamp: header.stamp,
            position: Point2 { x: 4.0, y: 4.0 },
            text: match (r.tendon, r.gate) {
                (_, Some(g)) => format!("{} frame: no tendon", g.name()),
                (true, _) => format!(
                    "tendon p={:.2}{}",
                    r.score,
                    r.direction_deg
                        .map(|d| format!(" {d:.0} deg"))
                        .unwrap_or_default()
                ),
                (false, _) => format!("no tendon p={:.2}", r.score),
            },
            font_size: 12.0,
            text_color: WHITE,
            background_color: SHADE,
        });
        if let Some(t) = tendon
            && let Some((deg, (cx, cy))) = t.direction
        {
            // The same line as the overlay PNG: through the centroid, in
            // the mask's pixels (their corners at integers, hence the 0.5).
            let (sn, cs) = deg.to_radians().sin_cos();
            let half = 0.45 * t.side as f64;
            let (px, py) = (cx + 0.5, cy + 0.5);
            annotations.points.push(PointsAnnotation {
                timestamp: header.stamp,
                r#type: LINE_LIST,
                points: vec![
                    Point2 {
                        x: px - cs * half,
                        y: py - sn * half,
                    },
                    Point2 {
                        x: px + cs * half,
                        y: py + sn * half,
                    },
                ],
                outline_color: RED,
                outline_colors: Vec::new(),
                fill_color: CLEAR,
                thickness: 2.0,
            });
        }
        messages.push((
            Topic::Annotations,
            encode(Topic::Annotations, &annotations)?,
        ));
        Ok(Self { stamp_ns, messages })
    }
}

/// The latest stamp a ROS 2 header holds: `builtin_interfaces/Time`'s
/// `sec` is an int32, so 2038-01-19 03:14:07.999999999.
pub const MAX_STAMP_NS: i64 = i32::MAX as i64 * 1_000_000_000 + 999_999_999;

/// `stamp_ns` of `frame` if a header and MCAP's log time can both hold it: MCAP's
/// time is unsigned, a header's seconds an int32. Outside that, a stamp
/// would be written as another time (before 1970 as 1970 in the log, past
/// 2038 wrapped in the header), so it is refused, naming it.
pub fn checked_stamp(frame: &str, stamp_ns: i64) -> Result<i64> {
    match (0..=MAX_STAMP_NS).contains(&stamp_ns) {
        true => Ok(stamp_ns),
        false => Err(tactile_core::Error::Invalid(format!(
            "frame {frame}: stamp_ns {stamp_ns}: a stamp must be 0 (1970) to {MAX_STAMP_NS} (2038, the last second a ROS 2 header's int32 holds) nanoseconds since the epoch; was it given in other units, or as a time before 1970?"
        ))
        .into()),
    }
}

pub(crate) fn now_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as i64)
}

/// Results of a run as an MCAP file of ROS 2 messages, written to a
/// temporary file beside `path` and moved there by [`McapResults::finish`]:
/// an error or an interrupt leaves no partial file.
pub struct McapResults {
    file: McapFile,
    channels: BTreeMap<Topic, u16>,
    frames: u64,
}

impl McapResults {
    /// Start the file that will be `path`, its `topics` registered now
    /// (those a run can write, [`Topic::written_by`]), so a reader lists
    /// them even when a run has no tendon frame. A topic not among them is
    /// registered when its first message comes.
    pub fn create(path: &Path, topics: &[Topic]) -> Result<Self> {
        let mut results = Self {
            file: McapFile::create(path)?,
            channels: BTreeMap::new(),
            frames: 0,
        };
        for &topic in topics {
            results.channel(topic)?;
        }
        Ok(results)
    }

    /// The channel of `topic`, registered on first use.
    fn channel(&mut self, topic: Topic) -> Result<u16> {
        if let Some(&id) = self.channels.get(&topic) {
            return Ok(id);
        }
        let id = self.file.channel(topic.name(), &topic.schema())?;
        self.channels.insert(topic, id);
        Ok(id)
    }

    /// Write one frame's messages, logged at their stamp.
    pub fn write(&mut self, frame: &FrameMessages) -> Result<()> {
        for (topic, data) in &frame.messages {
            let channel = self.channel(*topic)?;
            self.file.write(channel, frame.stamp_ns, data)?;
        }
        self.frames += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Close the file (its summary and index) and move it into place.
    pub fn finish(self) -> Result<PathBuf> {
        self.file.finish()
    }
}

/// Where a run's results go besides its JSON Lines: an MCAP file, a live
/// view, or both, fed per frame from [`tactile_pipeline::run()`]'s sink.
#[derive(Default)]
pub struct RobotOutputs {
    /// The MCAP file of results.
    pub mcap: Option<McapResults>,
    /// The Foxglove live view.
    pub live: Option<crate::live::LiveView>,
    /// Also write (and serve) the input frames on `/tactile/image`.
    pub with_frames: bool,
}

/// What the robot outputs did over a run.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct RobotSummary {
    /// The MCAP file written, and its frames.
    pub mcap: Option<(PathBuf, u64)>,
    /// Frames handed to the live view.
    pub live_sent: u64,
    /// Frames the live view dropped because its thread was behind.
    pub live_dropped: u64,
}

impl RobotOutputs {
    /// Whether there is anything to do per frame.
    pub fn is_empty(&self) -> bool {
        self.mcap.is_none() && self.live.is_none()
    }

    /// One frame of a run.
    pub fn handle(&mut self, item: &tactile_pipeline::RunItem<'_>) -> Result<()> {
        let watched = self.live.as_ref().is_some_and(|l| l.watched());
        if self.mcap.is_none() && !watched {
            return Ok(());
        }
        let frame = self.with_frames.then_some(item.frame);
        let messages = FrameMessages::encode(item.record, item.views, frame)?;
        if let Some(m) = self.mcap.as_mut() {
            m.write(&messages)?;
        }
        if let (Some(l), true) = (&self.live, watched) {
            l.publish(messages);
        }
        Ok(())
    }

    /// Close the file (moving it into place) and the live view.
    pub fn finish(mut self) -> Result<RobotSummary> {
        let mut s = RobotSummary::default();
        if let Some(m) = self.mcap.take() {
            let frames = m.frames();
            s.mcap = Some((m.finish()?, frames));
        }
        if let Some(mut l) = self.live.take() {
            l.close();
            s.live_sent = l.sent();
            s.live_dropped = l.dropped();
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped Foxglove layout shows only channels the toolkit writes.
    #[test]
    fn the_foxglove_layout_names_only_our_topics() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../docs/foxglove-layout.json"
        );
        let text = std::fs::read_to_string(path).expect("docs/foxglove-layout.json");
        let layout: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
        let names: Vec<&str> = Topic::ALL.iter().map(|t| t.name()).collect();
        let mut seen = 0;
        let mut check = |s: &str| {
            let topic = s.split('.').next().unwrap_or(s);
            if topic.starts_with("/") {
                assert!(names.contains(&topic), "{topic} is not one of {names:?}");
                seen += 1;
            }
        };
        fn walk(v: &serde_json::Value, f: &mut dyn FnMut(&str)) {
            match v {
                serde_json::Value::String(s) => f(s),
                serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, f)),
                serde_json::Value::Object(o) => o.iter().for_each(|(k, x)| {
                    f(k);
                    walk(x, f)
                }),
                _ => {}
            }
        }
        walk(&layout["configById"], &mut check);
        assert!(seen >= 8, "{seen}");
        // Every panel in the mosaic is configured.
        let ids: Vec<String> = layout["configById"]
            .as_object()
            .map(|o| o.keys().cloned().collect())
            .unwrap_or_default();
        let mut leaves = Vec::new();
        fn leaves_of(v: &serde_json::Value, out: &mut Vec<String>) {
            match v {
                serde_json::Value::String(s) => out.push(s.clone()),
                serde_json::Value::Object(o) => {
                    for k in ["first", "second"] {
                        if let Some(x) = o.get(k) {
                            leaves_of(x, out);
                        }
                    }
                }
                _ => {}
            }
        }
        leaves_of(&layout["layout"], &mut leaves);
        leaves.sort();
        let mut ids_sorted = ids.clone();
        ids_sorted.sort();
        assert_eq!(leaves, ids_sorted);
    }

    /// A stamp that a header or MCAP's log time cannot hold is refused,
    /// naming the frame, not written as another time.
    #[test]
    fn a_stamp_outside_what_ros_holds_is_refused() {
        let mut rec = FrameRecord::empty("000003");
        for (stamp, ok) in [
            (0, true),
            (MAX_STAMP_NS, true),
            (-1, false),
            (MAX_STAMP_NS + 1, false),
            (i64::MAX, false),
        ] {
            rec.stamp_ns = Some(stamp);
            let got = FrameMessages::encode(&rec, None, None);
            match ok {
                true => {
                    let m = got.expect("a stamp ROS holds");
                    let back: crate::messages::PalpationResult =
                        crate::messages::from_cdr(&m.messages[0].1).expect("decode");
                    assert_eq!((m.stamp_ns, back.header.stamp.nanos()), (stamp, stamp));
                }
                false => {
                    let e = got.map(|m| m.stamp_ns).expect_err("refused").to_string();
                    assert!(
                        e.starts_with(&format!(
                            "frame 000003: stamp_ns {stamp}: a stamp must be 0"
                        )),
                        "{e}"
                    );
                }
            }
        }
    }

    /// A frame's messages decode back to what was encoded.
    #[test]
    fn records_round_trip_through_cdr() {
        let mut rec = FrameRecord::empty("000007");
        rec.stamp_ns = Some(1_700_000_000_123_456_789);
        rec.tendon = true;
        rec.score = 0.75;
        rec.direction_deg = Some(42.0);
        let m = FrameMessages::encode(&rec, None, None).expect("encode");
        assert_eq!(m.stamp_ns, 1_700_000_000_123_456_789);
        let topics: Vec<Topic> = m.messages.iter().map(|(t, _)| *t).collect();
        assert_eq!(topics, [Topic::Result, Topic::Annotations]);
        let back: crate::messages::PalpationResult =
            crate::messages::from_cdr(&m.messages[0].1).expect("decode");
        assert_eq!(back.header.stamp.nanos(), 1_700_000_000_123_456_789);
        assert_eq!(
            (back.frame.as_str(), back.tendon, back.score),
            ("000007", true, 0.75)
        );
        assert!(back.has_direction && back.direction_deg == 42.0 && back.depth_mean_mm.is_nan());
        let ann: crate::messages::ImageAnnotations =
            crate::messages::from_cdr(&m.messages[1].1).expect("decode");
        assert_eq!(ann.texts[0].text, "tendon p=0.75 42 deg");
    }
}
