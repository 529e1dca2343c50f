"""Ball-press calibration from Python: the same options and model folder as
`tactile calibrate ball`, numpy frames reconstructed as the folder
reconstruction writes them, and clear refusals."""

from __future__ import annotations

import csv
import json
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import tactile
from conftest import SHARED_REAL, script, write_png

BALL = SHARED_REAL / "gelsight-ball"
# The shipped detector on 60 frames of scripts/gelsight_independent.py (seed
# 31), where it scores 0.967; on 1,000 of another seed 0.946
# (docs/own-sensor.md).
DETECTOR_ON_ANOTHER_SIMULATOR = 0.8


@pytest.fixture(scope="module")
def presses(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Six of the shared presses in a calibration folder of their own."""
    if not BALL.is_dir():
        pytest.fail(f"the shared ball presses are missing: {BALL}")
    d = tmp_path_factory.mktemp("ball") / "presses"
    (d / "frames").mkdir(parents=True)
    for f in ("sensor.json", "background.png"):
        shutil.copy(BALL / f, d / f)
    with open(BALL / "presses.csv") as src:
        rows = list(csv.reader(src))
    with open(d / "presses.csv", "w", newline="") as dst:
        w = csv.writer(dst)
        w.writerow(rows[0])
        for r in rows[1:7]:
            shutil.copy(BALL / r[0], d / r[0])
            w.writerow(r)
    return d


@pytest.fixture(scope="module")
def model(presses: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("model") / "gelsight"
    r = tactile.calibrate.ball(presses, out, factor=8, val_presses=2, max_epochs=6, kernels=[3, 1, 1])
    assert r["out"] == str(out)
    assert r["train_presses"] == 4 and r["val_presses"] == 2
    assert r["circles"]["presses"] == 6 and r["circles"]["centre_error_px"] < 8
    # The presses with their circles, to look at: a PNG of two lines of
    # thumbnails a third of the frame's size, under their captions.
    assert r["circle_pictures"] == ["circles.png"]
    png = (out / "circles.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert int.from_bytes(png[16:20], "big") == 4 * 213 and int.from_bytes(png[20:24], "big") == 2 * (160 + 22)

    cfg = json.loads((out / "gelsight.json").read_text())
    assert cfg["grid"]["factor"] == 8 and cfg["model"]["kernels"] == [3, 1, 1]
    return out


def test_a_numpy_frame_reconstructs_as_the_folder_does(presses: Path, model: Path, tmp_path: Path):
    frame_file = sorted((presses / "frames").glob("*.png"))[0]
    out = tmp_path / "maps"
    r = tactile.calibrate.reconstruct(model, frame_file, out, runtime="onnx")
    assert r["frames"] == 1
    saved = np.load(out / f"{frame_file.stem}.npy")
    rec = tactile.Reconstructor(model, "onnx")
    assert rec.frame_size == (640, 480)
    got = rec.reconstruct(tactile.read_rgb(frame_file))
    assert got.shape == (480, 640) and got.dtype == np.float32
    np.testing.assert_allclose(got, saved, atol=1e-7)
    # Pushed in where the ball was, at rest on the background.
    assert got.max() > 2e-4
    rest = rec.reconstruct(tactile.read_rgb(presses / "background.png"))
    assert np.abs(rest).max() < 1e-5
    # A folder: its frames in name order, a file that is not one named in a
    # warning and in the result.
    folder = tmp_path / "folder"
    folder.mkdir()
    shutil.copy(frame_file, folder / "0001.png")
    (folder / "notes.txt").write_text("not a frame")
    # macOS's resource fork beside a copied frame: hidden, not a picture.
    (folder / "._0001.png").write_bytes(b"\0\x05\x16\x07resource fork")
    with pytest.warns(UserWarning, match="notes.txt"):
        r = tactile.calibrate.reconstruct(model, folder, tmp_path / "maps2", runtime="onnx")
    assert r["frames"] == 1 and any("notes.txt" in w for w in r["warnings"])
    assert any("hidden" in w and "._0001.png" in w for w in r["warnings"])
    np.testing.assert_allclose(np.load(tmp_path / "maps2" / "0001.npy"), saved, atol=1e-7)


def test_a_folder_without_presses_csv_warns_of_files_that_are_no_presses(presses: Path, tmp_path: Path):
    d = tmp_path / "listed"
    shutil.copytree(presses, d)
    (d / "presses.csv").unlink()
    (d / "frames" / "notes.txt").write_text("pressed at 2 N")
    with pytest.warns(UserWarning, match="notes.txt"):
        r = tactile.calibrate.ball(d, tmp_path / "m", factor=8, val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert r["train_presses"] == 4 and r["val_presses"] == 2
    assert any("notes.txt" in w for w in r["warnings"])


def test_a_gs_sdk_calibration_folder_calibrates_as_it_is(presses: Path, tmp_path: Path):
    """gs_sdk's folder, its labels written by numpy itself (savez as
    label_data.py does, and savez_compressed), with the presses of a second
    ball that the calibration leaves out."""
    d = tmp_path / "gs_sdk"
    d.mkdir()
    shutil.copy(presses / "background.png", d / "background.png")
    (d / "sensor.json").write_text(json.dumps({"mm_per_px": 0.0295, "ball_diameter_mm": 4.0}))
    with open(presses / "presses.csv") as src:
        rows = list(csv.reader(src))[1:]
    catalog = ["experiment_reldir,diameter(mm)"]
    for i, (file, x, y, r) in enumerate(rows):
        press = d / "4.000mm" / str(i)
        press.mkdir(parents=True)
        shutil.copy(presses / file, press / "gelsight.png")
        save = np.savez if i % 2 == 0 else np.savez_compressed
        save(press / "label.npz", center=[float(x), float(y)], radius=int(r))
        catalog.append(f"4.000mm/{i},4.000")
    other = d / "6.000mm" / "0"
    other.mkdir(parents=True)
    shutil.copy(presses / rows[0][0], other / "gelsight.png")
    catalog.append("6.000mm/0,6.000")
    (d / "catalog.csv").write_text("\n".join(catalog) + "\n")
    with pytest.warns(UserWarning, match="other balls are left out"):
        r = tactile.calibrate.ball(d, tmp_path / "m", factor=8, val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert r["train_presses"] == 4 and r["val_presses"] == 2
    # Every label read: the circles found are scored against all six.
    assert r["circles"]["presses"] == 6 and r["circles"]["centre_error_px"] < 8
    # With no ball chosen, every press is fitted with its own ball.
    (d / "sensor.json").write_text(json.dumps({"mm_per_px": 0.0295}))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = tactile.calibrate.ball(d, tmp_path / "m1", factor=8, val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert r["train_presses"] + r["val_presses"] == 7
    (d / "sensor.json").unlink()
    with pytest.raises(ValueError, match="sensor.json: missing.*copy that config here.*ppmm"):
        tactile.calibrate.ball(d, tmp_path / "m2", max_epochs=1)
    # gs_sdk's config copied in gives the scale (and the frames' size it is of).
    config = 'device_name: "GelSight R1.5"\nppmm: 0.0295  # mm per pixel\nimgh: 480\nimgw: 640\nraw_imgh: 2464\nraw_imgw: 3280\n'
    (d / "r15.yaml").write_text(config)
    r = tactile.calibrate.ball(d, tmp_path / "m3", factor=8, val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert r["mm_per_px"] == 0.0295 and r["scale_from"] == "r15.yaml"
    # How gs_sdk cuts the camera's frames to the presses' (its resize_crop).
    assert r["camera"] == {"camera": [3280, 2464], "crop": [2344, 1758, 468, 354], "size": [640, 480]}
    assert r["train_presses"] + r["val_presses"] == 7
    (d / "r15.yaml").write_text(config.replace("480", "240").replace("640", "320"))
    with pytest.raises(ValueError, match="background.png: 640x480, but r15.yaml's ppmm 0.0295 is the scale of frames of 320x240"):
        tactile.calibrate.ball(d, tmp_path / "m4", max_epochs=1)
    assert not (tmp_path / "m4").exists()


def test_a_taxim_data_pack_calibrates_as_it_is(presses: Path, tmp_path: Path):
    """Taxim's dataPack.npz, saved by numpy as its generateDataPack.py saves
    it: the background and presses as OpenCV reads them (BGR), the circles
    as its labelling tool keeps them ([x, y] and a radius), the frames'
    names; the ball and scale, which Taxim keeps in its code, in sensor.json."""
    d = tmp_path / "taxim"
    d.mkdir()
    with open(presses / "presses.csv") as src:
        rows = list(csv.reader(src))[1:]
    bgr = lambda f: tactile.read_rgb(presses / f)[..., ::-1]  # noqa: E731
    f0 = bgr("background.png")
    np.savez(
        d / "dataPack.npz",
        f0=f0,
        imgs=[bgr(file) for file, *_ in rows],
        touch_center=[[float(x), float(y)] for _, x, y, _ in rows],
        touch_radius=[int(r) for *_, r in rows],
        names=[Path(file).name for file, *_ in rows],
        img_size=f0.shape,
    )
    (d / "sensor.json").write_text(json.dumps({"ball_diameter_mm": 4.0, "mm_per_px": 0.0295}))
    r = tactile.calibrate.ball(d, tmp_path / "m", factor=8, val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert r["train_presses"] == 4 and r["val_presses"] == 2
    # Every circle read: the circles found are scored against all six.
    assert r["circles"]["presses"] == 6 and r["circles"]["centre_error_px"] < 8
    assert [v["file"] for v in r["validation"]][0].startswith("dataPack.npz:press_")
    # The model keeps the pack's background, in RGB.
    assert np.array_equal(tactile.read_rgb(tmp_path / "m" / "background.png"), f0[..., ::-1])
    # The pack's presses are reconstructed as a folder of frames is.
    rec = tactile.calibrate.reconstruct(tmp_path / "m", d / "dataPack.npz", tmp_path / "maps")
    assert rec["frames"] == 6
    assert np.load(tmp_path / "maps" / "press_01.npy").shape == (480, 640)
    assert r["working_grid"]["factor"] == 8
    # The pack itself may be given; without a factor, the grid is the
    # scale's: 0.118 mm per working pixel, 4 frame pixels on the R1.5.
    r = tactile.calibrate.ball(d / "dataPack.npz", tmp_path / "m1", val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert r["train_presses"] == 4
    assert r["working_grid"]["factor"] == 4 and abs(r["working_pixel_mm"] - 0.118) < 1e-9
    (d / "sensor.json").unlink()
    with pytest.raises(ValueError, match="sensor.json: missing.*sensorParams.py"):
        tactile.calibrate.ball(d, tmp_path / "m2", max_epochs=1)


def test_a_scale_mistyped_tenfold_is_a_warning(presses: Path, tmp_path: Path):
    d = tmp_path / "tenfold"
    shutil.copytree(presses, d)
    sensor = json.loads((d / "sensor.json").read_text())
    sensor["mm_per_px"] = 0.00295
    (d / "sensor.json").write_text(json.dumps(sensor))
    with pytest.warns(UserWarning, match="its render model barely explains them"):
        r = tactile.calibrate.ball(d, tmp_path / "m", factor=8, val_presses=2, max_epochs=1, kernels=[3, 1, 1])
    assert any("0.00295 mm per pixel" in w and "check ball_diameter_mm and mm_per_px" in w
               for w in r["warnings"])


def test_refusals_name_the_problem(presses: Path, model: Path, tmp_path: Path):
    rec = tactile.Reconstructor(model, "burn-flex")
    with pytest.raises(ValueError, match=r"frame.*\(320, 240\).*\(640, 480\)"):
        rec.reconstruct(np.zeros((240, 320, 3), np.uint8))
    with pytest.raises(TypeError, match="uint8"):
        rec.reconstruct(np.zeros((480, 640, 3), np.float32))
    # A frame saved grey, of a sensor calibrated in colour: its colours are
    # what the slopes are read from, so it is refused, not read as a dent.
    rest = tactile.read_rgb(presses / "background.png")
    grey = rest.mean(axis=2).astype(np.uint8)
    with pytest.raises(ValueError, match="greyscale frame.*calibrated on colour"):
        rec.reconstruct(np.repeat(grey[:, :, None], 3, axis=2))
    # A frame in BGR order (as OpenCV's imread gives it) is named, not read
    # as a skin mirrored.
    press = tactile.read_rgb(sorted((presses / "frames").glob("*.png"))[0])
    with pytest.raises(ValueError, match=r"frame: red and blue look swapped \(BGR order.*frame\[\.\.\., ::-1\]"):
        rec.reconstruct(press[..., ::-1])
    # A blank frame (a covered lens, the light off) is named as such, not as
    # grey or another sensor's colour.
    for level in [(0, 0, 0), (255, 255, 255), (40, 200, 90)]:
        with pytest.raises(ValueError, match=r"a blank frame \(every pixel of one colour, RGB \(%d, %d, %d\)\)" % level):
            rec.reconstruct(np.full((480, 640, 3), level, np.uint8))
    with pytest.raises(ValueError, match="colour_jitter"):
        tactile.calibrate.ball(presses, tmp_path / "m", colour_jitter=0.9)
    with pytest.raises(ValueError, match="no_such_option"):
        tactile.calibrate.ball(presses, tmp_path / "m", no_such_option=1)
    assert not (tmp_path / "m").exists()
    # An output folder that already holds files is left alone.
    taken = tmp_path / "taken"
    taken.mkdir()
    (taken / "keep.txt").write_text("mine")
    with pytest.raises(Exception, match="already holds files"):
        tactile.calibrate.reconstruct(model, presses / "frames", taken)
    assert (taken / "keep.txt").read_text() == "mine"
    # Frames it cannot read after good ones are found before any frame is
    # reconstructed: counted, the first named, nothing written.
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    shutil.copy(sorted((presses / "frames").glob("*.png"))[0], mixed / "a.png")
    write_png(mixed / "y.png", np.zeros((240, 320, 3), np.uint8))
    write_png(mixed / "z.png", np.zeros((240, 320, 3), np.uint8))
    (mixed / "zz.png").write_bytes(b"")  # an empty file is counted with them
    with pytest.raises(ValueError, match=r"y\.png: frame is \(320, 240\).*; 3 of the 4 frames cannot be read by this sensor"):
        tactile.calibrate.reconstruct(model, mixed, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    # A press cut short behind a whole header is found when decoded:
    # skipped with a warning naming it, the other maps written.
    for f in ("y.png", "z.png", "zz.png"):
        (mixed / f).unlink()
    whole = (mixed / "a.png").read_bytes()
    (mixed / "b.png").write_bytes(whole[: len(whole) // 2])
    with pytest.warns(UserWarning, match=r"1 of the 2 frames could not be decoded.*b\.png: cannot decode"):
        r = tactile.calibrate.reconstruct(model, mixed, tmp_path / "out")
    assert r["frames"] == 1 and r["undecodable_frames"] == 1
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["a.npy"]


def test_the_pipeline_on_a_calibrated_sensor_gives_its_indentation(presses: Path, model: Path, tmp_path: Path):
    frame = tactile.read_rgb(sorted((presses / "frames").glob("*.png"))[0])
    pipe = tactile.Pipeline(model, "onnx")
    assert pipe.calibrated and pipe.threshold is None
    r = pipe.process(frame)
    # The same map as the reconstructor's, with its summary in the record.
    want = tactile.Reconstructor(model, "onnx").reconstruct(frame)
    np.testing.assert_allclose(r.indentation_m, want, atol=1e-7)
    assert r.indentation_peak_mm == pytest.approx(want.max() * 1e3, rel=1e-5)
    assert r.contact_area_mm2 > 1.0
    assert not r.tendon and r.depth_m is None and "reconstruct" in r.ms
    d = r.to_dict()
    assert d["indentation_peak_mm"] == pytest.approx(r.indentation_peak_mm)
    # Rest is flat, and a frame the sensor cannot read (another size, grey
    # for this colour sensor) is another sensor's or camera mode's: it gets
    # nothing, says why, and does not stop a sequence.
    rest = pipe.process(tactile.read_rgb(presses / "background.png"))
    assert rest.contact_area_mm2 == 0.0 and rest.unreadable is None
    small = pipe.process(np.zeros((240, 320, 3), np.uint8))
    assert small.out_of_distribution and small.indentation_peak_mm is None
    assert small.indentation_m is None and not small.tendon
    assert "(320, 240)" in small.unreadable and "(640, 480)" in small.unreadable
    grey = pipe.process(np.repeat(frame.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2))
    assert grey.out_of_distribution and grey.indentation_peak_mm is None
    assert "greyscale frame" in grey.unreadable and grey.to_dict()["unreadable"] == grey.unreadable
    assert "unreadable" not in rest.to_dict()
    bgr = pipe.process(frame[..., ::-1])
    assert bgr.out_of_distribution and bgr.indentation_m is None
    assert "red and blue look swapped" in bgr.unreadable, bgr.unreadable
    black = pipe.process(np.zeros((480, 640, 3), np.uint8))
    assert black.out_of_distribution and black.indentation_m is None
    assert "a blank frame" in black.unreadable, black.unreadable
    with pytest.raises(ValueError, match="no detector"):
        pipe.detector_frame(frame)
    # A whole run of the sensor alone: every press in contact, and no frame
    # said to be gated out by a detector it does not have.
    # (the six presses are numbered 1, 2, 4, 5, 7: the gaps are said)
    with pytest.warns(UserWarning, match=r"2 frame\(s\) missing from the numbering"):
        summary = tactile.run(presses / "frames", models=model)
    assert not summary["palpation"] and summary["frames"] == 6
    assert summary["contact"]["frames_in_contact"] == 6
    assert summary["gated_out"] == 0 and summary["tendon_frames"] == 0
    assert "unreadable" not in summary and summary["out_of_distribution"] == 0
    # A run over a folder with frames the sensor cannot read goes on past
    # them and names the first in a warning.
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    for f in sorted((presses / "frames").glob("*.png"))[:2]:
        shutil.copy(f, mixed / f.name)
    write_png(mixed / "zz-small.png", np.zeros((240, 320, 3), np.uint8))
    write_png(mixed / "zzz-grey.png", np.full((480, 640, 3), 90, np.uint8))
    with pytest.warns(UserWarning, match=r"^2 of 4 frames cannot be read by this calibrated sensor .*they got no indentation\. The first: zz-small\.png: .*\(320, 240\)"):
        summary = tactile.run(mixed, models=model)
    assert summary["frames"] == 4 and summary["out_of_distribution"] == 2
    assert summary["contact"]["frames_in_contact"] == 2
    assert summary["unreadable"]["frames"] == 2
    assert summary["unreadable"]["first"].startswith("zz-small.png: frame is (320, 240)")


def test_the_calibrated_sensor_renders_its_own_labelled_frames(model: Path, tmp_path: Path):
    # The calibration wrote a render model beside the sensor model.
    assert (model / "optics.json").is_file()
    d = tactile.synth.gelsight(model, count=6, seed=9, frames_per_sequence=3, tendon_share=1.0)
    assert d["frames"].shape == (6, 480, 640, 3) and d["frames"].dtype == np.uint8
    assert d["indentation_m"].shape == (6, 480, 640) and d["indentation_m"].dtype == np.float32
    pushed = d["indentation_m"] > 0.03e-3
    for i in range(6):
        # The mask is where the tendon pushes the skin in past 0.03 mm.
        np.testing.assert_array_equal(d["masks"][i], pushed[i])
        assert d["tendon"][i] == pushed[i].any()
        assert np.isnan(d["direction_deg"][i]) != bool(d["tendon"][i])
    # The same frames as the dataset the same call writes.
    out = tactile.synth.gelsight(model, count=6, seed=9, out=tmp_path / "set", frames_per_sequence=3, tendon_share=1.0)
    ds = tactile.Dataset(out)
    assert len(ds) == 6 and ds.width == 640 and ds.height == 480
    np.testing.assert_array_equal(tactile.read_rgb(out / "frames" / "000004.png"), d["frames"][4])
    with pytest.raises(ValueError, match="press_mm"):
        tactile.synth.gelsight(model, count=2, press_mm=(1.0, 0.5))
    with pytest.raises(Exception, match="render model"):
        tactile.synth.gelsight(tmp_path, count=2)


def test_plates_only_clip_the_frame_and_punch_rims_sharpen_when_asked(model: Path):
    """plate_edge_reach and punch_fillet reach the renderer from Python as
    --plate-edge-reach and --punch-fillet do from the command line."""
    plates = dict(count=12, seed=4, frames_per_sequence=1, tendon_share=0.0, sphere_share=0.0, punch_share=0.0,
                  nothing_share=0.0, flat_share=1.0, object_press_mm=(0.5, 1.0), progress=False)

    def pushed(**kw):
        ind = tactile.synth.gelsight(model, **plates, **kw)["indentation_m"] > 0.03e-3
        h, w = ind.shape[1:]
        return ind[:, h // 2, w // 2], ind.mean(axis=(1, 2))

    # By default every plate covers the frame's centre.
    centre, covering = pushed()
    assert centre.all(), covering
    # Its edge well past the centre (the gel's spread carries the push a
    # little beyond it): the plate only clips the frame, in a band smaller
    # than any plate that covers the centre.
    centre, clipping = pushed(plate_edge_reach=(0.5, 0.75))
    assert not centre.any() and (clipping > 0).all(), clipping
    assert clipping.max() < covering.min(), (clipping, covering)
    # A sharper punch rim pushes a wider flat: more of the frame at the same press.
    punches = {**plates, "flat_share": 0.0, "punch_share": 1.0}
    areas = [
        (tactile.synth.gelsight(model, **punches, punch_fillet=f)["indentation_m"] > 0.03e-3).mean()
        for f in [(0.05, 0.05), (0.9, 0.9)]
    ]
    assert areas[0] > areas[1], areas
    for bad, key in [({"plate_edge_reach": (0.5, -0.5)}, "plate_edge_reach"),
                     ({"plate_edge_reach": (-2.0, 0.5)}, "plate_edge_reach"),
                     ({"punch_fillet": (0.0, 0.5)}, "punch_fillet")]:
        with pytest.raises(ValueError, match=key):
            tactile.synth.gelsight(model, count=2, **bad)


def test_real_presses_join_the_rendered_set_as_negatives(model: Path, presses: Path, tmp_path: Path):
    out = tactile.synth.gelsight(model, count=4, seed=3, frames_per_sequence=2, out=tmp_path / "set",
                                 real_presses=presses, real_copies=2, real_held_out=2)
    ds = tactile.Dataset(out)
    # Four of the six presses, two copies each, after the four renders.
    assert len(ds) == 4 + 8
    real = json.loads((out / "manifest.json").read_text())["real_frames"]
    assert len(real["used"]) == 4 and len(real["held_out"]) == 2
    for i in range(4, 12):
        assert ds.depth_m(i).max() > 0  # the calibration's reconstruction of the press
        assert not ds.mask(i).any()
    # Real frames need a folder to go to.
    with pytest.raises(ValueError, match="out="):
        tactile.synth.gelsight(model, count=2, real_presses=presses)


def test_the_shipped_gelsight_pipeline_sees_no_tendon_on_real_presses(root: Path):
    models = root / "models" / "gelsight-r15"
    pipe = tactile.Pipeline(models, "onnx")
    assert pipe.calibrated and pipe.threshold is not None
    for f in sorted((BALL / "frames").glob("*.png"))[:6]:
        r = pipe.process(tactile.read_rgb(f))
        # A ball is no tendon; the frame is the sensor's own; the skin is
        # pushed in by the ball.
        assert not r.tendon and not r.out_of_distribution, f
        assert r.indentation_peak_mm > 0.5
    # A frame of another sensor's size is foreign, not an error.
    r = pipe.process(np.full((360, 640, 3), 128, np.uint8))
    assert r.out_of_distribution and not r.tendon


def tactip_on_the_canvas(shift: int = 0) -> np.ndarray:
    """A 331-pin TacTip frame laid on the GelSight's 640x480 canvas, tinted:
    another sensor's frame at this sensor's size and in colour."""
    t = tactile.read_grey(SHARED_REAL / "tactip331-surface/frames/train_image_1.png").astype(np.float32)
    canvas = np.full((480, 640, 3), 30, np.uint8)
    h, w = min(t.shape[0], 480), min(t.shape[1], 640 - shift)
    for c, gain in enumerate((1.0, 0.9, 0.8)):
        canvas[:h, shift:shift + w, c] = (t[:h, :w] * gain).astype(np.uint8)
    return canvas


def test_a_calibrated_sensor_names_frames_of_another_sensor(root: Path, tmp_path: Path):
    """The detector beside the shipped calibration knows this sensor's frames:
    `Reconstructor.reconstruct` and `tactile.calibrate.reconstruct` still
    reconstruct a frame of another sensor but name it in a `UserWarning`,
    once per call site in a loop; the pipeline gives it no indentation."""
    models = root / "models" / "gelsight-r15"
    press = tactile.read_rgb(sorted((BALL / "frames").glob("*.png"))[0])
    rec = tactile.Reconstructor(models, "onnx")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert rec.reconstruct(press).shape == (480, 640)
    assert not seen, [str(w.message) for w in seen]
    others = [tactip_on_the_canvas(shift) for shift in (0, 60, 120)]
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("default")
        for f in others:
            assert rec.reconstruct(f).shape == (480, 640)
    said = [str(w.message) for w in seen]
    assert len(said) == 1 and said[0].startswith("frame: colours unlike this sensor's"), said
    frames = tmp_path / "frames"
    frames.mkdir()
    shutil.copy(sorted((BALL / "frames").glob("*.png"))[0], frames / "a.png")
    write_png(frames / "b.png", others[0])
    with pytest.warns(UserWarning, match=r"b\.png: colours unlike this sensor's") as seen:
        r = tactile.calibrate.reconstruct(models, frames, tmp_path / "out")
    assert r["frames"] == 2 and (tmp_path / "out" / "b.npy").is_file()
    assert not any("a.png" in str(w.message) for w in seen)
    pipe = tactile.Pipeline(models, "onnx")
    r = pipe.process(others[0])
    assert r.out_of_distribution and r.indentation_peak_mm is None


def test_a_calibration_alone_names_frames_of_another_sensor_by_its_rest_frame(
    presses: Path, model: Path, tmp_path: Path
):
    """Without a detector beside it (`calibrate ball`'s folder before `train
    detector`), the calibration compares each frame with its rest frame: a
    press changes colour only where it touches, another sensor's frame
    everywhere. The presses, and the rest frame itself darker (another
    exposure), pass; the other sensor's frame is named."""
    rec = tactile.Reconstructor(model, "onnx")
    rest = tactile.read_rgb(presses / "background.png")
    darker = (rest.astype(np.float32) * 0.85).astype(np.uint8)
    own = [tactile.read_rgb(f) for f in sorted((presses / "frames").glob("*.png"))] + [darker]
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        for f in own:
            rec.reconstruct(f)
    assert not seen, [str(w.message) for w in seen]
    with pytest.warns(UserWarning, match=r"^frame: half of the picture or more changed colour from this sensor's rest frame, where"):
        rec.reconstruct(tactip_on_the_canvas())
    frames = tmp_path / "frames"
    frames.mkdir()
    write_png(frames / "a.png", own[0])
    write_png(frames / "b.png", tactip_on_the_canvas())
    with pytest.warns(UserWarning, match=r"b\.png: half of the picture or more changed colour from this sensor's rest frame by 0\.\d\d,") as seen:
        r = tactile.calibrate.reconstruct(model, frames, tmp_path / "out")
    assert r["frames"] == 2 and not any("a.png" in str(w.message) for w in seen)
    # The pipeline on the calibration alone gives that frame no indentation.
    pipe = tactile.Pipeline(model, "onnx")
    assert pipe.process(own[0]).indentation_peak_mm > 0
    r = pipe.process(tactip_on_the_canvas())
    assert r.out_of_distribution and r.indentation_peak_mm is None
    # While its detector is being trained (its folder there, the segmenter
    # and depth network not yet), the pipeline runs the calibration alone
    # and says why; before, it refused to load.
    training = tmp_path / "training"
    shutil.copytree(model, training)
    (training / "detector").mkdir()
    with pytest.warns(UserWarning, match=r"depth model folder does not exist: the palpation models beside this calibration cannot all be read \(still being trained\?\), so the calibration runs alone"):
        pipe = tactile.Pipeline(training, "onnx")
    assert pipe.calibrated and pipe.threshold is None
    assert pipe.process(own[0]).indentation_peak_mm > 0
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        summary = tactile.run(frames, models=training)
    said = [str(w.message) for w in seen]
    assert summary["frames"] == 2 and summary["out_of_distribution"] == 1
    assert len(said) == 2 and "runs alone" in said[0], said
    assert said[1].startswith("1 of 2 frames do not look like this sensor's (colours changed over half the picture from its rest frame)"), said


def test_a_depth_network_learns_a_correction_to_its_calibration(model: Path, tmp_path: Path):
    data = tactile.synth.gelsight(model, count=8, seed=5, frames_per_sequence=4, tendon_share=1.0,
                                  out=tmp_path / "set")
    sensor = tmp_path / "sensor"
    shutil.copytree(model, sensor)
    tactile.train.depth(data, sensor / "depth", encoder="tiny", input=(64, 32), decoder_width=16,
                        max_epochs=1, val_fraction=0.5, prior_calibration=str(sensor), augment=True)
    art = json.loads((sensor / "depth" / "depth.json").read_text())
    # Its frames' colours were augmented, its prior left as reconstructed.
    record = json.loads((sensor / "depth" / "training.json").read_text())
    assert record["config"]["augment"]["exposure"] > 0, record["config"]
    # The reconstruction is its fourth channel, found beside it.
    assert art["prior"] == {"calibration": ".."} and art["model"]["in_channels"] == 4
    assert art["model"]["residual_channel"] == 3
    # Scored on the 8 frames it trained on: said, and kept in the result.
    with pytest.warns(UserWarning, match="the model trained on every one of these 8 frames"):
        e = tactile.eval.depth(sensor / "depth", data)
    assert e["scores"]["frames"] == 8 and np.isfinite(e["scores"]["mae_mm"])
    assert "so these scores are on frames it fitted" in e["warning"]
    with pytest.raises(ValueError, match="not both"):
        tactile.train.depth(data, tmp_path / "x", prior_calibration=str(sensor), with_mask=True)
    assert not (tmp_path / "x").exists()
    # A second run (another seed) and the two averaged as one network in
    # the sensor's folder: the mean map errs by no more than the members'
    # mean error (the triangle inequality), so a mean in the wrong units fails.
    tactile.train.depth(data, tmp_path / "second", encoder="tiny", input=(64, 32), decoder_width=16,
                        max_epochs=1, val_fraction=0.5, prior_calibration=str(sensor), seed=7)
    said = tactile.train.ensemble([sensor / "depth", tmp_path / "second"], sensor / "depth-mean")
    assert said.startswith("2 depth networks averaged in"), said
    member = json.loads((sensor / "depth-mean" / "member-1" / "depth.json").read_text())
    assert member["prior"] == {"calibration": "../.."}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        mae = [tactile.eval.depth(m, data)["scores"]["mae_mm"]
               for m in (sensor / "depth", tmp_path / "second", sensor / "depth-mean")]
    assert mae[0] != mae[1] and mae[2] <= (mae[0] + mae[1]) / 2 + 1e-6, mae
    # A prior of another sensor than the frames were rendered from: said.
    other = tmp_path / "other"
    shutil.copytree(model, other)
    optics = json.loads((other / "optics.json").read_text())
    optics["sensor"] = "another unit"
    (other / "optics.json").write_text(json.dumps(optics))
    with pytest.warns(UserWarning, match="the prior is the calibration of \"another unit\""):
        r = tactile.train.depth(data, tmp_path / "d-other", encoder="tiny", input=(64, 32),
                                decoder_width=16, max_epochs=1, val_fraction=0.5,
                                prior_calibration=str(other))
    assert len(r["warnings"]) == 1


def test_the_own_sensor_pipeline_reads_another_simulators_renders(root: Path, tmp_path: Path):
    """Issue 33's checks render the sensor with a simulator of their own.
    scripts/gelsight_independent.py is one (numpy and Pillow, Taxim's
    recipe, fitted on the same ball presses): its frames are this sensor's
    to the detector's input profile (none flagged), the detector tells
    tendons from plate edges, punches and spheres at every press, and the
    segmenter points the tendons it finds (docs/own-sensor.md, "On renders
    of other simulators")."""
    independent = script("gelsight_independent")
    out = tmp_path / "independent"
    independent.main(str(out), 12, 31, str(BALL))
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["depth"] == "indentation" and manifest["count"] == 60
    models = root / "models" / "gelsight-r15"
    det = tactile.eval.detector(models / "detector", out)
    assert det["gated_foreign"] == 0, det
    assert det["all"]["accuracy"] >= DETECTOR_ON_ANOTHER_SIMULATOR, det["all"]
    seg = tactile.eval.segmenter(models / "segmenter", out)
    everything = seg["paths"][0]
    assert everything["path"] == "all" and everything["frames"] >= 15, everything
    assert everything["direction"]["median_deg"] <= 3.0, everything


def test_the_other_simulator_names_what_it_cannot_read(tmp_path: Path):
    """scripts/gelsight_independent.py on a calibration folder it cannot
    read names the file and line, and writes nothing."""
    independent = script("gelsight_independent")
    ball = tmp_path / "ball"
    (ball / "frames").mkdir(parents=True)
    shutil.copy(BALL / "background.png", ball / "background.png")
    with open(BALL / "presses.csv") as f:
        rows = list(csv.reader(f))
    for r in rows[1:3]:
        shutil.copy(BALL / r[0], ball / r[0])
    meta = json.loads((BALL / "sensor.json").read_text())
    cases = [
        ({**meta, "mm_per_px": "thin"}, rows[:3], r"sensor\.json: 'mm_per_px' must be a number, got 'thin'"),
        ({**meta, "ball_diameter_mm": -4}, rows[:3], r"sensor\.json: 'ball_diameter_mm' must be above 0"),
        (meta, rows[:2] + [[rows[2][0], "", "", ""]], r"presses\.csv:3: needs file, centre_x_px"),
    ]
    for i, (m, lines, said) in enumerate(cases):
        (ball / "sensor.json").write_text(json.dumps(m))
        with open(ball / "presses.csv", "w", newline="") as f:
            csv.writer(f).writerows(lines)
        out = tmp_path / f"out{i}"
        with pytest.raises(ValueError, match=said):
            independent.main(str(out), 1, 1, str(ball))
        assert not out.exists() and not list(tmp_path.glob(".gelsight-independent-*")), i
