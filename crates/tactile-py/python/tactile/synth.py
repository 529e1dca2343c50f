"""The virtual sensors of ``sensors.md``: frames with exact labels.

Each sample has its own random stream keyed by ``seed`` and its index, so
the same call gives the same frames on every machine, and they equal the
frames ``tactile synth`` writes with the same options.

Without ``out`` the frames come back as numpy arrays; with ``out`` they are
written as a dataset folder (the documented layout; see ``tactile.Dataset``)
and the folder is returned. Ranges are ``(min, max)`` tuples; any other key
of the generator's config (``docs/synth.md``) goes in ``config``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from . import _tactile

Range = Tuple[float, float]
PathLike = Union[str, "os.PathLike[str]"]


def _whole(name: str, value: Any) -> int:
    """A whole number of at least 1, or a ValueError naming the option."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected a whole number, got {type(value).__name__}")
    if value < 1:
        raise ValueError(f"{name}: must be at least 1, got {value}")
    if value >= 2**63:
        raise ValueError(f"{name}: {value} is far more frames than a dataset may hold")
    return int(value)


def _config(config: Optional[Dict[str, Any]], **ranges: Any) -> Optional[str]:
    merged: Dict[str, Any] = dict(config or {})
    for key, value in ranges.items():
        if value is None:
            continue
        if isinstance(value, tuple):
            if len(value) != 2:
                raise ValueError(f"{key}: a range is (min, max), got {value!r}")
            value = {"min": float(value[0]), "max": float(value[1])}
        elif isinstance(value, (list, tuple)) and key in ("shapes", "paths"):
            value = list(value)
        merged[key] = value
    return json.dumps(merged) if merged else None


def tactip(
    count: int,
    seed: int = 1234,
    out: Optional[PathLike] = None,
    *,
    shapes: Optional[Sequence[str]] = None,
    depth_mm: Optional[Range] = None,
    x_mm: Optional[Range] = None,
    y_mm: Optional[Range] = None,
    theta_deg: Optional[Range] = None,
    noise_sigma: Optional[Range] = None,
    blob_probability: Optional[float] = None,
    config: Optional[Dict[str, Any]] = None,
    force: bool = False,
    progress: bool = True,
) -> Union[Tuple[np.ndarray, Dict[str, Any]], Path]:
    """Virtual TacTip frames (paper A): 127 pins, seven contact shapes.

    Returns ``(frames, labels)``: ``frames`` is ``(count, 300, 300)`` uint8
    grey, ``labels`` maps ``shape`` to a list of names and ``x_mm``,
    ``y_mm``, ``theta_deg``, ``depth_mm``, ``force_n``, ``radius_mm`` to
    float64 arrays (NaN where a shape has no such label). With ``out``,
    writes a dataset there instead and returns its path; ``force=True``
    replaces an existing dataset (never a folder of other files).
    """
    cfg = _config(
        config,
        shapes=list(shapes) if shapes is not None else None,
        depth_mm=depth_mm,
        x_mm=x_mm,
        y_mm=y_mm,
        theta_deg=theta_deg,
        noise_sigma=noise_sigma,
        blob_probability=blob_probability,
    )
    r = _tactile.synth_tactip(
        _whole("count", count), int(seed), None if out is None else os.fspath(out), cfg, force, progress
    )
    return Path(r) if out is not None else r


def visuotactile(
    count: Optional[int] = None,
    seed: int = 1234,
    out: Optional[PathLike] = None,
    *,
    sequences: Optional[int] = None,
    frames_per_sequence: Optional[int] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    paths: Optional[Sequence[str]] = None,
    press_mm: Optional[Range] = None,
    tendon_radius_mm: Optional[Range] = None,
    burial_mm: Optional[Range] = None,
    noise_sigma: Optional[Range] = None,
    config: Optional[Dict[str, Any]] = None,
    force: bool = False,
    progress: bool = True,
) -> Union[Dict[str, Any], Path]:
    """Virtual visuo-tactile palpation videos (paper B).

    Give ``count`` frames or ``sequences`` videos of ``frames_per_sequence``
    frames (default 30). Returns a dict: ``frames`` ``(N, H, W, 3)`` uint8
    RGB, ``masks`` ``(N, H, W)`` bool, ``depth_m`` ``(N, H, W)`` float32
    metres, and the labels ``tendon``, ``direction_deg`` (NaN without a
    tendon), ``path``, ``press_mm``, ``sequence``, ``frame_index``,
    ``tendon_radius_mm``, ``burial_mm``, ``ridge_mm``. With ``out``, writes
    a dataset there instead and returns its path. ``width`` x ``height``
    must be an integer fraction of 1920 x 1080 (default 640 x 360).
    """
    fps = frames_per_sequence
    if fps is None:
        fps = int((config or {}).get("frames_per_sequence", 30))
    if count is None and sequences is None:
        raise ValueError("give count= (frames) or sequences= (videos)")
    if sequences is not None:
        frames = _whole("sequences", sequences) * _whole("frames_per_sequence", fps)
        if count is not None and int(count) != frames:
            raise ValueError(
                f"count={count} disagrees with sequences={sequences} x {fps} frames per sequence"
            )
        count = frames
    assert count is not None
    cfg = _config(
        config,
        width=width,
        height=height,
        frames_per_sequence=frames_per_sequence,
        paths=list(paths) if paths is not None else None,
        press_mm=press_mm,
        tendon_radius_mm=tendon_radius_mm,
        burial_mm=burial_mm,
        noise_sigma=noise_sigma,
    )
    r = _tactile.synth_visuotactile(
        _whole("count", count), int(seed), None if out is None else os.fspath(out), cfg, force, progress
    )
    return Path(r) if out is not None else r


__all__ = ["tactip", "visuotactile"]
