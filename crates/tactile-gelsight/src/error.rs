//! What can go wrong calibrating a sensor or reconstructing its skin.

use std::path::PathBuf;

/// Errors of this crate; each names the file or field at fault.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Foundation errors: I/O, images, configs.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// ONNX export or onnxruntime.
    #[error(transparent)]
    Onnx(#[from] tactile_onnx::Error),
    /// Writing the sensor's rendered dataset (an output folder in use).
    #[error(transparent)]
    Synth(#[from] datasets_synth::Error),
    /// A calibration folder that does not hold what the layout asks for.
    #[error("{path}: {why}")]
    Layout {
        /// The file or folder at fault.
        path: PathBuf,
        /// What is wrong with it.
        why: String,
    },
    /// A press whose contact circle cannot be used.
    #[error("{path}: {why}")]
    Press {
        /// The press's frame.
        path: PathBuf,
        /// What is wrong with its circle.
        why: String,
    },
    /// Too few presses to fit or score a model.
    #[error("{count} presses in {path}: {purpose} needs at least {needed}")]
    TooFewPresses {
        /// The calibration folder.
        path: PathBuf,
        /// Presses found.
        count: usize,
        /// Presses needed.
        needed: usize,
        /// What needs them ("the sensor model", "a cross-validation of 8
        /// folds").
        purpose: String,
    },
    /// A frame whose size is not the calibration's.
    #[error(
        "{path}: frame is {found:?} (width, height), the sensor was calibrated at {expected:?}"
    )]
    FrameSize {
        /// The frame.
        path: PathBuf,
        /// Calibrated size.
        expected: (usize, usize),
        /// The frame's size.
        found: (usize, usize),
    },
    /// A frame of one colour (black, saturated, a covered lens or its
    /// light off): no skin to read, whatever the sensor.
    #[error(
        "{path}: a blank frame (every pixel of one colour, {level}): the camera shows no skin (its lens covered, its light off, or its exposure at an end)"
    )]
    BlankFrame {
        /// The frame.
        path: PathBuf,
        /// Its colour as `RGB (r, g, b)`.
        level: String,
    },
    /// A frame (or rest frame) in BGR order: its red and blue swapped
    /// back, it is much nearer the sensor's rest frame
    /// ([`crate::prepare::PreparedBackground::swapped_channels`]).
    #[error(
        "{path}: red and blue look swapped (BGR order, as OpenCV's imread and VideoCapture give frames): swapped back, its colours change from this sensor's rest frame by {swapped:.3}, as given by {given:.3} (the median RGB distance on a 0-1 scale); give it in RGB order (numpy: frame[..., ::-1])"
    )]
    SwappedChannels {
        /// The frame.
        path: PathBuf,
        /// Its median colour change as given.
        given: f32,
        /// The same with red and blue swapped back.
        swapped: f32,
    },
    /// A grey frame (or rest frame) given to a sensor calibrated on colour
    /// frames, whose colours are what its slopes are read from.
    #[error(
        "{path}: a greyscale frame, but the sensor was calibrated on colour frames, whose colours are what it reads the skin's slopes from; give the camera's colour frame"
    )]
    GreyFrame {
        /// The frame.
        path: PathBuf,
    },
    /// A colour frame given to a sensor whose background is grey: a grey
    /// copy of the rest frame, or a frame of another sensor.
    #[error(
        "{path}: a colour frame (its channels {spread:.1} grey levels apart on average), but the sensor's background is grey: a grey sensor's frames are grey too. Give the background as the camera records it (in colour), or this sensor's own frames"
    )]
    ColourFrame {
        /// The frame.
        path: PathBuf,
        /// How far apart its channels are, grey levels on average.
        spread: f32,
    },
    /// Frames of a folder this sensor cannot read, found from their
    /// headers before any frame is reconstructed: the first one's refusal
    /// ([`Error::FrameSize`], [`Error::GreyFrame`], or the file's own) and
    /// how many.
    #[error(
        "{first}; {count} of the {total} frames cannot be read by this sensor (not a picture or cut short, larger than 8K, not 8 bits per channel, another size than its calibration's, or stored grey for a sensor calibrated in colour): nothing was reconstructed"
    )]
    UnreadableFrames {
        /// The first such frame's refusal.
        first: Box<Error>,
        /// Frames that cannot be read.
        count: usize,
        /// Frames in the folder.
        total: usize,
    },
}

impl Error {
    /// A [`Error::Layout`] refusal of the calibration folder's `path`.
    pub(crate) fn layout(path: &std::path::Path, why: impl Into<String>) -> Self {
        Self::Layout {
            path: path.to_path_buf(),
            why: why.into(),
        }
    }

    /// Whether this is [`Reconstructor::check_frame`]'s (or
    /// `check_working`'s) refusal of a frame the sensor cannot read
    /// (another size than its calibration's, blank, in BGR order, grey for
    /// a sensor calibrated in colour, colour for a grey one): the frame's
    /// fault, not the calibration's or the machine's. A pipeline gives
    /// such a frame nothing and goes on; any other error stops it.
    ///
    /// [`Reconstructor::check_frame`]: crate::Reconstructor::check_frame
    pub fn is_frame_refusal(&self) -> bool {
        matches!(
            self,
            Error::FrameSize { .. }
                | Error::BlankFrame { .. }
                | Error::SwappedChannels { .. }
                | Error::GreyFrame { .. }
                | Error::ColourFrame { .. }
        )
    }

    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Onnx(e) => e.core(),
            _ => None,
        }
    }
}

/// This crate's result.
pub type Result<T> = std::result::Result<T, Error>;

impl From<tactile_preprocess::Error> for Error {
    fn from(e: tactile_preprocess::Error) -> Self {
        Error::Core(tactile_core::Error::Invalid(e.to_string()))
    }
}

impl From<kornia_image::ImageError> for Error {
    fn from(e: kornia_image::ImageError) -> Self {
        Error::Core(tactile_core::Error::Invalid(e.to_string()))
    }
}
