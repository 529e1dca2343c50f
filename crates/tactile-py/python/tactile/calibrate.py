"""Calibrating a GelSight-like sensor from ball presses, with the options
of ``tactile calibrate ball``, and reconstructing its frames.

``ball(data, out, **options)`` reads a calibration folder (the layout in
docs/datasets.md: ``sensor.json``, ``background.png``, ``frames/`` (a frame
file per press: PNG, JPEG, BMP, TIFF, WebP or PGM/PPM), optionally ``presses.csv``;
or gs_sdk's folder as it is: ``catalog.csv``, ``<d>mm/<n>/gelsight.png`` and
``label.npz``, with gs_sdk's config of the sensor copied in (``gsmini.yaml``:
``ppmm``, ``imgw``, ``imgh``) or a ``sensor.json`` giving ``mm_per_px``; or Taxim's
``dataPack.npz``, its folder or the file, with a ``sensor.json`` giving
``ball_diameter_mm`` and ``mm_per_px``), finds each contact
circle, fits the sensor model and writes a new model folder; it returns
the summary ``tactile calibrate ball`` prints (circle agreement, the
frames' scale and the file it came from, the
held-out presses' scores; files in ``frames/`` that are no frames come as
a ``UserWarning``). Options are keywords named as the flags
(``max_epochs=...``), each defined once in the library;
``options("ball")`` is not needed: ``calibrate.pyi`` types them.
``reconstruct(model, data, out)`` writes one ``<stem>.npy`` (float32 H x
W, metres toward the camera) per frame, as ``tactile reconstruct`` does;
``tactile.Reconstructor`` does one numpy frame at a time.
"""

from __future__ import annotations

import os
from typing import Any, Dict, Optional, Union

from . import _tactile

PathLike = Union[str, "os.PathLike[str]"]


def ball(data: PathLike, out: PathLike, **options: Any) -> Dict[str, Any]:
    """Calibrate a sensor from presses of a ball of known radius into the
    new model folder ``out`` (``widths``, ``kernels``, ``factor``,
    ``height_weight``, ``circles``, ``max_epochs``, ... as keywords)."""
    return _tactile.calibrate_ball(data, out, **options)


def reconstruct(
    model: PathLike,
    data: PathLike,
    out: PathLike,
    *,
    background: Optional[PathLike] = None,
    render: Optional[PathLike] = None,
    runtime: str = "onnx",
) -> Dict[str, Any]:
    """Every frame of ``data`` (a frame, a folder of frames: PNG, JPEG, BMP,
    TIFF, WebP or PGM/PPM, a TIFF stack: ``<stack stem>-000000.npy``, ... per
    page, a dataset folder, or Taxim's ``dataPack.npz``: its presses) to
    ``out/<stem>.npy``; files that are not frames, and
    frames unlike the sensor's (by the profile of the detector beside the
    calibration, when the folder has ``detector/``, else by the rest frame:
    changed in colour over half the picture), are named in a
    ``UserWarning`` (and in the result's ``warnings``);
    ``render`` also writes pictures (frame, shaded skin, indentation with a
    colour bar); ``background`` replaces the calibration's rest frame."""
    return _tactile.reconstruct_frames(
        model,
        data,
        out,
        background=background,
        render=render,
        runtime=runtime,
    )

__all__ = ["ball", "reconstruct"]
