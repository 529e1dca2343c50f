//! ONNX export of every model, and running the exported files in
//! onnxruntime (through `ort`, loaded dynamically from the PyPI wheel's
//! `libonnxruntime.so`) for parity checks and benchmarks.

pub mod export;
pub mod runtime;

pub use export::{
    export_cae, export_cae_encoder, export_depth, export_detector, export_module_batch_dynamic,
    export_segmenter,
};
pub use runtime::{OrtModel, onnx_full_check, ort_library_path};
