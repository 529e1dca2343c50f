//! ONNX models that stand alone: the graph takes the frame as a user has
//! it and gives what a user wants, so onnxruntime (or any ONNX runtime)
//! needs no toolkit code around it.
//!
//! An exported network takes normalised `[N, C, H, W]` float values and
//! gives raw outputs. [`make_standalone`] edits its graph: the input
//! becomes `frame`, `uint8` `[N, H, W, C]`, cast, scaled to `[0, 1]`,
//! normalised by the training statistics and transposed inside; the
//! output passes a sigmoid (a probability) or an affine map (a depth in
//! millimetres) and takes a name that says what it is. A detector's
//! graph also holds its gates ([`GateSpec`]): blank and foreign frames get
//! probability 0 and say which gate stopped them, and the decision is an
//! output, so the graph answers a frame as the toolkit does. The model's
//! own numbers (threshold, statistics, input size, toolkit version) go
//! into its metadata.

use onnx_ir::{AttributeProto, AttributeType, Message, ModelProto, NodeProto, TensorProto};

use crate::{Error, Result};

/// ONNX's element type codes used here.
const FLOAT: i32 = 1;
const UINT8: i32 = 2;
const UINT16: i32 = 4;
const INT64: i32 = 7;
const BOOL: i32 = 9;

/// What the standalone output is.
#[derive(Debug, Clone, PartialEq)]
pub enum StandaloneOutput {
    /// The sigmoid of the network's logits, named `name`.
    Probability {
        /// Output name (`tendon_probability`, `mask_probability`).
        name: String,
    },
    /// `raw * scale + offset`, named `name` (a depth in mm).
    Affine {
        /// Output name (`depth_mm`).
        name: String,
        /// Multiplier.
        scale: f32,
        /// Offset.
        offset: f32,
    },
}

/// How to wrap a network.
#[derive(Debug, Clone, PartialEq)]
pub struct StandaloneSpec {
    /// The frame's height and width the network takes.
    pub height: usize,
    /// See `height`.
    pub width: usize,
    /// Per-channel mean of the `[0, 1]` training pixels.
    pub mean: Vec<f32>,
    /// Per-channel standard deviation of the `[0, 1]` training pixels.
    pub std: Vec<f32>,
    /// The output.
    pub output: StandaloneOutput,
    /// Key-value pairs for the model's metadata.
    pub metadata: Vec<(String, String)>,
    /// Bits per channel of the frame: 8 (`uint8`) or 16 (`uint16`).
    pub input_bits: u8,
    /// Divide each channel by its median over these pixels (row-major
    /// indices into the `H x W` frame) and multiply by the level, before
    /// the statistics, as `tactile_preprocess::visuo::normalise_exposure`
    /// does; a channel whose median is under one 8-bit level is left alone.
    pub exposure_level: Option<ExposureLevel>,
    /// A detector's gates and decision, in the graph (with a
    /// [`StandaloneOutput::Probability`] output only).
    pub gates: Option<GateSpec>,
}

/// The gates a detector's frame meets before its network, and the rule
/// that turns its probability into a decision, as
/// `tactile_detect::TendonDetector::gate` and `answer` apply them. The
/// graph gains three outputs: `gate` (int64 `[N]`: 0 passed, 1 blank,
/// 2 foreign), `input_score` (float `[N]`, 0 without a profile) and
/// `tendon` (bool `[N]`); a gated frame's probability is 0.
#[derive(Debug, Clone, PartialEq)]
pub struct GateSpec {
    /// A frame is blank when every channel's standard deviation over the
    /// frame (in [0, 1] units) is below this.
    pub blank_std: f32,
    /// The input profile, when the detector has one.
    pub profile: Option<ProfileGate>,
    /// A tendon at probabilities >= this (see [`f32_at_or_above`]).
    pub threshold: f32,
}

/// The smallest `f32` at or above `t`: `p >= f32_at_or_above(t)` exactly
/// when `p as f64 >= t`, so a graph in `f32` decides as the toolkit does.
pub fn f32_at_or_above(t: f64) -> f32 {
    let f = t as f32;
    if (f as f64) < t { f.next_up() } else { f }
}

/// An input profile in the graph: the descriptor of
/// `tactile_preprocess::profile::descriptor`, its score against the
/// training frames' centre and scale, and the threshold above which a
/// frame is foreign.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileGate {
    /// Luma weights of red, green and blue.
    pub luma: [f32; 3],
    /// Row-major `H x W` pixels of the sensing window.
    pub window: Vec<bool>,
    /// Window pixels where the fine texture (a Laplacian) is read.
    pub texture: Vec<bool>,
    /// Pixels of the housing.
    pub housing: Vec<bool>,
    /// Per statistic, the training centre.
    pub centre: Vec<f32>,
    /// Per statistic, the training scale.
    pub scale: Vec<f32>,
    /// Scores above this are foreign.
    pub threshold: f32,
    /// The training frames were grey: a frame that is not blank and is of
    /// the other camera mode (grey, every pixel's channels equal, where
    /// this is false) is foreign, as
    /// `tactile_preprocess::profile::InputProfile::other_camera_mode` says.
    pub grey_frames: bool,
    /// The colour layout, when the profile has one: its residual and
    /// contrast are the last two statistics.
    pub layout: Option<LayoutGate>,
}

/// The colour layout of `tactile_preprocess::profile::ColourLayout` in the
/// graph.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutGate {
    /// Cells across.
    pub columns: usize,
    /// Cells down.
    pub rows: usize,
    /// `rows x columns x 3` reference values.
    pub reference: Vec<f32>,
    /// The contrast's weight per reference value.
    pub contrast_weights: Vec<f32>,
}

/// The nodes of the upper median along axis 1 of `input` (`[N, K, ...]`,
/// `k` values) into `output` (the axis kept): the upper half by TopK, whose
/// minimum is the element a sort puts at index `K / 2`, as
/// `select_nth_unstable` picks it. Their names start with `prefix`.
fn upper_median_nodes(
    prefix: &str,
    input: &str,
    k: usize,
    output: &str,
) -> (Vec<TensorProto>, Vec<NodeProto>) {
    let (half, axis, top) = (
        format!("{prefix}_upper_half"),
        format!("{prefix}_median_axis"),
        format!("{prefix}_top"),
    );
    let ini = vec![
        int64_constant(&half, &[1], vec![(k - k / 2) as i64]),
        int64_constant(&axis, &[1], vec![1]),
    ];
    let mut topk = node("TopK", &top, &[input, &half], &top);
    topk.output.push(format!("{top}_indices"));
    topk.attribute.push(int_attribute("axis", 1));
    topk.attribute.push(int_attribute("largest", 1));
    let mut min = node(
        "ReduceMin",
        &format!("{prefix}_median"),
        &[&top, &axis],
        output,
    );
    min.attribute.push(int_attribute("keepdims", 1));
    (ini, vec![topk, min])
}

/// The nodes of the layout's statistics of `input` (`[N, H, W, 3]`):
/// each cell's channel means over the channels' means over the grid; the
/// residual `gate_layout` (`[N, 1]`), the median of their distances from
/// the reference ([`upper_median_nodes`]); the contrast
/// `gate_layout_contrast` (`[N, 1]`), `1 + sum((c - r) w)` as one MatMul
/// and a constant.
fn layout_nodes(
    l: &LayoutGate,
    (height, width): (usize, usize),
    input: &str,
) -> std::result::Result<(Vec<TensorProto>, Vec<NodeProto>), String> {
    let (cols, rows) = (l.columns, l.rows);
    if cols == 0
        || rows == 0
        || width < cols
        || height < rows
        || l.reference.len() != cols * rows * 3
        || l.contrast_weights.len() != l.reference.len()
    {
        return Err(format!(
            "a colour layout of {cols} x {rows} cells does not fit a {width} x {height} frame"
        ));
    }
    let (cw, ch) = (width / cols, height / rows);
    let k = cols * rows * 3;
    let mut ini = vec![
        int64_constant("gate_layout_starts", &[2], vec![0, 0]),
        int64_constant(
            "gate_layout_ends",
            &[2],
            vec![(rows * ch) as i64, (cols * cw) as i64],
        ),
        int64_constant("gate_layout_axes", &[2], vec![1, 2]),
        int64_constant(
            "gate_layout_grid",
            &[6],
            vec![0, rows as i64, ch as i64, cols as i64, cw as i64, 3],
        ),
        int64_constant("gate_layout_within", &[2], vec![2, 4]),
        constant("gate_layout_dark", &[], vec![1.0 / 255.0]),
        constant(
            "gate_layout_reference",
            &[rows as i64, cols as i64, 3],
            l.reference.clone(),
        ),
        constant(
            "gate_layout_weights",
            &[k as i64, 1],
            l.contrast_weights.clone(),
        ),
        constant(
            "gate_layout_contrast_offset",
            &[],
            vec![
                1.0 - l
                    .reference
                    .iter()
                    .zip(&l.contrast_weights)
                    .map(|(r, w)| (r * w) as f64)
                    .sum::<f64>() as f32,
            ],
        ),
    ];
    let reduce = |op: &str, name: &str, inputs: &[&str], keep: i64| {
        let mut n = node(op, name, inputs, name);
        n.attribute.push(int_attribute("keepdims", keep));
        n
    };
    let (median_ini, median) =
        upper_median_nodes("gate_layout", "gate_layout_flat", k, "gate_layout");
    ini.extend(median_ini);
    let mut nodes = vec![
        node(
            "Slice",
            "gate_layout_crop",
            &[
                input,
                "gate_layout_starts",
                "gate_layout_ends",
                "gate_layout_axes",
            ],
            "gate_layout_crop",
        ),
        node(
            "Reshape",
            "gate_layout_blocks",
            &["gate_layout_crop", "gate_layout_grid"],
            "gate_layout_blocks",
        ),
        reduce(
            "ReduceMean",
            "gate_layout_cells",
            &["gate_layout_blocks", "gate_layout_within"],
            0,
        ),
        reduce(
            "ReduceMean",
            "gate_layout_level_raw",
            &["gate_layout_cells", "gate_layout_axes"],
            1,
        ),
        node(
            "Max",
            "gate_layout_level",
            &["gate_layout_level_raw", "gate_layout_dark"],
            "gate_layout_level",
        ),
        node(
            "Div",
            "gate_layout_relative",
            &["gate_layout_cells", "gate_layout_level"],
            "gate_layout_relative",
        ),
        node(
            "Sub",
            "gate_layout_off",
            &["gate_layout_relative", "gate_layout_reference"],
            "gate_layout_off",
        ),
        node(
            "Reshape",
            "gate_layout_relative_flat",
            &["gate_layout_relative", "gate_flat"],
            "gate_layout_relative_flat",
        ),
        node(
            "MatMul",
            "gate_layout_weighted",
            &["gate_layout_relative_flat", "gate_layout_weights"],
            "gate_layout_weighted",
        ),
        node(
            "Add",
            "gate_layout_contrast",
            &["gate_layout_weighted", "gate_layout_contrast_offset"],
            "gate_layout_contrast",
        ),
        node(
            "Abs",
            "gate_layout_dist",
            &["gate_layout_off"],
            "gate_layout_dist",
        ),
        node(
            "Reshape",
            "gate_layout_flat",
            &["gate_layout_dist", "gate_flat"],
            "gate_layout_flat",
        ),
    ];
    nodes.extend(median);
    Ok((ini, nodes))
}

/// Where and to what each channel's level is set (see
/// [`StandaloneSpec::exposure_level`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ExposureLevel {
    /// The pixels whose median sets the level.
    pub pixels: Vec<usize>,
    /// What the median is mapped to.
    pub level: f32,
}

fn constant(name: &str, dims: &[i64], values: Vec<f32>) -> TensorProto {
    TensorProto {
        name: name.to_string(),
        dims: dims.to_vec(),
        data_type: FLOAT,
        float_data: values,
        ..Default::default()
    }
}

fn int64_constant(name: &str, dims: &[i64], values: Vec<i64>) -> TensorProto {
    TensorProto {
        name: name.to_string(),
        dims: dims.to_vec(),
        data_type: INT64,
        int64_data: values,
        ..Default::default()
    }
}

fn node(op: &str, name: &str, inputs: &[&str], output: &str) -> NodeProto {
    NodeProto {
        op_type: op.to_string(),
        name: name.to_string(),
        input: inputs.iter().map(|s| s.to_string()).collect(),
        output: vec![output.to_string()],
        ..Default::default()
    }
}

fn int_attribute(name: &str, value: i64) -> AttributeProto {
    AttributeProto {
        name: name.to_string(),
        type_: AttributeType::INT.into(),
        i: value,
        ..Default::default()
    }
}

fn ints_attribute(name: &str, values: &[i64]) -> AttributeProto {
    AttributeProto {
        name: name.to_string(),
        type_: AttributeType::INTS.into(),
        ints: values.to_vec(),
        ..Default::default()
    }
}

/// The nodes that set each channel of `input` (`[N, H, W, C]` in [0, 1])
/// to `e.level` at the median of `e.pixels`: gather those pixels, their
/// median by [`upper_median_nodes`].
fn exposure_nodes(
    e: &ExposureLevel,
    c: i64,
    input: &str,
    output: &str,
) -> std::result::Result<(Vec<TensorProto>, Vec<NodeProto>), &'static str> {
    let k = e.pixels.len();
    if k == 0 {
        return Err("no pixels set the exposure level");
    }
    let mut ini = vec![
        int64_constant("level_flat_shape", &[3], vec![0, -1, c]),
        int64_constant(
            "level_pixels",
            &[k as i64],
            e.pixels.iter().map(|&i| i as i64).collect(),
        ),
        int64_constant("level_shape", &[4], vec![0, 1, 1, c]),
        constant("level_target", &[], vec![e.level]),
        constant("level_dark", &[], vec![1.0 / 255.0]),
        constant("level_one", &[], vec![1.0]),
    ];
    let mut gather = node(
        "Gather",
        "level_gather",
        &["level_flat", "level_pixels"],
        "level_centre",
    );
    gather.attribute.push(int_attribute("axis", 1));
    let (median_ini, median) = upper_median_nodes("level", "level_centre", k, "level_median3");
    ini.extend(median_ini);
    let mut nodes = vec![
        node(
            "Reshape",
            "level_flatten",
            &[input, "level_flat_shape"],
            "level_flat",
        ),
        gather,
    ];
    nodes.extend(median);
    nodes.extend([
        node(
            "Reshape",
            "level_per_channel",
            &["level_median3", "level_shape"],
            "level_median",
        ),
        node(
            "Div",
            "level_gain",
            &["level_target", "level_median"],
            "level_gain_raw",
        ),
        node(
            "Less",
            "level_is_dark",
            &["level_median", "level_dark"],
            "level_dark_channel",
        ),
        node(
            "Where",
            "level_gain_kept",
            &["level_dark_channel", "level_one", "level_gain_raw"],
            "level_gain_used",
        ),
        node("Mul", "level_apply", &[input, "level_gain_used"], output),
    ]);
    Ok((ini, nodes))
}

/// Weights `1 / count` on the chosen pixels (0 elsewhere), as a column:
/// a MatMul with it is the mean over those pixels (0 over none).
fn mean_weights(name: &str, chosen: &[bool], column: bool) -> TensorProto {
    let n = chosen.iter().filter(|&&c| c).count().max(1) as f32;
    let w: Vec<f32> = chosen
        .iter()
        .map(|&c| if c { 1.0 / n } else { 0.0 })
        .collect();
    let len = w.len() as i64;
    let dims: &[i64] = if column { &[len, 1] } else { &[1, len] };
    constant(name, dims, w)
}

/// The nodes of the gates on `input` (`[N, H, W, C]` in [0, 1]); they
/// leave `gate` (int64 `[N]`), `input_score` (float `[N]`) and
/// `gate_passed` (bool `[N, 1]`).
fn gate_nodes(
    g: &GateSpec,
    height: usize,
    width: usize,
    input: &str,
) -> std::result::Result<(Vec<TensorProto>, Vec<NodeProto>), String> {
    let (h, w) = (height as i64, width as i64);
    let mut ini = vec![
        int64_constant("gate_axes_hw", &[2], vec![1, 2]),
        int64_constant("gate_axis_1", &[1], vec![1]),
        constant("gate_blank_std", &[], vec![g.blank_std]),
        constant("gate_half", &[], vec![0.5]),
        int64_constant("gate_code_none", &[], vec![0]),
        int64_constant("gate_code_blank", &[], vec![1]),
        int64_constant("gate_code_foreign", &[], vec![2]),
        int64_constant("gate_column", &[2], vec![-1, 1]),
    ];
    let reduce = |op: &str, name: &str, inputs: &[&str], out: &str, keep: i64| {
        let mut n = node(op, name, inputs, out);
        n.attribute.push(int_attribute("keepdims", keep));
        n
    };
    let mut cast_float = node(
        "Cast",
        "gate_blank_float",
        &["gate_chan_flat"],
        "gate_chan_flat_f",
    );
    cast_float.attribute.push(int_attribute("to", FLOAT as i64));
    // Blank: every channel's standard deviation under the limit.
    let mut nodes = vec![
        reduce(
            "ReduceMean",
            "gate_chan_mean",
            &[input, "gate_axes_hw"],
            "gate_chan_mean",
            1,
        ),
        node(
            "Sub",
            "gate_chan_dev",
            &[input, "gate_chan_mean"],
            "gate_chan_dev",
        ),
        node(
            "Mul",
            "gate_chan_sq",
            &["gate_chan_dev", "gate_chan_dev"],
            "gate_chan_sq",
        ),
        reduce(
            "ReduceMean",
            "gate_chan_var",
            &["gate_chan_sq", "gate_axes_hw"],
            "gate_chan_var",
            0,
        ),
        node("Sqrt", "gate_chan_sd", &["gate_chan_var"], "gate_chan_sd"),
        node(
            "Less",
            "gate_chan_flat",
            &["gate_chan_sd", "gate_blank_std"],
            "gate_chan_flat",
        ),
        cast_float,
        reduce(
            "ReduceMin",
            "gate_all_flat",
            &["gate_chan_flat_f", "gate_axis_1"],
            "gate_all_flat",
            0,
        ),
        node(
            "Greater",
            "gate_blank",
            &["gate_all_flat", "gate_half"],
            "gate_blank",
        ),
        node(
            "Where",
            "gate_blank_code",
            &["gate_blank", "gate_code_blank", "gate_code_none"],
            "gate_blank_code",
        ),
    ];
    let code = match &g.profile {
        None => {
            // A zero per frame: the blank test's shape times 0.
            ini.push(constant("gate_zero", &[], vec![0.0]));
            nodes.push(node(
                "Mul",
                "input_score",
                &["gate_all_flat", "gate_zero"],
                "input_score",
            ));
            "gate_blank_code"
        }
        Some(p) => {
            let n = height * width;
            if [p.window.len(), p.texture.len(), p.housing.len()] != [n; 3] {
                return Err(format!("the profile's regions are not {width} x {height}"));
            }
            let stats = 9 + p.layout.as_ref().map_or(0, |_| 2);
            if p.centre.len() != stats || p.scale.len() != stats {
                return Err(format!("a profile of {stats} statistics is expected"));
            }
            // The texture region on the Laplacian's (H-2) x (W-2) output.
            let inner: Vec<bool> = (1..height - 1)
                .flat_map(|y| (1..width - 1).map(move |x| (y, x)))
                .map(|(y, x)| p.texture[y * width + x])
                .collect();
            ini.extend([
                constant("gate_luma", &[3, 1], p.luma.to_vec()),
                int64_constant("gate_flat", &[2], vec![0, -1]),
                int64_constant("gate_flat_rgb", &[3], vec![0, -1, 3]),
                int64_constant("gate_rgb_shape", &[2], vec![0, 3]),
                int64_constant("gate_image", &[4], vec![0, 1, h, w]),
                mean_weights("gate_window_row", &p.window, false),
                mean_weights("gate_window", &p.window, true),
                mean_weights("gate_texture", &inner, true),
                mean_weights("gate_housing", &p.housing, true),
                constant(
                    "gate_laplacian",
                    &[1, 1, 3, 3],
                    vec![0.0, -1.0, 0.0, -1.0, 4.0, -1.0, 0.0, -1.0, 0.0],
                ),
                constant(
                    "gate_balance",
                    &[3, 2],
                    vec![1.0, 0.0, -1.0, -1.0, 0.0, 1.0],
                ),
                constant("gate_centre", &[stats as i64], p.centre.clone()),
                constant("gate_scale", &[stats as i64], p.scale.clone()),
                constant("gate_profile_threshold", &[], vec![p.threshold]),
                constant("gate_chroma", &[3, 2], vec![1.0, 0.0, -1.0, -1.0, 0.0, 1.0]),
                int64_constant("gate_axes_hwc", &[3], vec![1, 2, 3]),
                constant("gate_no_chroma", &[], vec![0.0]),
            ]);
            let mut concat = node(
                "Concat",
                "gate_descriptor",
                &[
                    "gate_rgb",
                    "gate_spread",
                    "gate_fine",
                    "gate_balanced",
                    "gate_house",
                    "gate_house_sd",
                ],
                "gate_descriptor",
            );
            concat.attribute.push(int_attribute("axis", 1));
            if let Some(l) = &p.layout {
                let (li, ln) = layout_nodes(l, (height, width), input)?;
                ini.extend(li);
                nodes.extend(ln);
                concat.input.push("gate_layout".into());
                concat.input.push("gate_layout_contrast".into());
            }
            let spread = |region: &str, mean: &str, sd: &str| {
                vec![
                    node("MatMul", mean, &["gate_luma_flat", region], mean),
                    node(
                        "Sub",
                        &format!("{sd}_dev"),
                        &["gate_luma_flat", mean],
                        &format!("{sd}_dev"),
                    ),
                    node(
                        "Mul",
                        &format!("{sd}_sq"),
                        &[&format!("{sd}_dev"), &format!("{sd}_dev")],
                        &format!("{sd}_sq"),
                    ),
                    node(
                        "MatMul",
                        &format!("{sd}_var"),
                        &[&format!("{sd}_sq"), region],
                        &format!("{sd}_var"),
                    ),
                    node("Sqrt", sd, &[&format!("{sd}_var")], sd),
                ]
            };
            let window = spread("gate_window", "gate_window_mean", "gate_spread");
            let housing = spread("gate_housing", "gate_house", "gate_house_sd");
            nodes.extend([
                node(
                    "MatMul",
                    "gate_luma_pixels",
                    &[input, "gate_luma"],
                    "gate_luma_pixels",
                ),
                node(
                    "Reshape",
                    "gate_luma_flat",
                    &["gate_luma_pixels", "gate_flat"],
                    "gate_luma_flat",
                ),
                node(
                    "Reshape",
                    "gate_rgb_flat",
                    &[input, "gate_flat_rgb"],
                    "gate_rgb_flat",
                ),
                node(
                    "MatMul",
                    "gate_rgb_mean",
                    &["gate_window_row", "gate_rgb_flat"],
                    "gate_rgb_mean",
                ),
                node(
                    "Reshape",
                    "gate_rgb",
                    &["gate_rgb_mean", "gate_rgb_shape"],
                    "gate_rgb",
                ),
                node(
                    "MatMul",
                    "gate_balanced",
                    &["gate_rgb", "gate_balance"],
                    "gate_balanced",
                ),
                node(
                    "Reshape",
                    "gate_luma_image",
                    &["gate_luma_flat", "gate_image"],
                    "gate_luma_image",
                ),
                node(
                    "Conv",
                    "gate_lap",
                    &["gate_luma_image", "gate_laplacian"],
                    "gate_lap",
                ),
                node("Abs", "gate_lap_abs", &["gate_lap"], "gate_lap_abs"),
                node(
                    "Reshape",
                    "gate_lap_flat",
                    &["gate_lap_abs", "gate_flat"],
                    "gate_lap_flat",
                ),
                node(
                    "MatMul",
                    "gate_fine",
                    &["gate_lap_flat", "gate_texture"],
                    "gate_fine",
                ),
            ]);
            nodes.extend(window);
            nodes.extend(housing);
            nodes.extend([
                concat,
                node(
                    "Sub",
                    "gate_off_centre",
                    &["gate_descriptor", "gate_centre"],
                    "gate_off_centre",
                ),
                node(
                    "Div",
                    "gate_in_scales",
                    &["gate_off_centre", "gate_scale"],
                    "gate_in_scales",
                ),
                node("Abs", "gate_distance", &["gate_in_scales"], "gate_distance"),
                reduce(
                    "ReduceMax",
                    "input_score",
                    &["gate_distance", "gate_axis_1"],
                    "input_score",
                    0,
                ),
                node(
                    "Greater",
                    "gate_outside",
                    &["input_score", "gate_profile_threshold"],
                    "gate_outside",
                ),
                // The camera mode: a frame is in colour when any pixel's
                // red or blue differs from its green.
                node(
                    "MatMul",
                    "gate_chroma_pixels",
                    &[input, "gate_chroma"],
                    "gate_chroma_pixels",
                ),
                node(
                    "Abs",
                    "gate_chroma_abs",
                    &["gate_chroma_pixels"],
                    "gate_chroma_abs",
                ),
                reduce(
                    "ReduceMax",
                    "gate_chroma_max",
                    &["gate_chroma_abs", "gate_axes_hwc"],
                    "gate_chroma_max",
                    0,
                ),
                node(
                    "Greater",
                    "gate_in_colour",
                    &["gate_chroma_max", "gate_no_chroma"],
                    "gate_in_colour",
                ),
                match p.grey_frames {
                    true => node(
                        "Identity",
                        "gate_mode_differs",
                        &["gate_in_colour"],
                        "gate_mode_differs",
                    ),
                    false => node(
                        "Not",
                        "gate_mode_differs",
                        &["gate_in_colour"],
                        "gate_mode_differs",
                    ),
                },
                node("Not", "gate_not_blank", &["gate_blank"], "gate_not_blank"),
                node(
                    "And",
                    "gate_other_mode",
                    &["gate_mode_differs", "gate_not_blank"],
                    "gate_other_mode",
                ),
                node(
                    "Or",
                    "gate_foreign",
                    &["gate_outside", "gate_other_mode"],
                    "gate_foreign",
                ),
                node(
                    "Where",
                    "gate_code",
                    &["gate_foreign", "gate_code_foreign", "gate_blank_code"],
                    "gate_code",
                ),
            ]);
            "gate_code"
        }
    };
    nodes.extend([
        node("Identity", "gate", &[code], "gate"),
        node(
            "Equal",
            "gate_is_none",
            &["gate", "gate_code_none"],
            "gate_is_none",
        ),
        node(
            "Reshape",
            "gate_passed",
            &["gate_is_none", "gate_column"],
            "gate_passed",
        ),
    ]);
    Ok((ini, nodes))
}

/// Wrap the exported network `onnx` (one `[N, C, H, W]` float input, one
/// output) as `spec` says; the new model's bytes.
pub fn make_standalone(onnx: &[u8], spec: &StandaloneSpec) -> Result<Vec<u8>> {
    let bad = |m: String| Error::Export(format!("standalone export: {m}"));
    let channels = spec.mean.len();
    if channels == 0 || spec.std.len() != channels {
        return Err(bad(format!(
            "{} means and {} standard deviations",
            channels,
            spec.std.len()
        )));
    }
    let mut model = ModelProto::parse_from_bytes(onnx)
        .map_err(|e| bad(format!("cannot read the export: {e}")))?;
    let graph = model.graph.mut_or_insert_default();
    let initialised: std::collections::HashSet<String> =
        graph.initializer.iter().map(|t| t.name.clone()).collect();
    let inputs: Vec<usize> = (0..graph.input.len())
        .filter(|&i| !initialised.contains(&graph.input[i].name))
        .collect();
    let (&[input], [_]) = (inputs.as_slice(), graph.output.as_slice()) else {
        return Err(bad(format!(
            "the network has {} inputs and {} outputs; one of each is needed",
            inputs.len(),
            graph.output.len()
        )));
    };
    let old_in = graph.input[input].name.clone();
    let old_out = graph.output[0].name.clone();
    // The batch axis as the export names it (symbolic), kept.
    let batch = graph.input[input]
        .type_
        .tensor_type()
        .shape
        .dim
        .first()
        .cloned()
        .unwrap_or_default();

    // frame (uint8 or uint16 NHWC) -> normalised float NCHW, the network's input.
    let c = channels as i64;
    let (elem, top) = match spec.input_bits {
        8 => (UINT8, 255.0),
        16 => (UINT16, 65535.0),
        b => return Err(bad(format!("{b} bits per channel; 8 or 16 are exported"))),
    };
    graph
        .initializer
        .push(constant("frame_scale", &[], vec![top]));
    graph
        .initializer
        .push(constant("channel_mean", &[1, 1, 1, c], spec.mean.clone()));
    graph
        .initializer
        .push(constant("channel_std", &[1, 1, 1, c], spec.std.clone()));
    let mut cast = node("Cast", "frame_to_float", &["frame"], "frame_f32");
    cast.attribute.push(int_attribute("to", FLOAT as i64));
    let mut transpose = node("Transpose", "frame_to_nchw", &["frame_normalised"], &old_in);
    transpose
        .attribute
        .push(ints_attribute("perm", &[0, 3, 1, 2]));
    let mut prefix = vec![
        cast,
        node(
            "Div",
            "frame_to_unit",
            &["frame_f32", "frame_scale"],
            "frame_unit",
        ),
    ];
    let levelled = match &spec.exposure_level {
        None => "frame_unit",
        Some(e) => {
            let (ini, nodes) = exposure_nodes(e, c, "frame_unit", "frame_levelled")
                .map_err(|m| bad(m.to_string()))?;
            graph.initializer.extend(ini);
            prefix.extend(nodes);
            "frame_levelled"
        }
    };
    prefix.extend([
        node(
            "Sub",
            "frame_centre",
            &[levelled, "channel_mean"],
            "frame_centred",
        ),
        node(
            "Div",
            "frame_normalise",
            &["frame_centred", "channel_std"],
            "frame_normalised",
        ),
        transpose,
    ]);
    if let Some(g) = &spec.gates {
        if !matches!(spec.output, StandaloneOutput::Probability { .. }) {
            return Err(bad("gates need a probability output".into()));
        }
        let (ini, nodes) = gate_nodes(g, spec.height, spec.width, "frame_unit").map_err(bad)?;
        graph.initializer.extend(ini);
        prefix.extend(nodes);
    }
    let tail = std::mem::take(&mut graph.node);
    graph.node = prefix.into_iter().chain(tail).collect();
    let frame = &mut graph.input[input];
    frame.name = "frame".into();
    let tensor = frame.type_.mut_or_insert_default().mut_tensor_type();
    tensor.elem_type = elem;
    let shape = tensor.shape.mut_or_insert_default();
    shape.dim.clear();
    for v in [spec.height as i64, spec.width as i64, c] {
        let mut d = batch.clone();
        d.set_dim_value(v);
        shape.dim.push(d);
    }
    shape.dim.insert(0, batch.clone());

    // The network's output -> what the user wants, named.
    let name = match &spec.output {
        StandaloneOutput::Probability { name } if spec.gates.is_some() => {
            let threshold = spec.gates.as_ref().map_or(0.5, |g| g.threshold);
            graph.initializer.extend([
                constant("gate_zero_probability", &[], vec![0.0]),
                constant("tendon_threshold", &[], vec![threshold]),
                int64_constant("tendon_flat", &[1], vec![-1]),
            ]);
            graph.node.extend([
                node(
                    "Sigmoid",
                    "to_probability",
                    &[&old_out],
                    "network_probability",
                ),
                node(
                    "Where",
                    "gated_probability",
                    &[
                        "gate_passed",
                        "network_probability",
                        "gate_zero_probability",
                    ],
                    name,
                ),
                node(
                    "GreaterOrEqual",
                    "tendon_at_threshold",
                    &[name, "tendon_threshold"],
                    "tendon_at_threshold",
                ),
                node(
                    "And",
                    "tendon_passed",
                    &["tendon_at_threshold", "gate_passed"],
                    "tendon_column",
                ),
                node(
                    "Reshape",
                    "tendon",
                    &["tendon_column", "tendon_flat"],
                    "tendon",
                ),
            ]);
            name
        }
        StandaloneOutput::Probability { name } => {
            graph
                .node
                .push(node("Sigmoid", "to_probability", &[&old_out], name));
            name
        }
        StandaloneOutput::Affine {
            name,
            scale,
            offset,
        } => {
            graph
                .initializer
                .push(constant("output_scale", &[], vec![*scale]));
            graph
                .initializer
                .push(constant("output_offset", &[], vec![*offset]));
            graph.node.push(node(
                "Mul",
                "output_scaled",
                &[&old_out, "output_scale"],
                "output_scaled",
            ));
            graph.node.push(node(
                "Add",
                "output_shifted",
                &["output_scaled", "output_offset"],
                name,
            ));
            name
        }
    };
    graph.output[0].name = name.clone();
    graph.output[0]
        .type_
        .mut_or_insert_default()
        .mut_tensor_type()
        .elem_type = FLOAT;
    if spec.gates.is_some() {
        // Per frame: which gate stopped it, its input score, the decision.
        for (out, elem) in [("gate", INT64), ("input_score", FLOAT), ("tendon", BOOL)] {
            let mut v = graph.output[0].clone();
            v.name = out.into();
            let t = v.type_.mut_or_insert_default().mut_tensor_type();
            t.elem_type = elem;
            let shape = t.shape.mut_or_insert_default();
            shape.dim.clear();
            shape.dim.push(batch.clone());
            graph.output.push(v);
        }
    }
    for (k, v) in &spec.metadata {
        model.metadata_props.push(Default::default());
        if let Some(entry) = model.metadata_props.last_mut() {
            entry.key = k.clone();
            entry.value = v.clone();
        }
    }
    model
        .write_to_bytes()
        .map_err(|e| bad(format!("cannot write the model: {e}")))
}

/// How many operations (nodes) an ONNX model's graph has, by kind, most
/// frequent first: what a runtime with a fixed cost per operation pays for.
pub fn op_counts(onnx: &[u8]) -> Result<Vec<(String, usize)>> {
    let model = ModelProto::parse_from_bytes(onnx)
        .map_err(|e| Error::Export(format!("cannot read the model: {e}")))?;
    let mut counts = std::collections::BTreeMap::<String, usize>::new();
    for n in &model.graph.node {
        *counts.entry(n.op_type.clone()).or_default() += 1;
    }
    let mut v: Vec<_> = counts.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Ok(v)
}
