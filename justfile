# Longer recipes. The two README commands (scripts/demo.sh, scripts/test.sh) do not need `just`.

real := "../shared/real"

# The demo on shipped weights.
demo:
    bash scripts/demo.sh

# Every test (installs onnxruntime from PyPI when needed).
test:
    bash scripts/test.sh

# What CI runs.
ci:
    bash .ci/run

# Train paper A's CAE on the shapes set (train split), then its shape head; writes models/cae-shapes.
train-cae out="models/cae-shapes":
    cargo run --release -p tactile -- train cae --data {{real}}/polic-shapes --out {{out}} --widths 16,16,8,4 --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 2500 --patience 300
    cargo run --release -p tactile -- train head --encoder {{out}} --data {{real}}/polic-shapes

# Encode the shapes set with the shipped encoder.
encode out="features.csv":
    cargo run --release -p tactile -- encode --model models/cae-shapes --data {{real}}/polic-shapes --out {{out}}

# Export the shipped encoder to ONNX.
export out="cae-encoder.onnx":
    cargo run --release -p tactile -- export --model models/cae-shapes --out {{out}}

# Benchmark the CAE (ndarray, flex, onnxruntime) and write docs/bench-cae.md.
bench-cae:
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- bench cae --out docs/bench-cae.md

# Synthetic data: a training and a test set of the virtual TacTip, and a palpation set.
synth-tactip out="data/synth-tactip":
    cargo run --release -p tactile -- synth tactip --count 3000 --seed 100 --out {{out}}-train --preview {{out}}-train.png
    cargo run --release -p tactile -- synth tactip --count 700 --seed 200 --out {{out}}-test

synth-visuotactile out="data/synth-vt":
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --seed 100 --out {{out}} --preview {{out}}.png

# The contact sheets in docs/.
synth-previews:
    cargo run --release -p tactile -- synth tactip --count 8 --seed 1 --out target/prev-t --force --preview docs/synth-tactip-preview.png --preview-frames 8
    cargo run --release -p tactile -- synth visuotactile --sequences 4 --seed 3 --out target/prev-v --force --preview docs/synth-visuotactile-preview.png --preview-frames 8

# The demo's shipped sample frames (held-out seed).
samples:
    cargo run --release -p tactile -- synth tactip --count 14 --seed 300 --out samples/virtual-tactip --force

# Train the CAE (grey-level area-downsampled pin images, linear latent) and every estimator on the virtual TacTip; writes models/cae-synth.
train-cae-synth out="models/cae-synth": synth-tactip
    cargo run --release -p tactile -- train cae --data data/synth-tactip-train --out {{out}} --preprocess configs/preprocess/virtual-tactip-area.json --widths 16,16,8,4 --linear-latent --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 300 --patience 40
    cargo run --release -p tactile -- train head --encoder {{out}} --data data/synth-tactip-train --test data/synth-tactip-test
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-tactip-train --targets depth_mm,force_n --hidden 128,64 --out {{out}}/regressor
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-tactip-train --targets x_mm,y_mm --only-labelled --hidden 128,64 --out {{out}}/position
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-tactip-train --targets theta_deg:180 --only-labelled --hidden 128,64 --out {{out}}/theta

# Frames/s of both virtual sensors; writes docs/bench-synth.md.
bench-synth:
    cargo run --release -p tactile -- bench synth --out docs/bench-synth.md

# Paper A on the real 127-pin edge set: CAE (train split made by seed), then every feature set x estimator; writes docs/paper-a-edge-compare.md.
train-cae-edge out="models/cae-edge":
    cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out {{out}} --preprocess configs/preprocess/tactip127-edge.json --widths 16,16,8,4 --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 250 --patience 40

compare-edge:
    cargo run --release -p tactile -- compare --encoder models/cae-edge --data {{real}}/tactip127-edge --targets x_mm,theta_deg:180,depth_mm --out docs/paper-a-edge-compare.md

compare-shapes:
    cargo run --release -p tactile -- compare --encoder models/cae-shapes --data {{real}}/polic-shapes --classify shape --out docs/paper-a-shapes-compare.md

# Paper A's feature-count search on the shapes set: trains 8/16/32/64-feature CAEs into data/sweep, then writes docs/paper-a-sweep.md and its plots.
sweep:
    for f in 8 16 32 64; do cargo run --release -p tactile -- train cae --data {{real}}/polic-shapes --out data/sweep/cae-$f --widths 16,16,8,4 --features $f --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 600 --patience 100; done
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- sweep --data {{real}}/polic-shapes --out docs/paper-a-sweep.md --encoders data/sweep/cae-8 data/sweep/cae-16 data/sweep/cae-32 data/sweep/cae-64
