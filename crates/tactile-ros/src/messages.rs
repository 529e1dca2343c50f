//! The messages written, as serde types for the CDR serialiser (the
//! image type is the one bags are read with, `tactile_core::bag::messages`).

use serde::{Deserialize, Serialize};
pub use tactile_core::bag::messages::{
    Header, Image, Time, from_cdr, to_cdr, to_cdr_with_capacity,
};

/// `tactile_msgs/msg/PalpationResult` (`msg/PalpationResult.msg`): one
/// frame's record; missing values are NaN.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PalpationResult {
    /// The input frame's stamp.
    pub header: Header,
    /// The frame's name.
    pub frame: String,
    /// The decision.
    pub tendon: bool,
    /// The detector's own threshold decision.
    pub tendon_raw: bool,
    /// Detector probability.
    pub score: f32,
    /// Whether a direction was measured.
    pub has_direction: bool,
    /// Direction, degrees in [0, 180).
    pub direction_deg: f64,
    /// Major / minor eigenvalue of the kept region.
    pub anisotropy: f64,
    /// Why a tendon frame has no direction.
    pub no_direction: String,
    /// Pixels of the kept region.
    pub mask_area_px: u64,
    /// Depth statistics in the sensing window, mm.
    pub depth_min_mm: f32,
    /// Mean depth, mm.
    pub depth_mean_mm: f32,
    /// Largest depth, mm.
    pub depth_max_mm: f32,
    /// `distance` or `indentation` ("" when the depth network did not run).
    pub depth_maps: String,
    /// A calibrated sensor's deepest indentation, mm.
    pub indentation_peak_mm: f32,
    /// A calibrated sensor's contact area, mm².
    pub contact_area_mm2: f32,
    /// Far outside the training frames.
    pub out_of_distribution: bool,
    /// The gate that answered (`blank`, `foreign`, or "").
    pub gate: String,
    /// The input statistics' distance from the training frames', spreads.
    pub input_score: f32,
    /// Stage times, ms.
    pub ms_prepare: f64,
    /// Detector, ms.
    pub ms_detect: f64,
    /// Segmenter and direction, ms.
    pub ms_segment: f64,
    /// Depth network, ms.
    pub ms_depth: f64,
    /// A calibrated sensor's reconstruction, ms.
    pub ms_reconstruct: f64,
    /// The whole frame, ms.
    pub ms_total: f64,
}

/// `foxglove_msgs/Point2`, pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Point2 {
    /// Column.
    pub x: f64,
    /// Row.
    pub y: f64,
}

/// `foxglove_msgs/Color`, each in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Color {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
    /// Opacity.
    pub a: f64,
}

/// `foxglove_msgs/CircleAnnotation`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CircleAnnotation {
    /// When.
    pub timestamp: Time,
    /// Centre.
    pub position: Point2,
    /// Diameter, pixels.
    pub diameter: f64,
    /// Line width, pixels.
    pub thickness: f64,
    /// Fill.
    pub fill_color: Color,
    /// Outline.
    pub outline_color: Color,
}

/// `foxglove_msgs/PointsAnnotation`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointsAnnotation {
    /// When.
    pub timestamp: Time,
    /// 1 points, 2 line loop, 3 line strip, 4 line list.
    pub r#type: u8,
    /// The points, pixels.
    pub points: Vec<Point2>,
    /// Line colour.
    pub outline_color: Color,
    /// Per-point colours (none here).
    pub outline_colors: Vec<Color>,
    /// Fill.
    pub fill_color: Color,
    /// Line width, pixels.
    pub thickness: f64,
}

/// `foxglove_msgs/TextAnnotation`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TextAnnotation {
    /// When.
    pub timestamp: Time,
    /// Where the text's corner is, pixels.
    pub position: Point2,
    /// The text.
    pub text: String,
    /// Font size, pixels.
    pub font_size: f64,
    /// Text colour.
    pub text_color: Color,
    /// Background.
    pub background_color: Color,
}

/// `foxglove_msgs/msg/ImageAnnotations`: drawn by Foxglove's image panel
/// over an image topic.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct ImageAnnotations {
    /// Circles.
    pub circles: Vec<CircleAnnotation>,
    /// Lines and points.
    pub points: Vec<PointsAnnotation>,
    /// Texts.
    pub texts: Vec<TextAnnotation>,
}
