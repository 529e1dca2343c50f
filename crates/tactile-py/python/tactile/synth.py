"""The virtual sensors of ``sensors.md``: frames with exact labels.

Each sample has its own random stream keyed by ``seed`` and its index, so
the same call gives the same frames on every machine, and they equal the
frames ``tactile synth`` writes with the same options.

Without ``out`` the frames come back as numpy arrays; with ``out`` they are
written as a dataset folder (the documented layout; see ``tactile.Dataset``)
and the folder is returned. Every option of the generator is a keyword,
as on the command line (``docs/synth.md``; the typed list is in
``tactile/synth.pyi``): ranges are ``(min, max)`` tuples; ``config=`` names a
JSON options file the keywords override, as ``--config`` does.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from . import _tactile

PathLike = Union[str, "os.PathLike[str]"]


def tactip(
    count: int,
    seed: int = 1234,
    out: Optional[PathLike] = None,
    *,
    force: bool = False,
    progress: bool = True,
    **options: Any,
) -> Union[Tuple[np.ndarray, Dict[str, Any]], Path]:
    """Virtual TacTip frames (paper A): 127 pins, seven contact shapes.

    Returns ``(frames, labels)``: ``frames`` is ``(count, 300, 300)`` uint8
    grey, ``labels`` maps ``shape`` to a list of names and ``x_mm``,
    ``y_mm``, ``theta_deg``, ``depth_mm``, ``force_n``, ``radius_mm`` to
    float64 arrays (NaN where a shape has no such label). With ``out``,
    writes a dataset there instead and returns its path; ``force=True``
    replaces an existing dataset (never a folder of other files).
    ``progress`` shows a bar on a terminal while the frames render, in
    memory or to disk; Ctrl-C stops the render and keeps nothing.
    """
    r = _tactile.synth_tactip(
        count, seed, out, force, progress,
        **options,
    )
    return Path(r) if out is not None else r


def visuotactile(
    count: Optional[int] = None,
    seed: int = 1234,
    out: Optional[PathLike] = None,
    *,
    sequences: Optional[int] = None,
    force: bool = False,
    progress: bool = True,
    **options: Any,
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
    ``progress`` and Ctrl-C as for :func:`tactip`.
    """
    r = _tactile.synth_visuotactile(
        count,
        sequences,
        seed,
        out,
        force,
        progress,
        **options,
    )
    return Path(r) if out is not None else r


def gelsight(
    sensor: PathLike,
    count: Optional[int] = None,
    seed: int = 1234,
    out: Optional[PathLike] = None,
    *,
    sequences: Optional[int] = None,
    force: bool = False,
    progress: bool = True,
    **options: Any,
) -> Union[Dict[str, Any], Path]:
    """A calibrated GelSight-like sensor's own palpation videos.

    ``sensor`` is the folder ``tactile.calibrate.ball`` wrote: the frames
    are rendered through its optics and gel over its background, at its
    size. Give ``count`` frames or ``sequences`` videos of
    ``frames_per_sequence`` frames (default 25). Returns a dict: ``frames``
    ``(N, H, W, 3)`` uint8 RGB, ``masks`` ``(N, H, W)`` bool (a tendon
    pushing the skin in past 0.03 mm), ``indentation_m`` ``(N, H, W)``
    float32 metres, and the labels ``tendon``, ``direction_deg`` (NaN
    without a tendon), ``path`` (the tendon's path, or ``sphere``,
    ``punch``, ``flat``, ``none``), ``press_mm``, ``peak_mm``, ``sequence``,
    ``frame_index``. With ``out``, writes a dataset there instead (its depth
    maps are indentation) and returns its path. ``progress`` and Ctrl-C as
    for :func:`tactip`.
    """
    r = _tactile.synth_gelsight(
        sensor,
        count,
        sequences,
        seed,
        out,
        force,
        progress,
        **options,
    )
    return Path(r) if out is not None else r


def ideal_detector(
    data: PathLike,
    out: Optional[PathLike] = None,
    *,
    progress: bool = True,
) -> Dict[str, Any]:
    """The ideal detector of a virtual visuo-tactile dataset.

    For every frame of ``data`` (written by ``visuotactile``; its scenes are
    drawn again from the manifest), how precisely the frame itself tells
    its ridge's height (``ridge_sigma_mm``: the Cramér–Rao bound of the
    reference renderer's optics and noise) and the best chance any
    detector has of labelling it right (``ideal_p_correct``). Returns a
    dict of those per-frame arrays (with ``file``, ``tendon``,
    ``ridge_mm``, ``in_view``) and the summary: ``frames``, ``accuracy``
    (the mean chance: no detector can expect more on the set),
    ``uncertain`` (frames under 0.99) and ``median_sigma_mm``. With
    ``out``, also writes the per-frame CSV there.
    """
    return _tactile.synth_ideal_detector(
        data, out, progress
    )


__all__ = ["tactip", "visuotactile", "gelsight", "ideal_detector"]
