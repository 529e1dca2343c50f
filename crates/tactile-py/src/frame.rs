//! numpy arrays in: an `(H, W, 3)` uint8 RGB frame or an `(H, W)` (or
//! `(H, W, 1)`) uint8 grey frame (an opaque alpha channel dropped),
//! checked for type and shape with a message that says what was given. A
//! C-contiguous array is read in place (no copy); any other layout (a
//! slice, a channel-reversed view of an OpenCV BGR frame) is copied once
//! into a contiguous buffer, as is a frame whose alpha is dropped.

use std::sync::Arc;

use kornia_image::{Image, ImageSize};
use numpy::ndarray::{ArrayView3, ArrayViewD, Axis, Ix2, Ix3};
use numpy::{
    PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// Largest frame side accepted, pixels (8K UHD is 7680 wide): a dataset's.
pub(crate) const MAX_SIDE: usize = tactile_core::dataset::MAX_SIDE as usize;

/// Channels a frame must have.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Layout {
    /// `(H, W, 3)`.
    Rgb,
    /// `(H, W)`, or `(H, W, 3)` converted to grey.
    GreyOrRgb,
}

/// A checked frame whose pixels are borrowed from numpy or copied.
pub(crate) struct FrameArg<'py> {
    array: PyReadonlyArrayDyn<'py, u8>,
    copy: Option<Vec<u8>>,
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// 1 or 3.
    pub channels: usize,
}

/// A shape as Python prints it: `(180, 320, 3)`, `(5,)`.
pub(crate) fn py_shape(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(usize::to_string).collect();
    match parts.len() {
        1 => format!("({},)", parts[0]),
        _ => format!("({})", parts.join(", ")),
    }
}

/// How to mend a frame whose shape is not what `layout` reads: grey (with
/// or without alpha) where only RGB is read, channels first (as
/// torchvision's `read_image` and a CHW tensor's `.numpy()` give a frame),
/// or a batch where one frame is read.
fn channel_hint(shape: &[usize], layout: Layout) -> String {
    // A side of 1 to 4 is a channel axis, not a frame's width or height.
    let channels = |c: usize| (1..=4).contains(&c);
    match (shape, layout) {
        (&[_, _, 1 | 2] | &[_, _], Layout::Rgb) => {
            " (a grey frame: repeat it to RGB with numpy.dstack([frame] * 3) if the sensor's frames are grey; a colour sensor's frames must stay in colour)".into()
        }
        (&[c, _, w], _) if channels(c) && !channels(w) => {
            " (channels first, as a torch tensor has them: numpy.transpose(frame, (1, 2, 0)) puts them last)".into()
        }
        (&[1, _, _, c], _) if channels(c) => " (a batch of one frame: pass frame[0])".into(),
        (&[n, _, _, c], _) if channels(c) => {
            format!(" (a stack of {n} frames: pass one at a time, frames[i])")
        }
        (&[_, c, _, w], _) if channels(c) && !channels(w) => {
            " (a batch of channels-first frames: numpy.transpose(frames[i], (1, 2, 0)) is one frame with its channels last)".into()
        }
        _ => String::new(),
    }
}

/// What `obj` is, for a message: its dtype and shape when it is an array.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    match obj.cast::<PyUntypedArray>() {
        Ok(a) => {
            // "an int8", "an object", but "a uint16" (said "you-int").
            let dtype = a.dtype().to_string();
            let article = match dtype.starts_with(['i', 'o']) {
                true => "an",
                false => "a",
            };
            format!("{article} {dtype} array of shape {}", py_shape(a.shape()))
        }
        Err(_) => match obj.get_type().name() {
            Ok(n) => {
                let n = n.to_string();
                format!("{} {n}", tactile_core::error::article(&n))
            }
            Err(_) => "another type".into(),
        },
    }
}

/// How to make a frame of another dtype 8-bit, told by its values: a
/// float frame of 0 to 1 (skimage's `img_as_float`, torchvision's
/// `ToTensor`) cast as it is would become black, and a camera's 12- or
/// 16-bit levels would wrap.
fn conversion_hint(obj: &Bound<'_, PyAny>, arr: &Bound<'_, PyUntypedArray>) -> String {
    let value = |m: &str| {
        obj.call_method0(m)
            .and_then(|v| v.extract::<f64>())
            .ok()
            .filter(|v| v.is_finite())
    };
    // Values are looked at only where they are levels (not complex, not
    // objects), and only here, on the way to the error.
    let kind = arr.dtype().kind();
    // A view larger than any frame (a broadcast claiming terabytes) is not
    // scanned.
    let largest = MAX_SIDE * MAX_SIDE * 4;
    if arr.len() == 0 || arr.len() > largest || !matches!(kind, b'b' | b'i' | b'u' | b'f') {
        return "convert it to uint8 levels 0-255".into();
    }
    let (Some(lo), Some(hi)) = (value("min"), value("max")) else {
        return "convert it to uint8 levels 0-255".into();
    };
    let short = |v: f64| match v.fract() == 0.0 {
        true => format!("{v:.0}"),
        false => format!("{v:.3}"),
    };
    let (lo_s, hi_s) = (short(lo), short(hi));
    match kind {
        b'b' => "a mask? frames are levels 0-255: frame.astype(numpy.uint8) * 255".into(),
        b'f' if lo >= 0.0 && hi <= 1.0 => format!(
            "its values lie in {lo_s}..{hi_s}, as a float image of 0 to 1 has: (frame * 255).round().astype(numpy.uint8); .astype(numpy.uint8) alone would make it black"
        ),
        b'f' if lo >= 0.0 && hi <= 255.0 => {
            format!("its values lie in {lo_s}..{hi_s}: frame.round().astype(numpy.uint8)")
        }
        _ if lo >= 0.0 && hi <= 255.0 => {
            format!("its values lie in {lo_s}..{hi_s}: frame.astype(numpy.uint8)")
        }
        _ if lo < 0.0 => format!(
            "its values lie in {lo_s}..{hi_s}, below 0: a normalised image? undo the normalisation to levels 0-255, then .round().astype(numpy.uint8)"
        ),
        _ => format!(
            "its values lie in {lo_s}..{hi_s}, past 8 bits: scale the levels the camera fills to 0-255 (a 12-bit camera's / 16, a 16-bit one's / 257), then .round().astype(numpy.uint8)"
        ),
    }
}

impl<'py> FrameArg<'py> {
    /// Check `obj` (named `what` in messages) and borrow its pixels.
    pub fn new(obj: &Bound<'py, PyAny>, layout: Layout, what: &str) -> PyResult<Self> {
        let want = match layout {
            Layout::Rgb => "an (H, W, 3) uint8 RGB array",
            Layout::GreyOrRgb => "an (H, W) uint8 grey or (H, W, 3) uint8 RGB array",
        };
        let arr = obj.cast::<PyUntypedArray>().map_err(|_| {
            PyTypeError::new_err(format!("{what}: expected {want}, got {}", describe(obj)))
        })?;
        if !arr.dtype().is_equiv_to(&numpy::dtype::<u8>(obj.py())) {
            return Err(PyTypeError::new_err(format!(
                "{what}: expected {want}, got {} ({})",
                describe(obj),
                conversion_hint(obj, arr)
            )));
        }
        let shape = arr.shape().to_vec();
        // Alpha (as imageio or PIL read a PNG that has it) is dropped when
        // every pixel is opaque, by the rule frame files follow.
        let (height, width, given) = match (layout, shape.as_slice()) {
            (_, &[h, w, c @ (3 | 4)]) => (h, w, c),
            (Layout::GreyOrRgb, &[h, w] | &[h, w, 1]) => (h, w, 1),
            (Layout::GreyOrRgb, &[h, w, 2]) => (h, w, 2),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "{what}: expected {want}, got shape {}{}",
                    py_shape(&shape),
                    channel_hint(&shape, layout)
                )));
            }
        };
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(PyValueError::new_err(format!(
                "{what}: {width}x{height} frame; width and height must be 1 to {MAX_SIDE} pixels"
            )));
        }
        let typed = obj.cast::<PyArrayDyn<u8>>()?;
        let array = typed
            .try_readonly()
            .map_err(|e| PyValueError::new_err(format!("{what}: cannot read the array ({e})")))?;
        // Read in place only in C order: numpy's `as_slice` also hands out a
        // Fortran-ordered buffer (a grey frame's `.T`, MATLAB's arrays
        // through scipy), whose bytes in that order are columns, not rows.
        let copy = match array.is_c_contiguous() {
            true => None,
            false => Some(standard_layout(&array.as_array())),
        };
        let mut frame = Self {
            array,
            copy,
            width,
            height,
            channels: given,
        };
        if given == 2 || given == 4 {
            let kind = if given == 4 {
                "an RGBA"
            } else {
                "a grey-with-alpha"
            };
            let dropped = tactile_core::image_io::drop_opaque_alpha(frame.pixels(), given)
                .map_err(|n| {
                    PyValueError::new_err(format!(
                        "{what}: {kind} frame of shape {} with {n} of its {} pixels not opaque; \
                         expected {want} (an alpha channel is dropped only when every pixel is opaque)",
                        py_shape(&shape),
                        width * height
                    ))
                })?;
            frame.copy = Some(dropped);
            frame.channels = given - 1;
        }
        Ok(frame)
    }

    /// The pixels, row-major interleaved.
    pub fn pixels(&self) -> &[u8] {
        match &self.copy {
            Some(v) => v,
            // Checked C-contiguous in `new`.
            None => self.array.as_slice().unwrap_or(&[]),
        }
    }
}

/// The pixels of a frame not laid out in place (a slice, a channel-reversed
/// view), copied in row-major order. A frame whose rows each lie in one
/// run of its buffer (a crop, OpenCV's BGR frame reversed to RGB,
/// `frame[::-1]`, `frame[:, ::-1]`) is copied row by row; any other view
/// (Fortran order, a transpose, a stride) through a view of fixed
/// dimension, as numpy's own copy walks it. Stepping a dynamic-dimension
/// index per byte, as before, took 19 ms for a VGA frame.
fn standard_layout(view: &ArrayViewD<'_, u8>) -> Vec<u8> {
    let frame = match view.ndim() {
        2 => view
            .view()
            .into_dimensionality::<Ix2>()
            .map(|v| v.insert_axis(Axis(2))),
        _ => view.view().into_dimensionality::<Ix3>(),
    };
    match frame {
        Ok(v) => copy_by_rows(&v).unwrap_or_else(|| v.iter().copied().collect()),
        Err(_) => view.iter().copied().collect(),
    }
}

/// `frame` (rows, columns, channels) copied in row-major order when each
/// of its rows, once its reversed axes are turned back, is one run of the
/// buffer; `None` for any other view.
fn copy_by_rows(frame: &ArrayView3<'_, u8>) -> Option<Vec<u8>> {
    let reversed: [bool; 3] = std::array::from_fn(|a| frame.strides()[a] < 0);
    let mut stored = frame.view();
    for (axis, _) in reversed.iter().enumerate().filter(|(_, r)| **r) {
        stored.invert_axis(Axis(axis));
    }
    let (h, w, c) = frame.dim();
    let mut out = Vec::with_capacity(h * w * c);
    for y in 0..h {
        let row = stored.index_axis(Axis(0), if reversed[0] { h - 1 - y } else { y });
        let row = row.to_slice()?;
        match (reversed[1], reversed[2]) {
            (false, false) => out.extend_from_slice(row),
            (false, true) => row.chunks_exact(c).for_each(|p| out.extend(p.iter().rev())),
            (true, false) => row
                .chunks_exact(c)
                .rev()
                .for_each(|p| out.extend_from_slice(p)),
            (true, true) => out.extend(row.iter().rev()),
        }
    }
    Some(out)
}

/// Borrowed pixels that can cross into a GIL-free closure.
#[derive(Clone, Copy)]
pub(crate) struct Pixels<'a> {
    /// Row-major interleaved.
    pub data: &'a [u8],
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// 1 or 3.
    pub channels: usize,
}

impl<'py> FrameArg<'py> {
    /// The pixels as a plain borrowed view.
    pub fn view(&self) -> Pixels<'_> {
        Pixels {
            data: self.pixels(),
            width: self.width,
            height: self.height,
            channels: self.channels,
        }
    }
}

impl Pixels<'_> {
    /// Run `f` on the frame as a kornia RGB image that reads these pixels
    /// in place. Grey frames are expanded to RGB (a copy).
    pub fn with_rgb<R>(
        &self,
        f: impl FnOnce(&tactile_core::image_io::RgbImage) -> R,
    ) -> tactile_core::Result<R> {
        let size = ImageSize {
            width: self.width,
            height: self.height,
        };
        if self.channels != 3 {
            let rgb = tactile_core::image_io::grey_to_rgb(self.data);
            return Ok(f(&tactile_core::image_io::rgb_image(
                self.width,
                self.height,
                rgb,
            )?));
        }
        if self.data.len() != size.width * size.height * 3 {
            return Err(tactile_core::Error::shape(
                "frame",
                format!("{} bytes", size.width * size.height * 3),
                format!("{} bytes", self.data.len()),
            ));
        }
        // SAFETY: `data` holds exactly width * height * 3 bytes (checked
        // above) and outlives the image, which is dropped before this
        // function returns; the image is read-only, and its keep-alive owns
        // nothing because the borrow of `data` already keeps the memory.
        #[allow(unsafe_code)]
        let img = unsafe {
            Image::<u8, 3>::from_borrowed_host_readonly(size, self.data.as_ptr(), Arc::new(()))
        }
        .map_err(|e| tactile_core::Error::Invalid(format!("frame: {e}")))?;
        Ok(f(&img))
    }

    /// The frame in grey levels: as given, or RGB converted the way a
    /// colour PNG is on load (OpenCV's weights).
    pub fn grey(&self) -> tactile_core::Result<tactile_core::image_io::GreyImage> {
        let data = if self.channels == 3 {
            tactile_core::image_io::rgb_to_grey(self.data)
        } else {
            self.data.to_vec()
        };
        tactile_core::image_io::grey_image(self.width, self.height, data)
    }
}

/// Most frames one call takes.
pub(crate) const MAX_BATCH: usize = 100_000;

/// Frames checked and handed on together by [`frame_chunks`], at most: a
/// dataset's chunk.
const CHUNK_FRAMES: usize = tactile_cae::data::DATASET_CHUNK;

/// Bytes of pixels handed on together by [`frame_chunks`], at most (but
/// for a chunk of one frame): the copies of frames not laid out in place
/// are held for one chunk only, so a batch of many large frames taken
/// from a view (`frames[..., ::-1]`) is never copied whole.
const CHUNK_BYTES: usize = 256 << 20;

/// `f` on each frame of `frames` in order, with its name for messages:
/// one frame (`frame`) or an `(N, ...)` array or iterable of them
/// (`frames[i]`), read one at a time (a generator of video frames is never
/// held whole). A 2-D array, or a 3-D one whose last axis is 4 or less, is
/// one frame (an `(H, W, 3)` RGB frame as OpenCV and imageio give it, not H
/// frames 3 pixels wide; no model reads frames 4 pixels wide or less), so a
/// frame with a channel axis or alpha is checked, and named, as one frame.
pub(crate) fn each_frame<'py, T>(
    frames: &Bound<'py, PyAny>,
    mut f: impl FnMut(&Bound<'py, PyAny>, &str) -> PyResult<T>,
) -> PyResult<Vec<T>> {
    const WANT: &str = "expected one (H, W) or (H, W, 3) uint8 frame, an (N, H, W) or (N, H, W, 3) uint8 array, or a list of frames";
    if let Ok(a) = frames.cast::<PyUntypedArray>() {
        if a.ndim() == 2 || (a.ndim() == 3 && a.shape()[2] <= 4) {
            return Ok(vec![f(frames, "frame")?]);
        }
        if a.ndim() != 3 && a.ndim() != 4 {
            return Err(PyValueError::new_err(format!(
                "frames: {WANT}; got shape {}",
                py_shape(a.shape())
            )));
        }
    }
    let items = frames
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("frames: {WANT}; got {}", describe(frames))))?;
    let mut out = Vec::new();
    for (i, item) in items.enumerate() {
        if i >= MAX_BATCH {
            return Err(PyValueError::new_err(format!(
                "frames: more than {MAX_BATCH} frames in one call; pass them in batches"
            )));
        }
        // Python's signal handlers run only between bytecodes: Ctrl-C is
        // looked for here, between frames, or a long batch would ignore it.
        frames.py().check_signals()?;
        out.push(f(&item?, &format!("frames[{i}]"))?);
    }
    Ok(out)
}

/// Every frame of `frames` ([`each_frame`]) checked as `layout` says and
/// handed to `f` in order, a chunk of them at a time (at most
/// [`CHUNK_FRAMES`] frames and, but for one frame, [`CHUNK_BYTES`] of
/// pixels) with the place of the chunk's first frame in the call: a long
/// batch's copies are never held whole.
pub(crate) fn frame_chunks<'py>(
    frames: &Bound<'py, PyAny>,
    layout: Layout,
    mut f: impl FnMut(&[FrameArg<'py>], usize) -> PyResult<()>,
) -> PyResult<()> {
    let (mut chunk, mut bytes, mut first) = (Vec::new(), 0usize, 0usize);
    each_frame(frames, |frame, what| {
        let arg = FrameArg::new(frame, layout, what)?;
        let full = chunk.len() == CHUNK_FRAMES || bytes + arg.pixels().len() > CHUNK_BYTES;
        if full && !chunk.is_empty() {
            f(&chunk, first)?;
            first += chunk.len();
            (chunk, bytes) = (Vec::new(), 0);
        }
        bytes += arg.pixels().len();
        chunk.push(arg);
        Ok(())
    })?;
    if chunk.is_empty() {
        return Ok(());
    }
    f(&chunk, first)
}
