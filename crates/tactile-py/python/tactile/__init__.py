"""tactile-rs: vision-based tactile sensing on the CPU, from Rust.

Paper B's palpation pipeline on numpy frames::

    import tactile
    pipe = tactile.Pipeline("models")        # detector/, segmenter/, depth/
    r = pipe.process(frame)                  # (H, W, 3) uint8 RGB, any size
    r.tendon, r.direction_deg, r.mask, r.depth_m, r.ms

Paper A's encoder and its estimators::

    enc = tactile.TactipEncoder("models/cae-synth")
    enc.encode(frames)                       # (N, 16) float32
    enc.estimate(frames)                     # {"shape": ..., "x_mm": ...}

A pose network (the pose straight from the frame; a deviation per target
where the model gives one)::

    pose = tactile.PoseEstimator("models/pose-edge")
    pose.estimate(frames)                    # {"x_mm": ..., "theta_deg": ..., "depth_mm": ...}
    surface = tactile.PoseEstimator("models/pose-surface")
    surface.estimate(frames)                 # {"depth_mm": ..., ..., "shear_theta_deg_std": ...}

Frames from a video file, a camera, a folder or a dataset::

    for f in tactile.frames("palpation.mp4"):   # or "/dev/video0", a folder
        r = pipe.process(f.image)

A TacTip model over a whole recording, as ``tactile predict`` (a dataset, a
folder of frames, a video or a ROS 2 bag; CSV or MCAP out)::

    est = tactile.predict("models/pose-surface", "tactip.mcap", "estimates.mcap")
    est["stamp_ns"], est["shear_theta_deg"], est["shear_theta_deg_std"]

Paper B's pipeline over a whole recording, as ``tactile run`` (records as
JSON Lines or ROS 2 messages in MCAP, overlays, a live Foxglove view)::

    summary = tactile.run("palpation.mp4", models="models", out="records.jsonl")
    summary["fps"], summary["tendon_frames"], summary["records"]

Any trained model to ONNX, as ``tactile export``::

    tactile.export("models/detector", "detector.onnx", standalone=True)

Datasets, generators, training and evaluation: ``tactile.Dataset``,
``tactile.synth``, ``tactile.train``, ``tactile.eval``.

Errors are Python exceptions with the command line's message:
``FileNotFoundError`` for a missing model or dataset folder, ``ValueError``
for bad input (a frame of the wrong shape, a bad label), ``TypeError`` for a
wrong dtype, ``RuntimeError`` when onnxruntime is missing or fails.
"""

from __future__ import annotations

import os
from importlib.util import find_spec as _find_spec
from pathlib import Path as _Path


def _find_onnxruntime() -> None:
    """Point the native module at the onnxruntime wheel's shared library.

    The ``onnx`` runtime loads ``libonnxruntime`` at run time; unless
    ``ORT_DYLIB_PATH`` names one already, the copy inside the installed
    ``onnxruntime`` wheel (a dependency of this package) is used. The
    module is located, not imported.
    """
    if os.environ.get("ORT_DYLIB_PATH"):
        return
    spec = _find_spec("onnxruntime")
    if spec is None or not spec.submodule_search_locations:
        return
    for root in spec.submodule_search_locations:
        libs = sorted((_Path(root) / "capi").glob("libonnxruntime.so*"))
        libs = [p for p in libs if p.is_file()]
        if libs:
            os.environ["ORT_DYLIB_PATH"] = str(libs[-1])
            return


_find_onnxruntime()

from ._tactile import (  # noqa: E402
    MAX_ARRAY_BYTES,
    MAX_BATCH,
    MAX_FRAME_SIDE,
    Dataset,
    Frame,
    FrameResult,
    FrameSource,
    LiveView,
    McapWriter,
    Pipeline,
    PoseEstimator,
    Reconstructor,
    TactipEncoder,
    VideoDecoder,
    __version__,
    bag_topics,
    export,
    frames,
    predict,
    read_grey,
    read_rgb,
    ros_image_to_rgb,
    run,
)
from . import calibrate, eval, study, synth, train  # noqa: E402

__all__ = [
    "Dataset",
    "Frame",
    "FrameResult",
    "FrameSource",
    "LiveView",
    "MAX_ARRAY_BYTES",
    "MAX_BATCH",
    "MAX_FRAME_SIDE",
    "McapWriter",
    "Pipeline",
    "PoseEstimator",
    "Reconstructor",
    "TactipEncoder",
    "VideoDecoder",
    "__version__",
    "bag_topics",
    "calibrate",
    "eval",
    "export",
    "frames",
    "predict",
    "read_grey",
    "read_rgb",
    "ros_image_to_rgb",
    "run",
    "study",
    "synth",
    "train",
]
