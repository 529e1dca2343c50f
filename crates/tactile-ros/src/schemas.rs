//! The `ros2msg` schemas registered in the files and channels written:
//! each message's definition followed by those it uses, separated as
//! `ros2 bag record` writes them (a line of `=` and `MSG: pkg/Name`), so
//! any ROS 2 MCAP reader decodes the messages without ROS installed.

/// `builtin_interfaces/msg/Time`.
const TIME: &str = "int32 sec\nuint32 nanosec\n";

/// `std_msgs/msg/Header`.
const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";

/// `sensor_msgs/msg/Image`.
const IMAGE: &str = "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n";

/// `foxglove_msgs/msg/ImageAnnotations` and what it uses.
const IMAGE_ANNOTATIONS: &str = "foxglove_msgs/CircleAnnotation[] circles\nfoxglove_msgs/PointsAnnotation[] points\nfoxglove_msgs/TextAnnotation[] texts\n";
const CIRCLE_ANNOTATION: &str = "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\nfloat64 diameter\nfloat64 thickness\nfoxglove_msgs/Color fill_color\nfoxglove_msgs/Color outline_color\n";
const POINTS_ANNOTATION: &str = "uint8 UNKNOWN=0\nuint8 POINTS=1\nuint8 LINE_LOOP=2\nuint8 LINE_STRIP=3\nuint8 LINE_LIST=4\nbuiltin_interfaces/Time timestamp\nuint8 type\nfoxglove_msgs/Point2[] points\nfoxglove_msgs/Color outline_color\nfoxglove_msgs/Color[] outline_colors\nfoxglove_msgs/Color fill_color\nfloat64 thickness\n";
const TEXT_ANNOTATION: &str = "builtin_interfaces/Time timestamp\nfoxglove_msgs/Point2 position\nstring text\nfloat64 font_size\nfoxglove_msgs/Color text_color\nfoxglove_msgs/Color background_color\n";
const POINT2: &str = "float64 x\nfloat64 y\n";
const COLOR: &str = "float64 r\nfloat64 g\nfloat64 b\nfloat64 a\n";

/// `tactile_msgs/msg/PalpationResult`: the repository's `msg/PalpationResult.msg`.
pub const PALPATION_RESULT_MSG: &str = include_str!("../msg/PalpationResult.msg");

/// `tactile_msgs/msg/Estimates`: the repository's `msg/Estimates.msg`.
pub const ESTIMATES_MSG: &str = include_str!("../msg/Estimates.msg");

/// A message type and its `ros2msg` schema text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Schema {
    /// The ROS 2 type name (`sensor_msgs/msg/Image`).
    pub name: &'static str,
    /// Its definition followed by those it uses.
    pub text: String,
}

/// The full `ros2msg` text: `main`, then each `(type, definition)` it uses.
fn join(main: &str, deps: &[(&str, &str)]) -> String {
    let mut s = main.to_string();
    for (name, text) in deps {
        s.push_str("\n================================================================================\nMSG: ");
        s.push_str(name);
        s.push('\n');
        s.push_str(text);
    }
    s
}

/// `sensor_msgs/msg/Image`.
pub fn image() -> Schema {
    Schema {
        name: tactile_core::bag::messages::IMAGE_TYPE,
        text: join(
            IMAGE,
            &[
                ("std_msgs/Header", HEADER),
                ("builtin_interfaces/Time", TIME),
            ],
        ),
    }
}

/// `tactile_msgs/msg/PalpationResult`.
pub fn palpation_result() -> Schema {
    Schema {
        name: "tactile_msgs/msg/PalpationResult",
        text: join(
            PALPATION_RESULT_MSG,
            &[
                ("std_msgs/Header", HEADER),
                ("builtin_interfaces/Time", TIME),
            ],
        ),
    }
}

/// `foxglove_msgs/msg/ImageAnnotations`.
pub fn image_annotations() -> Schema {
    Schema {
        name: "foxglove_msgs/msg/ImageAnnotations",
        text: join(
            IMAGE_ANNOTATIONS,
            &[
                ("foxglove_msgs/CircleAnnotation", CIRCLE_ANNOTATION),
                ("foxglove_msgs/PointsAnnotation", POINTS_ANNOTATION),
                ("foxglove_msgs/TextAnnotation", TEXT_ANNOTATION),
                ("builtin_interfaces/Time", TIME),
                ("foxglove_msgs/Point2", POINT2),
                ("foxglove_msgs/Color", COLOR),
            ],
        ),
    }
}

/// `tactile_msgs/msg/Estimates`.
pub fn estimates() -> Schema {
    Schema {
        name: "tactile_msgs/msg/Estimates",
        text: join(
            ESTIMATES_MSG,
            &[
                ("std_msgs/Header", HEADER),
                ("builtin_interfaces/Time", TIME),
            ],
        ),
    }
}
