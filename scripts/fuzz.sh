#!/usr/bin/env bash
# Fuzz every parser of untrusted input for a bounded time each (default 600
# s, the first argument overrides) with cargo-fuzz (libFuzzer, AddressSanitizer):
#   dataset       labels.csv + manifest.json of a dataset folder
#   npy           .npy depth maps
#   model_config  model config JSON of all six kinds of model folder
#   weights       burnpack weight files
#   bag           ROS 2 bags (MCAP files of Image and CompressedImage topics)
# Needs a nightly toolchain (rustup) and `cargo install cargo-fuzz`. Seeds
# come from the shipped models and a generated dataset; a single allocation
# above 4000 MB counts as a crash, as the hostile-input tests' `ulimit -v`.
# Prints the executions and crashes of each target.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds="${1:-600}"
# Further arguments pick targets (default: all five).
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(dataset npy model_config weights bag)
corpus=corpus
mkdir -p "$corpus"/{dataset,npy,model_config,weights,bag}
# Seeds: real inputs of each parser.
seed_ds=$(mktemp -d)
trap 'rm -rf "$seed_ds"' EXIT
cargo run --release -q --manifest-path ../Cargo.toml -p tactile -- synth visuotactile --sequences 1 --frames-per-sequence 3 --seed 1 --out "$seed_ds/vt" >/dev/null
{ cat "$seed_ds/vt/manifest.json"; printf '\xff'; cat "$seed_ds/vt/labels.csv"; } >"$corpus/dataset/vt"
cp "$seed_ds/vt/depth/000000.npy" "$corpus/npy/depth"
i=0
for f in ../models/*/*.json ../models/*/*/*.json; do
    case "$(basename "$f")" in
        detector.json) k='\x00' ;; segmenter.json) k='\x01' ;; depth.json) k='\x02' ;;
        cae.json) k='\x03' ;; head.json) k='\x04' ;; regressor.json) k='\x05' ;; *) continue ;;
    esac
    { printf "$k"; cat "$f"; } >"$corpus/model_config/$i"
    i=$((i + 1))
done
cp ../models/segmenter/segmenter.bpk "$corpus/weights/segmenter"
# A bag: the toolkit's own results with the input frames (an Image topic).
cargo run --release -q --manifest-path ../Cargo.toml -p tactile -- run --models ../models --data ../samples/palpation --limit 2 --with-frames --out "$corpus/bag/results.mcap" >/dev/null
# The fuzz builds (nightly, AddressSanitizer) get their own target folder,
# fuzz/target: in the workspace's they would hold its lock for the whole
# sanitizer build of burn.
unset CARGO_TARGET_DIR
for target in "${targets[@]}"; do
    log=$(mktemp)
    set +e
    cargo +nightly fuzz run -O "$target" "$corpus/$target" -- \
        -max_total_time="$seconds" -malloc_limit_mb=4000 -rss_limit_mb=4096 -print_final_stats=1 >"$log" 2>&1
    status=$?
    set -e
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    crashes=$(ls artifacts/"$target" 2>/dev/null | wc -l)
    echo "$target: ${runs:-?} executions in ${seconds} s, exit $status, $crashes crash file(s)"
    [ "$status" -eq 0 ] || tail -30 "$log"
    rm -f "$log"
done
