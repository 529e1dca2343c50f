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
    cargo run --release -p tactile -- train cae --data {{real}}/polic-shapes --out {{out}} --max-epochs 3000 --patience 300
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
