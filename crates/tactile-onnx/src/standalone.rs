//! ONNX models that stand alone: the graph takes the frame as a user has
//! it and gives what a user wants, so onnxruntime (or any ONNX runtime)
//! needs no toolkit code around it.
//!
//! An exported network takes normalised `[N, C, H, W]` float values and
//! gives raw outputs. [`make_standalone`] edits its graph: the input
//! becomes `frame`, `uint8` `[N, H, W, C]`, cast, scaled to `[0, 1]`,
//! normalised by the training statistics and transposed inside; the
//! output passes a sigmoid (a probability) or an affine map (a depth in
//! millimetres) and takes a name that says what it is. The model's own
//! numbers (threshold, statistics, input size, toolkit version) go into
//! its metadata.

use onnx_ir::{AttributeProto, AttributeType, Message, ModelProto, NodeProto, TensorProto};

use crate::{Error, Result};

/// ONNX's element type codes used here.
const FLOAT: i32 = 1;
const UINT8: i32 = 2;
const UINT16: i32 = 4;
const INT64: i32 = 7;

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
/// to `e.level` at the median of `e.pixels`: gather those pixels, take the
/// upper half with TopK, its minimum is the median (the element a sort
/// puts at index `K / 2`, as `select_nth_unstable` picks it).
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
    let upper = (k - k / 2) as i64;
    let ini = vec![
        int64_constant("level_flat_shape", &[3], vec![0, -1, c]),
        int64_constant(
            "level_pixels",
            &[k as i64],
            e.pixels.iter().map(|&i| i as i64).collect(),
        ),
        int64_constant("level_upper_half", &[1], vec![upper]),
        int64_constant("level_axis", &[1], vec![1]),
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
    let mut topk = node(
        "TopK",
        "level_topk",
        &["level_centre", "level_upper_half"],
        "level_top",
    );
    topk.output.push("level_top_indices".into());
    topk.attribute.push(int_attribute("axis", 1));
    topk.attribute.push(int_attribute("largest", 1));
    let mut min = node(
        "ReduceMin",
        "level_median",
        &["level_top", "level_axis"],
        "level_median3",
    );
    min.attribute.push(int_attribute("keepdims", 1));
    let nodes = vec![
        node(
            "Reshape",
            "level_flatten",
            &[input, "level_flat_shape"],
            "level_flat",
        ),
        gather,
        topk,
        min,
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
    ];
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
    shape.dim.insert(0, batch);

    // The network's output -> what the user wants, named.
    let name = match &spec.output {
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
