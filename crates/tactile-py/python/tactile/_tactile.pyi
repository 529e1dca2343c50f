"""Type stubs of the native module (see the ``tactile`` package docs)."""

from os import PathLike
from pathlib import Path
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]

__version__: str
MAX_FRAME_SIDE: int
MAX_BATCH: int
MAX_ARRAY_BYTES: int

class FrameResult:
    """What the pipeline made of one frame; pickles whole (record, mask, depth, indentation), so worker processes can return it."""

    @property
    def tendon(self) -> bool: ...
    @property
    def tendon_raw(self) -> bool: ...
    @property
    def out_of_distribution(self) -> bool: ...
    @property
    def unreadable(self) -> Optional[str]: ...
    @property
    def input_score(self) -> Optional[float]: ...
    @property
    def gate(self) -> Optional[str]: ...
    @property
    def score(self) -> float: ...
    @property
    def direction_deg(self) -> Optional[float]: ...
    @property
    def anisotropy(self) -> Optional[float]: ...
    @property
    def no_direction(self) -> Optional[str]: ...
    @property
    def mask_area_px(self) -> int: ...
    @property
    def mask(self) -> npt.NDArray[np.bool_]: ...
    @property
    def depth_m(self) -> Optional[npt.NDArray[np.float32]]: ...
    @property
    def depth_maps(self) -> Optional[str]: ...
    @property
    def depth_mm_stats(self) -> Optional[Tuple[float, float, float]]: ...
    @property
    def indentation_m(self) -> Optional[npt.NDArray[np.float32]]: ...
    @property
    def indentation_peak_mm(self) -> Optional[float]: ...
    @property
    def contact_area_mm2(self) -> Optional[float]: ...
    @property
    def ms(self) -> Dict[str, float]: ...
    def to_dict(self) -> Dict[str, Any]: ...

class Pipeline:
    """Paper B's palpation pipeline: detect, then segment, point and reconstruct depth; a calibrated sensor's indentation.

    Not pickled (it holds loaded models): make one per thread or worker process; one per thread runs frames in parallel."""

    def __init__(
        self,
        models: _Path = "models",
        runtime: str = "onnx",
        *,
        threads: int = 1,
        hysteresis: Optional[Sequence[float]] = None,
    ) -> None: ...
    def process(self, frame: npt.NDArray[np.uint8]) -> FrameResult: ...
    def process_many(
        self, frames: Union[npt.NDArray[np.uint8], Iterable[npt.NDArray[np.uint8]]]
    ) -> List[FrameResult]: ...
    def reset(self) -> None: ...
    def time_in_rust(self, frame: npt.NDArray[np.uint8], repeats: int = 100) -> List[float]: ...
    def detector_frame(
        self, frame: npt.NDArray[np.uint8]
    ) -> Union[npt.NDArray[np.uint8], npt.NDArray[np.uint16]]: ...
    @property
    def threshold(self) -> Optional[float]: ...
    @property
    def calibrated(self) -> bool: ...
    @property
    def runtime(self) -> str: ...
    @property
    def models(self) -> Path: ...
    @property
    def threads(self) -> int: ...
    @property
    def hysteresis(self) -> Optional[Tuple[float, float]]: ...

class TactipEncoder:
    """Paper A's encoder and every estimator trained on its features."""

    def __init__(
        self,
        model_dir: _Path,
        runtime: str = "burn-flex",
        *,
        estimators: Optional[Union[_Path, Sequence[_Path]]] = None,
    ) -> None: ...
    def preprocess(self, frame: npt.NDArray[np.uint8]) -> npt.NDArray[np.float32]: ...
    def encode(
        self, frames: Union[npt.NDArray[np.uint8], Iterable[npt.NDArray[np.uint8]]]
    ) -> npt.NDArray[np.float32]: ...
    def encode_dataset(
        self, data: _Path, *, out: Optional[_Path] = None
    ) -> Dict[str, Any]: ...
    def estimate(
        self, frames: Union[npt.NDArray[np.uint8], Iterable[npt.NDArray[np.uint8]]]
    ) -> Dict[str, npt.NDArray[Any]]: ...
    @property
    def feature_count(self) -> int: ...
    @property
    def pin_side(self) -> int: ...
    @property
    def estimators(self) -> List[str]: ...
    @property
    def runtime(self) -> str: ...

class PoseEstimator:
    """A supervised pose network (or an ensemble): its targets straight from
    the frame, with a ``<target>_std`` deviation where it gives one."""

    def __init__(self, model_dir: _Path, runtime: str = "burn-flex") -> None: ...
    def preprocess(self, frame: npt.NDArray[np.uint8]) -> npt.NDArray[np.float32]: ...
    def estimate(
        self, frames: Union[npt.NDArray[np.uint8], Iterable[npt.NDArray[np.uint8]]]
    ) -> Dict[str, npt.NDArray[np.float64]]: ...
    @property
    def targets(self) -> List[str]: ...
    @property
    def pin_side(self) -> int: ...
    @property
    def runtime(self) -> str: ...

def predict(
    model: _Path,
    data: _Path,
    out: Optional[_Path] = None,
    *,
    heads: Union[_Path, Sequence[_Path]] = (),
    topic: Optional[str] = None,
    limit: Optional[int] = None,
    runtime: str = "burn-flex",
) -> Dict[str, Any]:
    """``tactile predict``: every estimate of a TacTip model on every frame of a
    dataset, a folder of frames, an image, a video or a ROS 2 bag's image topic
    (``file``, ``stamp_ns`` for a bag, one array per estimate, ``ms_per_frame``),
    written to ``out`` too when given (CSV, or ROS 2 messages for ``.mcap``).
    A frame that cannot be decoded past its header (cut short) is left out with
    a ``UserWarning`` naming it; the other frames keep their estimates."""

def export(
    model: _Path,
    out: _Path,
    *,
    part: Optional[str] = None,
    standalone: bool = False,
) -> Dict[str, Any]:
    """``tactile export``: the model folder ``model`` to the ONNX file ``out``
    (``kind``, ``bytes``, ``out``). ``part`` is a CAE's, ``"encoder"`` (the
    default) or ``"autoencoder"``; ``standalone`` a detector's, segmenter's or
    depth network's model that stands alone (input ``frame``, uint8)."""

def run(
    source: Optional[_Path] = None,
    *,
    models: _Path = "models",
    runtime: str = "onnx",
    threads: int = 1,
    pipelines: int = 1,
    hysteresis: Optional[Sequence[float]] = None,
    out: Optional[_Path] = None,
    render: Optional[_Path] = None,
    with_frames: bool = False,
    view: Optional[str] = None,
    view_wait: float = 0.0,
    topic: Optional[str] = None,
    stdin_size: Optional[Sequence[int]] = None,
    live_queue: int = 2,
    limit: Optional[int] = None,
    prefetch: bool = True,
) -> Dict[str, Any]:
    """``tactile run``: paper B's pipeline over every frame of ``source`` (what
    ``frames`` reads), records to ``out`` (JSON Lines, ``"-"`` for standard
    output, or ROS 2 messages for ``.mcap``), overlays into the new folder
    ``render``, results served live at ``view`` (``HOST:PORT``); returns the
    summary the command line prints last, with ``records``, ``mcap``,
    ``mcap_frames``, ``render``, ``live_sent`` and ``live_dropped``. The
    summary's warnings (frames a calibrated sensor cannot read, frames
    unlike the sensor's) are raised as ``UserWarning``s. ``pipelines`` copies
    of the models take a recorded source's frames at once, each on a thread
    of its own (without a hysteresis; records stay in order)."""

class Reconstructor:
    """A calibrated GelSight-like sensor: frames to the skin's indentation."""

    def __init__(
        self, model_dir: _Path, runtime: str = "onnx", background: Optional[_Path] = None
    ) -> None: ...
    def reconstruct(self, frame: npt.NDArray[np.uint8]) -> npt.NDArray[np.float32]:
        """The indentation (metres) under an RGB frame of the calibrated size; a
        frame unlike the sensor's (by the detector beside the calibration, if
        any, else by the rest frame) is reconstructed too, with a
        ``UserWarning``."""
    @property
    def frame_size(self) -> Tuple[int, int]: ...
    @property
    def runtime(self) -> str: ...

def reconstruct_frames(
    model: str,
    data: str,
    out: str,
    *,
    background: Optional[str] = None,
    render: Optional[str] = None,
    runtime: str = "onnx",
) -> Dict[str, Any]: ...

class Dataset:
    """A dataset folder of the documented layout; pickles as its folder, opened and checked again where it is unpickled."""

    def __init__(self, path: _Path) -> None: ...
    @staticmethod
    def from_video(
        video: _Path,
        labels: _Path,
        kind: str,
        out: _Path,
        *,
        topic: Optional[str] = None,
        sensor: str = "real sensor",
        force: bool = False,
    ) -> Dataset:
        """``tactile dataset from-video``: the frames of a video, a ROS 2 bag's
        image topic or a folder of frames that a labels CSV (a ``frame`` column)
        labels, written as a ``"tactip"`` or ``"visuotactile"`` dataset into the
        new folder ``out``, then opened."""
    def __len__(self) -> int: ...
    def __fspath__(self) -> str: ...
    @overload
    def __getitem__(self, i: int) -> Dict[str, Any]: ...
    @overload
    def __getitem__(self, i: slice) -> List[Dict[str, Any]]: ...
    @property
    def path(self) -> Path: ...
    @property
    def kind(self) -> str: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def columns(self) -> List[str]: ...
    @property
    def manifest(self) -> Dict[str, Any]: ...
    @property
    def labels(self) -> Dict[str, Union[npt.NDArray[np.float64], List[Optional[str]]]]: ...
    def frame(self, i: int) -> npt.NDArray[np.uint8]: ...
    def mask(self, i: int) -> Optional[npt.NDArray[np.bool_]]: ...
    def depth_m(self, i: int) -> Optional[npt.NDArray[np.float32]]: ...

class Frame:
    """One frame of a source: `image` is (H, W, 3) uint8 RGB; pickles with its image and labels."""

    @property
    def image(self) -> npt.NDArray[np.uint8]: ...
    @property
    def name(self) -> str: ...
    @property
    def sequence(self) -> Optional[str]: ...
    @property
    def tendon(self) -> Optional[bool]: ...
    @property
    def age_ms(self) -> Optional[float]: ...
    @property
    def stamp_ns(self) -> Optional[int]: ...

class FrameSource:
    """Frames from a dataset, a folder, an image, a TIFF stack, a video file, a camera or stdin, in order."""

    def __iter__(self) -> FrameSource: ...
    def __next__(self) -> Frame: ...
    @property
    def kind(self) -> str: ...
    @property
    def dropped(self) -> int: ...
    @property
    def size(self) -> Optional[Tuple[int, int]]: ...

def frames(
    source: Optional[_Path] = None,
    *,
    topic: Optional[str] = None,
    stdin_size: Optional[Sequence[int]] = None,
    live_queue: int = 2,
    limit: Optional[int] = None,
    prefetch: bool = True,
) -> FrameSource:
    """Open a source of frames (a dataset, a folder, an image, a TIFF of many pages read page by page, a video file, a ROS 2 bag's image topic, a camera, a network stream's URL, or stdin)."""

def bag_topics(path: _Path) -> List[Dict[str, Any]]:
    """The image topics of a ROS 2 bag (its folder, or one MCAP or SQLite .db3 file, also an MCAP the Foxglove SDK recorded; video topics too): topic, message_type, count, rate_hz."""

def ros_image_to_rgb(msg: Any) -> np.ndarray:
    """A sensor_msgs/msg/Image or CompressedImage (an rclpy message, or any object with its fields) as (H, W, 3) uint8 RGB, as `tactile run` reads a bag's frames."""

class VideoDecoder:
    """A live video topic (foxglove_msgs/msg/CompressedVideo, ffmpeg_image_transport's FFMPEGPacket, h264_msgs/msg/Packet; H.264, H.265, VP9 or AV1) decoded as its packets arrive by the system's FFmpeg: `decode` gives the frames ready, normally the packet's own, each with its own packet's stamp (with B-frames, once the decoder lets them go: how many it holds is read from the first keyframe's parameters, so no call waits to learn it); packets before the first keyframe are skipped (`skipped`; `keyframes_without_parameters` counts the keyframes among them sent without their SPS or sequence header, which the encoder must repeat at every keyframe), packets that gave no frame are counted (`lost`), and changes of size whose frames were scaled to the earlier frames' size (`scaled`: past the first 64 changes, those sooner than one per 32 packets)."""

    def __init__(self, format: str, *, name: str = "video") -> None: ...
    def decode(self, data: Any, stamp_ns: int = 0) -> List[Frame]: ...
    def finish(self) -> List[Frame]: ...
    @property
    def skipped(self) -> int: ...
    @property
    def keyframes_without_parameters(self) -> int: ...
    @property
    def lost(self) -> int: ...
    @property
    def scaled(self) -> int: ...

class McapWriter:
    """Pipeline results as ROS 2 messages in an MCAP file (the channels of `tactile run --out X.mcap`)."""

    def __init__(self, path: _Path) -> None: ...
    def write(
        self,
        result: FrameResult,
        frame: Optional[npt.NDArray[np.uint8]] = None,
        *,
        stamp_ns: Optional[int] = None,
    ) -> None: ...
    @property
    def frames(self) -> int: ...
    def close(self) -> Path: ...
    def __enter__(self) -> McapWriter: ...
    def __exit__(self, exc_type: Any = None, _exc: Any = None, _tb: Any = None) -> bool: ...

class LiveView:
    """Pipeline results served to Foxglove over its WebSocket protocol (`tactile run --view`)."""

    def __init__(self, address: str = "127.0.0.1:8765") -> None: ...
    def publish(
        self,
        result: FrameResult,
        frame: Optional[npt.NDArray[np.uint8]] = None,
        *,
        stamp_ns: Optional[int] = None,
    ) -> bool: ...
    @property
    def port(self) -> int: ...
    @property
    def url(self) -> str: ...
    def wait_for_viewer(self, seconds: float) -> bool: ...
    @property
    def watched(self) -> bool: ...
    @property
    def sent(self) -> int: ...
    @property
    def dropped(self) -> int: ...
    def close(self) -> None: ...
    def __enter__(self) -> LiveView: ...
    def __exit__(self, _exc_type: Any = None, _exc: Any = None, _tb: Any = None) -> bool: ...

def read_rgb(path: _Path) -> npt.NDArray[np.uint8]:
    """A frame file (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM, 8 bits per channel) as (H, W, 3) uint8 RGB, decoded as the command line does."""

def read_grey(path: _Path) -> npt.NDArray[np.uint8]:
    """A frame file (PNG, JPEG, BMP, TIFF, WebP or PGM/PPM, 8 bits per channel) as (H, W) uint8 grey, decoded as the command line does."""

# --- generated by tactile_pipeline::options (TACTILE_BLESS=1 cargo test --release --workspace --test options): do not edit ---
def train_cae(
    data: _Path,
    out: _Path,
    *,
    config: Optional[_Path] = None,
    preprocess: str = "binary",
    widths: Sequence[int] = (16, 8, 8, 4),
    features: Optional[int] = None,
    linear_latent: bool = False,
    first_kernel: int = 3,
    shift: float = 0.0,
    optimizer: str = "adadelta",
    val_fraction: float = 0.2,
    exclude_test: Optional[float] = None,
    split_seed: int = 7,
    every_split: bool = False,
    max_epochs: int = 3000,
    patience: int = 300,
    batch_size: int = 256,
    lr: Optional[float] = None,
    lr_decay: float = 1.0,
    seed: int = 42,
    device: str = "flex",
    resume: bool = False,
    rotate_copies: int = 0,
    rotate_deg: float = 6.0,
    joint_targets: Sequence[str] = (),
    joint_weight: float = 1.0,
    joint_hidden: int = 64,
    joint_loss: str = "mse",
    also_tasks: Optional[str] = None,
) -> Dict[str, Any]: ...
def train_head_py(
    data: _Path,
    *,
    encoder: Optional[_Path] = None,
    features: Optional[_Path] = None,
    out: Optional[_Path] = None,
    test: Optional[_Path] = None,
    config: Optional[_Path] = None,
    folds: int = 10,
    repeats: int = 3,
    seed: int = 7,
    device: str = "flex",
    rotate_copies: int = 0,
    rotate_deg: float = 6.0,
) -> Dict[str, Any]: ...
def train_regressor_py(
    data: _Path,
    targets: Sequence[str],
    *,
    encoder: Optional[_Path] = None,
    features: Optional[_Path] = None,
    out: Optional[_Path] = None,
    config: Optional[_Path] = None,
    test_fraction: float = 0.2,
    val_fraction: float = 0.2,
    hidden: Sequence[int] = (32, 16),
    seed: int = 7,
    every_split: bool = False,
    device: str = "flex",
    only_labelled: bool = False,
    shapes: Sequence[str] = (),
    loss: str = "mse",
    uncertainty: bool = False,
) -> Dict[str, Any]: ...
def train_pose(
    data: _Path,
    out: _Path,
    *,
    config: Optional[_Path] = None,
    targets: Sequence[str] = ("x_mm", "theta_deg", "depth_mm"),
    input_px: int = 64,
    crop_px: int = 256,
    mask_radius_px: float = 100.0,
    uncertainty: bool = False,
    calibration_from: Optional[str] = None,
    every_split: bool = False,
    widths: Sequence[int] = (16, 32, 64, 64),
    kernels: Optional[Sequence[int]] = None,
    shift: float = 0.0,
    half_turn: Optional[Sequence[str]] = None,
    hidden: int = 128,
    dropout: float = 0.0,
    val_fraction: float = 0.2,
    all_rows: bool = False,
    loss: str = "mse",
    exclude_test: Optional[float] = None,
    split_seed: int = 7,
    max_epochs: int = 80,
    patience: int = 12,
    batch_size: int = 32,
    lr: Optional[float] = None,
    lr_decay: float = 0.97,
    seed: int = 7,
    device: str = "flex",
    resume: bool = False,
) -> Dict[str, Any]: ...
def train_detector(
    data: Union[_Path, Sequence[_Path]],
    out: _Path,
    *,
    config: Optional[_Path] = None,
    architecture: str = "mobilenet-v3-small",
    width: float = 0.5,
    input: Tuple[int, int] = (160, 120),
    input_bits: int = 8,
    normalise_exposure: bool = False,
    val_fraction: float = 0.2,
    soft_labels: Optional[float] = None,
    augment: bool = False,
    calibrate_only: bool = False,
    max_epochs: int = 12,
    patience: int = 4,
    batch_size: int = 16,
    lr: Optional[float] = None,
    lr_decay: float = 0.8,
    seed: int = 42,
    device: str = "flex",
    resume: bool = False,
) -> Dict[str, Any]: ...
def train_segmenter(
    data: _Path,
    out: _Path,
    *,
    config: Optional[_Path] = None,
    side: int = 96,
    base: int = 8,
    copies: int = 4,
    val_fraction: float = 0.2,
    rest: Optional[str] = None,
    max_epochs: int = 15,
    patience: int = 4,
    batch_size: int = 16,
    lr: Optional[float] = None,
    lr_decay: float = 0.8,
    seed: int = 42,
    device: str = "flex",
    resume: bool = False,
) -> Dict[str, Any]: ...
def train_depth(
    data: _Path,
    out: _Path,
    *,
    config: Optional[_Path] = None,
    encoder: str = "small",
    input: Tuple[int, int] = (160, 96),
    head: str = "conv1x1",
    loss: str = "l1",
    with_mask: bool = False,
    freeze_encoder: bool = False,
    prior_calibration: Optional[str] = None,
    augment: bool = False,
    pretrained: Optional[str] = None,
    unit_mm: float = 1.0,
    decoder_width: int = 64,
    val_fraction: float = 0.2,
    max_epochs: int = 12,
    patience: int = 3,
    batch_size: int = 8,
    lr: Optional[float] = None,
    lr_decay: float = 0.9,
    seed: int = 42,
    device: str = "flex",
    resume: bool = False,
) -> Dict[str, Any]: ...
def synth_tactip(
    count: int,
    seed: int,
    out: Optional[str],
    force: bool,
    progress: bool,
    *,
    config: Optional[_Path] = None,
    shapes: Sequence[str] = ("cuboid", "cylinderR4", "cylinderR8", "prism", "edge", "sphere", "flat"),
    depth_mm: Tuple[float, float] = (0.0, 5.0),
    x_mm: Tuple[float, float] = (-6.0, 6.0),
    y_mm: Tuple[float, float] = (-6.0, 6.0),
    theta_deg: Tuple[float, float] = (0.0, 180.0),
    sphere_radius_mm: Tuple[float, float] = (4.0, 10.0),
    pin_grey: Tuple[float, float] = (210.0, 240.0),
    background_grey: Tuple[float, float] = (20.0, 45.0),
    gain: Tuple[float, float] = (0.8, 1.2),
    gradient: Tuple[float, float] = (-0.25, 0.25),
    blob_probability: float = 0.3,
    blob_sigma_px: Tuple[float, float] = (40.0, 90.0),
    blob_amplitude: Tuple[float, float] = (20.0, 60.0),
    noise_sigma: Tuple[float, float] = (3.0, 8.0),
    force_noise: float = 0.02,
) -> Any: ...
def synth_visuotactile(
    count: Optional[int],
    sequences: Optional[int],
    seed: int,
    out: Optional[str],
    force: bool,
    progress: bool,
    *,
    config: Optional[_Path] = None,
    width: int = 640,
    height: int = 360,
    paths: Sequence[str] = ("straight", "arc", "s-curve"),
    tendon_radius_mm: Tuple[float, float] = (1.5, 4.0),
    burial_mm: Tuple[float, float] = (1.0, 4.0),
    curvature_radius_mm: Tuple[float, float] = (15.0, 60.0),
    press_mm: Tuple[float, float] = (0.0, 4.0),
    centre_fraction: float = 0.3,
    out_of_view_fraction: float = 0.15,
    out_of_view_margin_w: Optional[Tuple[float, float]] = None,
    exposure_jitter: Tuple[float, float] = (-0.1, 0.1),
    noise_sigma: Tuple[float, float] = (1.0, 3.0),
    frames_per_sequence: int = 30,
    renderer: Optional[str] = None,
) -> Any: ...
def synth_gelsight(
    sensor: str,
    count: Optional[int],
    sequences: Optional[int],
    seed: int,
    out: Optional[str],
    force: bool,
    progress: bool,
    *,
    config: Optional[_Path] = None,
    paths: Sequence[str] = ("straight", "arc", "s-curve"),
    tendon_radius_mm: Tuple[float, float] = (1.5, 3.5),
    curvature_radius_mm: Tuple[float, float] = (10.0, 40.0),
    press_mm: Tuple[float, float] = (0.05, 1.5),
    object_press_mm: Tuple[float, float] = (0.05, 2.5),
    centre_fraction: float = 0.6,
    out_of_view_fraction: float = 0.08,
    tendon_share: float = 0.6,
    sphere_share: float = 0.15,
    punch_share: float = 0.1,
    flat_share: float = 0.05,
    nothing_share: float = 0.1,
    sphere_radius_mm: Tuple[float, float] = (2.0, 6.0),
    punch_radius_mm: Tuple[float, float] = (1.0, 3.0),
    punch_fillet: Tuple[float, float] = (0.15, 0.5),
    plate_edge_reach: Optional[Tuple[float, float]] = None,
    optics_jitter: float = 0.15,
    gel_jitter: float = 0.25,
    blur_px: Tuple[float, float] = (0.0, 1.2),
    shift_px: int = 2,
    exposure_jitter: Tuple[float, float] = (-0.1, 0.1),
    noise_sigma: Tuple[float, float] = (0.5, 3.0),
    frames_per_sequence: int = 25,
    real_presses: Optional[str] = None,
    real_copies: int = 5,
    real_held_out: int = 0,
) -> Any: ...
def eval_detector(
    model: str,
    data: str,
    *,
    runtime: str = "burn-flex",
    config: Optional[_Path] = None,
    frames: Optional[str] = None,
    reliability: Optional[str] = None,
) -> Dict[str, Any]: ...
def eval_depth(
    model: str,
    data: str,
    *,
    runtime: str = "burn-flex",
    config: Optional[_Path] = None,
    save_png: Optional[str] = None,
    png_frames: int = 8,
) -> Dict[str, Any]: ...
def calibrate_ball(
    data: _Path,
    out: _Path,
    *,
    config: Optional[_Path] = None,
    widths: Sequence[int] = (32, 32),
    kernels: Sequence[int] = (3, 3, 1),
    factor: Optional[int] = None,
    val_presses: int = 4,
    colour_jitter: float = 0.03,
    height_weight: float = 4.0,
    circles: str = "auto",
    contact_gate: bool = False,
    max_epochs: int = 48,
    patience: int = 20,
    batch_size: int = 4,
    lr: Optional[float] = None,
    lr_decay: float = 0.97,
    seed: int = 42,
    device: str = "flex",
    resume: bool = False,
) -> Dict[str, Any]: ...
def study_compare(
    encoder: _Path,
    data: _Path,
    *,
    out: Optional[_Path] = None,
    config: Optional[_Path] = None,
    targets: Sequence[str] = (),
    classify: Optional[str] = None,
    test_fraction: float = 0.2,
    val_fraction: float = 0.2,
    seed: int = 7,
    preprocess: Optional[str] = None,
    hidden: Sequence[int] = (256, 128),
) -> Dict[str, Any]: ...
def study_sweep(
    encoders: Union[_Path, Sequence[_Path]],
    data: _Path,
    *,
    out: Optional[_Path] = None,
    config: Optional[_Path] = None,
    classify: str = "shape",
    seed: int = 7,
    runs: int = 30,
) -> Dict[str, Any]: ...
def study_robustness(
    encoder: _Path,
    data: _Path,
    *,
    out: Optional[_Path] = None,
    config: Optional[_Path] = None,
    heads: Sequence[str] = (),
    limit: Optional[int] = None,
    seed: int = 11,
) -> Dict[str, Any]: ...
# --- end of generated part ---
def options(trainer: str) -> List[Dict[str, Any]]: ...
def synth_ideal_detector(data: str, out: Optional[str], progress: bool) -> Dict[str, Any]: ...
def train_ensemble(members: List[str], out: str) -> str: ...
def train_calibrate(
    model: str, data: List[str], split: Optional[str] = None, calibration_from: Optional[str] = None
) -> str: ...
def train_profile(model: str, data: List[str], split: Optional[str] = None) -> str: ...
def train_align(model: str, data: List[str]) -> str: ...
def eval_segmenter(model: str, data: str, *, runtime: str = ...) -> Dict[str, Any]: ...
def eval_tactip(
    encoder: str,
    data: str,
    *,
    estimators: Optional[List[str]] = None,
    runtime: str = ...,
    split: Optional[str] = None,
) -> Dict[str, Any]: ...
