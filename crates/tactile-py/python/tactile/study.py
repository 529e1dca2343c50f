"""Paper A's studies of an encoder, as ``tactile compare``, ``tactile sweep``
and ``tactile robustness`` run them, with their options as keywords named
as the flags (each defined once in the library; ``study.pyi`` types them).

Each returns a dict: the page the command prints (``markdown``) and its
rows, numbers rather than text, so they can be plotted or tabulated:

- ``compare(encoder, data, targets=[...], classify=...)``: the encoder's
  features beside PCA, the raw pin image and pin tracking, each with an
  MLP, ridge and k-NN (regression) or an MLP head, naive Bayes and k-NN
  (classification). ``regression`` and ``classification`` rows give
  ``features``, ``estimator``, ``values`` (``[target, MAE]`` pairs in the
  labels' units, or ``["accuracy", 0..1]``) and ``seconds``; ``warnings``
  (also raised as ``UserWarning``) says when the encoder fitted test frames
  or a row was left out for a split too small.
- ``sweep(encoders, data)``: each encoder's test reconstruction BCE, shape
  accuracy and speed per runtime (``rows``).
- ``robustness(encoder, data)``: every estimator's errors on clean frames
  and on copies with more noise, an illumination gradient, a light blob or
  a rotation (``rows``: ``condition`` and its ``values``); ``warnings``
  (also raised as ``UserWarning``) names a frame cut short behind its
  header, left out of every condition as ``tactile.eval.tactip`` leaves it
  out.

With ``out=`` the page is written too, its rows (``NAME.json``) and plots
beside it, as the command's ``--out`` writes them.
"""

from __future__ import annotations

import os
from typing import Any, Dict, Optional, Sequence, Union

from . import _tactile

PathLike = Union[str, "os.PathLike[str]"]


def compare(
    encoder: PathLike, data: PathLike, *, out: Optional[PathLike] = None, **options: Any
) -> Dict[str, Any]:
    """Feature sets against estimators on one split (``targets=``,
    ``classify=``, ``test_fraction=``, ``seed=``, ``hidden=``, ...)."""
    return _tactile.study_compare(encoder, data, out=out, **options)


def sweep(
    encoders: Union[PathLike, Sequence[PathLike]],
    data: PathLike,
    *,
    out: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """Paper A's feature-count search over ``encoders`` (``classify=``,
    ``seed=``, ``runs=``)."""
    return _tactile.study_sweep(encoders, data, out=out, **options)


def robustness(
    encoder: PathLike, data: PathLike, *, out: Optional[PathLike] = None, **options: Any
) -> Dict[str, Any]:
    """Estimator errors under perturbed camera conditions (``heads=``,
    ``limit=``, ``seed=``)."""
    return _tactile.study_robustness(encoder, data, out=out, **options)


__all__ = ["compare", "robustness", "sweep"]
