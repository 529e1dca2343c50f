//! `tactile.frames`: every source the command line reads (a dataset, a
//! folder of frames, a video file, a ROS 2 bag's image topic,
//! a V4L2 camera, raw frames on stdin) as a Python iterator of numpy
//! frames; `tactile.bag_topics` lists a bag's image topics.

use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use tactile_pipeline::{FrameSource, SourceOptions, SourceSpec};

use crate::args::{Given, PathArg, Whole, optional};
use crate::errors::PyResultExt;

/// One frame of a source: `image` is `(H, W, 3)` uint8 RGB; `name` the
/// file name or the frame's number in a stream; `sequence` and `tendon`
/// what a dataset's labels say (else None); `age_ms` how long ago a live
/// frame arrived, when it was handed over (None for recorded sources);
/// `stamp_ns` a bag frame's header stamp, nanoseconds since the epoch.
#[pyclass(module = "tactile", name = "Frame", frozen, get_all)]
pub struct PyFrame {
    pub(crate) image: Py<PyAny>,
    pub(crate) name: String,
    pub(crate) sequence: Option<String>,
    pub(crate) tendon: Option<bool>,
    pub(crate) age_ms: Option<f64>,
    pub(crate) stamp_ns: Option<i64>,
}

#[pymethods]
impl PyFrame {
    fn __repr__(&self) -> String {
        format!("Frame(name={:?})", self.name)
    }

    /// Pickled whole (image and labels), so frames can be sent to worker
    /// processes.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::pickling::reduce_frame(py, self)
    }
}

/// Frames from a dataset, a folder, an image, a TIFF stack, a video file, a
/// camera or stdin, in order. Iterate it; `kind`, `dropped` and `size` say what it is,
/// how many live frames were dropped and the frame size when known.
#[pyclass(module = "tactile", name = "FrameSource")]
pub struct PyFrameSource {
    source: Mutex<FrameSource>,
    /// The warnings found while reading have been given.
    late_warned: AtomicBool,
}

impl PyFrameSource {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, FrameSource>> {
        self.source
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the frame source failed in another thread"))
    }
}

#[pymethods]
impl PyFrameSource {
    /// Refused: an open stream stays in the process that opened it.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::open_stream(
            "FrameSource",
            "an open stream (a file, camera, bag or pipe being read)",
            "Send its frames (tactile.Frame pickles), or give each worker a source of its own",
        ))
    }

    /// What the source is: "dataset", "folder", "video", "stack" (a TIFF of
    /// many pages given alone), "bag", "camera", "stream" (a network
    /// stream without a length; a served file with one is "video") or
    /// "stdin".
    #[getter]
    fn kind(&self) -> PyResult<String> {
        let k = self.lock()?.kind();
        Ok(serde_json::to_value(k)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default())
    }

    /// Live frames dropped so far because they were not taken fast enough.
    #[getter]
    fn dropped(&self) -> PyResult<u64> {
        Ok(self.lock()?.dropped())
    }

    /// `(width, height)` when known before reading (videos, stdin, datasets).
    #[getter]
    fn size(&self) -> PyResult<Option<(usize, usize)>> {
        Ok(self.lock()?.size())
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__(&self, py: Python<'_>) -> PyResult<Option<PyFrame>> {
        let read = || -> PyResult<_> { self.lock()?.next_frame().py() };
        // A camera or stdin may keep the next frame waiting for ever (the
        // live queue looks for a stop every 100 ms); a file's comes now.
        let live = self.lock()?.kind().is_live();
        let next = crate::work::released(py, live, read)?;
        let Some(f) = next else {
            // What the read found (a bag file cut short), once, at the end.
            if !self.late_warned.swap(true, Ordering::Relaxed) {
                for w in self.lock()?.late_warnings() {
                    crate::errors::user_warning(py, &w)?;
                }
            }
            return Ok(None);
        };
        let age_ms = f.arrived.map(|t| 1e3 * t.elapsed().as_secs_f64());
        let image = crate::image::rgb_array(py, f.image)?.unbind();
        Ok(Some(PyFrame {
            image,
            name: f.name,
            sequence: f.sequence,
            tendon: f.tendon,
            age_ms,
            stamp_ns: f.stamp_ns,
        }))
    }
}

/// A live video topic decoded as its packets arrive, for a node that
/// subscribes to `foxglove_msgs/msg/CompressedVideo`,
/// `ffmpeg_image_transport_msgs/msg/FFMPEGPacket` or `h264_msgs/msg/Packet`
/// itself: `format` is the message's `format` or `encoding` (H.264 or H.265
/// in Annex B, VP9, AV1 OBUs; "h264" for an `h264_msgs` Packet). `decode`
/// takes each message's `data` (bytes, or rclpy's array) and stamp and
/// gives the frames decoded so far, normally that packet's own (with
/// B-frames, once the decoder lets them go: how many it holds is read from
/// the first keyframe's parameters, so no call waits to learn it); packets
/// before the first keyframe are skipped (`skipped` counts them, and
/// `keyframes_without_parameters` those of them that were keyframes sent
/// without their parameter sets), packets that gave no frame (damaged)
/// are counted in `lost`, and changes of size whose frames were scaled (a
/// hostile stream's) in `scaled`. The system's FFmpeg decodes, as it does a bag's video.
#[pyclass(module = "tactile", name = "VideoDecoder")]
pub struct PyVideoDecoder {
    decoder: Mutex<tactile_core::bag::LiveVideo>,
}

impl PyVideoDecoder {
    fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, tactile_core::bag::LiveVideo>> {
        self.decoder
            .lock()
            .map_err(|_| PyRuntimeError::new_err("the decoder failed in another thread"))
    }

    fn with<T>(
        &self,
        f: impl FnOnce(&mut tactile_core::bag::LiveVideo) -> PyResult<T>,
    ) -> PyResult<T> {
        f(&mut *self.lock()?)
    }
}

/// A message's `data` as Python bytes: rclpy gives it as an
/// array.array('B'); bytes() takes that, bytes, a bytearray or a numpy
/// array alike. An int is refused: bytes(n) is n zero bytes, a packet
/// no one sent. `what` names it in the error.
fn message_bytes<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<Bound<'py, pyo3::types::PyBytes>> {
    if data.is_instance_of::<pyo3::types::PyInt>() {
        return Err(PyValueError::new_err(format!(
            "{what}: not bytes (an int, {data}: bytes() would make it that many zero bytes); give the message's data: bytes, a bytearray, an array.array('B') or a uint8 numpy array"
        )));
    }
    let data = py
        .import("builtins")?
        .getattr("bytes")?
        .call1((data,))
        .map_err(|e| PyValueError::new_err(format!("{what}: not bytes ({e})")))?;
    Ok(data.cast_into::<pyo3::types::PyBytes>()?)
}

/// Frames of a live video as Python frames, named by their packet's place.
fn live_frames(
    py: Python<'_>,
    frames: Vec<tactile_core::bag::LiveFrame>,
) -> PyResult<Vec<PyFrame>> {
    frames
        .into_iter()
        .map(|f| {
            Ok(PyFrame {
                image: crate::image::rgb_array(py, f.image)?.unbind(),
                name: f.packet.to_string(),
                sequence: None,
                tendon: None,
                age_ms: None,
                stamp_ns: Some(f.stamp_ns),
            })
        })
        .collect()
}

#[pymethods]
impl PyVideoDecoder {
    /// Refused: a decoder holds the stream's state so far.
    fn __reduce__(&self) -> PyResult<Py<PyAny>> {
        Err(crate::pickling::open_stream(
            "VideoDecoder",
            "an open decoder (the stream's packets so far)",
            "Decode in one process and send the frames (numpy arrays pickle)",
        ))
    }

    #[new]
    #[pyo3(
        signature = (format, *, name=Given::of("video")),
        text_signature = "(format, *, name='video')"
    )]
    fn new(py: Python<'_>, format: Given<String>, name: Given<String>) -> PyResult<Self> {
        crate::args::keywords!(format, name);
        let decoder = py
            .detach(|| tactile_core::bag::LiveVideo::new(&format, &name))
            .py()?;
        Ok(Self {
            decoder: Mutex::new(decoder),
        })
    }

    /// Give the next packet and its stamp (nanoseconds); the frames ready.
    #[pyo3(signature = (data, stamp_ns=Whole::of(0)), text_signature = "(self, data, stamp_ns=0)")]
    fn decode(
        &self,
        py: Python<'_>,
        data: &Bound<'_, PyAny>,
        stamp_ns: Whole,
    ) -> PyResult<Vec<PyFrame>> {
        let stamp_ns = stamp_ns.within("stamp_ns", i64::MIN, i64::MAX)?;
        let data = message_bytes(py, data, "a packet's data")?
            .as_bytes()
            .to_vec();
        let frames = self.with(|d| py.detach(|| d.push(&data, stamp_ns)).py())?;
        live_frames(py, frames)
    }

    /// End the stream: the frames still held.
    fn finish(&self, py: Python<'_>) -> PyResult<Vec<PyFrame>> {
        let frames = self.with(|d| py.detach(|| d.finish()).py())?;
        live_frames(py, frames)
    }

    /// Packets given before the first keyframe, which no decoder can read.
    #[getter]
    fn skipped(&self) -> PyResult<u64> {
        self.with(|d| Ok(d.skipped()))
    }

    /// Keyframes among the packets skipped that came without their
    /// parameters (H.264's and H.265's SPS, AV1's sequence header): an
    /// encoder that sent them only before the subscription began. No frame
    /// comes until a keyframe carries them: have the encoder repeat them
    /// at every keyframe (x264's `repeat-headers=1`, GStreamer's
    /// `h264parse config-interval=-1`).
    #[getter]
    fn keyframes_without_parameters(&self) -> PyResult<u64> {
        self.with(|d| Ok(d.keyframes_without_parameters()))
    }

    /// Packets that gave no frame (damaged): shown before a frame that
    /// came, or left without one at `finish`.
    #[getter]
    fn lost(&self) -> PyResult<u64> {
        self.with(|d| Ok(d.lost()))
    }

    /// Changes of the stream's parameters (a camera restarted at another
    /// size) whose frames were scaled to the earlier frames' size: those
    /// past the first 64 that came sooner than one per 32 packets. Every
    /// other change's frames keep their own size.
    #[getter]
    fn scaled(&self) -> PyResult<u64> {
        self.with(|d| Ok(d.scaled()))
    }
}

/// Open a source of frames: `source` is a dataset folder, a folder of frames
/// (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM), an image, a TIFF of many pages
/// (a stack, read page by page), a video file (decoded by the system's FFmpeg,
/// every frame), a ROS 2 bag (its folder, or one ".mcap" or ".db3"; `topic` names its
/// image topic, else its only one is read), a camera device such as
/// "/dev/video0" (live) or a network stream's URL such as
/// "rtsp://192.168.1.20/stream" (live; a file served with a length, every
/// frame); or give
/// `stdin_size=(width, height)` (and no source) to read raw rgb24 frames
/// from standard input (live). Live sources keep at most `live_queue`
/// frames waiting and drop the oldest when more arrive.
#[pyfunction]
#[pyo3(
    signature = (source=None, *, topic=None, stdin_size=None, live_queue=Whole::of(2), limit=None, prefetch=Given::of(true)),
    text_signature = "(source=None, *, topic=None, stdin_size=None, live_queue=2, limit=None, prefetch=True)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn frames(
    py: Python<'_>,
    source: Option<PathArg>,
    topic: Option<Given<String>>,
    stdin_size: Option<Given<[Whole; 2]>>,
    live_queue: Whole,
    limit: Option<Whole>,
    prefetch: Given<bool>,
) -> PyResult<PyFrameSource> {
    crate::args::keywords!(source, topic, prefetch, stdin_size);
    let spec = source_spec(source, topic, stdin_size)?;
    let options = SourceOptions {
        overlap: prefetch,
        live_queue: self::live_queue(&live_queue)?,
        limit: source_limit(limit.as_ref())?,
    };
    let source = py.detach(move || FrameSource::open(&spec, options)).py()?;
    for w in source.warnings() {
        crate::errors::user_warning(py, &w)?;
    }
    Ok(PyFrameSource {
        source: Mutex::new(source),
        late_warned: AtomicBool::new(false),
    })
}

/// `live_queue=`: frames a live source keeps waiting, as the command line
/// bounds them.
pub(crate) fn live_queue(arg: &Whole) -> PyResult<usize> {
    arg.within("live_queue", 1, tactile_core::source::MAX_LIVE_QUEUE)
}

/// `limit=`: at most this many frames (`None`: all of them).
pub(crate) fn source_limit(arg: Option<&Whole>) -> PyResult<Option<u64>> {
    optional(arg, "limit", 1, u64::MAX)
}

/// The source a path, a bag's topic or a size of raw frames on stdin
/// names: `tactile.frames`' and `tactile.run`'s first arguments.
pub(crate) fn source_spec(
    source: Option<PathBuf>,
    topic: Option<String>,
    stdin_size: Option<[Whole; 2]>,
) -> PyResult<SourceSpec> {
    // How large a frame may be is the library's check (1 pixel to 8K).
    let side = |w: &Whole, name| w.within(name, 1, usize::MAX);
    let stdin_size = match stdin_size {
        Some([w, h]) => Some((
            side(&w, "stdin_size width")?,
            side(&h, "stdin_size height")?,
        )),
        None => None,
    };
    Ok(match (source, stdin_size) {
        (None, Some(_)) if topic.is_some() => {
            return Err(PyValueError::new_err(
                "topic picks a ROS 2 bag's images, and raw frames on stdin (stdin_size) have none: \
                 leave topic out, or give the bag as the source",
            ));
        }
        (Some(path), None) if topic.is_some() => SourceSpec::Bag { path, topic },
        (None, Some((width, height))) => SourceSpec::Stdin { width, height },
        (Some(p), None) => SourceSpec::Path(p),
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "give a source path or stdin_size, not both",
            ));
        }
        (None, None) => {
            return Err(PyValueError::new_err(
                "give a source path, or stdin_size=(width, height) for raw frames on stdin",
            ));
        }
    })
}

/// The image topics of a ROS 2 bag (its folder, or one MCAP or SQLite
/// `.db3` file): a list
/// of dicts with `topic`, `message_type`, `count` and `rate_hz`.
#[pyfunction]
pub(crate) fn bag_topics(py: Python<'_>, path: PathArg) -> PyResult<Vec<Py<PyAny>>> {
    crate::args::keywords!(path);
    let listing = py
        .detach(move || tactile_core::bag::list_image_topics(&path))
        .py()?;
    for w in &listing.warnings {
        crate::errors::user_warning(py, w)?;
    }
    listing
        .topics
        .into_iter()
        .map(|t| {
            let d = pyo3::types::PyDict::new(py);
            d.set_item("topic", t.topic)?;
            d.set_item("message_type", t.message_type)?;
            d.set_item("count", t.count)?;
            d.set_item("rate_hz", t.rate_hz)?;
            Ok(d.into_any().unbind())
        })
        .collect()
}

/// A `sensor_msgs/msg/Image` (an rclpy message, or any object with its
/// `height`, `width`, `encoding`, `is_bigendian`, `step` and `data`), or a
/// `sensor_msgs/msg/CompressedImage` (`format` and `data`: JPEG, PNG or
/// another frame format), as
/// an `(H, W, 3)` uint8 RGB array: the conversion `tactile run` gives a
/// bag's frames, for a node that subscribes to a topic itself.
#[pyfunction]
pub(crate) fn ros_image_to_rgb(py: Python<'_>, msg: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
    use tactile_core::bag::messages::{CompressedImage, Header, Image};
    let compressed = msg.hasattr("format")? && !msg.hasattr("encoding")?;
    let kind = match compressed {
        true => "sensor_msgs/msg/CompressedImage",
        false => "sensor_msgs/msg/Image",
    };
    let field = |name: &str| {
        msg.getattr(name)
            .map_err(|_| PyValueError::new_err(format!("not a {kind}: it has no field {name:?}")))
    };
    let data = message_bytes(py, &field("data")?, &format!("{kind} field \"data\""))?;
    let data = data.as_bytes();
    let string = |name: &str| -> PyResult<String> {
        field(name)?
            .extract()
            .map_err(|_| PyValueError::new_err(format!("{kind} field {name:?}: must be a string")))
    };
    if compressed {
        let image = CompressedImage {
            header: Header::default(),
            format: string("format")?,
            data,
        };
        let rgb = py
            .detach(|| image.to_rgb())
            .map_err(PyValueError::new_err)?;
        return Ok(crate::image::rgb_array(py, rgb)?.unbind());
    }
    let number = |name: &str| -> PyResult<u32> {
        field(name)?.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "{kind} field {name:?}: must be an integer from 0 to 4294967295"
            ))
        })
    };
    let (height, width, step) = (number("height")?, number("width")?, number("step")?);
    let is_bigendian = u8::from(field("is_bigendian")?.is_truthy()?);
    let image = Image {
        header: Header::default(),
        height,
        width,
        encoding: string("encoding")?,
        is_bigendian,
        step,
        data,
    };
    let rgb = image.to_rgb().map_err(PyValueError::new_err)?;
    Ok(crate::image::rgb_array(py, rgb)?.unbind())
}
