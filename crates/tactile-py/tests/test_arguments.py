"""Keywords: a wrong one is refused naming the keyword (and a number's
range), before any work, on every Python the package supports (PyO3 names
a keyword only in a note, and only from Python 3.11); numpy integers are
whole numbers, bytes are paths, a pair may be a list."""

from __future__ import annotations

import inspect
import os

import numpy as np
import pytest

import tactile
import tactile.synth


def _calls(root, pipeline, palpation_frames, tmp_path):
    """Every whole-number keyword of the package, as one call taking the
    value, with the name its error must start with."""
    data = root / "samples" / "palpation"
    frame = palpation_frames[0]
    result = pipeline.process(frame)
    writer = tactile.McapWriter(tmp_path / "out.mcap")
    view = tactile.LiveView("127.0.0.1:0")
    decoder = tactile.VideoDecoder("h264")
    return writer, view, [
        ("threads", lambda v: tactile.Pipeline(root / "models", threads=v)),
        ("repeats", lambda v: pipeline.time_in_rust(frame, repeats=v)),
        ("threads", lambda v: tactile.run(data, models=root / "models", threads=v)),
        ("pipelines", lambda v: tactile.run(data, models=root / "models", pipelines=v)),
        ("live_queue", lambda v: tactile.run(data, models=root / "models", live_queue=v)),
        ("limit", lambda v: tactile.run(data, models=root / "models", limit=v)),
        ("stdin_size width", lambda v: tactile.run(models=root / "models", stdin_size=(v, 8))),
        ("stdin_size height", lambda v: tactile.frames(stdin_size=(8, v))),
        ("live_queue", lambda v: tactile.frames(data, live_queue=v)),
        ("limit", lambda v: tactile.frames(data, limit=v)),
        ("limit", lambda v: tactile.predict(root / "models" / "pose-surface", data, limit=v)),
        ("stamp_ns", lambda v: writer.write(result, stamp_ns=v)),
        ("stamp_ns", lambda v: view.publish(result, stamp_ns=v)),
        ("stamp_ns", lambda v: decoder.decode(b"", stamp_ns=v)),
        ("count", lambda v: tactile.synth.tactip(v)),
        ("seed", lambda v: tactile.synth.tactip(1, seed=v)),
        ("count", lambda v: tactile.synth.visuotactile(v)),
        ("sequences", lambda v: tactile.synth.visuotactile(sequences=v)),
        ("seed", lambda v: tactile.synth.visuotactile(1, seed=v)),
    ]


def test_a_wrong_whole_number_is_refused_naming_its_keyword(root, pipeline, palpation_frames, tmp_path):
    writer, view, calls = _calls(root, pipeline, palpation_frames, tmp_path)
    with writer, view:
        for name, call in calls:
            # Before, PyO3's "can't convert negative int to unsigned", "int too
            # big to convert" and "'float' object cannot be interpreted as an
            # integer" named no keyword, and synth's seed=2.5 became 2.
            for value, error in [(-(10**30), ValueError), (10**30, ValueError), ("two", TypeError),
                                 (2.5, TypeError), (True, TypeError)]:
                with pytest.raises(error) as e:
                    call(value)
                assert str(e.value).startswith(f"{name}: "), (name, value, str(e.value))
                kind = "expected a whole number, got " if error is TypeError else "must be "
                assert kind in str(e.value), (name, value, str(e.value))
        assert writer.frames == 0
    with pytest.raises(ValueError, match=r"^threads: must be 1 to 256, got -1$"):
        tactile.Pipeline(root / "models", threads=-1)
    with pytest.raises(ValueError, match=r"^seed: must be at least 0, got -1$"):
        tactile.synth.tactip(1, seed=-1)
    with pytest.raises(ValueError, match=r"^limit: must be at most 18446744073709551615, got 10{30}$"):
        tactile.frames(root / "samples" / "palpation", limit=10**30)
    with pytest.raises(ValueError, match=r"^threads: must be 1 to 256, got an integer of thousands of digits$"):
        tactile.Pipeline(root / "models", threads=10**5000)


def test_numpy_integers_are_whole_numbers(root, pipeline, palpation_frames):
    data = root / "samples" / "palpation"
    assert len(list(tactile.frames(data, limit=np.int64(2), live_queue=np.uint8(2)))) == 2
    assert tactile.Pipeline(root / "models", threads=np.int32(1)).threads == 1
    assert len(pipeline.time_in_rust(palpation_frames[0], repeats=np.uint64(2))) == 2
    a, _ = tactile.synth.tactip(np.int16(2), seed=np.uint64(2**64 - 1), progress=False)
    b, _ = tactile.synth.tactip(2, seed=2**64 - 1, progress=False)
    assert a.shape == (2, 300, 300) and np.array_equal(a, b)


def test_signatures_show_the_defaults(pipeline):
    """The keywords' defaults read as numbers in help() and inspect."""
    assert inspect.signature(tactile.Pipeline).parameters["threads"].default == 1
    assert inspect.signature(tactile.run).parameters["pipelines"].default == 1
    assert inspect.signature(tactile.run).parameters["live_queue"].default == 2
    assert inspect.signature(tactile.frames).parameters["live_queue"].default == 2
    assert inspect.signature(pipeline.time_in_rust).parameters["repeats"].default == 100



def test_a_dataset_index_reads_as_a_list_index(root):
    """Negative from the end; past either end, however far, an IndexError;
    not an integer, a TypeError. Before, 10**30 was PyO3's OverflowError."""
    ds = tactile.Dataset(root / "samples" / "virtual-tactip")
    n = len(ds)
    assert np.array_equal(ds[-1]["frame"], ds[n - 1]["frame"])
    assert np.array_equal(ds.frame(np.int64(0)), ds[0]["frame"])
    for i in [n, -n - 1, 10**30, -(10**30)]:
        with pytest.raises(IndexError, match=f"index {i} out of range for a dataset of {n} frames"):
            ds[i]
        with pytest.raises(IndexError):
            ds.frame(i)
    for i in [1.0, "0", None]:
        with pytest.raises(TypeError, match="^dataset indices must be integers or slices, not "):
            ds[i]
    assert len(list(ds)) == n
    # A slice reads as a list's slice: the list of its samples.
    files = [ds[i]["file"] for i in range(n)]
    for s in [slice(None, 3), slice(None, None, 5), slice(-4, None), slice(None, None, -3),
              slice(n + 10, None), slice(-10**30, 10**30, 2)]:
        got = ds[s]
        assert isinstance(got, list) and [x["file"] for x in got] == files[s], s
    assert np.array_equal(ds[2:3][0]["frame"], ds[2]["frame"])
    with pytest.raises(ValueError, match="slice step cannot be zero"):
        ds[::0]


def _path_calls(root):
    """Every path keyword of the package, as one call taking the value,
    with the name its error must start with."""
    m, d = root / "models", root / "samples" / "palpation"
    pose = m / "pose-surface"
    return [
        ("path", lambda v: tactile.Dataset(v)),
        ("video", lambda v: tactile.Dataset.from_video(v, "l.csv", "tactip", "o")),
        ("labels", lambda v: tactile.Dataset.from_video(d, v, "tactip", "o")),
        ("out", lambda v: tactile.Dataset.from_video(d, "l.csv", "tactip", v)),
        ("models", lambda v: tactile.Pipeline(v)),
        ("model_dir", lambda v: tactile.PoseEstimator(v)),
        ("model_dir", lambda v: tactile.TactipEncoder(v)),
        ("estimators[1]", lambda v: tactile.TactipEncoder(m / "cae-synth", estimators=["a", v])),
        ("model_dir", lambda v: tactile.Reconstructor(v)),
        ("background", lambda v: tactile.Reconstructor(m / "gelsight-r15", background=v)),
        ("path", lambda v: tactile.McapWriter(v)),
        ("path", lambda v: tactile.read_rgb(v)),
        ("path", lambda v: tactile.read_grey(v)),
        ("path", lambda v: tactile.bag_topics(v)),
        ("source", lambda v: tactile.frames(v)),
        ("source", lambda v: tactile.run(v)),
        ("models", lambda v: tactile.run(d, models=v)),
        ("out", lambda v: tactile.run(d, out=v)),
        ("render", lambda v: tactile.run(d, render=v)),
        ("model", lambda v: tactile.predict(v, d)),
        ("data", lambda v: tactile.predict(pose, v)),
        ("out", lambda v: tactile.predict(pose, d, v)),
        ("heads[0]", lambda v: tactile.predict(pose, d, heads=[v])),
        ("model", lambda v: tactile.export(v, "x.onnx")),
        ("out", lambda v: tactile.export(pose, v)),
        ("data", lambda v: tactile.train.cae(v, "o")),
        ("out", lambda v: tactile.train.pose(d, v)),
        ("data[1]", lambda v: tactile.train.detector([d, v], "o")),
        ("out", lambda v: tactile.train.segmenter(d, v)),
        ("data", lambda v: tactile.train.depth(v, "o")),
        ("encoder", lambda v: tactile.train.head(d, encoder=v)),
        ("test", lambda v: tactile.train.head(d, encoder=m / "cae-synth", test=v)),
        ("features", lambda v: tactile.train.regressor(d, ["x_mm"], features=v)),
        ("members[1]", lambda v: tactile.train.ensemble([pose, v], "o")),
        ("calibration_from", lambda v: tactile.train.calibrate(pose, calibration_from=v)),
        ("model", lambda v: tactile.eval.detector(v, d)),
        ("data", lambda v: tactile.eval.segmenter(m / "segmenter", v)),
        ("model", lambda v: tactile.eval.depth(v, d)),
        ("estimators[0]", lambda v: tactile.eval.tactip(m / "cae-synth", d, estimators=[v])),
        ("out", lambda v: tactile.synth.tactip(1, out=v)),
        ("out", lambda v: tactile.synth.visuotactile(1, out=v)),
        ("sensor", lambda v: tactile.synth.gelsight(v)),
        ("data", lambda v: tactile.synth.ideal_detector(v)),
        ("data", lambda v: tactile.calibrate.ball(v, "o")),
        ("render", lambda v: tactile.calibrate.reconstruct(m / "gelsight-r15", d, "o", render=v)),
    ]


def _path_list_calls(root):
    """Every keyword taking a list of paths or one alone, as one call."""
    m, d = root / "models", root / "samples" / "palpation"
    pose = m / "pose-surface"
    return [
        ("heads", lambda v: tactile.predict(pose, d, heads=v)),
        ("estimators", lambda v: tactile.TactipEncoder(m / "cae-synth", estimators=v)),
        ("estimators", lambda v: tactile.eval.tactip(m / "cae-synth", d, estimators=v)),
        ("data", lambda v: tactile.train.detector(v, "o")),
        ("members", lambda v: tactile.train.ensemble(v, "o")),
        ("data", lambda v: tactile.train.calibrate(pose, v)),
        ("data", lambda v: tactile.train.profile(pose, v)),
    ]


def test_a_wrong_path_is_refused_naming_its_keyword(root, tmp_path, monkeypatch):
    # Before, PyO3's "expected str, bytes or os.PathLike object, not int"
    # (and os.fspath's, in the Python wrappers) named no keyword.
    monkeypatch.chdir(tmp_path)
    for name, call in _path_calls(root):
        for value in [5, 2.5, np.zeros((4, 4), np.uint8), [1.0]]:
            with pytest.raises(TypeError) as e:
                call(value)
            got = type(value).__name__
            assert str(e.value) == f"{name}: expected a path (str, bytes or os.PathLike), got {got}", (
                name, str(e.value))
    # A list keyword takes one path alone too; its items are named by place.
    for name, call in _path_list_calls(root):
        for value, said in [(5, f"{name}: expected a path or a list of paths, got int"),
                            (2.5, f"{name}: expected a path or a list of paths, got float"),
                            ([1.0], f"{name}[0]: expected a path (str, bytes or os.PathLike), got float"),
                            (np.zeros((4, 4), np.uint8),
                             f"{name}[0]: expected a path (str, bytes or os.PathLike), got ndarray")]:
            with pytest.raises(TypeError) as e:
                call(value)
            assert str(e.value) == said, (name, str(e.value))
    assert list(tmp_path.iterdir()) == [], "a refused call wrote something"


def test_one_path_alone_is_a_list_of_one(root):
    # Before, predict's heads="…" was refused ("Can't extract `str` to
    # `Vec`") and eval.tactip's estimators="…" read letter by letter.
    enc = root / "models" / "cae-synth"
    heads = sorted(p.name for p in enc.iterdir() if (p / "head.json").exists())
    assert heads, "the shipped encoder has a shape head"
    one = tactile.TactipEncoder(enc, estimators=enc / heads[0])
    assert one.estimators == tactile.TactipEncoder(enc, estimators=[enc / heads[0]]).estimators


def test_bytes_and_path_like_objects_are_paths(root):
    frame = root / "samples" / "virtual-tactip" / "frames" / "000000.png"

    class BytesPath(os.PathLike):
        def __fspath__(self):
            return os.fsencode(frame)

    for given in [str(frame), frame, os.fsencode(frame), BytesPath()]:
        assert tactile.read_grey(given).shape == (300, 300), given
    assert len(tactile.Dataset(os.fsencode(root / "samples" / "virtual-tactip"))) == 14


def test_any_other_wrong_keyword_is_refused_naming_it(root, tmp_path, monkeypatch):
    # Strings, flags, numbers and pairs: before, PyO3's "'int' object is not
    # an instance of 'bool'" and the like named no keyword.
    monkeypatch.chdir(tmp_path)
    m, d = root / "models", root / "samples" / "palpation"
    pose = m / "pose-surface"
    calls = [
        ("runtime", TypeError, lambda: tactile.Pipeline(m, runtime=5)),
        ("hysteresis", TypeError, lambda: tactile.Pipeline(m, hysteresis=0.5)),
        ("hysteresis", ValueError, lambda: tactile.Pipeline(m, hysteresis=(0.6, 0.3, 0.1))),
        ("runtime", TypeError, lambda: tactile.run(d, runtime=None)),
        ("hysteresis", ValueError, lambda: tactile.run(d, hysteresis="0.6,0.3")),
        ("with_frames", TypeError, lambda: tactile.run(d, with_frames=1)),
        ("view", TypeError, lambda: tactile.run(d, view=8765)),
        ("view_wait", TypeError, lambda: tactile.run(d, view_wait="5")),
        ("view_wait", OverflowError, lambda: tactile.run(d, view_wait=10**400)),
        ("topic", TypeError, lambda: tactile.run(d, topic=3)),
        ("stdin_size", TypeError, lambda: tactile.run(stdin_size=640)),
        ("prefetch", TypeError, lambda: tactile.run(d, prefetch="yes")),
        ("topic", TypeError, lambda: tactile.frames(d, topic=b"/cam")),
        ("stdin_size", ValueError, lambda: tactile.frames(stdin_size=(640, 360, 3))),
        ("prefetch", TypeError, lambda: tactile.frames(d, prefetch=0)),
        ("topic", TypeError, lambda: tactile.predict(pose, d, topic=1)),
        ("runtime", TypeError, lambda: tactile.predict(pose, d, runtime=1)),
        ("part", TypeError, lambda: tactile.export(pose, "x.onnx", part=3)),
        ("standalone", TypeError, lambda: tactile.export(pose, "x.onnx", standalone=1)),
        ("runtime", TypeError, lambda: tactile.PoseEstimator(pose, runtime=2)),
        ("runtime", TypeError, lambda: tactile.TactipEncoder(m / "cae-synth", runtime=2)),
        ("runtime", TypeError, lambda: tactile.Reconstructor(m / "gelsight-r15", runtime=2)),
        ("kind", TypeError, lambda: tactile.Dataset.from_video(d, "l.csv", 3, "o")),
        ("sensor", TypeError, lambda: tactile.Dataset.from_video(d, "l.csv", "tactip", "o", sensor=1)),
        ("force", TypeError, lambda: tactile.Dataset.from_video(d, "l.csv", "tactip", "o", force="no")),
        ("address", TypeError, lambda: tactile.LiveView(8765)),
        ("format", TypeError, lambda: tactile.VideoDecoder(264)),
        ("name", TypeError, lambda: tactile.VideoDecoder("h264", name=1)),
        ("runtime", TypeError, lambda: tactile.eval.detector(m / "detector", d, runtime=1)),
        ("runtime", TypeError, lambda: tactile.calibrate.reconstruct(m / "gelsight-r15", d, "o", runtime=1)),
        ("split", TypeError, lambda: tactile.train.calibrate(pose, d, split=1)),
        ("force", TypeError, lambda: tactile.synth.tactip(1, out="o", force="yes")),
        ("progress", TypeError, lambda: tactile.synth.tactip(1, progress=None)),
    ]
    for name, error, call in calls:
        with pytest.raises(error) as e:
            call()
        assert str(e.value).startswith(f"{name}: "), (name, str(e.value))
    assert list(tmp_path.iterdir()) == [], "a refused call wrote something"


def test_a_pair_may_be_a_list(root):
    pipe = tactile.Pipeline(root / "models", hysteresis=[0.6, 0.3])
    assert pipe.hysteresis == pytest.approx((0.6, 0.3))


def test_a_result_that_is_not_one_is_refused_naming_it(tmp_path):
    with tactile.McapWriter(tmp_path / "r.mcap") as writer, tactile.LiveView("127.0.0.1:0") as view:
        for call in [writer.write, view.publish]:
            with pytest.raises(TypeError) as e:
                call({"tendon": True})
            assert str(e.value).startswith("result: "), str(e.value)
        assert writer.frames == 0
