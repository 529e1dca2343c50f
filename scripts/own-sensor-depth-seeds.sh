#!/usr/bin/env bash
# The own-sensor depth network over training runs (docs/own-sensor-depth-
# seeds.md): the loop's depth recipe trained alone per seed (the networks
# whose mean it ships, each on its own, and other seeds), and the other
# recipes of scripts/own-sensor-depth.env (`depth_variants`: the frames'
# colours augmented, fewer epochs), each network scored by `tactile bench
# own-sensor` beside the shipped calibration, detector and segmenter, as
# docs/own-sensor.md scores the shipped one.
#
#   SEEDS="42 43 44 45" bash scripts/own-sensor-depth-seeds.sh [MODELS_DIR] [DATA_DIR]
#
# after scripts/own-sensor.sh (its rendered sets in DATA_DIR, default
# data/own-sensor; MODELS_DIR, default models/gelsight-r15). SEEDS defaults
# to the env file's depth_seeds, the seeds whose mean the loop ships: the
# page sets each of its networks alone beside their mean. VARIANTS="..."
# names the other recipes to run (default all, "" none). Each run is built
# in a staging folder and moved to DATA_DIR/depth-seeds/SEED (another
# recipe's: DATA_DIR/depth-seeds/NAME/SEED) when its page is written;
# then the means of the first 2, 3, ... seeds' networks (short of all of
# them) go to DATA_DIR/depth-seeds/mean-K;
# a run that is there already is kept (set RETRAIN=1 to train it again,
# after the loop rendered new sets, or REBENCH=1 to score its network
# again, after the bench changed), unless it was trained with another
# recipe than scripts/own-sensor-depth.env's (each run keeps its recipe in
# `recipe`): then it is trained again. The shipped models are read, never
# changed.
set -euo pipefail
cd "$(dirname "$0")/.."
models="${1:-models/gelsight-r15}"
data="${2:-data/own-sensor}"
ball="${TACTILE_BALL:-../shared/real/gelsight-ball}"
python="${PYTHON:-python3}"
for need in "$models/optics.json" "$data/train/manifest.json" \
    "$data/test/manifest.json" "$data/times.json" docs/own-sensor.json; do
    if [ ! -e "$need" ]; then
        echo "error: $need is missing: run scripts/own-sensor.sh first" >&2
        exit 1
    fi
done
# The shipped depth network: one (its training record) or an ensemble.
if [ ! -e "$models/depth/training.json" ] && [ ! -e "$models/depth/ensemble.json" ]; then
    echo "error: $models/depth holds neither training.json nor ensemble.json: run scripts/own-sensor.sh first" >&2
    exit 1
fi
if [ -z "${ORT_DYLIB_PATH:-}" ]; then
    eval "$(bash scripts/install-ort.sh)"
    export ORT_DYLIB_PATH
fi
cargo build --release -p tactile
tactile="${CARGO_TARGET_DIR:-target}/release/tactile"
# shellcheck source=scripts/own-sensor-depth.env
source scripts/own-sensor-depth.env
seeds="${SEEDS:-${depth_seeds[*]}}"
others=()
for set in light-test objects-test independent; do
    if [ -e "$data/$set/manifest.json" ]; then others+=("$data/$set"); fi
done
# Scores the networks in MODELS beside the shipped ones; the page to OUT.
bench() {
    "$tactile" bench own-sensor --models "$1" --test "$data/test" --ball "$ball" \
        --times "$data/times.json" --train "$data/train" --other-renders "${others[@]}" \
        --out "$2"
}
runs=()
# A staging folder STAGE for a run: the shipped calibration, detector and
# segmenter in STAGE/models, for a depth network of its own (removed on
# exit unless finish_run moves it into place).
begin_run() {
    stage="$1"
    trap 'rm -rf "$stage"' EXIT
    mkdir -p "$stage/models"
    local f
    for f in "$models"/*; do
        if [ "$(basename "$f")" != depth ]; then cp -r "$f" "$stage/models/"; fi
    done
}
# The staged run scored, its RECIPE recorded, and moved to RUN.
finish_run() {
    local run="$1" recipe="$2"
    bench "$stage/models" "$stage/page.md"
    printf '%s\n' "$recipe" > "$stage/recipe"
    rm -rf "$run"
    mv "$stage" "$run"
    trap - EXIT
    runs+=("$run")
}
# One run: SEED into DIR, trained with the recipe FLAGS...
one_run() {
    local seed="$1" run="$2"
    shift 2
    local flags=("$@")
    local recipe="${flags[*]}"
    if [ -f "$run/page.json" ] && [ "$(cat "$run/recipe" 2>/dev/null)" != "$recipe" ]; then
        echo "== seed $seed: $run was trained with another recipe ($(cat "$run/recipe" 2>/dev/null || echo "none recorded")) than $recipe: training it again" >&2
    elif [ -f "$run/page.json" ] && [ -z "${RETRAIN:-}" ]; then
        if [ -n "${REBENCH:-}" ]; then
            echo "== seed $seed: tactile bench own-sensor on the kept $run" >&2
            stage="$(dirname "$run")/.$seed.page.$$"
            trap 'rm -rf "$stage"' EXIT
            mkdir -p "$stage"
            bench "$run/models" "$stage/page.md"
            for f in "$stage"/*; do mv "$f" "$run/"; done
            rmdir "$stage"
            trap - EXIT
        else
            echo "== seed $seed: kept $run (RETRAIN=1 trains it again, REBENCH=1 scores it again)" >&2
        fi
        runs+=("$run")
        return
    fi
    begin_run "$(dirname "$run")/.$seed.new.$$"
    echo "== seed $seed: tactile train depth $recipe" >&2
    "$tactile" train depth --data "$data/train" --out "$stage/models/depth" \
        "${flags[@]}" --prior-calibration "$stage/models" --seed "$seed"
    echo "== seed $seed: tactile bench own-sensor" >&2
    finish_run "$run" "$recipe"
}
# The mean of the plain runs RUN... (the first K seeds') as one network in
# DIR, scored as the runs are: what each added network buys. Kept while
# its members are the same networks (their paths and weights' digests are
# its `recipe`).
mean_run() {
    local k="$1" run="$2"
    shift 2
    local members=() recipe="mean of" m
    for m in "$@"; do
        members+=("$m/models/depth")
        recipe+=" $m $(sha256sum "$m/models/depth/depth.bpk" | cut -d' ' -f1)"
    done
    if [ -f "$run/page.json" ] && [ "$(cat "$run/recipe" 2>/dev/null)" = "$recipe" ] && [ -z "${REBENCH:-}" ]; then
        echo "== mean of $k: kept $run (its members are the same networks)" >&2
        runs+=("$run")
        return
    fi
    begin_run "$(dirname "$run")/.mean-$k.new.$$"
    echo "== mean of $k: tactile train ensemble, tactile bench own-sensor" >&2
    "$tactile" train ensemble --members "${members[@]}" --out "$stage/models/depth"
    finish_run "$run" "$recipe"
}
# SEEDS and every entry of depth_variants are checked before any run trains.
# Each of SEEDS... is a whole number, else WHERE is named.
check_seeds() {
    local where="$1" seed
    shift
    for seed in "$@"; do
        case "$seed" in
            *[!0-9]*) echo "error: $where: $seed is not a whole number" >&2; exit 1 ;;
        esac
    done
}
# The seeds as words (not globbed).
read -ra seed_list <<< "$seeds"
check_seeds SEEDS "${seed_list[@]}"
for variant in "${depth_variants[@]}"; do
    IFS=';' read -r name variant_seeds variant_flags <<< "$variant"
    # Its runs go to depth-seeds/NAME: a name of one path component, and
    # seeds and flags given (else the entry would run nothing, or the
    # command's defaults rather than a recipe).
    case "$name" in
        '' | *[!A-Za-z0-9_-]*) echo "error: scripts/own-sensor-depth.env: depth_variants entry \"$variant\": its NAME \"$name\" is not letters, digits, - and _ (the form is NAME;SEEDS;FLAGS)" >&2; exit 1 ;;
    esac
    if [ -z "${variant_seeds// /}" ] || [ -z "${variant_flags// /}" ]; then
        echo "error: scripts/own-sensor-depth.env: depth_variants entry \"$variant\" has no SEEDS or no FLAGS (the form is NAME;SEEDS;FLAGS)" >&2
        exit 1
    fi
    read -ra variant_seed_list <<< "$variant_seeds"
    check_seeds "scripts/own-sensor-depth.env: depth_variants entry \"$variant\"" "${variant_seed_list[@]}"
done
for seed in "${seed_list[@]}"; do
    one_run "$seed" "$data/depth-seeds/$seed" "${depth_recipe[@]}"
done
# The means of the first 2, 3, ... of them, short of all (with SEEDS the
# loop's depth_seeds, all of them is the shipped network).
plain_runs=("${runs[@]}")
for ((k = 2; k < ${#plain_runs[@]}; k++)); do
    mean_run "$k" "$data/depth-seeds/mean-$k" "${plain_runs[@]:0:k}"
done
for variant in "${depth_variants[@]}"; do
    IFS=';' read -r name variant_seeds variant_flags <<< "$variant"
    case " ${VARIANTS-$name} " in
        *" $name "*) ;;
        *) continue ;;
    esac
    read -ra flags <<< "$variant_flags"
    read -ra variant_seed_list <<< "$variant_seeds"
    for seed in "${variant_seed_list[@]}"; do
        one_run "$seed" "$data/depth-seeds/$name/$seed" "${flags[@]}"
    done
done
"$python" scripts/own_sensor_depth_seeds.py docs/own-sensor-depth-seeds.md "$models/depth" docs/own-sensor.json "${runs[@]}"
echo "wrote docs/own-sensor-depth-seeds.md" >&2
