//! onnxruntime through `ort` (`load-dynamic`): the shared library comes
//! from the PyPI wheel `onnxruntime==1.31.1`
//! (`onnxruntime/capi/libonnxruntime.so.1.31.1`). `ORT_DYLIB_PATH` names
//! it; otherwise the folder the test and demo scripts install it into
//! (`.ort/` at the workspace root) is searched.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use ort::environment::Environment;
use ort::session::Session;
use ort::value::Tensor;
use tactile_burn::runtime::{Network, Runtime};

use crate::{Error, Result};

/// Where the scripts install the wheel, relative to the workspace root.
pub const LOCAL_ORT_DIR: &str = ".ort";
const LIB_IN_WHEEL: &str = "onnxruntime/capi/libonnxruntime.so.1.31.1";

/// The onnxruntime shared library to load.
pub fn ort_library_path() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("ORT_DYLIB_PATH") {
        let p = PathBuf::from(p);
        return if p.is_file() {
            Ok(p)
        } else {
            Err(tactile_core::Error::model(&p, "ORT_DYLIB_PATH does not name a file").into())
        };
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let candidates = [
        root.join(LOCAL_ORT_DIR).join(LIB_IN_WHEEL),
        PathBuf::from(LOCAL_ORT_DIR).join(LIB_IN_WHEEL),
    ];
    candidates.into_iter().find(|p| p.is_file()).ok_or_else(|| {
        Error::Library(format!(
            "onnxruntime not found: set ORT_DYLIB_PATH, or run `bash scripts/install-ort.sh` \
             (installs the PyPI wheel onnxruntime==1.31.1 into {LOCAL_ORT_DIR}/)"
        ))
    })
}

fn environment() -> Result<&'static Environment> {
    static ENV: OnceLock<std::result::Result<Environment, String>> = OnceLock::new();
    ENV.get_or_init(|| {
        let lib = ort_library_path().map_err(|e| e.to_string())?;
        ort::init_from(&lib)
            .map_err(|e| format!("{}: cannot load onnxruntime: {e}", lib.display()))?
            .with_name("tactile-rs")
            .build()
            .map_err(|e| format!("cannot start onnxruntime: {e}"))
    })
    .as_ref()
    .map_err(|e| Error::Library(e.clone()))
}

/// One ONNX model loaded into onnxruntime.
pub struct OrtModel {
    session: Session,
}

/// Most onnxruntime intra-op threads a model may ask for.
pub const MAX_THREADS: usize = 256;

impl OrtModel {
    /// Load a model from bytes, with `threads` intra-op threads (0 = ORT's
    /// default; at most [`MAX_THREADS`]).
    pub fn from_bytes(bytes: &[u8], threads: usize) -> Result<Self> {
        if threads > MAX_THREADS {
            return Err(tactile_core::Error::Config(format!(
                "threads: {threads} onnxruntime threads asked, at most {MAX_THREADS}"
            ))
            .into());
        }
        let env = environment()?;
        let err = |e: ort::Error| Error::Run(format!("rejected the model: {e}"));
        let mut b = Session::builder(env).map_err(err)?;
        if threads > 0 {
            b = b.with_intra_threads(threads).map_err(|e| err(e.into()))?;
        }
        // Several threads asked for: their workers sleep between runs
        // rather than spin. A pipeline holds three sessions, each with its
        // own workers; spinning, they took the cores from each other and
        // from the thread that runs them (`tactile run --threads 2
        // --no-overlap`: 94-119 frames/s spinning, 171-174 not, 175-189 on
        // one thread).
        if threads > 1 {
            b = b.with_intra_op_spinning(false).map_err(|e| err(e.into()))?;
        }
        let session = b.commit_from_memory(bytes).map_err(err)?;
        Ok(Self { session })
    }

    /// Run the model's single float input, returning its first output's shape and values.
    pub fn run_f32(&mut self, shape: &[usize], data: Vec<f32>) -> Result<(Vec<usize>, Vec<f32>)> {
        let err = |e: ort::Error| Error::Run(format!("run failed: {e}"));
        let input = Tensor::from_array((shape.to_vec(), data)).map_err(err)?;
        let outputs = self.session.run(ort::inputs![input]).map_err(err)?;
        let (s, v) = outputs[0].try_extract_tensor::<f32>().map_err(err)?;
        Ok((s.iter().map(|&d| d as usize).collect(), v.to_vec()))
    }

    /// Run the model's single uint8 input (a standalone model's `frame`),
    /// returning its first output's shape and values.
    pub fn run_u8(&mut self, shape: &[usize], data: Vec<u8>) -> Result<(Vec<usize>, Vec<f32>)> {
        self.run_frame(shape, data)
    }

    /// Run the model's single uint16 input (the `frame` of a standalone
    /// model whose network reads 16-bit levels).
    pub fn run_u16(&mut self, shape: &[usize], data: Vec<u16>) -> Result<(Vec<usize>, Vec<f32>)> {
        self.run_frame(shape, data)
    }

    /// The first output of [`Self::run_frame_outputs`].
    fn run_frame<T>(&mut self, shape: &[usize], data: Vec<T>) -> Result<(Vec<usize>, Vec<f32>)>
    where
        T: ort::value::PrimitiveTensorElementType + std::fmt::Debug + Clone + 'static,
    {
        let first = self
            .run_frame_outputs(shape, data)?
            .into_iter()
            .next()
            .ok_or_else(|| Error::Run("the model gave no output".into()))?;
        Ok((first.shape, first.values))
    }
}

/// One output of a model run: its name, shape and values (integers and
/// booleans as floats: 0/1 for booleans).
#[derive(Debug, Clone, PartialEq)]
pub struct NamedOutput {
    /// The output's name in the graph.
    pub name: String,
    /// Its shape.
    pub shape: Vec<usize>,
    /// Its values, row-major.
    pub values: Vec<f32>,
}

impl OrtModel {
    /// Run a standalone model's `frame` (uint8 or uint16 levels), returning
    /// every output in the graph's order.
    pub fn run_frame_outputs<T>(
        &mut self,
        shape: &[usize],
        data: Vec<T>,
    ) -> Result<Vec<NamedOutput>>
    where
        T: ort::value::PrimitiveTensorElementType + std::fmt::Debug + Clone + 'static,
    {
        let err = |e: ort::Error| Error::Run(format!("run failed: {e}"));
        let input = Tensor::from_array((shape.to_vec(), data)).map_err(err)?;
        let outputs = self.session.run(ort::inputs![input]).map_err(err)?;
        let mut all = Vec::with_capacity(outputs.len());
        for (name, value) in outputs.iter() {
            let dims = |s: &ort::value::Shape| s.iter().map(|&d| d as usize).collect::<Vec<_>>();
            let (shape, values) = if let Ok((s, v)) = value.try_extract_tensor::<f32>() {
                (dims(s), v.to_vec())
            } else if let Ok((s, v)) = value.try_extract_tensor::<i64>() {
                (dims(s), v.iter().map(|&x| x as f32).collect())
            } else {
                let (s, v) = value.try_extract_tensor::<bool>().map_err(err)?;
                (dims(s), v.iter().map(|&x| f32::from(u8::from(x))).collect())
            };
            all.push(NamedOutput {
                name: name.to_string(),
                shape,
                values,
            });
        }
        Ok(all)
    }
}

impl Network for OrtModel {
    fn run(&mut self, shape: [usize; 4], input: Vec<f32>) -> tactile_core::Result<Vec<f32>> {
        tactile_core::interrupt::check()?;
        Ok(self.run_f32(&shape, input)?.1)
    }

    fn runtime(&self) -> Runtime {
        Runtime::Onnx
    }
}

/// Run `onnx.checker.check_model(path, full_check=True)` in Python (the
/// `onnx` package from `$TACTILE_PYTHONPATH` or `.ort/`, as the scripts
/// install it). Errors carry the checker's message.
pub fn onnx_full_check(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let pythonpath = std::env::var_os("TACTILE_PYTHONPATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../..")
                .join(LOCAL_ORT_DIR)
        });
    let out = std::process::Command::new("python3")
        .env("PYTHONPATH", &pythonpath)
        .args([
            "-c",
            "import sys, onnx; onnx.checker.check_model(sys.argv[1], full_check=True); print('ok')",
        ])
        .arg(path)
        .output()
        .map_err(|e| tactile_core::Error::io("python3", e))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(tactile_core::Error::model(
            path,
            format!(
                "onnx.checker failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ),
        )
        .into())
    }
}
