//! Paper A's estimates as ROS 2 messages in MCAP: one
//! `tactile_msgs/msg/Estimates` per frame on `/tactile/estimates`
//! (`tactile perceive --out estimates.mcap`).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use tactile_estimate::{Column, Estimates};
use tactile_pipeline::tactip::Perception;

use crate::mcap_file::McapFile;
use crate::messages::{Header, Time, to_cdr};
use crate::results::{FRAME_ID, now_ns};
use crate::{Error, Result};

/// The topic estimates are written on.
pub const ESTIMATES_TOPIC: &str = "/tactile/estimates";

/// `tactile_msgs/msg/Estimates` (`msg/Estimates.msg`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimatesMsg {
    /// When it was written.
    pub header: Header,
    /// The frame's file.
    pub frame: String,
    /// Numeric estimates' names.
    pub names: Vec<String>,
    /// Their values.
    pub values: Vec<f64>,
    /// Classifier estimates' names.
    pub class_names: Vec<String>,
    /// Their answers.
    pub classes: Vec<String>,
}

/// Write what `tactile predict` made of its frames to `path`: ROS 2
/// messages for a name ending in `.mcap` ([`write_estimates`]), else CSV
/// (`file`, `stamp_ns` when the frames had stamps, every estimate).
pub fn write_perception(path: &Path, perception: &Perception) -> Result<PathBuf> {
    if tactile_core::bag::is_bag_file(path) {
        return write_estimates(
            path,
            &perception.files,
            perception.stamps_ns.as_deref(),
            &perception.estimates,
        );
    }
    perception.write_csv(path)?;
    Ok(path.to_path_buf())
}

/// Write `estimates` of `files` (one row per file) to `path` as MCAP,
/// staged and moved into place. Each message is stamped like its frame
/// when `stamps_ns` gives the frames' stamps (a bag's), else when written.
pub fn write_estimates(
    path: &Path,
    files: &[String],
    stamps_ns: Option<&[i64]>,
    estimates: &Estimates,
) -> Result<PathBuf> {
    let mut file = McapFile::create(path)?;
    let channel = file.channel(ESTIMATES_TOPIC, &crate::schemas::estimates())?;
    let mut last = 0i64;
    for (i, frame) in files.iter().enumerate() {
        let mut msg = EstimatesMsg {
            header: Header {
                stamp: Time::default(),
                frame_id: FRAME_ID.into(),
            },
            frame: frame.clone(),
            names: Vec::new(),
            values: Vec::new(),
            class_names: Vec::new(),
            classes: Vec::new(),
        };
        for (name, column) in &estimates.columns {
            match column {
                Column::Number(v) => {
                    msg.names.push(name.clone());
                    msg.values.push(v.get(i).copied().unwrap_or(f64::NAN));
                }
                Column::Class(v) => {
                    msg.class_names.push(name.clone());
                    msg.classes.push(v.get(i).cloned().unwrap_or_default());
                }
            }
        }
        let stamp = match stamps_ns.and_then(|s| s.get(i)) {
            Some(&s) => s,
            // Strictly increasing, so readers keep the frames' order.
            None => now_ns().max(last + 1),
        };
        last = stamp;
        msg.header.stamp = Time::from_nanos(stamp);
        let data = to_cdr(&msg).map_err(|message| Error::Encode {
            topic: ESTIMATES_TOPIC.into(),
            message,
        })?;
        file.write(channel, stamp, &data)?;
    }
    file.finish()
}
