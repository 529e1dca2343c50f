//! Results into the robot stack, without ROS installed: what the palpation
//! pipeline makes of each frame as ROS 2 messages (CDR), written to an MCAP
//! file ([`McapResults`]) or served live to Foxglove ([`live`]). Both take
//! the same messages from [`FrameMessages`], so a file and a live view show
//! the same thing.
//!
//! Channels (all ROS 2 `cdr` with `ros2msg` schemas, shown by Foxglove and
//! RViz without plugins):
//! - `/tactile/image` (`sensor_msgs/msg/Image`, rgb8): the input frame, when asked;
//! - `/tactile/result` (`tactile_msgs/msg/PalpationResult`, this crate's
//!   `msg/PalpationResult.msg`): the decision, direction, depth statistics
//!   and timings;
//! - `/tactile/tendon_mask` (`sensor_msgs/msg/Image`, mono8): the kept
//!   region in the segmenter's window, on tendon frames;
//! - `/tactile/depth` (`sensor_msgs/msg/Image`, 32FC1, mm): the depth
//!   network's map, on tendon frames;
//! - `/tactile/indentation` (`sensor_msgs/msg/Image`, 32FC1, mm): a
//!   calibrated sensor's indentation;
//! - `/tactile/annotations` (`foxglove_msgs/msg/ImageAnnotations`): the
//!   decision as text and the direction as a line over the tendon mask.
//!
//! Every message carries the input frame's stamp (a bag's header stamp).
//! Paper A's estimates go to `/tactile/estimates`
//! (`tactile_msgs/msg/Estimates`, [`estimates`]).

#![deny(missing_docs)]

mod error;
pub mod estimates;
pub mod live;
mod mcap_file;
pub mod messages;
mod results;
pub mod schemas;
pub mod session;

pub use error::{Error, Result};
pub use results::{
    FrameMessages, MAX_STAMP_NS, McapResults, RobotOutputs, RobotSummary, Topic, checked_stamp,
};
pub use session::{RunReport, RunRequest, RunSession};
