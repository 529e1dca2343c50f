//! What can go wrong training, loading or running the depth network.

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Errors of the depth network.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file, dataset, model folder or configuration problem.
    #[error(transparent)]
    Core(#[from] tactile_core::Error),
    /// A frame that could not be made into the network's input.
    #[error(transparent)]
    Preprocess(#[from] tactile_preprocess::Error),
    /// Export or onnxruntime.
    #[error(transparent)]
    Onnx(#[from] tactile_onnx::Error),
    /// The sensor calibration a network with a prior starts from.
    #[error(transparent)]
    Calibration(#[from] tactile_gelsight::Error),
    /// A mask-channel network given no mask (or one of the wrong size).
    #[error("this depth network takes a {}x{} tendon mask as a fourth channel", size[0], size[1])]
    MaskRequired {
        /// The network's input size.
        size: [usize; 2],
    },
    /// A network with a prior given none (or one of the wrong size).
    #[error("this depth network corrects its sensor calibration's reconstruction: it takes a {}x{} prior as a fourth channel", size[0], size[1])]
    PriorRequired {
        /// The network's input size.
        size: [usize; 2],
    },
    /// Targets in units so coarse that training would stall (paper B's
    /// metres).
    #[error(
        "the depth targets vary by only {std_units:.2e} model units ({std_mm:.3} mm at {unit_mm} mm per unit): the loss would barely move and training would stall; use millimetres (unit 1 mm)"
    )]
    Stall {
        /// Standard deviation in model units.
        std_units: f64,
        /// In millimetres.
        std_mm: f64,
        /// Millimetres per model unit.
        unit_mm: f32,
    },
}

impl Error {
    /// The foundation error underneath, when there is one.
    pub fn core(&self) -> Option<&tactile_core::Error> {
        match self {
            Error::Core(e) => Some(e),
            Error::Preprocess(e) => e.core(),
            Error::Onnx(e) => e.core(),
            Error::Calibration(e) => e.core(),
            _ => None,
        }
    }
}
