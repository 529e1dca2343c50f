"""The own-sensor depth network over training runs, as a page.

    python scripts/own_sensor_depth_seeds.py OUT.md SHIPPED_DEPTH SHIPPED_PAGE RUN...

SHIPPED_DEPTH is the loop's depth network (`models/gelsight-r15/depth`:
its `training.json`, or an ensemble's `ensemble.json` and its members'
records) and SHIPPED_PAGE the page that scored it
(`docs/own-sensor.json`); each RUN is a run of
`scripts/own-sensor-depth-seeds.sh`: `models/depth/training.json` (or a
mean's `models/depth/ensemble.json` and its members' records) and the
`page.json` that `tactile bench own-sensor` wrote for it. Every number on
the page is read from those files.
"""
import json
import os
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"{path}: {e}")


def other_sets(page):
    """The page's other renders, by folder name, in its order."""
    return [(os.path.basename(os.path.normpath(o["set"])), o["depth"]["mae_mm"]) for o in page["other_renders"]]


def ball_summaries(page):
    """The page's summaries of the real presses by name (`all`, and
    `held-out` when some joined training): `tactile bench own-sensor` takes
    the means, this page only reads them."""
    return {b["presses"]: b for b in page["ball_summary"]}


def values(loss, page, sets):
    """A run's numbers, in the columns' order (None where its page lacks a set)."""
    by_set = dict(other_sets(page))
    ball = ball_summaries(page)
    every = ball["all"]
    return [
        loss,
        page["test"]["depth"]["mae_mm"],
        page["test"]["depth"]["mae_tendon_mm"],
        *(by_set.get(s) for s in sets),
        every["network_far_field_mm"],
        every["shape_ratio"],
        ball["held-out"]["shape_ratio"] if "held-out" in ball else None,
        every["network_peak_mm"],
    ]


def same_recipe(config):
    """What makes two runs the same recipe: their whole training config but
    the seed and the prior's folder (each run's own). A field an older
    record lacks is read as its default, none (`augment`)."""
    rest = {k: v for k, v in config.items() if k != "prior_calibration" and v is not None}
    rest["schedule"] = {k: v for k, v in config["schedule"].items() if k != "seed"}
    return json.dumps(rest, sort_keys=True)


def run_values(training_path, page_path, sets=None):
    """The seed, recipe (in words, and as `same_recipe`'s key) and numbers
    of the network in `training_path` scored in `page_path` (and the page's
    sets, and the page); a file without a field the page needs is named."""
    training, page = load(training_path), load(page_path)
    try:
        config = training["config"]
        seed, loss = config["schedule"]["seed"], training["summary"]["best_val_loss"]
        w, h = config["model"]["input_size"]
        recipe = f"{w}x{h}, {config['schedule']['max_epochs']} epochs"
        if config.get("augment") is not None:
            recipe += ", `--augment`"
        key = same_recipe(config)
    except (KeyError, TypeError, ValueError) as e:
        sys.exit(f"{training_path}: no {e} (not a depth network's training record?)")
    try:
        sets = sets if sets is not None else [s for s, _ in other_sets(page)]
        return (seed, recipe, key), values(loss, page, sets), sets, page
    except (KeyError, TypeError) as e:
        if isinstance(page, dict) and "ball" in page and "ball_summary" not in page:
            sys.exit(f"{page_path}: no 'ball_summary' (written by an older `tactile bench own-sensor`: "
                     "run it again as the page says; REBENCH=1 bash scripts/own-sensor-depth-seeds.sh "
                     "does so for its runs)")
        sys.exit(f"{page_path}: no {e} (not a page of `tactile bench own-sensor`?)")


def depth_row(depth, page_path, sets=None):
    """The row of the depth network in the folder `depth` scored in
    `page_path`: one network's, or an ensemble's (its members' seeds and
    recipe, no validation loss of its own; its recipe key its own and its
    size's, so that its row joins no spread of single runs)."""
    ensemble = os.path.join(depth, "ensemble.json")
    if not os.path.exists(ensemble):
        return run_values(os.path.join(depth, "training.json"), page_path, sets)
    e = load(ensemble)
    members = e.get("members") if isinstance(e, dict) else None
    if not isinstance(members, list) or not members or not all(
            isinstance(m, str) and m and os.sep not in m and m not in (".", "..") for m in members):
        sys.exit(f"{ensemble}: 'members' is not a list of member folder names")
    per = [run_values(os.path.join(depth, m, "training.json"), page_path, sets) for m in members]
    _, v, sets, page = per[0]
    words = sorted({r for (_, r, _), _, _, _ in per})
    recipe = f"mean of {len(per)}: {'; '.join(words)}"
    keys = sorted({k for (_, _, k), _, _, _ in per})
    seeds = ", ".join(str(s) for (s, _, _), _, _, _ in per)
    return (seeds, recipe, f"ensemble of {len(per)} " + " ".join(keys)), [None, *v[1:]], sets, page


def fmt(x, spec):
    return "-" if x is None else format(x, spec)


def cells(v, n, value=".4f", times="x"):
    """A row's cells (`v` in the columns' order, `n` other sets): pairs
    joined by ` / `, the shape ratios marked `times`."""
    return [
        fmt(v[0], value),
        f"{fmt(v[1], value)} / {fmt(v[2], value)}",
        *(fmt(x, value) for x in v[3:3 + n]),
        fmt(v[3 + n], value),
        f"{fmt(v[4 + n], '.2f')}{times} / {fmt(v[5 + n], '.2f')}{times}",
        fmt(v[6 + n], ".2f"),
    ]


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    out, shipped, shipped_page, runs = argv[0], argv[1], argv[2], argv[3:]
    seed, v, sets, page = depth_row(shipped, shipped_page)
    table = [("shipped (`scripts/own-sensor.sh`)", seed, v)]
    for run in runs:
        seed, v, _, _ = depth_row(os.path.join(run, "models", "depth"), os.path.join(run, "page.json"), sets)
        table.append((f"`{run}`", seed, v))
    calibration_peak = ball_summaries(page)["all"]["calibration_peak_mm"]
    # The spread over the runs of one recipe, named by its words.
    recipes = dict((key, recipe) for _, (_, recipe, key), _ in table)
    spreads = []
    for key, recipe in recipes.items():
        rows = [v for _, (_, _, k), v in table if k == key]
        if len(rows) < 2:
            continue
        spread = []
        for k in range(len(rows[0])):
            col = [v[k] for v in rows if v[k] is not None]
            spread.append(max(col) / min(col) if col and min(col) > 0 else None)
        spreads.append((recipe if len(recipes) > 1 else "-", spread))
    n = len(sets)
    md = [
        "# The own-sensor depth network over training runs",
        "",
        "Generated by `bash scripts/own-sensor-depth-seeds.sh` after `bash scripts/own-sensor.sh`: the loop's depth step "
        "(`tactile train depth ... --prior-calibration` with the recipe of `scripts/own-sensor-depth.env`: input size, "
        "epochs, photometric augmentation as each row's training record says) alone per seed (which draws the weights, "
        "the shuffles and the validation videos; the loop ships the mean of the networks of its seeds, `depth_seeds`, "
        "as one, `tactile train ensemble`, and its row is that mean; the rows `mean-K` are the means of the first K seeds' "
        "networks, what each added network buys), and with the other recipes of that file (`depth_variants`: the "
        "training frames' colours augmented with `--augment`, the detector's photometric augmentation with the prior "
        "left as reconstructed; fewer epochs), each network scored by `tactile bench own-sensor` beside the shipped "
        "calibration, detector and segmenter, as `docs/own-sensor.md` scores the shipped one. Mean absolute errors "
        "of the indentation over the frame, mm; on the real presses, the network's shape error inside the contact "
        "against the calibration's, its far field, and how deep it says the ball went (the calibration: "
        f"{calibration_peak:.2f} mm).",
        "",
        "| network | seed | recipe | validation loss | held-out renders: frame / tendon | "
        + " | ".join(f"`{s}`" for s in sets)
        + " | real presses: far field | real presses: shape, all / held out | real presses: deepest point |",
        "|---" * (8 + n) + "|",
        *("| " + " | ".join([name, str(seed), recipe, *cells(v, n)]) + " |" for name, (seed, recipe, _), v in table),
        *(f"| **largest over smallest** | - | {recipe} | " + " | ".join(cells(spread, n, value=".2f", times="")) + " |"
          for recipe, spread in spreads),
        "",
        "Each network corrects the calibration's reconstruction, and its training loss is measured on renders of this "
        "simulator only: where frames are unlike them (another simulator's, the real presses) the correction is what "
        "a run happened to learn. Compare a retrained network with every row here, not with the shipped one's alone.",
        "",
    ]
    tmp = f"{out}.{os.getpid()}.tmp"
    try:
        with open(tmp, "w") as f:
            f.write("\n".join(md))
        os.replace(tmp, out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


if __name__ == "__main__":
    main(sys.argv[1:])
