"""`tactile export --standalone` runs in onnxruntime with numpy alone (no
toolkit code) and gives the tendon decisions and scores of `tactile run`;
`tactile.export` writes what the command line writes."""

from __future__ import annotations

import json

import numpy as np
import onnxruntime as ort
import pytest

import tactile

from conftest import run_cli


def test_standalone_detector_matches_tactile_run(tactile_bin, root, tmp_path, palpation_frames):
    model = tmp_path / "detector.onnx"
    run_cli(tactile_bin, "export", "--model", "models/detector", "--out", str(model), "--standalone")
    session = ort.InferenceSession(str(model), providers=["CPUExecutionProvider"])
    meta = session.get_modelmeta().custom_metadata_map
    threshold = float(meta["threshold"])
    width, height = map(int, meta["input_size"].split("x"))
    (inp,) = session.get_inputs()
    assert inp.name == "frame" and inp.type in ("tensor(uint8)", "tensor(uint16)")
    assert session.get_outputs()[0].name == "tendon_probability"

    # The user's own resize: 320x180 frames averaged over 4x3 blocks.
    frames = np.stack(palpation_frames)
    n, h, w, _ = frames.shape
    small = frames.reshape(n, height, h // height, width, w // width, 3).mean(axis=(2, 4))
    if inp.type == "tensor(uint16)":
        # A 16-bit detector reads levels of 65535: the resized frame times 257.
        batch = np.round(small * 257.0).astype(np.uint16)
    else:
        batch = np.round(small).astype(np.uint8)
    (probability,) = session.run(["tendon_probability"], {"frame": batch})

    out = run_cli(tactile_bin, "run", "--data", "samples/palpation", "--out", "-")
    records = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    records = [r for r in records if "score" in r]
    assert len(records) == n
    # numpy's block mean and the toolkit's resize round a few pixels one grey
    # level apart, which moves a probability by up to 0.005 here; on the
    # toolkit's own bytes the two agree within 1e-5 (tests/standalone.rs).
    for p, r in zip(probability[:, 0], records):
        assert abs(float(p) - r["score"]) < 0.01, (p, r["score"])
        assert (p >= threshold) == r["tendon"]


def test_python_exports_what_the_command_line_exports(tactile_bin, root, tmp_path):
    cli = tmp_path / "cli.onnx"
    run_cli(tactile_bin, "export", "--model", "models/detector", "--out", str(cli), "--standalone")
    r = tactile.export(root / "models/detector", tmp_path / "py.onnx", standalone=True)
    assert r["kind"] == "detector" and r["bytes"] == (tmp_path / "py.onnx").stat().st_size
    # One library call behind both: the same graph, byte for byte.
    assert (tmp_path / "py.onnx").read_bytes() == cli.read_bytes()

    # A CAE's whole autoencoder: a pin image in, its reconstruction out.
    r = tactile.export(root / "models/cae-shapes", tmp_path / "ae.onnx", part="autoencoder")
    assert r["kind"] == "CAE autoencoder"
    session = ort.InferenceSession(str(tmp_path / "ae.onnx"), providers=["CPUExecutionProvider"])
    (inp,) = session.get_inputs()
    side = inp.shape[-1]
    pins = np.zeros((1, 1, side, side), np.float32)
    (out,) = session.run(None, {inp.name: pins})
    assert out.shape == pins.shape and np.isfinite(out).all()

    bad = [
        (dict(model=root / "models/segmenter", part="autoencoder"), ValueError, "only a CAE has an autoencoder"),
        (dict(model=root / "models/detector", part="encoder", standalone=True), ValueError, "part and standalone together"),
        (dict(model=root / "models/cae-shapes", part="decoder"), ValueError, "unknown part 'decoder'"),
        (dict(model=root / "models/none"), FileNotFoundError, "model folder does not exist"),
    ]
    for kwargs, kind, message in bad:
        with pytest.raises(kind, match=message):
            tactile.export(out=tmp_path / "bad.onnx", **kwargs)
    assert not (tmp_path / "bad.onnx").exists()
    # Never over a file of the model it exports.
    config = root / "models/segmenter/segmenter.json"
    before = config.read_bytes()
    with pytest.raises(ValueError, match="would break the model"):
        tactile.export(root / "models/segmenter", config)
    assert config.read_bytes() == before
