"""Training and evaluation from Python: the command line's options and
results, errors as exceptions, and Ctrl-C leaving a folder marked incomplete."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import tactile
from conftest import interrupt, interrupt_after, run_cli, run_python


def copy_relabelled(src, dst, edit):
    """A copy of the dataset `src` at `dst` whose label rows are edited in
    place by `edit(row)`, a dict of the header's columns."""
    shutil.copytree(src, dst)
    lines = (dst / "labels.csv").read_text().splitlines()
    header = lines[0].split(",")
    out = [lines[0]]
    for line in lines[1:]:
        row = dict(zip(header, line.split(",")))
        edit(row)
        out.append(",".join(row[c] for c in header))
    (dst / "labels.csv").write_text("\n".join(out) + "\n")


@pytest.fixture(scope="module")
def small_vt(tmp_path_factory):
    out = tmp_path_factory.mktemp("vt") / "vt"
    return tactile.synth.visuotactile(sequences=4, frames_per_sequence=6, width=320, height=180,
                                      seed=11, out=out, progress=False)


def test_train_then_eval_detector(small_vt, tmp_path):
    out = tmp_path / "det"
    s = tactile.train.detector(small_vt, out, width=0.25, input=(64, 48), max_epochs=2,
                               batch_size=8, seed=1)
    assert s["epochs_run"] == 2 and 0.0 <= s["threshold"] <= 1.0
    assert (out / "detector.json").is_file()
    csv, png = tmp_path / "frames.csv", tmp_path / "reliability.png"
    # Scored on the frames it trained on: said, as a warning.
    with pytest.warns(UserWarning, match="the model trained on every one of these 24 frames"):
        e = tactile.eval.detector(out, small_vt, frames=csv, reliability=png)
    assert e["all"]["frames"] == 24 and 0.0 <= e["all"]["accuracy"] <= 1.0
    assert "so these scores are on frames it fitted" in e["warning"]
    assert set(e) >= {"all", "ungated", "onset_release", "ms_per_frame", "calibration"}
    # The same files `tactile eval detector --frames --reliability` writes.
    rows = csv.read_text().splitlines()
    assert rows[0] == "file,tendon,probability,predicted,onset_release" and len(rows) == 25
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="frame"):
        tactile.eval.detector(out, small_vt, frame=csv)


def test_the_shipped_detector_recipe_trains_from_python_as_from_the_cli(root, small_vt, tmp_path,
                                                                        tactile_bin):
    # Every option of the shipped detector's members, read from their
    # training record; only the size and schedule are made small.
    shipped = json.loads((root / "models/detector/member-0/training.json").read_text())["config"]
    m = shipped["model"]
    recipe = dict(architecture=m["architecture"], input_bits=m["input_bits"],
                  normalise_exposure=m["normalise_exposure"],
                  soft_labels=shipped["soft_labels"]["width"], augment=True,
                  val_fraction=shipped["val_fraction"], lr_decay=shipped["schedule"]["lr_decay"],
                  width=0.25, input=(64, 48), max_epochs=1, batch_size=8, seed=3)
    tactile.train.detector(small_vt, tmp_path / "py", **recipe)
    flags = []
    for k, v in recipe.items():
        if v is True:
            flags.append("--" + k.replace("_", "-"))
        elif k == "input":
            flags += ["--input", f"{v[0]}x{v[1]}"]
        else:
            flags += ["--" + k.replace("_", "-"), str(v)]
    run_cli(tactile_bin, "train", "detector", "--data", str(small_vt), "--out",
            str(tmp_path / "cli"), *flags)
    py = json.loads((tmp_path / "py/training.json").read_text())["config"]
    cli = json.loads((tmp_path / "cli/training.json").read_text())["config"]
    assert py == cli
    assert py["model"]["input_bits"] == 16 and py["model"]["normalise_exposure"] is True
    assert py["augment"] is not None and py["soft_labels"]["width"] == shipped["soft_labels"]["width"]
    # Every option the command line has is a keyword here, listed with its default.
    names = {o["name"] for o in tactile.train.options("detector")}
    assert {"input_bits", "normalise_exposure", "augment", "soft_labels", "max_epochs",
            "device", "resume", "calibrate_only"} <= names
    with pytest.raises(ValueError, match="unknown option 'input_bit'"):
        tactile.train.detector(small_vt, tmp_path / "bad", input_bit=16)
    assert not (tmp_path / "bad").exists()


def test_two_detectors_average_as_one(root, small_vt, tmp_path):
    # The shipped detector's first network and a copy of it whose notes
    # differ: the ensemble's answer is that network's, and members that
    # read frames differently are refused. The same folder twice (or a
    # plain copy) is one model given twice, refused naming it.
    member = root / "models/detector/member-0"
    if not member.is_dir():
        member = root / "models/detector"
    with pytest.raises(ValueError, match="the same model as"):
        tactile.train.ensemble([member, member], tmp_path / "twice")
    assert not (tmp_path / "twice").exists()
    # One model alone is no average, and an ensemble is no member.
    with pytest.raises(ValueError, match="2 to 8 models trained apart, got 1"):
        tactile.train.ensemble([member], tmp_path / "one")
    with pytest.raises(ValueError, match="an ensemble already"):
        tactile.train.ensemble([root / "models/detector", member], tmp_path / "nested")
    assert not (tmp_path / "one").exists() and not (tmp_path / "nested").exists()
    noted = tmp_path / "noted"
    shutil.copytree(member, noted)
    config = json.loads((noted / "detector.json").read_text())
    config["notes"]["copied_for"] = "a test"
    (noted / "detector.json").write_text(json.dumps(config))
    said = tactile.train.ensemble([member, noted], tmp_path / "ens")
    assert said.startswith("2 detectors"), said
    one = tactile.eval.detector(member, small_vt)
    two = tactile.eval.detector(tmp_path / "ens", small_vt)
    assert two["all"] == one["all"]
    small = tmp_path / "det"
    tactile.train.detector(small_vt, small, width=0.25, input=(64, 48), max_epochs=1,
                           batch_size=8, seed=1)
    with pytest.raises(ValueError, match="differ from the first member"):
        tactile.train.ensemble([member, small], tmp_path / "bad")
    assert not (tmp_path / "bad").exists()


def test_training_errors(small_vt, tmp_path):
    with pytest.raises(FileNotFoundError):
        tactile.train.segmenter(tmp_path / "missing", tmp_path / "seg")
    with pytest.raises(ValueError, match="architecture"):
        tactile.train.detector(small_vt, tmp_path / "d", architecture="vgg")
    with pytest.raises(ValueError, match="batch size"):
        tactile.train.detector(small_vt, tmp_path / "d", batch_size=0, max_epochs=1)
    with pytest.raises(ValueError, match="device"):
        tactile.train.depth(small_vt, tmp_path / "dp", device="cuda")
    # Frames of one class: a detector learns nothing from them.
    one = tmp_path / "one-class"
    copy_relabelled(small_vt, one, lambda row: row.update(tendon="0"))
    with pytest.raises(ValueError, match=r"training frames is labelled tendon = 0 \(no tendon\)"):
        tactile.train.detector(one, tmp_path / "d1", input=(64, 48), max_epochs=1)
    assert not (tmp_path / "d1").exists()
    # Sequences of one class each: the validation sequence is of one
    # class, a warning, and the threshold stays at a half.
    apart = tmp_path / "apart"
    copy_relabelled(small_vt, apart,
                    lambda row: row.update(tendon="1" if int(row["sequence"]) < 2 else "0"))
    with pytest.warns(UserWarning, match="the threshold stays at 0.5"):
        s = tactile.train.detector(apart, tmp_path / "d2", input=(64, 48), max_epochs=1,
                                   val_fraction=0.25)
    assert s["threshold"] == 0.5 and len(s["warnings"]) == 1


def test_eval_on_the_wrong_kind_of_model(root, small_vt):
    with pytest.raises(ValueError, match="segmenter"):
        tactile.eval.segmenter(root / "models/detector", small_vt)
    with pytest.raises(ValueError, match=r"not a detector folder.*the folder detector in it is: pass it"):
        tactile.eval.detector(root / "models", small_vt)


def test_ctrl_c_stops_training_and_marks_it_incomplete(small_vt, tmp_path):
    out = tmp_path / "det"
    p = run_python(
        f"tactile.train.detector({str(small_vt)!r}, {str(out)!r}, width=0.25, input=(64, 48),"
        " max_epochs=100000, patience=100000, batch_size=8)"
    )
    deadline = time.time() + 120
    while not (out / "checkpoint").exists():
        assert p.poll() is None, p.stderr.read()
        assert time.time() < deadline, "training never wrote a checkpoint"
        time.sleep(0.2)
    # A second run into the folder while the first trains: refused, as a
    # held lock is (fcntl.flock's BlockingIOError), not mixed in.
    with pytest.raises(BlockingIOError, match="another run is writing this folder"):
        tactile.train.detector(small_vt, out, width=0.25, input=(64, 48), max_epochs=1)
    interrupt(p)
    assert (out / "INCOMPLETE").is_file()
    with pytest.raises(ValueError, match="did not finish training"):
        tactile.eval.detector(out, small_vt)


def test_ctrl_c_stops_a_long_prediction_and_writes_nothing(root, tmp_path, shared_real):
    """`tactile.predict` over the 8,000 real surface frames (half a minute)
    stops within a batch at Ctrl-C: KeyboardInterrupt, no estimates file."""
    data = shared_real / "tactip331-surface"
    if not data.is_dir():
        pytest.skip("the real TacTip surface set is in ../shared/real")
    out = tmp_path / "estimates.csv"
    p = run_python(f"tactile.predict({str(root / 'models/pose-surface')!r}, {str(data)!r}, {str(out)!r})")
    interrupt_after(p, running_s=4, within_s=10)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_stops_a_virtual_set_rendered_in_memory():
    """`tactile.synth.visuotactile` without out= renders through the
    writer's own loop (datasets_synth::render_frames): 600 frames take
    about 13 s on two cores, and Ctrl-C ends them within a frame or two."""
    p = run_python("tactile.synth.visuotactile(count=600, progress=False)")
    interrupt_after(p, running_s=2, within_s=5)


def test_ctrl_c_stops_the_main_threads_work_while_another_thread_runs_batches(root):
    """Ctrl-C stops the main thread's long call even while another thread
    (a ROS callback, a worker) keeps making calls that run off the
    interpreter where Ctrl-C can stop them. Before, every such call cleared
    the stop request as it began and ended, so the main thread's render
    ran on to its end (about 13 s) before `KeyboardInterrupt`."""
    p = run_python(
        "import threading, warnings, numpy as np\n"
        "warnings.simplefilter('ignore')\n"
        f"pipe = tactile.Pipeline({str(root / 'models')!r})\n"
        "frame = np.zeros((180, 320, 3), np.uint8)\n"
        "def batches():\n"
        "    while True:\n"
        "        try:\n"
        "            pipe.time_in_rust(frame, repeats=2)\n"
        "        except Exception:\n"
        "            pass\n"
        "threading.Thread(target=batches, daemon=True).start()\n"
        "tactile.synth.visuotactile(count=600, progress=False)"
    )
    interrupt_after(p, running_s=3, within_s=5)


def test_a_sphere_regressor_and_a_turned_head_from_python(root, tmp_path):
    data = tactile.synth.tactip(count=30, seed=6, out=tmp_path / "ds", progress=False)
    spheres = tactile.synth.tactip(count=20, seed=7, out=tmp_path / "spheres", shapes=["sphere"],
                                   progress=False)
    enc = root / "models/cae-synth"
    out = tmp_path / "position-sphere"
    s = tactile.train.regressor(spheres, ["x_mm", "y_mm"], encoder=enc, out=out,
                                shapes=["sphere"], test_fraction=0.25, loss="l1")
    assert set(s["test_mae"]) == {"x_mm", "y_mm"}
    # Targets given as one string, read as the trainers' list options are
    # (commas separate, spaces trimmed); before, it was read letter by
    # letter: targets 'x', '_', 'm', 'm', ...
    for given, names in [("x_mm", {"x_mm"}), ("x_mm, y_mm", {"x_mm", "y_mm"})]:
        s2 = tactile.train.regressor(spheres, given, encoder=enc, out=tmp_path / given,
                                     shapes=["sphere"], test_fraction=0.25)
        assert set(s2["test_mae"]) == names
    saved = json.loads((out / "regressor.json").read_text())
    assert saved["shapes"] == ["sphere"]
    assert saved["model"]["loss"] == "l1"
    head = tmp_path / "head"
    tactile.train.head(data, encoder=enc, out=head, folds=2, repeats=1, rotate_copies=1,
                       rotate_deg=4.0)
    notes = json.loads((head / "head.json").read_text())["notes"]
    assert notes["rotation_augment"]["copies"] == 1
    with pytest.raises(ValueError, match="rotation augmentation"):
        tactile.train.head(data, encoder=enc, out=tmp_path / "h2", rotate_copies=99)
    # A turn without copies would do nothing: refused, not ignored.
    with pytest.raises(ValueError, match="rotate_deg 4.0 turns the rotated copies, and rotate_copies is 0"):
        tactile.train.head(data, encoder=enc, out=tmp_path / "h2", rotate_deg=4.0)
    assert not (tmp_path / "h2").exists()
    # Tested on its own training frames: refused, and nothing is written.
    with pytest.raises(ValueError, match="30 of its 30 frames are frames the head trains on"):
        tactile.train.head(data, encoder=enc, out=tmp_path / "h3", folds=2, repeats=1, test=data)
    assert not (tmp_path / "h3").exists()
    # Frames of one shape: nothing to tell apart, refused naming the labels.
    with pytest.raises(ValueError, match=r"labels\.csv.*every one of its 20 frames is 'sphere'"):
        tactile.train.head(spheres, encoder=enc, out=tmp_path / "h4", folds=2, repeats=1)
    assert not (tmp_path / "h4").exists()


def test_regressors_of_other_seeds_average_as_one_estimator(root, tmp_path):
    spheres = tactile.synth.tactip(count=20, seed=7, out=tmp_path / "spheres", shapes=["sphere"],
                                   progress=False)
    enc = root / "models/cae-synth"
    members = []
    for seed in (7, 8):
        out = tmp_path / f"seed{seed}"
        tactile.train.regressor(spheres, ["x_mm", "y_mm"], encoder=enc, out=out, seed=seed,
                                test_fraction=0.25)
        members.append(out)
    assert "2 regressors averaged" in tactile.train.ensemble(members, tmp_path / "ens")
    ds = tactile.Dataset(spheres)
    frames = [ds.frame(i) for i in range(len(ds))]
    one = [tactile.TactipEncoder(enc, estimators=[m]).estimate(frames) for m in members]
    both = tactile.TactipEncoder(enc, estimators=[tmp_path / "ens"]).estimate(frames)
    assert set(both) == {"x_mm", "y_mm"}
    for t in both:
        assert abs(both[t] - (one[0][t] + one[1][t]) / 2).max() <= 1e-4, t


def test_an_uncertain_regressor_ensemble_is_calibrated_in_its_encoder(root, tmp_path):
    spheres = tactile.synth.tactip(count=24, seed=7, out=tmp_path / "spheres", shapes=["sphere"],
                                   progress=False)
    # The encoder's folder, copied, to keep the estimator inside it.
    enc = tmp_path / "enc"
    enc.mkdir()
    for f in ("cae.json", "cae.bpk"):
        shutil.copy(root / "models/cae-synth" / f, enc / f)
    members = []
    for seed in (7, 8):
        out = tmp_path / f"seed{seed}"
        tactile.train.regressor(spheres, ["x_mm", "y_mm"], encoder=enc, out=out, seed=seed,
                                test_fraction=0.25, uncertainty=True)
        members.append(out)
    with pytest.raises(ValueError, match="theta_deg is an angle"):
        tactile.train.regressor(spheres, ["theta_deg:180"], encoder=enc, out=tmp_path / "bad",
                                uncertainty=True)
    # Outside an encoder folder a regressor has no features to calibrate on.
    with pytest.raises(ValueError, match="inside the encoder folder"):
        tactile.train.calibrate(members[0], spheres)
    tactile.train.ensemble(members, enc / "position")
    said = tactile.train.calibrate(enc / "position", spheres)
    assert "24 frames" in said and "regressor in" in said, said
    # A quarter of them its members never fitted: no warning. A regressor
    # trained on every frame, calibrated on them, is warned that its
    # factors fit training errors (its notes say what it trained on).
    assert "warning" not in said, said
    tactile.train.regressor(spheres, ["x_mm", "y_mm"], encoder=enc, out=enc / "final",
                            test_fraction=0.0, uncertainty=True)
    notes = json.loads((enc / "final/regressor.json").read_text())["notes"]
    assert notes["excluded_test"] is None and notes["trained_on"].endswith("spheres"), notes
    with pytest.warns(UserWarning, match="these 24 frames are frames it trained on"):
        said = tactile.train.calibrate(enc / "final", spheres)
    assert "24 frames" in said and "regressor in" in said and "warning" not in said, said
    factors = json.loads((enc / "position/ensemble.json").read_text())["notes"]["std_scale"]
    assert len(factors) == 2 and all(f > 0 for f in factors)
    ds = tactile.Dataset(spheres)
    got = tactile.TactipEncoder(enc).estimate([ds.frame(i) for i in range(len(ds))])
    assert set(got) == {"x_mm", "y_mm", "x_mm_std", "y_mm_std"}
    # Calibrated on these frames, ±1 deviation holds 68.3 % of their errors
    # (the 17th smallest of 24 ratios sits on the bound).
    for t in ("x_mm", "y_mm"):
        truth = np.asarray(ds.labels[t], dtype=float)
        inside = (abs(got[t] - truth) <= got[f"{t}_std"] * (1 + 1e-9)).mean()
        assert 0.68 <= inside <= 0.75, (t, inside)


def test_a_cae_trains_jointly_with_pose_heads(root, tmp_path):
    data = root / "samples/virtual-tactip"
    out = tmp_path / "joint"
    s = tactile.train.cae(data, out, preprocess="lighting-compensated", optimizer="adam",
                          linear_latent=True, joint_targets=["depth_mm", "force_n"],
                          joint_weight=10.0, joint_loss="l1", max_epochs=2, patience=2,
                          first_kernel=5, shift=0.05)
    assert (out / "cae.json").is_file()
    record = json.loads((out / "training.json").read_text())
    assert record["config"]["model"]["first_kernel"] == 5
    assert record["config"]["shift"] == 0.05
    assert [t["name"] for t in record["config"]["joint"]["targets"]] == ["depth_mm", "force_n"]
    assert record["config"]["joint"]["loss"] == "l1"
    assert record["summary"]["best_val_metric"] is not None
    # Its features fitted every frame, the test frames of a regressor on
    # it too: its test error is said to be on frames the encoder fitted.
    with pytest.warns(UserWarning, match="the encoder trained on every one of these .* test frames"):
        r = tactile.train.regressor(data, ["depth_mm"], encoder=out, out=tmp_path / "reg",
                                    test_fraction=0.25)
    assert r["frames"]["test"] > 0
    with pytest.raises(ValueError, match="weight"):
        tactile.train.cae(data, tmp_path / "bad", joint_targets=["depth_mm"], joint_weight=0.0)
    assert not (tmp_path / "bad" / "cae.json").exists()
    with pytest.raises(ValueError, match="joint_loss"):
        tactile.train.cae(data, tmp_path / "bad", joint_targets=["depth_mm"], joint_loss="l3")
    with pytest.raises(ValueError, match="joint_hidden set the joint head, and no joint_targets"):
        tactile.train.cae(data, tmp_path / "bad", joint_hidden=8)
    assert not (tmp_path / "bad" / "cae.json").exists()
    with pytest.raises(ValueError, match="augmentation shift"):
        tactile.train.cae(data, tmp_path / "bad", shift=0.5)
    assert not (tmp_path / "bad" / "cae.json").exists()



def test_one_cae_trains_on_two_datasets_each_with_its_own_head(root, tmp_path):
    data = root / "samples/virtual-tactip"
    second = tactile.synth.tactip(count=6, seed=5, out=tmp_path / "second", progress=False)
    tasks = tmp_path / "tasks.json"
    tasks.write_text(json.dumps([{"data": os.fspath(second), "preprocess": "binary",
                                  "joint_targets": ["x_mm"], "shift": 0.05}]))
    out = tmp_path / "both"
    s = tactile.train.cae(data, out, joint_targets=["depth_mm"], joint_loss="l1", max_epochs=1,
                          patience=1, val_fraction=0.5, also_tasks=tasks)
    record = json.loads((out / "training.json").read_text())
    assert record["config"]["also"][0]["joint"]["targets"][0]["name"] == "x_mm"
    notes = json.loads((out / "cae.json").read_text())["notes"]
    assert notes["also_trained_on"] == [os.fspath(second)]
    assert s["train_items"] + s["val_items"] == 6 + len(
        (data / "labels.csv").read_text().splitlines()) - 1
    # Its pin images must be the encoder's side (28 px here, not 56).
    wide = root / "configs/preprocess/tactip127-edge-area-56.json"
    tasks.write_text(json.dumps([{"data": os.fspath(second), "preprocess": os.fspath(wide)}]))
    with pytest.raises(ValueError, match="tasks.json.*56 px"):
        tactile.train.cae(data, tmp_path / "bad", also_tasks=tasks, max_epochs=1)
    assert not (tmp_path / "bad" / "cae.json").exists()

def test_a_segmenter_keeps_its_sensors_rest_frame(root, small_vt, tmp_path):
    # rest= (the CLI's --rest): a frame of the dataset's size is kept as
    # rest.png, the frame directions are read against; another size is
    # refused before training, naming the file, and nothing is written.
    rest = sorted((Path(small_vt) / "frames").glob("*.png"))[0]
    out = tmp_path / "seg"
    s = tactile.train.segmenter(small_vt, out, side=32, max_epochs=1, rest=rest)
    assert s["epochs_run"] == 1
    assert (out / "rest.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert np.array_equal(tactile.read_rgb(out / "rest.png"), tactile.read_rgb(rest))
    other = root / "samples/virtual-tactip/frames/000000.png"
    with pytest.raises(ValueError, match=r"000000\.png.*the rest frame is .* 320x180"):
        tactile.train.segmenter(small_vt, tmp_path / "other", side=32, max_epochs=1, rest=other)
    assert not (tmp_path / "other").exists()


TRAINERS = ["cae", "head", "regressor", "pose", "detector", "segmenter", "depth"]


def test_every_trainer_option_is_a_typed_keyword(small_vt, tmp_path):
    import ast
    from pathlib import Path

    stub = ast.parse(Path(tactile.train.__file__).with_name("train.pyi").read_text())
    defs = {n.name: n for n in stub.body if isinstance(n, ast.FunctionDef)}
    for name in TRAINERS:
        listed = [o["name"] for o in tactile.train.options(name)]
        typed = [a.arg for a in defs[name].args.kwonlyargs]
        assert typed[typed.index("config") + 1:] == listed, name
        assert callable(getattr(tactile.train, name)), name
    with pytest.raises(ValueError, match="no trainer 'vgg'"):
        tactile.train.options("vgg")
    # An unknown keyword is refused by every trainer before any data is read.
    calls = {
        "cae": lambda **k: tactile.train.cae(tmp_path / "none", tmp_path / "o", **k),
        "head": lambda **k: tactile.train.head(tmp_path / "none", encoder=tmp_path, **k),
        "regressor": lambda **k: tactile.train.regressor(tmp_path / "none", ["x_mm"],
                                                         encoder=tmp_path, **k),
        "pose": lambda **k: tactile.train.pose(tmp_path / "none", tmp_path / "o", **k),
        "detector": lambda **k: tactile.train.detector(small_vt, tmp_path / "o", **k),
        "segmenter": lambda **k: tactile.train.segmenter(small_vt, tmp_path / "o", **k),
        "depth": lambda **k: tactile.train.depth(small_vt, tmp_path / "o", **k),
    }
    for name, call in calls.items():
        with pytest.raises(ValueError, match="unknown option 'max_epoch'"):
            call(max_epoch=1)
        if "lr" not in [o["name"] for o in tactile.train.options(name)]:
            continue
        # NaN is named as the option it was given for, not as JSON's parse
        # error; a wrong type is named with its own error.
        with pytest.raises(ValueError, match=r"option 'lr' = nan: not a finite number"):
            call(lr=float("nan"))
        with pytest.raises(ValueError, match=r"option 'max_epochs' = \"one\": invalid type: string \"one\""):
            call(max_epochs="one", patience="many")
    # A list as one string reads as its flag does: commas separate.
    with pytest.raises(ValueError, match=r"option 'widths' = \"16,x\""):
        calls["pose"](targets="x_mm,y_mm", widths="16,x")
    assert not (tmp_path / "o").exists()


def test_a_pose_network_trains_from_python_as_from_the_cli(root, tmp_path, tactile_bin):
    data = root / "samples/virtual-tactip"
    recipe = tmp_path / "recipe.json"
    recipe.write_text(json.dumps({"widths": [8, 8, 8, 8], "hidden": 16, "max_epochs": 5,
                                  "patience": 5}))
    s = tactile.train.pose(data, tmp_path / "py", config=recipe,
                           targets=["depth_mm", "force_n"], max_epochs=1, batch_size=8)
    assert s["epochs_run"] == 1 and s["out"].endswith("py")
    run_cli(tactile_bin, "train", "pose", "--data", str(data), "--out", str(tmp_path / "cli"),
            "--config", str(recipe), "--targets", "depth_mm,force_n", "--max-epochs", "1",
            "--batch-size", "8")
    py = json.loads((tmp_path / "py/training.json").read_text())["config"]
    cli = json.loads((tmp_path / "cli/training.json").read_text())["config"]
    assert py == cli
    assert py["model"]["widths"] == [8, 8, 8, 8] and py["schedule"]["max_epochs"] == 1
    assert py["schedule"]["patience"] == 5, "the file's option, no keyword over it"
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"widht": [8]}))
    with pytest.raises(ValueError, match="bad.json: unknown option 'widht'"):
        tactile.train.pose(data, tmp_path / "bad", config=bad)
    with pytest.raises(FileNotFoundError):
        tactile.train.pose(data, tmp_path / "bad", config=tmp_path / "missing.json")
    assert not (tmp_path / "bad").exists()


def test_a_target_labelled_alike_on_every_frame_is_a_warning(root, tmp_path):
    data = tmp_path / "d"
    # y_mm is 0 on every frame that has one (a flat has none).
    copy_relabelled(root / "samples/virtual-tactip", data,
                    lambda row: row.update(y_mm="0.0000" if row["y_mm"] else ""))
    with pytest.warns(UserWarning, match="y_mm is 0 on every one of the 10 frames this model fits"):
        s = tactile.train.pose(data, tmp_path / "pose", targets=["x_mm", "y_mm"], input_px=32,
                               max_epochs=1)
    assert len(s["warnings"]) == 1 and "never changes" in s["warnings"][0]
    with pytest.warns(UserWarning, match="y_mm is 0 on every one of the"):
        tactile.train.regressor(data, ["x_mm", "y_mm"], encoder=root / "models/cae-synth",
                                out=tmp_path / "reg", only_labelled=True, val_fraction=0.25)


def test_eval_depth_scores_the_shipped_network_and_draws_heat_maps(root, small_vt, tmp_path):
    maps = tmp_path / "maps"
    e = tactile.eval.depth(root / "models/depth", small_vt, save_png=maps, png_frames=2)
    assert e["scores"]["frames"] == 24 and e["heat_maps"] == 2
    assert "warning" not in e  # frames it never trained on
    assert 0.0 <= e["scores"]["mae_mm"] < 1.0 and -1.0 <= e["scores"]["ssim"] <= 1.0
    assert sorted(p.name for p in maps.iterdir()) == ["depth-000.png", "depth-001.png"]
    # A folder that already holds files is left alone.
    with pytest.raises(Exception, match="already holds files"):
        tactile.eval.depth(root / "models/depth", small_vt, save_png=maps, png_frames=2)
    assert len(list(maps.iterdir())) == 2
    # A folder for heat maps and none of them is refused, no folder made.
    with pytest.raises(ValueError, match="png_frames: must be 1 to 10000 heat maps"):
        tactile.eval.depth(root / "models/depth", small_vt, save_png=tmp_path / "none", png_frames=0)
    assert not (tmp_path / "none").exists()
    # A count of heat maps with no folder for them is refused, not ignored.
    with pytest.raises(ValueError, match="png_frames 3: the heat maps save_png writes, and no save_png"):
        tactile.eval.depth(root / "models/depth", small_vt, png_frames=3)


def test_align_saves_the_lattice_as_tactile_train_align_does(root, tmp_path, tactile_bin):
    """tactile.train.align measures an encoder's pin lattice on its frames
    and saves it in the encoder's config, exactly as the command line does;
    a dataset of another kind is refused naming it, the config kept."""
    data = tmp_path / "tt"
    tactile.synth.tactip(16, seed=5, out=data)
    mine, theirs = tmp_path / "py", tmp_path / "cli"
    for copy in (mine, theirs):
        shutil.copytree(root / "models/cae-synth", copy)
        config = json.loads((copy / "cae.json").read_text())
        del config["preprocess"]["align"]
        (copy / "cae.json").write_text(json.dumps(config))
    said = tactile.train.align(mine, [data])
    assert said.startswith("pin lattice at ") and "over 16 frames" in said, said
    run_cli(tactile_bin, "train", "align", "--model", str(theirs), "--data", str(data))
    saved = json.loads((mine / "cae.json").read_text())["preprocess"]["align"]
    assert saved == json.loads((theirs / "cae.json").read_text())["preprocess"]["align"]
    # The virtual TacTip's lattice is upright.
    assert abs(saved["reference_deg"]) < 1.0
    before = (mine / "cae.json").read_bytes()
    vt = tactile.synth.visuotactile(sequences=1, frames_per_sequence=2, width=160, height=90,
                                    seed=1, out=tmp_path / "vt", progress=False)
    with pytest.raises(ValueError, match="vt"):
        tactile.train.align(mine, vt)
    assert (mine / "cae.json").read_bytes() == before
