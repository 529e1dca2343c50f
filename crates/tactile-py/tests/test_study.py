"""tactile.study: paper A's studies from Python give the numbers the
command line writes, with their pages, and refuse bad options before any
work."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

import tactile

from conftest import run_cli


@pytest.fixture(scope="module")
def tactip_set(tmp_path_factory) -> Path:
    """60 virtual TacTip frames: 38 train, 10 validation, 12 test."""
    out = tmp_path_factory.mktemp("study") / "ds"
    tactile.synth.tactip(60, seed=3, out=out)
    return out


def _without_seconds(rows):
    return [{k: v for k, v in r.items() if k != "seconds"} for r in rows]


def test_compare_gives_the_rows_and_page_of_tactile_compare(root, tactip_set, tmp_path, tactile_bin):
    encoder = root / "models/cae-synth"
    page = tmp_path / "compare.md"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = tactile.study.compare(
            encoder, tactip_set, targets=["depth_mm", "force_n"], classify="shape", out=page
        )
    # 38 training frames: PCA-64 is left out and said; the other four
    # feature sets get three estimators each, for each task.
    left_out = "PCA-64 is left out: PCA with 64 components needs at least 64 training frames, got 38."
    assert r["warnings"] == [left_out]
    assert [str(w.message) for w in caught if w.category is UserWarning] == [left_out]
    assert len(r["regression"]) == 12 and len(r["classification"]) == 12
    assert [row["features"] for row in r["regression"][::3]] == [
        "CAE-16",
        "PCA-16",
        "raw 28x28",
        "pin tracking (127 pins)",
    ]
    for row in r["regression"]:
        assert [name for name, _ in row["values"]] == ["depth_mm", "force_n"]
        # The page prints the same numbers.
        cells = " | ".join(f"{mae:.3f}" for _, mae in row["values"])
        assert f"| {row['features']} | {row['estimator']} | {cells} |" in r["markdown"]
    for row in r["classification"]:
        (name, accuracy), = row["values"]
        assert name == "accuracy" and 0.0 <= accuracy <= 1.0
        assert f"| {row['features']} | {row['estimator']} | {100 * accuracy:.1f} % |" in r["markdown"]
    # Better than guessing: depth is uniform on 0-5 mm (the mean errs by
    # 1.25 mm); 7 shapes (chance 14 %).
    assert min(row["values"][0][1] for row in r["regression"]) < 1.0
    assert max(row["values"][0][1] for row in r["classification"]) > 2 / 7
    # out= writes the page and its rows beside it, as --out does.
    assert page.read_text() == r["markdown"]
    beside = json.loads(page.with_suffix(".json").read_text())
    assert beside == {k: v for k, v in r.items() if k != "markdown"}
    # The command line on the same split and seed: the same numbers.
    cli_page = tmp_path / "cli.md"
    run_cli(
        tactile_bin,
        "compare",
        "--encoder",
        str(encoder),
        "--data",
        str(tactip_set),
        "--targets",
        "depth_mm,force_n",
        "--classify",
        "shape",
        "--out",
        str(cli_page),
    )
    cli = json.loads(cli_page.with_suffix(".json").read_text())
    for task in ("regression", "classification"):
        assert _without_seconds(cli[task]) == _without_seconds(r[task])


def test_sweep_and_robustness_give_their_rows(root, tactip_set, tmp_path):
    encoder = root / "models/cae-synth"
    s = tactile.study.sweep(encoder, tactip_set, runs=2, out=tmp_path / "sweep.md")
    (row,) = s["rows"]
    assert row["name"] == "cae-synth" and row["features"] == 16
    assert 0.0 < row["bce"] < 1.0 and 2 / 7 < row["accuracy"] <= 1.0
    assert {runtime for runtime, _, _ in row["speed"]} >= {"burn flex"}
    assert all(ms > 0 and fps > 0 for _, ms, fps in row["speed"])
    assert (tmp_path / "sweep.md").read_text() == s["markdown"]
    assert json.loads((tmp_path / "sweep.json").read_text()) == s["rows"]
    assert (tmp_path / "sweep-features.png").is_file()

    # Estimators named as paths in a list, as pathlib gives them.
    heads = [encoder / "head", encoder / "regressor"]
    r = tactile.study.robustness(encoder, tactip_set, heads=heads, limit=12,
                                 out=tmp_path / "robust.md")
    conditions = [row["condition"] for row in r["rows"]]
    # Clean, then four perturbations at three strengths each.
    assert conditions[0] == "clean" and len(conditions) == 13
    names = [name for name, _ in r["rows"][0]["values"]]
    assert names[0] == "shape accuracy" and "depth_mm MAE" in names
    assert "with 2 estimator(s)" in r["markdown"]
    for row in r["rows"]:
        assert [name for name, _ in row["values"]] == names
        assert f"| {row['condition']} |" in r["markdown"]
    assert (tmp_path / "robust.png").is_file()
    assert json.loads((tmp_path / "robust.json").read_text()) == r["rows"]


def test_study_options_are_refused_before_any_work(root, tactip_set):
    encoder = root / "models/cae-synth"
    with pytest.raises(ValueError, match="give regression targets"):
        tactile.study.compare(encoder, tactip_set)
    with pytest.raises(ValueError, match="unknown option 'target'.*known: classify, hidden"):
        tactile.study.compare(encoder, tactip_set, target=["depth_mm"])
    with pytest.raises(ValueError, match="hidden width 0: must be 1 to 4096"):
        tactile.study.compare(encoder, tactip_set, targets=["depth_mm"], hidden=[64, 0])
    with pytest.raises(ValueError, match="no column 'nope_mm'"):
        tactile.study.compare(encoder, tactip_set, targets="nope_mm")
    with pytest.raises(ValueError, match="encoders: give at least one"):
        tactile.study.sweep([], tactip_set)
    with pytest.raises(ValueError, match="unknown option 'runz'"):
        tactile.study.sweep(encoder, tactip_set, runz=3)
    # A whole number past 64 bits is said as one (it was "invalid type:
    # floating point `1.1805916207174113e+21`, expected u64").
    with pytest.raises(ValueError, match=r"option 'seed' = 1180591620717411303424: a whole number beyond 64 bits"):
        tactile.study.robustness(encoder, tactip_set, seed=2**70)
    # So inside a list.
    with pytest.raises(ValueError, match=r"option 'hidden' = \[64, 1180591620717411303424\]: a whole number beyond 64 bits"):
        tactile.study.compare(encoder, tactip_set, targets=["depth_mm"], hidden=[64, 2**70])
    # A page over a file of the dataset it studies is refused before the
    # study runs; the file is kept.
    labels = (tactip_set / "labels.csv").read_bytes()
    with pytest.raises(ValueError, match="part of the input dataset"):
        tactile.study.robustness(encoder, tactip_set, out=tactip_set / "labels.csv")
    assert (tactip_set / "labels.csv").read_bytes() == labels


def test_robustness_leaves_out_a_frame_cut_short_with_a_warning(root, tactip_set, tmp_path):
    # A copy of the set with its 3rd frame cut to half its bytes behind a
    # whole header: the study scores the other frames, as tactile.eval.tactip
    # does, and warns naming it (before, it stopped at the frame).
    import shutil

    data = tmp_path / "ds"
    shutil.copytree(tactip_set, data)
    first = (data / "labels.csv").read_text().splitlines()[1:4]
    name = first[2].split(",")[0]
    whole = (data / name).read_bytes()
    (data / name).write_bytes(whole[: len(whole) // 2])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = tactile.study.robustness(root / "models/cae-synth", data, limit=6)
    told = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert len(told) == 1 and told == r["warnings"], told
    assert "1 of the 6 frames could not be decoded past their header" in told[0]
    assert name in told[0]
    assert " on 5 of the first 6 frames of " in r["markdown"]
    assert len(r["rows"]) == 13
