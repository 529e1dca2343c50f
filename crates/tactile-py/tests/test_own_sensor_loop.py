"""scripts/own-sensor.sh, the own-sensor loop, with `tactile` and `cargo`
stood in for: the depth step trains one network per seed of
scripts/own-sensor-depth.env and ships their mean, one network for one
seed, and a bad DEPTH_SEEDS is refused before any step runs."""

import json
import os
import shutil
import subprocess

from conftest import stand_in_tools

FAKE_TACTILE = '''#!PYTHON
"""A stand-in for the tactile binary: every command makes its --out (a
folder, or a file for a page or an ONNX export) and is logged."""
import json, os, sys
args = sys.argv[1:]
with open(os.environ["FAKE_LOG"], "a") as f:
    f.write(" ".join(args) + "\\n")
def flag(name):
    return args[args.index(name) + 1]
out = flag("--out")
if out.endswith((".md", ".onnx")):
    with open(out, "w") as f:
        f.write("fake\\n")
elif args[:2] == ["train", "ensemble"]:
    members = args[args.index("--members") + 1:args.index("--out")]
    os.makedirs(out)
    with open(os.path.join(out, "ensemble.json"), "w") as f:
        json.dump({"members": [f"member-{k}" for k in range(len(members))], "notes": {"members_from": members}}, f)
    print(f"{len(members)} depth networks averaged in {out}")
else:
    os.makedirs(out)
    if args[:2] == ["synth", "gelsight"]:
        with open(os.path.join(out, "manifest.json"), "w") as f:
            f.write("{}")
    if args[:2] == ["train", "depth"]:
        with open(os.path.join(out, "training.json"), "w") as f:
            json.dump({"seed": int(flag("--seed")), "prior": flag("--prior-calibration")}, f)
'''


def loop_sandbox(root, tmp_path):
    """A copy of the loop and its env file, with `tactile` and `cargo`
    stood in for and ball presses without their circles (so the other
    simulator's renders are left out)."""
    box = tmp_path / "box"
    (box / "scripts").mkdir(parents=True)
    for f in ["own-sensor.sh", "own-sensor-depth.env"]:
        shutil.copy(root / "scripts" / f, box / "scripts" / f)
    (box / "docs").mkdir()
    (box / "models").mkdir()
    (box / "ball").mkdir()
    env = stand_in_tools(box, FAKE_TACTILE, TACTILE_BALL=str(box / "ball"))
    env.pop("DEPTH_SEEDS", None)
    return box, env


def loop_run(box, env, **more):
    return subprocess.run(["bash", str(box / "scripts" / "own-sensor.sh"), "models/sensor", "data/own"],
                          cwd=box, env=dict(env, **more), capture_output=True, text=True)


def calls(box, prefix):
    log = box / "log"
    lines = log.read_text().splitlines() if log.exists() else []
    return [line for line in lines if line.startswith(prefix)]


def test_the_loop_ships_the_mean_of_one_depth_network_per_seed(root, tmp_path):
    box, env = loop_sandbox(root, tmp_path)
    r = loop_run(box, env)
    assert r.returncode == 0, r.stderr
    trained = calls(box, "train depth")
    assert [t.split("--seed ")[1] for t in trained] == ["42", "43", "44", "45"], trained
    # Each into its own folder of the staged sensor, its prior the staged
    # calibration; then averaged into depth/ and the runs removed.
    stage = trained[0].split("--prior-calibration ")[1].split(" ")[0]
    assert os.path.basename(stage).startswith(".sensor.new."), stage
    for t, seed in zip(trained, [42, 43, 44, 45]):
        assert f"--out {stage}/depth-runs/{seed} " in t and "--max-epochs 4" in t, t
    [ensemble] = calls(box, "train ensemble")
    assert ensemble == ("train ensemble --members " + " ".join(f"{stage}/depth-runs/{s}" for s in [42, 43, 44, 45])
                        + f" --out {stage}/depth"), ensemble
    shipped = box / "models" / "sensor"
    assert json.loads((shipped / "depth" / "ensemble.json").read_text())["members"] == [
        f"member-{k}" for k in range(4)]
    assert not (shipped / "depth-runs").exists() and not list((box / "models").glob(".sensor.new.*"))
    # The ensemble is exported with the other networks, and the depth step timed whole.
    assert any(e.startswith(f"export --model {stage}/depth --out {stage}/depth/depth.onnx") for e in calls(box, "export"))
    times = json.loads((box / "data" / "own" / "times.json").read_text())
    assert "depth" in times and times["frames"] == 15000, times


def test_one_depth_seed_ships_one_network_and_a_bad_seed_list_stops_the_loop_before_it_starts(root, tmp_path):
    box, env = loop_sandbox(root, tmp_path)
    r = loop_run(box, env, DEPTH_SEEDS="7")
    assert r.returncode == 0, r.stderr
    [trained] = calls(box, "train depth")
    assert " --out " in trained and trained.split(" --out ")[1].split(" ")[0].endswith("/depth"), trained
    assert trained.endswith("--seed 7") and not calls(box, "train ensemble")
    before = (box / "log").read_text()
    shipped = sorted(p.name for p in (box / "models" / "sensor").iterdir())
    for seeds, message in [
        ("", "DEPTH_SEEDS: 1 to 8 seeds"),
        ("1 2 3 4 5 6 7 8 9", "DEPTH_SEEDS: 1 to 8 seeds"),
        ("42 4a", "DEPTH_SEEDS: 4a is not a whole number"),
        ("42 042", "a seed given twice"),
    ]:
        r = loop_run(box, env, DEPTH_SEEDS=seeds)
        assert r.returncode != 0 and message in r.stderr, (seeds, r.stderr)
        # Nothing ran, and the rendered data and the shipped models are as they were.
        assert (box / "log").read_text() == before, seeds
        assert (box / "data" / "own" / "times.json").exists(), seeds
        assert sorted(p.name for p in (box / "models" / "sensor").iterdir()) == shipped
