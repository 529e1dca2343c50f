"""scripts/own_sensor_depth_seeds.py: the page of the own-sensor depth
network over training runs, every number read from the runs' files."""

import json
import shutil
import subprocess
import sys

from conftest import stand_in_tools


def run(root, *args):
    return subprocess.run([sys.executable, str(root / "scripts" / "own_sensor_depth_seeds.py"), *map(str, args)],
                          capture_output=True, text=True)


def write_run(folder, seed, loss, independent, network_shape, held_out_shape, augment=False):
    """A depth network's training record and its page: two presses, the
    second never in training, each with the calibration's shape 0.04 mm
    (summed up as `tactile bench own-sensor` does)."""
    (folder / "models" / "depth").mkdir(parents=True)
    (folder / "models" / "depth" / "training.json").write_text(json.dumps(
        {"config": {"schedule": {"seed": seed, "max_epochs": 2}, "model": {"input_size": [128, 96]},
                    "augment": {"exposure": 0.25} if augment else None},
         "summary": {"best_val_loss": loss}}))
    summary = lambda presses, shapes: {  # noqa: E731
        "presses": presses,
        "network_shape_mm": sum(shapes) / len(shapes),
        "network_far_field_mm": 0.01,
        "calibration_shape_mm": 0.04,
        "shape_ratio": sum(shapes) / len(shapes) / 0.04,
        "network_peak_mm": 1.9,
        "calibration_peak_mm": 1.88,
    }
    page = {
        "test": {"depth": {"mae_mm": 0.0176, "mae_tendon_mm": 0.048}},
        "other_renders": [{"set": "data/own-sensor/light-test", "depth": {"mae_mm": 0.017}},
                          {"set": "data/own-sensor/independent/", "depth": {"mae_mm": independent}}],
        "ball": [{"in_training": True}, {"in_training": False}],
        "ball_summary": [summary("all", [network_shape, held_out_shape]),
                         summary("held-out", [held_out_shape])],
    }
    (folder / "page.json").write_text(json.dumps(page))
    return folder


def test_each_run_is_a_row_and_the_spread_of_every_column_is_given(root, tmp_path):
    shipped = write_run(tmp_path / "shipped", 42, 0.0245, 0.068, 0.04, 0.044)
    other = write_run(tmp_path / "43", 43, 0.0274, 0.136, 0.048, 0.06)
    augmented = write_run(tmp_path / "augment-42", 42, 0.0278, 0.5, 0.05, 0.05, augment=True)
    out = tmp_path / "seeds.md"
    r = run(root, out, shipped / "models" / "depth", shipped / "page.json", other, augmented)
    assert r.returncode == 0, r.stderr
    lines = [line for line in out.read_text().splitlines() if line.startswith("| ")]
    header, rows = lines[0], lines[1:]
    assert "`light-test` | `independent`" in header
    cells = [row.strip("| ").split(" | ") for row in rows]
    assert [c[1] for c in cells[:3]] == ["42", "43", "42"]
    # Each row's recipe, from its training record.
    assert [c[2] for c in cells[:3]] == ["128x96, 2 epochs"] * 2 + ["128x96, 2 epochs, `--augment`"]
    # The shipped row; the run's shape against the calibration's over both
    # presses (0.054 / 0.04) and the held-out one alone (0.06 / 0.04).
    assert cells[0][3:7] == ["0.0245", "0.0176 / 0.0480", "0.0170", "0.0680"]
    assert cells[1][8] == "1.35x / 1.50x", cells[1]
    # Largest over smallest, over the runs of one recipe: the other
    # simulator's error doubled (the augmented run's 0.5 is not in it); a
    # recipe of one run has no spread.
    assert len(cells) == 4, cells
    assert cells[3][0] == "**largest over smallest**" and cells[3][2] == "128x96, 2 epochs", cells[3]
    assert cells[3][6] == "2.00", cells[3]
    assert not list(tmp_path.glob("*.tmp"))


def test_a_file_that_is_no_run_is_named(root, tmp_path):
    shipped = write_run(tmp_path / "shipped", 42, 0.0245, 0.068, 0.04, 0.044)
    out = tmp_path / "seeds.md"
    r = run(root, out, shipped / "models" / "depth", shipped / "page.json", tmp_path / "missing")
    assert r.returncode != 0 and str(tmp_path / "missing") in r.stderr and "training.json" in r.stderr
    record = shipped / "models" / "depth" / "training.json"
    record.write_text(json.dumps({"config": {}}))
    r = run(root, out, shipped / "models" / "depth", shipped / "page.json", tmp_path / "missing")
    assert r.returncode != 0 and f"{record}: no 'schedule'" in r.stderr, r.stderr
    shipped = write_run(tmp_path / "shipped-again", 42, 0.0245, 0.068, 0.04, 0.044)
    (tmp_path / "bad").mkdir()
    bad = write_run(tmp_path / "bad" / "run", 44, 0.03, 0.1, 0.04, 0.04)
    (bad / "page.json").write_text(json.dumps({"test": {}}))
    r = run(root, out, shipped / "models" / "depth", shipped / "page.json", bad)
    assert r.returncode != 0 and str(bad / "page.json") in r.stderr and "'other_renders'" in r.stderr, r.stderr
    assert not out.exists()


def test_a_page_of_an_older_bench_is_named_with_how_to_score_it_again(root, tmp_path):
    shipped = write_run(tmp_path / "shipped", 42, 0.0245, 0.068, 0.04, 0.044)
    old = write_run(tmp_path / "43", 43, 0.0274, 0.136, 0.048, 0.06)
    page = json.loads((old / "page.json").read_text())
    del page["ball_summary"]
    (old / "page.json").write_text(json.dumps(page))
    out = tmp_path / "seeds.md"
    r = run(root, out, shipped / "models" / "depth", shipped / "page.json", old)
    assert r.returncode != 0 and f"{old / 'page.json'}: no 'ball_summary'" in r.stderr, r.stderr
    assert "REBENCH=1" in r.stderr and not out.exists()


def test_runs_are_one_recipe_only_when_their_whole_training_config_is(root, tmp_path):
    shipped = write_run(tmp_path / "shipped", 42, 0.0245, 0.068, 0.04, 0.044)
    other = write_run(tmp_path / "43", 43, 0.0274, 0.136, 0.048, 0.06)
    # The same words in the recipe column, another patience: no spread with
    # the shipped network's runs.
    patient = write_run(tmp_path / "44", 44, 0.03, 0.5, 0.05, 0.05)
    record = patient / "models" / "depth" / "training.json"
    training = json.loads(record.read_text())
    training["config"]["schedule"]["patience"] = 5
    record.write_text(json.dumps(training))
    # A record written before `augment` was a field: the same recipe as one
    # whose `augment` is none.
    older = write_run(tmp_path / "45", 45, 0.0309, 0.034, 0.04, 0.04)
    record = older / "models" / "depth" / "training.json"
    training = json.loads(record.read_text())
    del training["config"]["augment"]
    record.write_text(json.dumps(training))
    out = tmp_path / "seeds.md"
    r = run(root, out, shipped / "models" / "depth", shipped / "page.json", other, patient, older)
    assert r.returncode == 0, r.stderr
    spread = [line for line in out.read_text().splitlines() if line.startswith("| **largest")]
    assert len(spread) == 1 and " | 4.00 | " in spread[0], spread


def test_a_shipped_ensemble_is_its_members_mean_and_joins_no_spread_of_single_runs(root, tmp_path):
    # The loop's ensemble of seeds 42 and 43, scored on its page as a whole.
    shipped = tmp_path / "shipped"
    for k, seed in enumerate([42, 43]):
        member = write_run(tmp_path / f"m{k}", seed, 0.02, 0.06, 0.04, 0.04)
        (shipped / "depth" / f"member-{k}").mkdir(parents=True)
        shutil.copy(member / "models" / "depth" / "training.json", shipped / "depth" / f"member-{k}" / "training.json")
    (shipped / "depth" / "ensemble.json").write_text(json.dumps({"members": ["member-0", "member-1"]}))
    page = write_run(tmp_path / "page", 1, 0.0, 0.05, 0.036, 0.036) / "page.json"
    # Each member alone, as the seeds script trains them.
    alone = [write_run(tmp_path / str(seed), seed, 0.02, independent, 0.04, 0.04)
             for seed, independent in [(42, 0.047), (43, 0.113)]]
    out = tmp_path / "seeds.md"
    r = run(root, out, shipped / "depth", page, *alone)
    assert r.returncode == 0, r.stderr
    cells = [line.strip("| ").split(" | ") for line in out.read_text().splitlines() if line.startswith("| ")][1:]
    assert cells[0][1:4] == ["42, 43", "mean of 2: 128x96, 2 epochs", "-"], cells[0]
    assert cells[0][6] == "0.0500", cells[0]
    # The spread is over the single runs only: 0.113 / 0.047, not the mean's 0.05.
    spread = [c for c in cells if c[0] == "**largest over smallest**"]
    assert len(spread) == 1 and spread[0][6] == "2.40", spread
    # An ensemble.json whose members are not folder names inside it is named.
    (shipped / "depth" / "ensemble.json").write_text(json.dumps({"members": ["../m0"]}))
    r = run(root, tmp_path / "again.md", shipped / "depth", page, *alone)
    assert r.returncode != 0 and "ensemble.json: 'members' is not a list of member folder names" in r.stderr
    assert not (tmp_path / "again.md").exists()


FAKE_TACTILE = '''#!PYTHON
"""A stand-in for the tactile binary: `train depth` writes a training record
of its flags, `bench own-sensor` a page; each call is logged."""
import json, os, sys
args = sys.argv[1:]
with open(os.environ["FAKE_LOG"], "a") as f:
    f.write(" ".join(args) + "\\n")
def flag(name):
    return args[args.index(name) + 1]
if args[:2] == ["train", "depth"]:
    if os.environ.get("FAKE_FAIL"):
        sys.exit("error: training failed")
    out = flag("--out")
    os.makedirs(out)
    config = {"schedule": {"seed": int(flag("--seed")), "max_epochs": int(flag("--max-epochs")),
                           "patience": int(flag("--patience"))},
              "model": {"input_size": [128, 96]}, "augment": {} if "--augment" in args else None,
              "prior_calibration": flag("--prior-calibration")}
    with open(os.path.join(out, "training.json"), "w") as f:
        json.dump({"config": config, "summary": {"best_val_loss": 0.02}}, f)
    # Weights that differ with the seed and the flags.
    with open(os.path.join(out, "depth.bpk"), "w") as f:
        f.write(" ".join(a for a in args if "/" not in a))
elif args[:2] == ["train", "ensemble"]:
    members = args[args.index("--members") + 1:args.index("--out")]
    out = flag("--out")
    for k, m in enumerate(members):
        os.makedirs(os.path.join(out, f"member-{k}"))
        with open(os.path.join(m, "training.json")) as f, \
                open(os.path.join(out, f"member-{k}", "training.json"), "w") as g:
            g.write(f.read())
    with open(os.path.join(out, "ensemble.json"), "w") as f:
        json.dump({"members": [f"member-{k}" for k in range(len(members))]}, f)
elif args[:2] == ["bench", "own-sensor"]:
    out = flag("--out")
    with open(os.environ["FAKE_PAGE"]) as f:
        page = f.read()
    with open(out[:-3] + ".json", "w") as f:
        f.write(page)
    with open(out, "w") as f:
        f.write("# page\\n")
'''


def seeds_sandbox(root, tmp_path, recipe):
    """A copy of the seeds script and what it reads, with `tactile` and
    `cargo` stood in for; `recipe` is the loop's depth recipe."""
    box = tmp_path / "box"
    (box / "scripts").mkdir(parents=True)
    for f in ["own-sensor-depth-seeds.sh", "own_sensor_depth_seeds.py"]:
        shutil.copy(root / "scripts" / f, box / "scripts" / f)
    (box / "scripts" / "own-sensor-depth.env").write_text(
        f"depth_recipe=({recipe})\ndepth_variants=(\"more;7;{recipe} --augment\")\n")
    (box / "docs").mkdir()
    shutil.copy(root / "docs" / "own-sensor.json", box / "docs" / "own-sensor.json")
    models, data = box / "models", box / "data"
    (models / "depth").mkdir(parents=True)
    (models / "optics.json").write_text("{}")
    # The shipped depth network as the loop ships it: an ensemble.
    shipped = root / "models" / "gelsight-r15" / "depth"
    (models / "depth" / "member-0").mkdir()
    (models / "depth" / "ensemble.json").write_text(json.dumps({"members": ["member-0"]}))
    shutil.copy(shipped / "member-0" / "training.json", models / "depth" / "member-0" / "training.json")
    for d in ["train", "test"]:
        (data / d).mkdir(parents=True)
        (data / d / "manifest.json").write_text("{}")
    (data / "times.json").write_text("{}")
    env = stand_in_tools(box, FAKE_TACTILE, FAKE_PAGE=str(root / "docs" / "own-sensor.json"), SEEDS="43",
                         TACTILE_BALL="unused")
    return box, env


def seeds_run(box, env, **more):
    return subprocess.run(["bash", str(box / "scripts" / "own-sensor-depth-seeds.sh"), "models", "data"],
                          cwd=box, env=dict(env, **more), capture_output=True, text=True)


def test_the_seeds_script_keeps_a_run_retrains_one_of_another_recipe_and_loses_nothing_on_failure(root, tmp_path):
    box, env = seeds_sandbox(root, tmp_path, "--max-epochs 2 --patience 2")
    runs = box / "data" / "depth-seeds"
    r = seeds_run(box, env)
    assert r.returncode == 0, r.stderr
    assert (runs / "43" / "recipe").read_text() == "--max-epochs 2 --patience 2\n"
    assert (runs / "more" / "7" / "recipe").read_text() == "--max-epochs 2 --patience 2 --augment\n"
    page = (box / "docs" / "own-sensor-depth-seeds.md").read_text()
    assert "`data/depth-seeds/43`" in page and "`data/depth-seeds/more/7`" in page, page
    trained = [line for line in (box / "log").read_text().splitlines() if line.startswith("train depth")]
    assert len(trained) == 2, trained
    # Run again: both are kept, nothing is trained.
    r = seeds_run(box, env)
    assert r.returncode == 0 and r.stderr.count("kept") == 2, r.stderr
    assert sum(line.startswith("train depth") for line in (box / "log").read_text().splitlines()) == 2
    # The loop's recipe changes: its run is trained again, with the new
    # recipe recorded; the variant, whose recipe is its own, is too.
    env_file = box / "scripts" / "own-sensor-depth.env"
    env_file.write_text(env_file.read_text().replace("--max-epochs 2", "--max-epochs 4"))
    r = seeds_run(box, env)
    assert r.returncode == 0, r.stderr
    assert "trained with another recipe (--max-epochs 2 --patience 2)" in r.stderr, r.stderr
    assert (runs / "43" / "recipe").read_text() == "--max-epochs 4 --patience 2\n"
    record = json.loads((runs / "43" / "models" / "depth" / "training.json").read_text())
    assert record["config"]["schedule"]["max_epochs"] == 4
    # A training that fails leaves the kept run as it was and no staging
    # folder behind.
    env_file.write_text(env_file.read_text().replace("--max-epochs 4", "--max-epochs 6"))
    r = seeds_run(box, env, FAKE_FAIL="1")
    assert r.returncode != 0 and "training failed" in r.stderr, r.stderr
    assert (runs / "43" / "recipe").read_text() == "--max-epochs 4 --patience 2\n"
    assert sorted(p.name for p in runs.iterdir()) == ["43", "more"]


def test_the_seeds_script_scores_the_mean_of_the_first_seeds_and_builds_it_again_when_a_member_changes(root, tmp_path):
    box, env = seeds_sandbox(root, tmp_path, "--max-epochs 2 --patience 2")
    env["SEEDS"], env["VARIANTS"] = "43 44 45", ""
    r = seeds_run(box, env)
    assert r.returncode == 0, r.stderr
    # The mean of the first two (all three would be the loop's own).
    [made] = [line for line in (box / "log").read_text().splitlines() if line.startswith("train ensemble")]
    assert made.startswith("train ensemble --members data/depth-seeds/43/models/depth data/depth-seeds/44/models/depth "), made
    assert not (box / "data" / "depth-seeds" / "mean-3").exists()
    rows = [line for line in (box / "docs" / "own-sensor-depth-seeds.md").read_text().splitlines()
            if line.startswith("| `data/depth-seeds/mean-2`")]
    assert len(rows) == 1 and "| 43, 44 | mean of 2: 128x96, 2 epochs | - |" in rows[0], rows
    # Run again: kept. Retrained members (another recipe): built again.
    r = seeds_run(box, env)
    assert r.returncode == 0 and "mean of 2: kept" in r.stderr, r.stderr
    env_file = box / "scripts" / "own-sensor-depth.env"
    env_file.write_text(env_file.read_text().replace("--max-epochs 2", "--max-epochs 4"))
    r = seeds_run(box, env)
    assert r.returncode == 0 and "mean of 2: kept" not in r.stderr, r.stderr
    assert sum(line.startswith("train ensemble") for line in (box / "log").read_text().splitlines()) == 2
    assert "mean of 2: 128x96, 4 epochs" in (box / "docs" / "own-sensor-depth-seeds.md").read_text()


def test_the_seeds_script_names_a_bad_seed_or_variant_before_it_trains_anything(root, tmp_path):
    box, env = seeds_sandbox(root, tmp_path, "--max-epochs 2 --patience 2")
    env_file = box / "scripts" / "own-sensor-depth.env"
    recipe = env_file.read_text().splitlines()[0]
    cases = [
        ({"SEEDS": "43 4a"}, None, "SEEDS: 4a is not a whole number"),
        ({"SEEDS": "*"}, None, "SEEDS: * is not a whole number"),
        ({}, "../up;7;--max-epochs 2", 'its NAME "../up" is not letters'),
        ({}, "none;;--max-epochs 2", "has no SEEDS or no FLAGS"),
        ({}, "bare;7;", "has no SEEDS or no FLAGS"),
        ({}, "odd;7 x;--max-epochs 2", '"odd;7 x;--max-epochs 2": x is not a whole number'),
    ]
    for more, variant, message in cases:
        if variant is not None:
            env_file.write_text(f'{recipe}\ndepth_variants=("{variant}")\n')
        r = seeds_run(box, env, **more)
        assert r.returncode != 0 and message in r.stderr, (more, variant, r.stderr)
        assert not (box / "log").exists() and not (box / "data" / "depth-seeds").exists(), (more, variant)
        assert not (box / "docs" / "own-sensor-depth-seeds.md").exists()
