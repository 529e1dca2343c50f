"""Evaluation, as ``tactile eval ...`` and ``tactile evaluate``: each
returns the dict those commands print as their last line. A frame cut
short behind its header is left out of the scores with a ``UserWarning``
naming it (the dict's ``frame_warnings``), as ``tactile.predict`` leaves
it out of its rows; a model that trained on the frames scored is warned of
too (its ``warning``)."""

from __future__ import annotations

import os
from typing import Any, Dict, Optional, Sequence, Union

from . import _tactile

PathLike = Union[str, "os.PathLike[str]"]


def detector(
    model: PathLike, data: PathLike, *, runtime: str = "burn-flex", **options: Any
) -> Dict[str, Any]:
    """Accuracy, precision, recall, F1 and the onset/release frames of a
    tendon detector on a labelled visuo-tactile dataset, gated and ungated.
    ``frames=`` (a CSV of every frame's answer) and ``reliability=`` (a
    PNG) as ``tactile eval detector``; see ``eval.pyi``."""
    return _tactile.eval_detector(model, data, runtime=runtime, **options)


def segmenter(model: PathLike, data: PathLike, *, runtime: str = "burn-flex") -> Dict[str, Any]:
    """Mean IoU and direction error per tendon path of a segmenter."""
    return _tactile.eval_segmenter(model, data, runtime=runtime)


def depth(
    model: PathLike, data: PathLike, *, runtime: str = "burn-flex", **options: Any
) -> Dict[str, Any]:
    """MAE (sensing window and tendon), RMSE and SSIM of a depth network,
    mm. ``save_png=`` (a new folder) and ``png_frames=`` write heat maps, as
    ``tactile eval depth``; see ``eval.pyi``."""
    return _tactile.eval_depth(model, data, runtime=runtime, **options)


def tactip(
    encoder: PathLike,
    data: PathLike,
    *,
    estimators: Optional[Union[PathLike, Sequence[PathLike]]] = None,
    runtime: str = "burn-flex",
    split: Optional[str] = None,
) -> Dict[str, Any]:
    """Every estimator of an encoder, or every target of a pose network (its
    folder as ``encoder``), scored on a labelled TacTip dataset: on the rows
    of its ``split`` column's ``split`` alone when given (``"val"``)."""
    return _tactile.eval_tactip(
        encoder,
        data,
        estimators=estimators,
        runtime=runtime,
        split=split,
    )


__all__ = ["depth", "detector", "segmenter", "tactip"]
