"""Paper A's encoder from Python: bit-for-bit the features of `tactile
encode`, the estimates of `tactile perceive`, and clear errors."""

from __future__ import annotations

import csv
import json
import re
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import tactile
from conftest import interrupt_after, run_cli, run_python


def _frames(ds: tactile.Dataset) -> np.ndarray:
    return np.stack([ds.frame(i) for i in range(len(ds))])


def test_encode_equals_tactile_encode_bit_for_bit(tactile_bin, root, tmp_path):
    out = tmp_path / "features.csv"
    run_cli(tactile_bin, "encode", "--model", "models/cae-synth", "--data",
            "samples/virtual-tactip", "--out", str(out), "--device", "flex")
    with open(out) as f:
        rows = list(csv.reader(f))[1:]
    cli = np.array([[np.float32(v) for v in r[1:]] for r in rows], dtype=np.float32)
    enc = tactile.TactipEncoder(root / "models/cae-synth", "burn-flex")
    ds = tactile.Dataset(root / "samples/virtual-tactip")
    got = enc.encode(_frames(ds))
    assert got.dtype == np.float32 and got.shape == (len(ds), enc.feature_count)
    assert np.array_equal(got.view(np.uint32), cli.view(np.uint32))
    # A list of frames, and frames given as RGB, encode the same.
    assert np.array_equal(enc.encode([ds.frame(i) for i in range(len(ds))]), got)
    rgb = np.repeat(_frames(ds)[..., None], 3, axis=-1)
    assert np.array_equal(enc.encode(rgb), got)


def test_estimate_matches_tactile_perceive(tactile_bin, root, tmp_path):
    out = tmp_path / "estimates.csv"
    run_cli(tactile_bin, "perceive", "--encoder", "models/cae-synth", "--data",
            "samples/virtual-tactip", "--out", str(out), "--device", "flex")
    with open(out) as f:
        rows = list(csv.DictReader(f))
    enc = tactile.TactipEncoder(root / "models/cae-synth")
    ds = tactile.Dataset(root / "samples/virtual-tactip")
    est = enc.estimate(_frames(ds))
    assert set(est) == set(rows[0]) - {"file"}
    for name, values in est.items():
        assert len(values) == len(ds)
        for v, row in zip(values, rows):
            if values.dtype.kind in "fc":
                assert abs(v - float(row[name])) <= 5e-5, name
            else:
                assert v == row[name], name


def test_preprocess_gives_the_pin_image(root):
    enc = tactile.TactipEncoder(root / "models/cae-synth")
    ds = tactile.Dataset(root / "samples/virtual-tactip")
    pin = enc.preprocess(ds.frame(0))
    assert pin.shape == (enc.pin_side, enc.pin_side) and pin.dtype == np.float32
    assert 0.0 <= pin.min() and pin.max() <= 1.0 and pin.std() > 0.0


# Its frames are blank or noise on purpose: that they are named as blank
# frames or frames without this sensor's pins is asserted in the tests below.
@pytest.mark.filterwarnings("ignore:.*pins spaced unlike:UserWarning")
@pytest.mark.filterwarnings("ignore:.*one grey level throughout the crop:UserWarning")
def test_encoder_errors(root, tmp_path):
    with pytest.raises(FileNotFoundError):
        tactile.TactipEncoder(tmp_path / "missing")
    with pytest.raises(ValueError, match="cae"):
        tactile.TactipEncoder(root / "models/detector")
    bare = tmp_path / "bare"  # an encoder folder without estimator subfolders
    bare.mkdir()
    for f in ("cae.json", "cae.bpk"):
        shutil.copy(root / "models/cae-edge" / f, bare / f)
    enc = tactile.TactipEncoder(bare)
    assert enc.estimators == []
    assert tactile.TactipEncoder(root / "models/cae-edge").estimators == ["pose"]
    frames = np.zeros((2, 300, 300), np.uint8)
    assert enc.encode(frames).shape == (2, enc.feature_count)
    with pytest.raises(ValueError, match="no estimators"):
        enc.estimate(frames)
    with pytest.raises(TypeError, match="got a float64 array"):
        enc.encode(np.zeros((2, 300, 300)))
    with pytest.raises(TypeError, match="got an int16 array"):
        enc.encode(np.zeros((2, 300, 300), np.int16))
    with pytest.raises(TypeError, match="got an object array"):
        enc.encode(np.empty((2, 300, 300), object))
    with pytest.raises(ValueError, match=r"\(2, 300, 300, 3, 1\)"):
        enc.encode(np.zeros((2, 300, 300, 3, 1), np.uint8))
    with pytest.raises(ValueError, match=r"frames\[1\]"):
        enc.encode([np.zeros((300, 300), np.uint8), np.zeros((300, 300, 2), np.uint8)])
    # Frames as image readers give them: grey with a channel axis is grey;
    # an opaque alpha channel (an RGBA or grey-alpha PNG) is dropped, as the
    # command line drops it from such a file, and a frame with transparent
    # pixels is refused as one frame, not read as a batch of 4-pixel-wide
    # frames. Before, every frame with alpha was refused.
    grey = np.random.default_rng(3).integers(0, 256, (300, 300), np.uint8)
    np.testing.assert_array_equal(enc.encode(grey[..., None]), enc.encode(grey))
    opaque = np.full((300, 300), 255, np.uint8)
    np.testing.assert_array_equal(enc.encode(np.dstack([grey, opaque])), enc.encode(grey))
    rgb = np.dstack([grey, grey[::-1], grey.T])
    np.testing.assert_array_equal(enc.encode(np.dstack([rgb, opaque])), enc.encode(rgb))
    with pytest.raises(ValueError, match=r"an RGBA frame of shape \(300, 300, 4\) with 90000 of its 90000 pixels not opaque"):
        enc.encode(np.zeros((300, 300, 4), np.uint8))
    half = np.dstack([grey, opaque])
    half[:150, :, 1] = 0
    with pytest.raises(ValueError, match=r"a grey-with-alpha frame of shape \(300, 300, 2\) with 45000 of"):
        enc.encode(half)
    with pytest.raises(TypeError, match="list of frames; got a NoneType"):
        enc.encode(None)


def test_pose_estimator_matches_tactile_predict(tactile_bin, root, tmp_path, shared_real):
    """The pose network from Python gives `tactile predict`'s estimates."""
    data = shared_real / "tactip127-edge"
    out = tmp_path / "estimates.csv"
    # The dataset's first 40 rows, where every frame took half a minute.
    run_cli(tactile_bin, "predict", "--model", "models/pose-edge", "--data", str(data),
            "--out", str(out), "--device", "flex", "--limit", "40")
    with open(out) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 40
    pose = tactile.PoseEstimator(root / "models/pose-edge", "burn-flex")
    assert pose.targets == ["x_mm", "theta_deg", "depth_mm"]
    frames = np.stack([tactile.read_grey(data / r["file"]) for r in rows])
    got = pose.estimate(frames)
    for name in pose.targets:
        cli = np.array([float(r[name]) for r in rows])
        # predict writes four decimals.
        assert np.allclose(got[name], cli, atol=6e-5), name
    assert pose.preprocess(frames[0]).shape == (pose.pin_side, pose.pin_side)
    # One RGB frame as OpenCV or imageio give it, (H, W, 3): one frame, not
    # three-pixel-wide grey ones; the same estimate as its grey levels.
    rgb = np.repeat(frames[0][:, :, None], 3, axis=2)
    one = pose.estimate(rgb)
    for name in pose.targets:
        assert one[name].shape == (1,) and np.allclose(one[name], got[name][:1], atol=1e-5), name
    with pytest.raises(ValueError):
        pose.estimate(np.zeros((2, 3, 4, 5, 6), dtype=np.uint8))
    with pytest.raises(FileNotFoundError):
        tactile.PoseEstimator(tmp_path / "nowhere")


def test_surface_pose_gives_tactile_predicts_estimates_and_deviations(tactile_bin, root, tmp_path, shared_real):
    """models/pose-surface from Python: each target and its calibrated
    standard deviation, as `tactile predict` writes them."""
    src = shared_real / "tactip331-surface"
    data = tmp_path / "surface"
    (data / "frames").mkdir(parents=True)
    with open(src / "labels.csv") as f:
        lines = f.read().splitlines()
    keep = [lines[0]] + lines[1:21]
    for line in keep[1:]:
        name = line.split(",")[0]
        shutil.copy(src / name, data / name)
    (data / "labels.csv").write_text("\n".join(keep) + "\n")
    manifest = json.loads((src / "manifest.json").read_text())
    manifest["count"] = 20
    (data / "manifest.json").write_text(json.dumps(manifest))
    out = tmp_path / "estimates.csv"
    run_cli(tactile_bin, "predict", "--model", "models/pose-surface", "--data", str(data),
            "--out", str(out), "--device", "flex")
    with open(out) as f:
        rows = list(csv.DictReader(f))
    pose = tactile.PoseEstimator(root / "models/pose-surface", "burn-flex")
    frames = np.stack([tactile.read_grey(data / r["file"]) for r in rows])
    got = pose.estimate(frames)
    assert sorted(got) == sorted(pose.targets + [t + "_std" for t in pose.targets])
    for name, values in got.items():
        cli = np.array([float(r[name]) for r in rows])
        assert np.allclose(values, cli, atol=6e-5), name
    assert all((got[t + "_std"] > 0).all() for t in pose.targets)
    # Frames of another camera (smaller than the model's 440 px crop): still
    # estimated, with one warning per size naming its first frame; frames of
    # the rig's own size get none.
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        pose.estimate(frames[:2])
    assert not [w for w in seen if "smaller than" in str(w.message)]
    small = np.full((3, 120, 160), 128, dtype=np.uint8)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        mixed = pose.estimate([frames[0], *small])
    said = [str(w.message) for w in seen]
    assert any(re.match(r"frames\[1\]: the frame is 160x120.*440x440 crop", m) for m in said), said
    assert len(mixed["depth_mm"]) == 4
    assert sum("smaller than" in str(w.message) for w in seen) == 1
    # Grey frames without pins: named in one warning too, as blank.
    blank = [str(w.message) for w in seen if "one grey level" in str(w.message)]
    assert len(blank) == 1 and blank[0].startswith("frames[1], frames[2], frames[3]: "), blank
    assert not [w for w in seen if "pins spaced unlike" in str(w.message)]
    # A frame too small for even the pin image is refused, named by its place
    # (after the warning that it is smaller than the model's crop).
    crop = r"the frame is 12x10, smaller than the model's 440x440 crop"
    with pytest.raises(ValueError, match=r"frames\[2\]: frame is 12x10, smaller than the 64x64"), \
            pytest.warns(UserWarning, match=r"frames\[2\]: " + crop):
        pose.estimate([frames[0], frames[1], np.zeros((10, 12), dtype=np.uint8)])
    with pytest.raises(ValueError, match=r"^frame is 12x10, smaller than the 64x64"), \
            pytest.warns(UserWarning, match=r"frames\[0\]: " + crop):
        pose.preprocess(np.zeros((10, 12), dtype=np.uint8))

    # Calibrated again from Python (`tactile train calibrate`): on these 20
    # frames ±1 deviation then holds ceil(0.683 * 20) = 14 of each target's
    # errors, the estimates unchanged; too few rows of a split are refused.
    model = tmp_path / "pose"
    shutil.copytree(root / "models/pose-surface", model)
    with pytest.raises(ValueError, match="'val'.*20"):
        tactile.train.calibrate(model, data, split="val")
    with pytest.warns(UserWarning, match="these 20 frames are frames it trained on"):
        said = tactile.train.calibrate(model, data)
    assert "20 frames" in said and "cross-fitted" in said
    again = tactile.PoseEstimator(model, "burn-flex").estimate(frames)
    labels = {r["file"]: r for r in csv.DictReader(keep)}
    truth = {t: np.array([float(labels[r["file"]][t]) for r in rows]) for t in pose.targets}
    for t in pose.targets:
        assert np.allclose(again[t], got[t], atol=1e-6), t
        inside = np.abs(again[t] - truth[t]) <= again[t + "_std"] * (1 + 1e-9)
        assert inside.sum() == 14, t
    with pytest.raises(ValueError, match="one of the two"):
        tactile.train.calibrate(model, data, calibration_from=root / "models/pose-surface")

    # Scored as `tactile evaluate` scores it: each target's mean absolute
    # error of these estimates against the labels, with a warning that the
    # shipped model trained on these frames.
    fitted = "the model trained on every one of these 20 frames"
    with pytest.warns(UserWarning, match=fitted):
        scores = tactile.eval.tactip(root / "models/pose-surface", data)
    maes = {s["target"]: s["mae"] for s in scores["targets"]}
    assert sorted(maes) == sorted(pose.targets) and scores["frames"] == 20
    for t in pose.targets:
        assert abs(maes[t] - np.abs(got[t] - truth[t]).mean()) < 1e-4, t
    # With each estimate's deviation, the share of frames inside ±1 and
    # ±1.96 of them (these frames' errors against the shipped deviations).
    for sc in scores["targets"]:
        t, c = sc["target"], sc["coverage"]
        err, std = np.abs(got[t] - truth[t]), got[t + "_std"]
        assert c["within_1_std"] == pytest.approx(np.mean(err <= std), abs=1e-9), t
        assert c["within_1_96_std"] == pytest.approx(np.mean(err <= 1.959964 * std), abs=1e-9), t
    # One split alone: these 20 rows are all of the authors' `train`.
    with pytest.warns(UserWarning, match=fitted):
        train = tactile.eval.tactip(root / "models/pose-surface", data, split="training")
    assert train["targets"] == scores["targets"]
    with pytest.raises(ValueError, match=r"labels\.csv: no row of its 'split' column is 'val'"):
        tactile.eval.tactip(root / "models/pose-surface", data, split="val")
    with pytest.raises(TypeError, match="^split: "):
        tactile.eval.tactip(root / "models/pose-surface", data, split=1)
    # An encoder with its estimators (models/cae-surface, trained on this
    # set too) says so as well.
    with pytest.warns(UserWarning, match=fitted):
        cae = tactile.eval.tactip(root / "models/cae-surface", data)
    assert all(0 <= sc["coverage"]["within_1_std"] <= 1 for sc in cae["targets"])
    said = run_cli(tactile_bin, "evaluate", "--model", "models/pose-surface", "--data", str(data))
    assert said.startswith("Pose network models/pose-surface on ") and "| **all** |" in said, said
    assert "| shear_theta_deg | " in said.split("±1.96 deviations |")[1], said
    cli = json.loads(said.splitlines()[-1])
    assert cli["warning"].startswith(fitted) and scores["warning"] == cli["warning"]
    for a, b in zip(cli["targets"], scores["targets"]):
        assert a["target"] == b["target"] and a["mae"] == pytest.approx(b["mae"], abs=1e-6)

    # A frame of the dataset cut short behind its whole header (a copy
    # stopped half-way): left out with one warning naming it, the other 19
    # frames' estimates kept as they were, in Python and the command line.
    cut = rows[7]["file"]
    whole = (data / cut).read_bytes()
    (data / cut).write_bytes(whole[: len(whole) // 2])
    told = r"1 of the 20 frames could not be decoded.*" + re.escape(cut) + ": cannot decode"
    with pytest.warns(UserWarning, match=told):
        kept = tactile.predict(root / "models/pose-surface", data)
    assert kept["file"] == [r["file"] for r in rows if r["file"] != cut]
    for t in pose.targets:
        assert np.allclose(kept[t], np.delete(got[t], 7), atol=6e-5), t
    run_cli(tactile_bin, "predict", "--model", "models/pose-surface", "--data", str(data),
            "--out", str(out), "--device", "flex")
    with open(out) as f:
        assert [r["file"] for r in csv.DictReader(f)] == kept["file"]
    # Scored, it is left out too: the other 19 frames' errors, with the
    # same warning.
    with pytest.warns(UserWarning, match=told):
        scored = tactile.eval.tactip(root / "models/pose-surface", data)
    assert scored["frames"] == 19
    for sc in scored["targets"]:
        t = sc["target"]
        assert sc["mae"] == pytest.approx(np.abs(np.delete(got[t] - truth[t], 7)).mean(), abs=1e-4), t


def test_the_surface_cae_route_runs_alike_on_burn_and_onnxruntime(root, shared_real):
    """models/cae-surface (a 9 px first kernel) through burn and through its
    ONNX export: the same features and estimates on real surface frames."""
    src = shared_real / "tactip331-surface"
    with open(src / "labels.csv") as f:
        rows = list(csv.DictReader(f))[:16]
    frames = [tactile.read_grey(src / r["file"]) for r in rows]
    burn = tactile.TactipEncoder(root / "models/cae-surface", "burn-flex")
    ort = tactile.TactipEncoder(root / "models/cae-surface", "onnx")
    assert burn.feature_count == 32 and burn.pin_side == 56
    a, b = burn.encode(frames), ort.encode(frames)
    assert np.abs(a - b).max() <= 1e-4 * max(1.0, np.abs(a).max())
    ea, eb = burn.estimate(frames), ort.estimate(frames)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        burn.encode(np.zeros((1, 120, 160), dtype=np.uint8))
    said = [str(w.message) for w in seen]
    # A small blank frame: its size, and no pins to read.
    assert len(said) == 2 and said[0].startswith("frames[0]: the frame is 160x120"), said
    assert said[1].startswith("frames[0]: one grey level throughout the crop"), said
    with pytest.raises(ValueError, match=r"frames\[1\]: frame is 12x10, smaller than the 56x56"), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its size, said above
        burn.encode([frames[0], np.zeros((10, 12), dtype=np.uint8)])
    for t in ["depth_mm", "roll_deg", "pitch_deg", "shear_x_mm", "shear_y_mm", "shear_theta_deg"]:
        assert np.allclose(ea[t], eb[t], atol=1e-3), t


def test_predict_reads_a_folder_of_frames_as_tactile_predict(tactile_bin, root, tmp_path, shared_real):
    """`tactile.predict` is `tactile predict`: on a folder of 8 real surface
    frames (no dataset around them), the same CSV byte for byte, the same
    values returned; an encoder route with a limit; bad input named. (A
    bag written by `rosbags`: tests/test_robots.py.)"""
    src = shared_real / "tactip331-surface"
    with open(src / "labels.csv") as f:
        names = [r["file"] for r in csv.DictReader(f)][:8]
    folder = tmp_path / "frames"
    folder.mkdir()
    for n in names:
        shutil.copy(src / n, folder / Path(n).name)
    out = tmp_path / "cli.csv"
    run_cli(tactile_bin, "predict", "--model", "models/pose-surface", "--data", str(folder),
            "--out", str(out))
    with open(out) as f:
        rows = list(csv.DictReader(f))
    py_out = tmp_path / "py.csv"
    got = tactile.predict(root / "models/pose-surface", folder, py_out)
    assert got["file"] == [r["file"] for r in rows]
    assert py_out.read_text() == out.read_text()
    assert "stamp_ns" not in got and got["ms_per_frame"] > 0
    for name in rows[0]:
        if name != "file":
            assert np.allclose(got[name], [float(r[name]) for r in rows], atol=6e-5), name
    # One encoder with its estimators, a limit, and bad input named.
    cae = tactile.predict(root / "models/cae-surface", folder, limit=3)
    assert len(cae["file"]) == 3 and cae["shear_theta_deg_std"].shape == (3,)
    with pytest.raises(FileNotFoundError, match="nowhere"):
        tactile.predict(root / "models/pose-surface", tmp_path / "nowhere")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ValueError, match=r"no frames \(PNG, JPEG, BMP, TIFF, WebP or PGM/PPM\)"):
        tactile.predict(root / "models/pose-surface", empty)
    with pytest.raises(ValueError, match=r"not a TacTip model folder.*the folders cae-edge, .*pass one"):
        tactile.predict(root / "models", folder)
    with pytest.raises(ValueError, match=r"is a file of a dataset.*pass the dataset's folder"):
        tactile.predict(root / "models/pose-surface", src / "labels.csv")
    with pytest.raises(ValueError, match="this output is the input"):
        tactile.predict(root / "models/pose-surface", folder / Path(names[0]).name,
                        folder / Path(names[0]).name)
    # Nor a model's config: its estimates over `pose.json` would break it.
    model = tmp_path / "model"
    shutil.copytree(root / "models/pose-edge", model)
    config = (model / "pose.json").read_bytes()
    with pytest.raises(ValueError, match="pose.json: is a file of the model in"):
        tactile.predict(model, folder, model / "pose.json")
    assert (model / "pose.json").read_bytes() == config
    # A frame of another camera (the virtual TacTip's 300x300, smaller than
    # the model's 440 px crop) among them: still estimated, with one Python
    # warning naming it.
    shutil.copy(root / "samples" / "virtual-tactip" / "frames" / "000000.png", folder / "zz-small.png")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        mixed = tactile.predict(root / "models/pose-surface", folder)
    assert len(mixed["file"]) == 9
    smaller = [str(w.message) for w in seen if "smaller than" in str(w.message)]
    assert len(smaller) == 1 and re.search("zz-small.png.*smaller than the model's 440x440 crop", smaller[0])
    assert all(w.category is UserWarning for w in seen)
    # Its pins (another sensor's, the virtual TacTip's) are named too, and
    # only its: the model's pin profile knows the real frames.
    unlike = [str(w.message) for w in seen if "pins spaced unlike" in str(w.message)]
    assert len(unlike) == 1 and "zz-small.png" in unlike[0], unlike
    # The real frames show pins; a blank one (a covered camera) is still
    # estimated, and named: there are no pins to read.
    assert not any("grey level" in str(w.message) for w in seen)
    if shutil.which("ffmpeg") is None:  # installed by scripts/test.sh
        return
    (folder / "zz-small.png").unlink()
    subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", "-f", "lavfi", "-i",
                    "color=c=black:s=445x440", "-frames:v", "1", "-pix_fmt", "gray",
                    str(folder / "zz-blank.png")], check=True)
    with pytest.warns(UserWarning, match=r"zz-blank\.png: one grey level throughout the crop.*no pins to read") as seen:
        blanked = tactile.predict(root / "models/pose-surface", folder)
    assert len(blanked["file"]) == 9
    assert sum("grey level" in str(w.message) for w in seen) == 1



def test_train_profile_gives_an_older_tactip_model_its_pin_profile(root, tmp_path, shared_real):
    """`tactile.train.profile` is `tactile train profile`: a TacTip model
    without a pin profile (trained before it) names no frame of another
    sensor; fitted on its training frames, it names them in a warning."""
    model = tmp_path / "cae"
    shutil.copytree(root / "models/cae-synth", model)
    config = json.loads((model / "cae.json").read_text())
    del config["input_profile"]
    (model / "cae.json").write_text(json.dumps(config))
    own = tmp_path / "own"
    tactile.synth.tactip(24, seed=5, out=own, progress=False)
    folder = tmp_path / "frames"
    shutil.copytree(root / "samples/virtual-tactip/frames", folder)
    edge = shared_real / "tactip127-edge/frames/frame_0_0.png"
    grey = tactile.read_grey(edge)
    shutil.copy(edge, folder / "zz-edge.png")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        tactile.predict(model, folder)
    assert not any("pins spaced unlike" in str(w.message) for w in seen)
    with pytest.raises(ValueError, match=r"labels\.csv.*no 'split' column"):
        tactile.train.profile(model, own, split="train")
    with pytest.raises(ValueError, match=r"virtual-tactip: 14 frames with pins to read, and a pin profile needs at least 20"):
        tactile.train.profile(model, root / "samples/virtual-tactip")
    said = tactile.train.profile(model, [own])
    assert said.startswith("input profile of 24 frames") and str(model) in said
    assert json.loads((model / "cae.json").read_text())["input_profile"]["names"][0] == "pin spectrum band 1/16"
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        got = tactile.predict(model, folder)
    assert len(got["file"]) == len(list(folder.iterdir())) and grey.shape == (256, 256)
    unlike = [str(w.message) for w in seen if "pins spaced unlike" in str(w.message)]
    assert len(unlike) == 1 and re.search(r"zz-edge\.png: pins spaced unlike those of the 24 frames", unlike[0]), unlike


def test_frames_of_another_sensor_given_to_the_models_one_call_at_a_time_are_named(root, shared_real):
    """`PoseEstimator.estimate` and `TactipEncoder.encode` / `estimate` on
    frames (a robot's loop, no dataset or source) estimate every frame and
    name the ones outside the model's pin profile in a `UserWarning`, as
    `predict` does; a frame of the model's own sensor passes."""
    surface = tactile.read_grey(shared_real / "tactip331-surface/frames/train_image_1.png")
    press = tactile.read_rgb(shared_real / "gelsight-ball/frames/press_01.png")
    edge = tactile.read_grey(shared_real / "tactip127-edge/frames/frame_0_0.png")
    pose = tactile.PoseEstimator(root / "models/pose-surface")
    cae = tactile.TactipEncoder(root / "models/cae-edge")

    def unlike(call):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            out = call()
        return out, [str(w.message) for w in seen if "pins spaced unlike" in str(w.message)]

    got, said = unlike(lambda: pose.estimate(surface))
    assert said == [] and got["depth_mm"].shape == (1,)
    got, said = unlike(lambda: pose.estimate([surface, press]))
    assert got["depth_mm"].shape == (2,)
    assert len(said) == 1 and said[0].startswith("frames[1]: pins spaced unlike those of the 8000 frames"), said
    feats, said = unlike(lambda: cae.encode(edge))
    assert said == [] and feats.shape == (1, cae.feature_count)
    feats, said = unlike(lambda: cae.encode([edge, surface]))
    assert feats.shape == (2, cae.feature_count)
    assert len(said) == 1 and said[0].startswith("frames[1]: "), said
    got, said = unlike(lambda: cae.estimate([surface]))
    assert len(said) == 1 and said[0].startswith("frames[0]: "), said


def test_a_loop_fed_another_camera_is_warned_once_and_a_blank_frame_as_blank(root, shared_real):
    """A robot's loop calling `PoseEstimator.estimate` / `TactipEncoder.encode`
    frame by frame on the wrong camera is warned once per call site under
    Python's default filter (the text names no score, so it repeats alike),
    not once per frame; a blank frame given so is named as blank (no pins to
    read), as `predict` names it, not as another sensor's."""
    presses = sorted((shared_real / "gelsight-ball/frames").glob("press_*.png"))[:4]
    frames = [tactile.read_rgb(p) for p in presses]
    pose = tactile.PoseEstimator(root / "models/pose-surface")
    cae = tactile.TactipEncoder(root / "models/cae-surface")
    for call in (pose.estimate, cae.encode, cae.estimate):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("default")
            for f in frames:
                call(f)
        said = [str(w.message) for w in seen]
        assert len(said) == 1 and said[0].startswith("frames[0]: pins spaced unlike those of the 8000 frames"), said
        assert "scores above the" in said[0], said
        # Every frame is still unlike: with every warning shown, each is named.
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            for f in frames:
                call(f)
        assert len(seen) == len(frames), [str(w.message) for w in seen]
    surface = tactile.read_grey(shared_real / "tactip331-surface/frames/train_image_1.png")
    blank = np.full_like(surface, 255)
    for call in (pose.estimate, cae.encode):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            call([surface, blank])
        said = [str(w.message) for w in seen]
        assert len(said) == 1 and said[0].startswith("frames[1]: one grey level throughout the crop"), said


def test_a_long_batch_names_each_frame_by_its_place_in_the_call(root, shared_real):
    """A batch longer than a chunk (1,024 frames are preprocessed at a
    time) names a blank, a foreign or a bad frame by its place in the whole
    call, not in its chunk, and estimates every frame as a short batch does."""
    surface = tactile.read_grey(shared_real / "tactip331-surface/frames/train_image_1.png")
    press = tactile.read_grey(shared_real / "gelsight-ball/frames/press_01.png")
    frames = [surface] * 1030
    frames[1025] = np.full_like(surface, 255)
    frames[1027] = press
    pose = tactile.PoseEstimator(root / "models/pose-surface")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        got = pose.estimate(frames)
    said = sorted(str(w.message) for w in seen)
    assert len(said) == 2, said
    assert said[0].startswith("frames[1025]: one grey level throughout the crop"), said
    assert said[1].startswith("frames[1027]: pins spaced unlike those of the 8000 frames"), said
    assert got["depth_mm"].shape == (1030,)
    # The network's batches of other sizes round alike to 1e-5.
    one = pose.estimate(surface)
    for target, values in got.items():
        assert values[1029] == pytest.approx(one[target][0], abs=1e-5), target
    cae = tactile.TactipEncoder(root / "models/cae-surface")
    with pytest.raises(ValueError, match=r"^frames\[1026\]: frame is 8x8, smaller than"), \
            pytest.warns(UserWarning, match=r"^frames\[1026\]: the frame is 8x8, smaller than the model's"):
        cae.encode(frames[:1026] + [np.zeros((8, 8), np.uint8)])


@pytest.mark.parametrize("call", [
    "tactile.PoseEstimator(m / 'pose-surface').estimate(frames)",
    "tactile.TactipEncoder(m / 'cae-surface').encode(frames)",
    "tactile.Pipeline(m).process_many(np.broadcast_to(one[..., None], (99_999, 445, 440, 3)))",
])
def test_ctrl_c_stops_a_long_batch_of_frames(root, call):
    """A batch of 99,999 frames (minutes of work) stops within a second of
    Ctrl-C with KeyboardInterrupt, as the dataset commands do: the work runs
    off the interpreter, which looks for the signal every 100 ms."""
    p = run_python(
        "import numpy as np, pathlib, warnings\n"
        "warnings.simplefilter('ignore')\n"
        f"m = pathlib.Path({str(root / 'models')!r})\n"
        "one = np.random.default_rng(0).integers(0, 256, (445, 440), dtype=np.uint8)\n"
        "frames = np.broadcast_to(one, (99_999, 445, 440))\n"
        f"{call}"
    )
    interrupt_after(p, running_s=4, within_s=3)


def test_a_long_batch_of_copied_frames_is_held_a_chunk_at_a_time(root):
    """Frames not laid out in place (here 40 mirrored 8K views, 1.3 GB once
    copied) are copied and made grey a chunk (256 MB) at a time: the call's
    memory stays under 1 GB where a whole copy and its grey frames are 2.7 GB."""
    r = subprocess.run([sys.executable, "-c", (
        "import numpy as np, resource, tactile, warnings\n"
        "warnings.simplefilter('ignore')\n"
        f"e = tactile.PoseEstimator({str(root / 'models/pose-surface')!r})\n"
        "one = np.random.default_rng(0).integers(0, 256, (4320, 7680), dtype=np.uint8)\n"
        "got = e.estimate(np.broadcast_to(one, (40, 4320, 7680))[:, :, ::-1])\n"
        "assert got['depth_mm'].shape == (40,)\n"
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024)\n"
    )], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert int(r.stdout) < 1024, f"peak {r.stdout.strip()} MB"


def test_encode_dataset_is_tactile_encode_and_leaves_out_a_frame_cut_short(tactile_bin, root, tmp_path):
    """TacTip's dataset pass from Python: the CSV and features of `tactile
    encode`, a frame cut short behind its header left out with its row and
    a UserWarning naming it, and the output checked before any frame is
    read."""
    data = tmp_path / "ds"
    shutil.copytree(root / "samples/virtual-tactip", data)
    ds = tactile.Dataset(data)
    cut = data / ds.labels["file"][3]
    whole = _frames(ds)
    cut.write_bytes(cut.read_bytes()[: len(cut.read_bytes()) // 2])
    enc = tactile.TactipEncoder(root / "models/cae-synth", "burn-flex")
    mine = tmp_path / "py.csv"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = enc.encode_dataset(data, out=mine)
    said = [str(w.message) for w in caught if w.category is UserWarning]
    assert any(f"1 of the {len(ds)} frames could not be decoded" in w and cut.name in w
               for w in said), said
    kept = [i for i in range(len(ds)) if i != 3]
    assert list(got["row"]) == kept
    assert got["file"] == [ds.labels["file"][i] for i in kept]
    assert got["features"].dtype == np.float32
    assert got["features"].shape == (len(kept), enc.feature_count)
    # The same features as the frames encoded one call at a time.
    assert np.array_equal(got["features"], enc.encode(whole[kept]))
    # The same CSV as the command line writes.
    theirs = tmp_path / "cli.csv"
    run_cli(tactile_bin, "encode", "--model", str(root / "models/cae-synth"), "--data",
            str(data), "--out", str(theirs))
    assert mine.read_text() == theirs.read_text()
    # A CSV over the dataset's labels is refused before any frame is read.
    labels = (data / "labels.csv").read_bytes()
    with pytest.raises(ValueError, match="part of the input dataset"):
        enc.encode_dataset(data, out=data / "labels.csv")
    assert (data / "labels.csv").read_bytes() == labels
    with pytest.raises(ValueError, match="not a TacTip dataset"):
        vt = tactile.synth.visuotactile(sequences=1, frames_per_sequence=2, width=160,
                                        height=90, seed=1, out=tmp_path / "vt", progress=False)
        enc.encode_dataset(vt)
