"""Training, with the options of ``tactile train ...``.

Every option left as None keeps the model's default (the same default the
command line shows in ``--help``). Schedule options: ``max_epochs``,
``patience``, ``batch_size``, ``lr``, ``lr_decay`` and ``seed``. Training runs
with the interpreter free for other threads, prints a line per epoch (a
progress bar on a terminal), writes the same model folder as the command
line, and returns a summary dict. Ctrl-C stops it cleanly: the folder is
marked incomplete (``resume=True`` continues it) and ``KeyboardInterrupt``
is raised.
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from . import _tactile

PathLike = Union[str, "os.PathLike[str]"]
Size = Tuple[int, int]


def _schedule(**kw: Any) -> Optional[Dict[str, Any]]:
    d = {k: v for k, v in kw.items() if v is not None}
    return d or None


def _path(p: Optional[PathLike]) -> Optional[str]:
    return None if p is None else os.fspath(p)


def cae(
    data: PathLike,
    out: PathLike,
    *,
    preprocess: str = "binary",
    widths: Optional[Sequence[int]] = None,
    features: Optional[int] = None,
    linear_latent: bool = False,
    optimizer: str = "adadelta",
    val_fraction: Optional[float] = None,
    exclude_test: Optional[float] = None,
    split_seed: int = 7,
    device: str = "flex",
    resume: bool = False,
    max_epochs: Optional[int] = None,
    patience: Optional[int] = None,
    batch_size: Optional[int] = None,
    lr: Optional[float] = None,
    lr_decay: Optional[float] = None,
    seed: Optional[int] = None,
    rotate_copies: int = 0,
    rotate_deg: float = 6.0,
    joint_targets: Optional[Sequence[str]] = None,
    joint_weight: float = 1.0,
    joint_hidden: int = 64,
    joint_loss: str = "mse",
) -> Dict[str, Any]:
    """Paper A's convolutional autoencoder on a TacTip dataset.

    ``preprocess``: "binary" (frames already binarised), "paper",
    "lighting-compensated" or a JSON file. ``widths``: four encoder widths,
    e.g. (16, 8, 8, 4); ``features`` sets the last one. ``optimizer``:
    "adadelta" (paper A) or "adam". ``device``: "flex" or "ndarray".
    ``rotate_copies`` > 0: each epoch, each training frame is seen as it is
    or as one of that many copies turned by up to ``rotate_deg`` degrees.
    ``joint_targets`` (e.g. ``["x_mm", "theta_deg:180", "depth_mm"]``):
    semi-supervised, the features also feed a head of ``joint_hidden``
    units trained to predict those label columns, its loss ("mse" or
    "l1") weighted by ``joint_weight``; only the autoencoder is saved. The
    pin images' side (the preprocessing's ``output_px``: 28, 56 or 112)
    sets the encoder's input; larger ones pass through stem blocks down to
    Table I's 28.
    """
    return _tactile.train_cae(
        os.fspath(data),
        os.fspath(out),
        preprocess=preprocess,
        widths=None if widths is None else list(widths),
        features=features,
        linear_latent=linear_latent,
        optimizer=optimizer,
        val_fraction=val_fraction,
        exclude_test=exclude_test,
        split_seed=split_seed,
        device=device,
        resume=resume,
        schedule=_schedule(
            max_epochs=max_epochs, patience=patience, batch_size=batch_size,
            lr=lr, lr_decay=lr_decay, seed=seed,
        ),
        rotate_copies=rotate_copies,
        rotate_deg=rotate_deg,
        joint_targets=None if joint_targets is None else list(joint_targets),
        joint_weight=joint_weight,
        joint_hidden=joint_hidden,
        joint_loss=joint_loss,
    )


def detector(
    data: Union[PathLike, Sequence[PathLike]],
    out: PathLike,
    **options: Any,
) -> Dict[str, Any]:
    """Paper B's tendon detector on one or more visuo-tactile datasets.

    ``options`` are the flags of ``tactile train detector`` by their
    keyword names (``input_bits=16``, ``normalise_exposure=True``,
    ``soft_labels=0.6``, ``augment=True``, ``input=(320, 240)``,
    ``max_epochs=...``); ``options("detector")`` lists every one with its
    help and default, and an unknown keyword is a ``ValueError``. The
    summary includes the threshold chosen on the validation sequences.
    """
    paths = [data] if isinstance(data, (str, os.PathLike)) else list(data)
    return _tactile.train_detector(
        [os.fspath(p) for p in paths], os.fspath(out), **options
    )


def options(trainer: str) -> List[Dict[str, Any]]:
    """Every option of a trainer (``"detector"``): ``name``, ``help`` and
    ``default`` of each, as ``tactile train <trainer> --help`` shows them."""
    return _tactile.options(trainer)


def segmenter(
    data: PathLike,
    out: PathLike,
    *,
    side: Optional[int] = None,
    base: Optional[int] = None,
    copies: Optional[int] = None,
    val_fraction: Optional[float] = None,
    device: str = "flex",
    resume: bool = False,
    max_epochs: Optional[int] = None,
    patience: Optional[int] = None,
    batch_size: Optional[int] = None,
    lr: Optional[float] = None,
    lr_decay: Optional[float] = None,
    seed: Optional[int] = None,
) -> Dict[str, Any]:
    """Paper B's U-Net tendon segmenter (``side``: window, a multiple of 16)."""
    return _tactile.train_segmenter(
        os.fspath(data),
        os.fspath(out),
        side=side,
        base=base,
        copies=copies,
        val_fraction=val_fraction,
        device=device,
        resume=resume,
        schedule=_schedule(
            max_epochs=max_epochs, patience=patience, batch_size=batch_size,
            lr=lr, lr_decay=lr_decay, seed=seed,
        ),
    )


def depth(
    data: PathLike,
    out: PathLike,
    *,
    encoder: str = "small",
    input: Optional[Size] = None,
    head: Optional[str] = None,
    loss: Optional[str] = None,
    with_mask: bool = False,
    freeze_encoder: bool = False,
    pretrained: Optional[PathLike] = None,
    unit_mm: Optional[float] = None,
    decoder_width: Optional[int] = None,
    val_fraction: Optional[float] = None,
    device: str = "flex",
    resume: bool = False,
    max_epochs: Optional[int] = None,
    patience: Optional[int] = None,
    batch_size: Optional[int] = None,
    lr: Optional[float] = None,
    lr_decay: Optional[float] = None,
    seed: Optional[int] = None,
) -> Dict[str, Any]:
    """Paper B's depth U-Net with a DenseNet encoder.

    ``encoder``: a DenseNet preset ("small", "densenet121", ...);
    ``input``: (width, height), multiples of 32; ``head``: "conv1x1" or
    "custom"; ``loss``: "l1", "mse" or "l1-grad-ssim".
    """
    return _tactile.train_depth(
        os.fspath(data),
        os.fspath(out),
        encoder=encoder,
        input=input,
        head=head,
        loss=loss,
        with_mask=with_mask,
        freeze_encoder=freeze_encoder,
        pretrained=_path(pretrained),
        unit_mm=unit_mm,
        decoder_width=decoder_width,
        val_fraction=val_fraction,
        device=device,
        resume=resume,
        schedule=_schedule(
            max_epochs=max_epochs, patience=patience, batch_size=batch_size,
            lr=lr, lr_decay=lr_decay, seed=seed,
        ),
    )


def head(
    data: PathLike,
    *,
    encoder: Optional[PathLike] = None,
    features: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    test: Optional[PathLike] = None,
    folds: Optional[int] = None,
    repeats: Optional[int] = None,
    seed: Optional[int] = None,
    device: str = "flex",
    rotate_copies: int = 0,
    rotate_deg: float = 6.0,
) -> Dict[str, Any]:
    """Paper A's shape head on an encoder's features (or a feature CSV).

    Saved in ``out`` (default ``ENCODER/head``); tested on ``test`` or the
    ``test`` split, the accuracy and confusion matrix are in the result.
    ``rotate_copies`` > 0 also trains on that many copies of each frame
    turned by up to ``rotate_deg`` degrees (needs ``encoder``), for a head
    that holds on a sensor mounted turned.
    """
    return _tactile.train_head_py(
        os.fspath(data),
        encoder=_path(encoder),
        features=_path(features),
        out=_path(out),
        test=_path(test),
        folds=folds,
        repeats=repeats,
        seed=seed,
        device=device,
        rotate_copies=rotate_copies,
        rotate_deg=rotate_deg,
    )


def regressor(
    data: PathLike,
    targets: Sequence[str],
    *,
    encoder: Optional[PathLike] = None,
    features: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    test_fraction: Optional[float] = None,
    val_fraction: Optional[float] = None,
    hidden: Optional[Sequence[int]] = None,
    seed: Optional[int] = None,
    device: str = "flex",
    only_labelled: bool = False,
    shapes: Sequence[str] = (),
) -> Dict[str, Any]:
    """A regressor on an encoder's features: ``targets`` are label columns,
    angles with their period (e.g. ``["x_mm", "theta_deg:180"]``). Saved in
    ``out`` (default ``ENCODER/regressor``); returns the test MAE per target.
    ``shapes`` trains it on frames of those shapes only (a sphere's
    position, say); beside a shape head it then answers for the frames the
    head puts in them.
    """
    return _tactile.train_regressor_py(
        os.fspath(data),
        list(targets),
        encoder=_path(encoder),
        features=_path(features),
        out=_path(out),
        test_fraction=test_fraction,
        val_fraction=val_fraction,
        hidden=None if hidden is None else list(hidden),
        seed=seed,
        device=device,
        only_labelled=only_labelled,
        shapes=list(shapes),
    )


def ensemble(members: Sequence[PathLike], out: PathLike) -> str:
    """Average models trained apart: pose networks, or detectors that read a
    frame alike (input size, bits, exposure normalisation, threshold).
    Copies them into the new folder ``out`` (an existing one is left alone)
    that ``PoseEstimator``, ``Pipeline`` and ``tactile.eval`` load as one
    model; a detector ensemble is one network (the members' mean logit).
    Returns what was made, in words.
    """
    return _tactile.train_ensemble([os.fspath(m) for m in members], os.fspath(out))


__all__ = ["cae", "depth", "detector", "ensemble", "head", "regressor", "segmenter"]
