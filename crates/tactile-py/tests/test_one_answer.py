"""One answer per frame, whoever asks: the same 202 frames (rendered
palpation videos, the sample video, blank frames, frames of other kinds and
grey copies of the sensor's own)
get the same tendon decision and the same gate from `tactile eval detector`,
`tactile run`, the Python package and the standalone ONNX export."""

from __future__ import annotations

import csv
import json

import numpy as np
import onnxruntime as ort

import tactile
from conftest import run_cli


def _others(palpation_frames: list[np.ndarray], root) -> list[np.ndarray]:
    """The sample video, then 10 frames no detector should answer: blank
    ones (black, saturated, one colour), ones of other kinds, and two of
    the video's frames made grey (a camera in a mono mode)."""
    h, w = 180, 320
    y, x = np.mgrid[0:h, 0:w]
    tactip = tactile.read_rgb(sorted((root / "samples" / "virtual-tactip" / "frames").glob("*.png"))[0])
    rng = np.random.default_rng(3)
    odd = [
        np.zeros((h, w, 3), np.uint8),
        np.full((h, w, 3), 255, np.uint8),
        np.broadcast_to(np.array([30, 200, 30], np.uint8), (h, w, 3)).copy(),
        np.repeat(np.where((x // 8) % 2 == 0, 240, 20).astype(np.uint8)[..., None], 3, axis=2),
        rng.integers(0, 256, (h, w, 3), dtype=np.uint8),
        np.repeat(((x + y) * 255 // (w + h)).astype(np.uint8)[..., None], 3, axis=2),
        np.ascontiguousarray(tactip),
        np.ascontiguousarray(tactip[::-1]),
    ]
    for f in (palpation_frames[3], palpation_frames[6]):
        grey = f.astype(np.uint16).sum(axis=2) // 3
        odd.append(np.repeat(grey.astype(np.uint8)[..., None], 3, axis=2))
    return list(palpation_frames) + odd


def test_eval_run_python_and_standalone_onnx_give_one_answer(
    tactile_bin, root, tmp_path, palpation_frames
):
    # 180 rendered frames, written as a dataset `eval` and `run` read.
    data = tmp_path / "rendered"
    tactile.synth.visuotactile(
        sequences=6, frames_per_sequence=30, seed=31, width=320, height=180, out=data, progress=False
    )
    ds = tactile.Dataset(data)
    rendered = [ds.frame(i) for i in range(len(ds))]
    frames = rendered + _others(palpation_frames, root)
    assert len(frames) == 202

    # Python.
    pipe = tactile.Pipeline(root / "models", "onnx")
    results = [pipe.process(f) for f in frames]
    py_tendon = [r.tendon_raw for r in results]
    py_gate = [r.gate for r in results]

    # The standalone export, on the frames as the detector takes them.
    model = tmp_path / "detector.onnx"
    run_cli(tactile_bin, "export", "--model", "models/detector", "--out", str(model), "--standalone")
    session = ort.InferenceSession(str(model), providers=["CPUExecutionProvider"])
    names = [o.name for o in session.get_outputs()]
    assert names == ["tendon_probability", "gate", "input_score", "tendon"], names
    batch = np.stack([pipe.detector_frame(f) for f in frames])
    p, gate, _, tendon = session.run(None, {"frame": batch})
    codes = {None: 0, "blank": 1, "foreign": 2}
    assert [bool(t) for t in tendon] == py_tendon
    assert [int(g) for g in gate] == [codes[g] for g in py_gate]
    for r, q in zip(results, p[:, 0]):
        assert abs(r.score - float(q)) < 1e-4, (r.score, q)

    # `tactile eval detector` and `tactile run` on the rendered frames.
    decisions = tmp_path / "decisions.csv"
    run_cli(tactile_bin, "eval", "detector", "--model", "models/detector", "--data", str(data),
            "--frames", str(decisions))
    with decisions.open() as f:
        evaluated = [row["predicted"] == "1" for row in csv.DictReader(f)]
    out = run_cli(tactile_bin, "run", "--data", str(data), "--out", "-")
    records = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    records = [r for r in records if "score" in r]
    ran = [r.get("tendon_raw", r["tendon"]) for r in records]
    assert evaluated == py_tendon[: len(rendered)]
    assert ran == py_tendon[: len(rendered)]

    # The videos pass through the network and show tendons; every blank
    # frame and every frame of another kind is stopped by a gate.
    assert sum(py_tendon) > 20
    assert all(g is None for g in py_gate[: len(rendered) + len(palpation_frames)])
    assert all(g is not None for g in py_gate[-10:]), py_gate[-10:]
    assert py_gate[-2:] == ["foreign", "foreign"], py_gate[-2:]
