"""Training, with the options of ``tactile train ...``.

Every trainer takes its options as keywords named as the command line's
flags (``max_epochs=...`` for ``--max-epochs``), each defined once in the
library with its default: ``options("detector")`` lists a trainer's options
with their help and defaults, ``train.pyi`` types them for editors, an
unknown keyword or a value of the wrong type is a ``ValueError`` naming it,
and ``config=FILE`` reads a JSON object of options that the keywords
override (as ``--config FILE`` does). Training runs with the interpreter
free for other threads, prints a line per epoch (a progress bar on a
terminal), writes the same model folder as the command line, and returns a
summary dict. Ctrl-C stops it cleanly: the folder is marked incomplete
(``resume=True`` continues it) and ``KeyboardInterrupt`` is raised.
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Union

from . import _tactile

PathLike = Union[str, "os.PathLike[str]"]


def cae(data: PathLike, out: PathLike, **options: Any) -> Dict[str, Any]:
    """Paper A's convolutional autoencoder on a TacTip dataset.

    ``preprocess``: "binary" (frames already binarised), "paper",
    "lighting-compensated" or a JSON file. ``widths``: four encoder widths,
    e.g. (16, 8, 8, 4); ``features`` sets the last one. ``rotate_copies`` >
    0: each training frame is also seen turned by up to ``rotate_deg``
    degrees. ``joint_targets`` (e.g. ``["x_mm", "theta_deg:180"]``): the
    features also feed a head trained to predict those label columns.
    ``also_tasks``: a JSON file listing further datasets the one encoder
    trains on beside ``data``, each with its own ``preprocess``,
    ``joint_targets`` and ``shift``. Every option: ``options("cae")``.
    """
    return _tactile.train_cae(data, out, **options)


def pose(data: PathLike, out: PathLike, **options: Any) -> Dict[str, Any]:
    """A supervised pose network (a CNN on grey pin images) on TacTip
    frames: ``targets`` are label columns (``NAME:PERIOD`` for an angle);
    ``config="configs/pose/p128.json"`` is the shipped recipe's network.
    With ``exclude_test`` the result has the scores on the test frames it
    left out. Every option: ``options("pose")``.
    """
    return _tactile.train_pose(data, out, **options)


def detector(
    data: Union[PathLike, Sequence[PathLike]], out: PathLike, **options: Any
) -> Dict[str, Any]:
    """Paper B's tendon detector on one or more visuo-tactile datasets
    (``input_bits=16``, ``normalise_exposure=True``, ``soft_labels=0.6``,
    ``augment=True``, ``input=(320, 240)``, ...). The summary includes the
    threshold chosen on the validation sequences. Every option:
    ``options("detector")``.
    """
    return _tactile.train_detector(data, out, **options)


def segmenter(data: PathLike, out: PathLike, **options: Any) -> Dict[str, Any]:
    """Paper B's U-Net tendon segmenter (``side``: window, a multiple of
    16). Every option: ``options("segmenter")``."""
    return _tactile.train_segmenter(data, out, **options)


def depth(data: PathLike, out: PathLike, **options: Any) -> Dict[str, Any]:
    """Paper B's depth U-Net with a DenseNet encoder (``encoder``: a preset;
    ``input``: (width, height), multiples of 32; ``head``: "conv1x1" or
    "custom"; ``loss``: "l1", "mse" or "l1-grad-ssim"). Every option:
    ``options("depth")``."""
    return _tactile.train_depth(data, out, **options)


def head(
    data: PathLike,
    *,
    encoder: Optional[PathLike] = None,
    features: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    test: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """Paper A's shape head on an encoder's features (or a feature CSV).

    Saved in ``out`` (default ``ENCODER/head``); tested on ``test`` or the
    ``test`` split, the accuracy and confusion matrix are in the result.
    ``rotate_copies`` > 0 also trains on turned copies of each frame (needs
    ``encoder``). Every option: ``options("head")``.
    """
    return _tactile.train_head_py(
        data, encoder=encoder, features=features, out=out, test=test, **options,
    )


def regressor(
    data: PathLike,
    targets: Sequence[str],
    *,
    encoder: Optional[PathLike] = None,
    features: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """A regressor on an encoder's features: ``targets`` are label columns,
    angles with their period (e.g. ``["x_mm", "theta_deg:180"]``, or one
    string as ``--targets`` takes it: ``"x_mm,theta_deg:180"``). Saved in
    ``out`` (default ``ENCODER/regressor``); returns the test MAE per target.
    ``shapes`` trains it on frames of those shapes only. Every option:
    ``options("regressor")``.
    """
    return _tactile.train_regressor_py(
        data, targets if isinstance(targets, str) else list(targets),
        encoder=encoder, features=features, out=out, **options,
    )


def options(trainer: str) -> List[Dict[str, Any]]:
    """Every option of a trainer (``"cae"``, ``"head"``, ``"regressor"``,
    ``"pose"``, ``"detector"``, ``"segmenter"``, ``"depth"``): ``name``,
    ``help`` and ``default`` of each, as ``tactile train <trainer> --help``
    shows them."""
    return _tactile.options(trainer)


def ensemble(members: Sequence[PathLike], out: PathLike) -> str:
    """Average 2 to 8 models trained apart: pose networks, detectors that
    read a frame alike (input size, bits, exposure normalisation,
    threshold), depth networks that read a frame alike (input size,
    channels, the same mask or calibration as fourth channel), or
    regressors on one encoder's features trained with other seeds (single
    models: an ensemble's members, not the ensemble).
    Copies them into the new folder ``out`` (an existing one is left alone)
    that ``PoseEstimator``, ``Pipeline`` and ``tactile.eval`` load as one
    model; a detector ensemble is one network (the members' mean logit), a
    depth ensemble one network (the members' mean map); a
    regressor ensemble inside an encoder folder is one of the estimators
    ``TactipEncoder`` runs (the members' mean).
    Returns what was made, in words.
    """
    return _tactile.train_ensemble(members, out)


def calibrate(model: PathLike, data=None, *, split: Optional[str] = None,
              calibration_from: Optional[PathLike] = None) -> str:
    """Calibrate a trained model on frames it was not trained on (the CLI's
    ``tactile train calibrate``): a detector's probabilities on ``data``
    (one logit scale, decisions unchanged), or the deviations of a pose
    network or of a regressor (or regressor ensemble) kept in its encoder's
    folder (one factor per target so ±1 holds 68.3 % of the errors) on
    ``data``'s rows of ``split``, or the factors of the validated run
    ``calibration_from`` for a model trained on every frame. Rewrites the
    model folder; returns what changed, in words.
    """
    return _tactile.train_calibrate(model, [] if data is None else data, split, calibration_from)


def profile(model: PathLike, data, *, split: Optional[str] = None) -> str:
    """Fit a trained model's input profile on ``data`` (a dataset or a list
    of them: its training frames) and save it in its config (the CLI's
    ``tactile train profile``): a detector's reads colour frames and gives
    frames of another sensor no answer; a TacTip model's (an encoder, a
    pose network or ensemble; the rows of ``split`` alone when given)
    reads its pin images, and ``predict`` names such frames in a
    ``UserWarning``. Models trained now have one already. Returns what was
    saved, in words.
    """
    return _tactile.train_profile(model, data, split)


def align(model: PathLike, data) -> str:
    """Measure the pin lattice's orientation on an encoder's training frames
    (``data``: a dataset or a list of them, every frame measured) and save it
    in the encoder's config (the CLI's ``tactile train align``): frames of a
    sensor mounted turned are then turned back before encoding, by
    ``TactipEncoder``, ``predict`` and the CLI alike. Returns what was saved,
    in words.
    """
    return _tactile.train_align(model, data)


__all__ = ["align", "cae", "calibrate", "depth", "detector", "ensemble", "head", "options", "pose", "profile",
           "regressor", "segmenter"]
