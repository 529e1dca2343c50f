#!/usr/bin/env bash
# The own-sensor loop (docs/own-sensor.md): a real GelSight calibrated from
# its ball presses, its own palpation videos rendered through that
# calibration, the detector, segmenter and depth network (the mean of one
# per seed of scripts/own-sensor-depth.env) trained on them, each exported
# to ONNX; then the page measures everything (held-out
# renders, the real ball presses, frames of other sensors) with each
# step's time.
#
#   bash scripts/own-sensor.sh [MODELS_DIR] [DATA_DIR]
#
# MODELS_DIR (default models/gelsight-r15) is built in a staging folder and
# moved into place when every step has finished; DATA_DIR (default
# data/own-sensor) holds the rendered sets. Step times go to
# DATA_DIR/times.json, the page to docs/own-sensor.md. TACTILE_BALL (default
# ../shared/real/gelsight-ball) names the sensor's ball presses: the
# calibration layout of docs/datasets.md, gs_sdk's folder, or Taxim's
# dataPack.npz (the file or its folder). DEPTH_SEEDS (default the env
# file's depth_seeds, 42 43 44 45) trains one depth network per seed and
# ships their mean; one seed ships one network.
set -euo pipefail
cd "$(dirname "$0")/.."
models="${1:-models/gelsight-r15}"
data="${2:-data/own-sensor}"
ball="${TACTILE_BALL:-../shared/real/gelsight-ball}"
if [ -z "${ORT_DYLIB_PATH:-}" ]; then
    eval "$(bash scripts/install-ort.sh)"
    export ORT_DYLIB_PATH
fi
# shellcheck source=scripts/own-sensor-depth.env
source scripts/own-sensor-depth.env
read -ra depth_seed_list <<< "${DEPTH_SEEDS-${depth_seeds[*]}}"
if [ "${#depth_seed_list[@]}" -eq 0 ] || [ "${#depth_seed_list[@]}" -gt 8 ]; then
    echo "error: DEPTH_SEEDS: 1 to 8 seeds (an ensemble averages at most 8 networks), got ${#depth_seed_list[@]}" >&2
    exit 1
fi
for seed in "${depth_seed_list[@]}"; do
    case "$seed" in
        *[!0-9]*) echo "error: DEPTH_SEEDS: $seed is not a whole number" >&2; exit 1 ;;
    esac
done
if [ "$(printf '%s\n' "${depth_seed_list[@]}" | sort -nu | wc -l)" -ne "${#depth_seed_list[@]}" ]; then
    echo "error: DEPTH_SEEDS: a seed given twice (${depth_seed_list[*]}): one seed trains one network" >&2
    exit 1
fi
cargo build --release -p tactile
target="${CARGO_TARGET_DIR:-target}"
tactile="$target/release/tactile"
stage="$(dirname "$models")/.$(basename "$models").new.$$"
trap 'rm -rf "$stage"' EXIT
rm -rf "$data"
mkdir -p "$data"
times="$data/times.json.tmp"
echo "{" > "$times"
step() {
    local name="$1"
    shift
    echo "== $name: $*" >&2
    local t0 cs
    t0=$(date +%s%N)
    "$@"
    # Hundredths of a second, in the shell's integers (no bc needed).
    cs=$(( ($(date +%s%N) - t0) / 10000000 ))
    printf '  "%s": %d.%02d,\n' "$name" $((cs / 100)) $((cs % 100)) >> "$times"
}
step calibrate "$tactile" calibrate ball --data "$ball" --out "$stage" --val-presses 0
# Many short videos: the detector generalises with the number of scenes
# far more than with frames of one scene (docs/own-sensor.md). The ball
# presses that calibrated the sensor join as real negatives, all but the
# last 8, which stay out for the page's held-out check.
sequences=3000
step render "$tactile" synth gelsight --sensor "$stage" --sequences $sequences --frames-per-sequence 5 \
    --flat-share 0.1 --seed 100 --out "$data/train" --preview "$data/train.png" \
    --real-presses "$ball" --real-copies 15 --real-held-out 8
# Light presses (tendons pressed 0.05-0.3 mm; spheres, punches and plate
# edges 0.05-0.4 mm) for the detector alone: at a light press a punch's rim
# or a plate's edge shades a line as a tendon does, and the default
# distribution holds few such frames (its objects go to 2.5 mm for the
# depth network), so a detector trained on it alone took 44 % of light
# plate edges and 24 % of light punches for tendons (docs/own-sensor.md,
# "By kind of frame"). The same settings, another seed, test it after.
light=(--frames-per-sequence 5 --press-mm 0.05,0.3 --object-press-mm 0.05,0.4 --tendon-share 0.4
    --sphere-share 0.15 --punch-share 0.2 --flat-share 0.2 --nothing-share 0.05)
step render-light "$tactile" synth gelsight --sensor "$stage" --sequences 600 "${light[@]}" \
    --seed 101 --out "$data/light"
# Plate edges and punches at every press beside tendons, for the detector
# alone: a plate's edge shades one band as one side of a tendon does, and
# the default set holds few of them (a tenth of its videos), so a detector
# trained without these took 28 % of deep plate edges and 17 % of light
# ones for tendons on renders of a fresh seed (seed 301 below; before,
# 7 % and 30 % with the plate always over the frame's centre, and on
# scripts/gelsight_independent.py's renders, whose plates often only clip
# the frame, 34 % and 64 %). The same settings, another seed, test it after.
objects=(--frames-per-sequence 5 --tendon-share 0.4 --sphere-share 0 --punch-share 0.2 --flat-share 0.4
    --nothing-share 0 --plate-edge-reach -0.75,0.75 --punch-fillet 0.05,0.5)
step render-objects "$tactile" synth gelsight --sensor "$stage" --sequences 600 "${objects[@]}" \
    --seed 102 --out "$data/objects"
# Photometric augmentation (--augment: exposure, LED balance, blur, noise,
# glare, JPEG) keeps the detector from taking a camera's compression or
# noise for a light press: without it, the real frames recorded as Motion
# JPEG or H.264 gave false tendons and held-out renders so recorded fell to
# 53-79 % (docs/own-sensor.md, "Recorded through a camera or a recorder").
# With --input-bits 16 it adds only a camera's noise averaged down to the
# input, which keeps a light press's sub-level shading
# (PhotometricAugment::recording).
step detector "$tactile" train detector --data "$data/train" "$data/light" "$data/objects" --out "$stage/detector" \
    --input 80x60 --input-bits 16 --soft-labels 0.2 --max-epochs 12 --patience 4 --augment
# The segmenter keeps the sensor's rest frame (--rest): a tendon's direction
# is read from the window's shading against it, so the gel's own texture
# (the R1.5's streaks of paint) does not pull the angle.
step segmenter "$tactile" train segmenter --data "$data/train" --out "$stage/segmenter" \
    --copies 1 --max-epochs 4 --patience 2 --rest "$stage/background.png"
# The depth network corrects the calibration's own reconstruction (its
# fourth channel), which carries over to the real sensor's frames. One
# network per seed of depth_seeds (DEPTH_SEEDS overrides), their mean
# shipped as one (an ensemble folder) when there are several.
depth_networks() {
    local seed
    if [ "${#depth_seed_list[@]}" -eq 1 ]; then
        "$tactile" train depth --data "$data/train" --out "$stage/depth" \
            "${depth_recipe[@]}" --prior-calibration "$stage" --seed "${depth_seed_list[0]}"
        return
    fi
    local members=()
    for seed in "${depth_seed_list[@]}"; do
        echo "== depth: seed $seed" >&2
        "$tactile" train depth --data "$data/train" --out "$stage/depth-runs/$seed" \
            "${depth_recipe[@]}" --prior-calibration "$stage" --seed "$seed"
        members+=("$stage/depth-runs/$seed")
    done
    "$tactile" train ensemble --members "${members[@]}" --out "$stage/depth"
    rm -rf "$stage/depth-runs"
}
step depth depth_networks
step export bash -c "for m in detector segmenter depth; do '$tactile' export --model '$stage/'\$m --out '$stage/'\$m/\$m.onnx; done && '$tactile' export --model '$stage' --out '$stage/gelsight.onnx'"
echo "  \"frames\": $((sequences * 5))" >> "$times"
echo "}" >> "$times"
mv "$times" "$data/times.json"
# Held-out renders for the page (a seed no training set used).
"$tactile" synth gelsight --sensor "$stage" --sequences 200 --frames-per-sequence 5 --seed 200 --out "$data/test"
# Other renders no choice was made on, scored the same way: light presses
# of every kind, and plate edges and punches at every press (seeds no
# training used), and another simulator of the
# sensor (scripts/gelsight_independent.py, numpy and Pillow) when Python
# has them.
"$tactile" synth gelsight --sensor "$stage" --sequences 200 "${light[@]}" --seed 300 --out "$data/light-test"
"$tactile" synth gelsight --sensor "$stage" --sequences 200 "${objects[@]}" --seed 301 --out "$data/objects-test"
others=("$data/light-test" "$data/objects-test")
python="${PYTHON:-python3}"
if [ ! -f "$ball/presses.csv" ]; then
    echo "note: $ball has no presses.csv (the calibration layout's annotated circles): the page leaves out scripts/gelsight_independent.py's renders" >&2
elif "$python" -c "import numpy, PIL" 2>/dev/null; then
    "$python" scripts/gelsight_independent.py "$data/independent" 200 500 "$ball"
    others+=("$data/independent")
else
    echo "note: $python lacks numpy or Pillow (pip install numpy pillow): the page leaves out scripts/gelsight_independent.py's renders" >&2
fi
rm -rf "$models.old"
if [ -e "$models" ]; then mv "$models" "$models.old"; fi
mv "$stage" "$models"
rm -rf "$models.old"
"$tactile" bench own-sensor --models "$models" --test "$data/test" --ball "$ball" --times "$data/times.json" --train "$data/train" --other-renders "${others[@]}" --out docs/own-sensor.md
