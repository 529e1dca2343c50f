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
    cargo run --release -p tactile -- synth tactip --count 9000 --seed 120 --shapes sphere --out data/synth-sphere-train

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
# Spheres have their own position regressor, used where the head sees a sphere.
train-cae-synth out="models/cae-synth": synth-tactip
    cargo run --release -p tactile -- train cae --data data/synth-tactip-train --out {{out}} --preprocess configs/preprocess/virtual-tactip-area.json --widths 16,16,8,4 --linear-latent --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 300 --patience 40
    cargo run --release -p tactile -- train head --encoder {{out}} --data data/synth-tactip-train --test data/synth-tactip-test
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-tactip-train --targets depth_mm,force_n --hidden 128,64 --out {{out}}/regressor
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-tactip-train --targets x_mm,y_mm --only-labelled --hidden 128,64 --out {{out}}/position
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-tactip-train --targets theta_deg:180 --only-labelled --hidden 128,64 --out {{out}}/theta
    cargo run --release -p tactile -- train regressor --encoder {{out}} --data data/synth-sphere-train --targets x_mm,y_mm --shapes sphere --hidden 128,64 --out {{out}}/position-sphere

# Measure the pin lattice's orientation on models/cae-synth's training frames and save it with the encoder: frames of a sensor mounted turned are turned back before encoding (scripts/paper-a.sh's robustness table).
align-cae-synth: synth-tactip
    cargo run --release -p tactile -- train align --model models/cae-synth --data data/synth-tactip-train

# A shape head trained with rotation augmentation (4 copies of each frame turned by up to 6 degrees) on models/cae-synth without its alignment (which would turn the copies back): the remedy scripts/paper-a.sh compares with alignment.
train-turned-head out="data/cae-synth-turned-head": synth-tactip
    bash scripts/cae-synth-unaligned.sh
    cargo run --release -p tactile -- train head --encoder data/cae-synth-unaligned --data data/synth-tactip-train --test data/synth-tactip-test --rotate-copies 4 --rotate-deg 6 --out {{out}}

# Frames/s of both virtual sensors and of the shipped calibrated sensor's renderer; writes docs/bench-synth.md.
bench-synth:
    cargo run --release -p tactile -- bench synth --sensor models/gelsight-r15 --out docs/bench-synth.md

# Paper A on the real 127-pin edge set: the grey-level CAE (never sees the frames `compare --seed 7` tests on) and the binary one of the paper.
train-cae-edge:
    cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out models/cae-edge-unsupervised --preprocess configs/preprocess/tactip127-edge-area.json --widths 32,32,16,4 --linear-latent --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 400 --patience 40 --exclude-test 0.2
    cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out models/cae-edge-binary --preprocess configs/preprocess/tactip127-edge.json --widths 16,16,8,4 --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 250 --patience 40 --exclude-test 0.2

# The CAE route trained jointly with the edge-pose heads on 28 px pin images (semi-supervised: reconstruction plus a 64-unit head on the features predicting x, theta, depth, its mean squared error weighted 1 or 10; only the autoencoder is kept). Scored runs (32 features) without the test frames `compare --seed 7` scores, each with its MLP estimator. The shipped models/cae-edge is the 112 px recipe of train-cae-edge-large (ship-cae-edge).
train-cae-edge-joint:
    for w in 1 10; do cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out data/cae-joint-32-w$w --preprocess configs/preprocess/tactip127-edge-area.json --widths 32,32,16,4 --features 32 --linear-latent --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 150 --patience 25 --exclude-test 0.2 --joint-targets x_mm,theta_deg:180,depth_mm --joint-weight $w; done
    for w in 1 10; do cargo run --release -p tactile -- train regressor --encoder data/cae-joint-32-w$w --data {{real}}/tactip127-edge --targets x_mm,theta_deg:180,depth_mm --hidden 256,128 --out data/cae-joint-32-w$w/pose; done

# The CAE route on larger pin images: 56 and 112 px through one or two stem blocks down to Table I's 28 px, 32 features, the joint head on the L1 loss (weight 10) and the learning rate decayed per epoch; trained and scored without the test frames of split seed 7, each with its MLP estimator, beside the best pose network of that split (`just train-pose-l1-ensemble` trains it). Writes docs/paper-a/edge-pose-cae-large.md.
train-cae-edge-large:
    cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out data/cae-joint-56 --preprocess configs/preprocess/tactip127-edge-area-56.json --widths 32,32,16,4 --features 32 --linear-latent --optimizer adam --lr 1e-3 --lr-decay 0.98 --batch-size 32 --max-epochs 120 --patience 120 --exclude-test 0.2 --joint-targets x_mm,theta_deg:180,depth_mm --joint-weight 10 --joint-loss l1
    cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out data/cae-joint-112 --preprocess configs/preprocess/tactip127-edge-area-112.json --widths 32,32,16,4 --features 32 --linear-latent --optimizer adam --lr 1e-3 --lr-decay 0.97 --batch-size 32 --max-epochs 80 --patience 80 --exclude-test 0.2 --joint-targets x_mm,theta_deg:180,depth_mm --joint-weight 10 --joint-loss l1
    for px in 56 112; do cargo run --release -p tactile -- train regressor --encoder data/cae-joint-$px --data {{real}}/tactip127-edge --targets x_mm,theta_deg:180,depth_mm --hidden 256,128 --out data/cae-joint-$px/pose; done
    cargo run --release -p tactile -- bench pose --models data/pose-l1/p128-l1d-s8 data/cae-joint-112 data/cae-joint-56 --data {{real}}/tactip127-edge --runs 200 --out docs/paper-a/edge-pose-cae-large.md

# The shipped models/cae-edge: the 112 px recipe of train-cae-edge-large on every frame (80 epochs; 20 % of the frames choose the best epoch), its MLP estimator trained on every frame. About 45 min on 2 cores; staged in data/ and then put in place.
ship-cae-edge:
    rm -rf data/cae-edge-112-all
    cargo run --release -p tactile -- train cae --data {{real}}/tactip127-edge --out data/cae-edge-112-all --preprocess configs/preprocess/tactip127-edge-area-112.json --widths 32,32,16,4 --features 32 --linear-latent --optimizer adam --lr 1e-3 --lr-decay 0.97 --batch-size 32 --max-epochs 80 --patience 80 --joint-targets x_mm,theta_deg:180,depth_mm --joint-weight 10 --joint-loss l1
    cargo run --release -p tactile -- train regressor --encoder data/cae-edge-112-all --data {{real}}/tactip127-edge --targets x_mm,theta_deg:180,depth_mm --hidden 256,128 --test-fraction 0 --out data/cae-edge-112-all/pose
    rm -rf models/.cae-edge-new && mkdir -p models/.cae-edge-new/pose && cp data/cae-edge-112-all/cae.* data/cae-edge-112-all/curves.* data/cae-edge-112-all/training.json models/.cae-edge-new/ && cp data/cae-edge-112-all/pose/regressor.* models/.cae-edge-new/pose/
    rm -rf models/cae-edge && mv models/.cae-edge-new models/cae-edge

# The own-sensor loop (issue 33): calibrate the shared GelSight from its ball presses, render its palpation videos, train and export its pipeline into models/gelsight-r15 (its depth the mean of four networks; DEPTH_SEEDS=42 trains one), then write docs/own-sensor.md.
own-sensor:
    bash scripts/own-sensor.sh

# The own-sensor depth network over training runs: each of the networks whose mean the loop ships (seeds 42-45 of scripts/own-sensor-depth.env) alone, and the file's other recipes (2 epochs; 2 epochs with --augment), each scored as docs/own-sensor.md scores the shipped mean (after `just own-sensor`); writes docs/own-sensor-depth-seeds.md.
own-sensor-depth-seeds:
    bash scripts/own-sensor-depth-seeds.sh

# Surface pose and shear on the real 331-pin set (issue 34): the candidates on the authors' train split, the shipped models/pose-surface (all 8,000 frames) and models/cae-surface; then `PAPER_A_ONLY='surface|surface_compare|shared' bash scripts/paper-a.sh` scores them into docs/paper-a.md.
surface:
    bash scripts/surface.sh

# Paper A's feature-count search on the shapes set: trains 8/16/32/64-feature CAEs into data/sweep, then writes docs/paper-a/sweep.md and its plots.
sweep:
    for f in 8 16 32 64; do cargo run --release -p tactile -- train cae --data {{real}}/polic-shapes --out data/sweep/cae-$f --widths 16,16,8,4 --features $f --optimizer adam --lr 1e-3 --batch-size 32 --max-epochs 600 --patience 100; done
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- sweep --data {{real}}/polic-shapes --out docs/paper-a/sweep.md --encoders data/sweep/cae-8 data/sweep/cae-16 data/sweep/cae-32 data/sweep/cae-64

# Every paper A table and plot (shapes, sweep, edge set, synthetic, robustness, cross-dataset) into docs/paper-a.md and docs/paper-a/.
paper-a:
    bash scripts/paper-a.sh

# Paper B data: palpation videos of the virtual visuo-tactile sensor (all tendon paths), a training set and a held-out one.
synth-vt:
    cargo run --release -p tactile -- synth visuotactile --sequences 120 --frames-per-sequence 25 --seed 100 --out data/vt-train --preview data/vt-train.png
    cargo run --release -p tactile -- synth visuotactile --sequences 40 --frames-per-sequence 25 --seed 200 --out data/vt-test

# Detector training data: the default distribution (seed 110) plus light presses (peak 0.1-0.6 mm, seed 130) that crowd the frames near the label's threshold (ridge 0.03 mm), where every detector error was. The detector's selection set (seed 260, 3000 frames): 500 frames cannot tell 0.990 from 0.995. Its final test (seed 220) was generated after the choice; seeds 200 and 210 had been looked at while the training recipe was worked out.
synth-vt-detector:
    cargo run --release -p tactile -- synth visuotactile --sequences 200 --frames-per-sequence 25 --seed 110 --out data/vt-train2
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed 130 --press-mm 0.1,0.6 --out data/vt-train-onset
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed 140 --press-mm 0.1,0.6 --out data/vt-train-onset2
    cargo run --release -p tactile -- synth visuotactile --sequences 120 --frames-per-sequence 25 --seed 260 --out data/vt-select-det
    cargo run --release -p tactile -- synth visuotactile --sequences 40 --frames-per-sequence 25 --seed 220 --out data/vt-test-final

# The detector sweep into data/det (soft labels from the ridge amplitude): MobileNetV3-small at three sizes and the ResNet-18 baseline on the default set plus one light-press set, and MobileNetV3-small at four sizes with a second light-press set; `bench-paper-b` applies the selection rule and the chosen folder is copied to models/detector.
sweep-detector: synth-vt synth-vt-detector
    for spec in "mobilenet-v3-small 0.25 80x60 20" "mobilenet-v3-small 0.5 80x60 20" "mobilenet-v3-small 0.5 120x90 12" "resnet18 0.25 80x60 20"; do set -- $spec; cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset --out data/det/onset-soft-$1-w$2-$3 --architecture $1 --width $2 --input $3 --max-epochs $4 --patience 6 --soft-labels 0.2; done
    for spec in "mobilenet-v3-small 0.5 120x90 20" "mobilenet-v3-small 0.5 80x60 20" "mobilenet-v3-small 0.25 80x60 20" "mobilenet-v3-small 0.5 160x120 15"; do set -- $spec; cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset data/vt-train-onset2 --out data/det/onset2-$1-w$2-$3 --architecture $1 --width $2 --input $3 --max-epochs $4 --patience 6 --soft-labels 0.2; done

# What each ingredient of the detector's training gave (w0.5 80x60): default data with hard labels, soft labels alone, light presses alone; the sweep's onset-soft w0.5 80x60 has both.
ablate-detector: synth-vt-detector
    cargo run --release -p tactile -- train detector --data data/vt-train2 --out data/det/big-mobilenet-w0.5-80x60 --width 0.5 --input 80x60 --max-epochs 15 --patience 5
    cargo run --release -p tactile -- train detector --data data/vt-train2 --out data/det/soft-w0.5-80x60 --width 0.5 --input 80x60 --max-epochs 20 --patience 6 --soft-labels 0.2
    cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset --out data/det/onset-hard-w0.5-80x60 --width 0.5 --input 80x60 --max-epochs 20 --patience 6

# Pose networks on the real edge set: each candidate trained without the test frames of the split every candidate is scored on (seed 7, 0.2), then the chosen one (p128) on all 3,762 frames for the epochs its validated run needed; `bench pose` (in `bash scripts/paper-a.sh`) tabulates them.
train-pose:
    for c in p64 p128; do cargo run --release -p tactile -- train pose --data {{real}}/tactip127-edge --out data/pose/$c --config configs/pose/$c.json --exclude-test 0.2 --max-epochs 60 --patience 12; done
    cargo run --release -p tactile -- train pose --data {{real}}/tactip127-edge --out models/pose-edge --config configs/pose/p128.json --all-rows --max-epochs 45 --patience 45

# The L1 recipe (loss on the standardised columns, learning rate decayed 8 % per epoch to 2 % of its start) validated on the 80 % of frames the split's test leaves (no early stopping: 45 epochs, about 67 minutes on 2 cores): 0.155 mm / 1.49 deg / 0.034 mm on the 752 test frames (seed 8: 0.137 / 1.32 / 0.031). `train-pose-edge-l1` trains the shipped model with it on every frame (seed 8; 45 min).
train-pose-l1:
    cargo run --release -p tactile -- train pose --data {{real}}/tactip127-edge --out data/pose-l1/p128-l1d --config configs/pose/p128.json --exclude-test 0.2 --all-rows --max-epochs 45 --patience 45 --lr-decay 0.92 --loss l1
    cargo run --release -p tactile -- bench pose --models data/pose-l1/p128-l1d --data {{real}}/tactip127-edge --runs 200 --out docs/paper-a/edge-pose-l1.md

train-pose-edge-l1:
    cargo run --release -p tactile -- train pose --data {{real}}/tactip127-edge --out models/pose-edge --config configs/pose/p128.json --all-rows --max-epochs 45 --patience 45 --lr-decay 0.92 --loss l1 --seed 8

# The light-press detector (#20): four more light-press sets (peak 0.05-0.4 mm, the range the detector missed) beside the default and onset sets; 16-bit inputs with each channel divided by its level at the window's centre; soft labels of width 0.6 (the logit measures the ridge over a wider range). Selection sets: light presses on both renderers, 3000 frames each (100 sequences: a 1200-frame set holds too few sequences near the threshold to tell 0.975 from 0.98), and the default distribution.
synth-vt-detector-light: synth-vt-detector
    for s in 150 160 170 180; do cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed $s --press-mm 0.05,0.4 --out data/vt-train-light$s; done
    cargo run --release -p tactile -- synth visuotactile --count 3000 --seed 280 --press-mm 0.05,0.4 --out data/sel2-light-ref
    cargo run --release -p tactile -- synth visuotactile --count 3000 --seed 281 --press-mm 0.05,0.4 --renderer alternate --out data/sel2-light-alt
    cargo run --release -p tactile -- synth visuotactile --count 1200 --seed 260 --out data/sel-default

train-detector-light: synth-vt-detector-light
    cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset data/vt-train-onset2 data/vt-train-light150 data/vt-train-light160 data/vt-train-light170 data/vt-train-light180 --out data/det/light --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --max-epochs 25 --patience 25 --soft-labels 0.6
    for d in sel2-light-ref sel2-light-alt sel-default; do cargo run --release -p tactile -- eval detector --model data/det/light --data data/$d; done

# The shipped detector (#20, round three): the light-press recipe on four more light-press sets (seeds 510-540, peak 0.05-0.4 mm), averaged with the light-press recipe's network and its photometrically augmented twin (`train ensemble`: the mean logit, one network to every runtime and export); ship-detector-ensemble calibrates it on seeds 610/611 (staged, then put in place).
train-detector-ensemble: train-detector-light
    for s in 510 520 530 540; do cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed $s --press-mm 0.05,0.4 --out data/vt-train-light$s; done
    cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset data/vt-train-onset2 data/vt-train-light150 data/vt-train-light160 data/vt-train-light170 data/vt-train-light180 data/vt-train-light510 data/vt-train-light520 data/vt-train-light530 data/vt-train-light540 --out data/det/light8 --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --max-epochs 25 --patience 25 --soft-labels 0.6
    cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset data/vt-train-onset2 data/vt-train-light150 data/vt-train-light160 data/vt-train-light170 data/vt-train-light180 --out data/det/light-aug --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --max-epochs 25 --patience 25 --soft-labels 0.6 --augment
    rm -rf data/det/ensemble && cargo run --release -p tactile -- train ensemble --members data/det/light8 data/det/light data/det/light-aug --out data/det/ensemble
    for d in sel2-light-ref sel2-light-alt sel-default sel-light-ref sel-light-alt; do cargo run --release -p tactile -- eval detector --model data/det/ensemble --data data/$d; done

# Round four, not shipped (docs/detector-light-presses.md): the light8 proportions as 3,300 five-frame videos.
train-detector-scenes: synth-vt-detector-light
    cargo run --release -p tactile -- synth visuotactile --sequences 600 --frames-per-sequence 5 --seed 9110 --out data/det2/train-9110
    cargo run --release -p tactile -- synth visuotactile --sequences 600 --frames-per-sequence 5 --seed 9130 --press-mm 0.1,0.6 --out data/det2/train-9130
    cargo run --release -p tactile -- synth visuotactile --sequences 2100 --frames-per-sequence 5 --seed 9150 --press-mm 0.05,0.4 --out data/det2/train-9150
    cargo run --release -p tactile -- train detector --data data/det2/train-9110 data/det2/train-9130 data/det2/train-9150 --out data/det2/scenes --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --max-epochs 25 --patience 25 --soft-labels 0.6
    for d in sel2-light-ref sel2-light-alt sel-default; do cargo run --release -p tactile -- eval detector --model data/det2/scenes --data data/$d; done

ship-detector-ensemble: calibrate-detector-data
    rm -rf models/.detector-new && cp -r data/det/ensemble models/.detector-new
    cargo run --release -p tactile -- train calibrate --model models/.detector-new --data data/vt-cal data/vt-cal-light
    rm -rf models/detector && mv models/.detector-new models/detector

# The calibration frames: the default distribution (seed 610) and light presses (seed 611), no detector trained, chosen or tested on them.
calibrate-detector-data:
    cargo run --release -p tactile -- synth visuotactile --count 600 --seed 610 --out data/vt-cal
    cargo run --release -p tactile -- synth visuotactile --count 300 --seed 611 --press-mm 0.05,0.5 --out data/vt-cal-light
    cargo run --release -p tactile -- synth visuotactile --count 3000 --seed 612 --press-mm 0.05,0.4 --out data/vt-cal-light2

# The ensemble's test, on sets rendered after the choice: light presses on both renderers (3,000 frames each) and the default distribution on both (the alternate at 960x540).
test-detector-ensemble:
    cargo run --release -p tactile -- synth visuotactile --count 3000 --seed 750 --press-mm 0.05,0.4 --out data/test2-light-ref
    cargo run --release -p tactile -- synth visuotactile --count 3000 --seed 751 --press-mm 0.05,0.4 --renderer alternate --out data/test2-light-alt
    cargo run --release -p tactile -- synth visuotactile --count 1200 --seed 752 --renderer alternate --width 960 --height 540 --out data/test2-default-alt-960
    cargo run --release -p tactile -- synth visuotactile --count 1200 --seed 753 --out data/test2-default-ref
    for d in test2-light-ref test2-light-alt test2-default-ref test2-default-alt-960; do cargo run --release -p tactile -- eval detector --model models/detector --data data/$d; done

# Tried and not shipped (docs/synth.md, "An independent virtual visuo-tactile sensor"): a detector trained on this generator's tendons just outside the window (--out-of-view-margin-w 0,3, a tendon by the spec's label rule) beside its twin on the default distribution (same recipe, 6,000 frames, 12 epochs), the same with the photometric augmentation, and one on both sets for 25 epochs, with the shipped one, by kind of frame on the independent implementation, the default distribution, light presses and such tendons alone.
detector-near-rim:
    mkdir -p data/near-rim
    cargo run --release -p tactile -- synth visuotactile --sequences 200 --frames-per-sequence 30 --seed 901 --out data/near-rim/base
    cargo run --release -p tactile -- synth visuotactile --sequences 200 --frames-per-sequence 30 --seed 901 --out-of-view-fraction 0.3 --out-of-view-margin-w 0,3 --out data/near-rim/rim
    for set in base rim; do name=$([ $set = base ] && echo trained-default || echo trained-near-rim); cargo run --release -p tactile -- train detector --data data/near-rim/$set --out data/near-rim/$name --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --soft-labels 0.6 --max-epochs 12 --patience 12; done
    cargo run --release -p tactile -- train detector --data data/near-rim/rim --out data/near-rim/trained-near-rim-aug --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --soft-labels 0.6 --max-epochs 12 --patience 25 --augment
    cargo run --release -p tactile -- train detector --data data/near-rim/base data/near-rim/rim --out data/near-rim/trained-both-25 --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --soft-labels 0.6 --max-epochs 25 --patience 25
    cargo run --release -p tactile -- synth visuotactile --press-mm 0.05,0.4 --sequences 60 --frames-per-sequence 30 --seed 777 --out data/near-rim/light
    cargo run --release -p tactile -- synth visuotactile --sequences 60 --frames-per-sequence 30 --seed 778 --out data/near-rim/default
    cargo run --release -p tactile -- synth visuotactile --sequences 60 --frames-per-sequence 30 --seed 779 --out-of-view-fraction 1 --out-of-view-margin-w 0,3 --out data/near-rim/near-rim
    python scripts/visuotactile_independent.py data/near-rim/independent 50 21
    python scripts/visuotactile_crosscheck.py docs/detector-near-rim.md --detectors models/detector data/near-rim/trained-default data/near-rim/trained-near-rim data/near-rim/trained-near-rim-aug data/near-rim/trained-both-25 --sets data/near-rim/independent data/near-rim/default data/near-rim/light data/near-rim/near-rim

# Issue 33's "Also", tried and not shipped (docs/detector-light-presses.md): the light-press recipe's data plus light-press sets at the two corners of the tendon ranges (radius 1.5 with burial 4, radius 4 with burial 1), trained with the photometric augmentation, then put in the augmented member's place in the ensemble (light8 stays first, so its input profile gates the frames; the members' folded calibration is unfolded by `train ensemble`).
train-detector-corners: synth-vt-detector-light
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed 1510 --press-mm 0.05,0.4 --tendon-radius-mm 1.5,1.5 --burial-mm 4,4 --out data/vt-train-corner1510
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed 1520 --press-mm 0.05,0.4 --tendon-radius-mm 4,4 --burial-mm 1,1 --out data/vt-train-corner1520
    cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset data/vt-train-onset2 data/vt-train-light150 data/vt-train-light160 data/vt-train-light170 data/vt-train-light180 data/vt-train-corner1510 data/vt-train-corner1520 --out data/det/corner-aug --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --max-epochs 25 --patience 25 --soft-labels 0.6 --augment
    rm -rf data/det/ensemble-corners && cargo run --release -p tactile -- train ensemble --members models/detector/member-0 models/detector/member-1 data/det/corner-aug --out data/det/ensemble-corners
    for d in sel2-light-ref sel2-light-alt sel-default; do cargo run --release -p tactile -- eval detector --model data/det/ensemble-corners --data data/$d; done
    KEEP_SETS=1 DETECTOR=data/det/ensemble-corners OUT=data/det/ensemble-corners-extremes.md bash scripts/detector-extremes.sh

# Issue 33's "Also", round five (docs/detector-light-presses.md): light8's data plus the two corner sets, soft labels of width 0.3 (a sharper cut than 0.6), no augmentation; in member 1's place and as a fourth member; scored on the selection sets and at the extremes.
train-detector-corners-sharp: train-detector-ensemble
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed 1510 --press-mm 0.05,0.4 --tendon-radius-mm 1.5,1.5 --burial-mm 4,4 --out data/vt-train-corner1510
    cargo run --release -p tactile -- synth visuotactile --sequences 100 --frames-per-sequence 25 --seed 1520 --press-mm 0.05,0.4 --tendon-radius-mm 4,4 --burial-mm 1,1 --out data/vt-train-corner1520
    cargo run --release -p tactile -- train detector --data data/vt-train2 data/vt-train-onset data/vt-train-onset2 data/vt-train-light150 data/vt-train-light160 data/vt-train-light170 data/vt-train-light180 data/vt-train-light510 data/vt-train-light520 data/vt-train-light530 data/vt-train-light540 data/vt-train-corner1510 data/vt-train-corner1520 --out data/det4/light8-corners --width 0.5 --input 80x60 --input-bits 16 --normalise-exposure --max-epochs 25 --patience 25 --soft-labels 0.3
    rm -rf data/det4/E1 data/det4/E2 data/det4/E3 data/det4/E4
    cargo run --release -p tactile -- train ensemble --members data/det/light8 data/det4/light8-corners data/det/light-aug --out data/det4/E1
    cargo run --release -p tactile -- train ensemble --members data/det/light8 data/det/light data/det/light-aug data/det4/light8-corners --out data/det4/E2
    cargo run --release -p tactile -- train ensemble --members data/det/light8 data/det4/light8-corners data/det/light --out data/det4/E3
    cargo run --release -p tactile -- train ensemble --members data/det/light8 data/det4/light8-corners --out data/det4/E4
    for m in data/det4/light8-corners data/det4/E1 data/det4/E2 data/det4/E3 data/det4/E4; do for d in sel2-light-ref sel2-light-alt sel-default; do cargo run --release -p tactile -- eval detector --model $m --data data/$d; done; done
    for m in light8-corners E1 E2 E3 E4; do KEEP_SETS=1 DETECTOR=data/det4/$m OUT=data/det4/$m-extremes.md bash scripts/detector-extremes.sh; done

# Ship round five's pair (light8 + corners, data/det4/E4 from train-detector-corners-sharp; docs/detector-light-presses.md), calibrated on the three calibration sets (the pair makes no error on the first two, so the scale would run to its bound).
ship-detector-corners-sharp: calibrate-detector-data
    rm -rf models/.detector-new
    cp -r data/det4/E4 models/.detector-new && rm -rf models/.detector-new/member-*/checkpoint
    cargo run --release -p tactile -- train calibrate --model models/.detector-new --data data/vt-cal data/vt-cal-light data/vt-cal-light2
    rm -rf models/detector && mv models/.detector-new models/detector

# The shipped detector at the extremes of each range of the sensor spec, both renderers (docs/detector-extremes.md, about 12 min).
detector-extremes:
    bash scripts/detector-extremes.sh

# The light-press detector's test, on sets rendered after the choice (docs/detector-light-presses.md): light presses on both renderers and the default distribution on both (the alternate at 960x540).
test-detector-light:
    cargo run --release -p tactile -- synth visuotactile --count 3000 --seed 740 --press-mm 0.05,0.4 --out data/test-light-ref
    cargo run --release -p tactile -- synth visuotactile --count 2400 --seed 741 --press-mm 0.05,0.4 --renderer alternate --out data/test-light-alt
    cargo run --release -p tactile -- synth visuotactile --count 1200 --seed 742 --renderer alternate --width 960 --height 540 --out data/test-default-alt-960
    cargo run --release -p tactile -- synth visuotactile --count 1200 --seed 743 --out data/test-default-ref
    for d in test-light-ref test-light-alt test-default-alt-960 test-default-ref; do cargo run --release -p tactile -- eval detector --model models/detector --data data/$d; done

# A second seed of the L1 pose recipe on the same 80 % of frames, and the two averaged (`train ensemble`); `bench pose` scores both members and the ensemble on the 752 test frames with the ensemble's latency (the members' sum).
train-pose-l1-ensemble: train-pose-l1
    cargo run --release -p tactile -- train pose --data {{real}}/tactip127-edge --out data/pose-l1/p128-l1d-s8 --config configs/pose/p128.json --exclude-test 0.2 --all-rows --max-epochs 45 --patience 45 --lr-decay 0.92 --loss l1 --seed 8
    cargo run --release -p tactile -- bench pose --models data/pose-l1/p128-l1d-s8 --data {{real}}/tactip127-edge --runs 200 --out docs/paper-a/edge-pose-l1-seed8.md
    cargo run --release -p tactile -- train ensemble --members data/pose-l1/p128-l1d data/pose-l1/p128-l1d-s8 --out data/pose-l1/ensemble-2
    cargo run --release -p tactile -- bench pose --models data/pose-l1/p128-l1d data/pose-l1/p128-l1d-s8 data/pose-l1/ensemble-2 --data {{real}}/tactip127-edge --runs 200 --out docs/paper-a/edge-pose-ensemble.md

# Calibrate the shipped detector's probabilities (one logit scale about the threshold, decisions unchanged) on frames no detector was trained, chosen or tested on: the default distribution (seed 610) and light presses (seed 611).
calibrate-detector: calibrate-detector-data
    cargo run --release -p tactile -- train calibrate --model models/detector --data data/vt-cal data/vt-cal-light

# The segmenter sweep (four window sizes and widths) into data/seg; the shipped one is copied to models/segmenter.
sweep-segmenter: synth-vt
    for spec in "48 4" "64 8" "96 8"; do set -- $spec; cargo run --release -p tactile -- train segmenter --data data/vt-train --out data/seg/unet-s$1-b$2 --side $1 --base $2 --copies 4 --max-epochs 8 --patience 3; done

# A selection set (its own seed) picks the smallest model meeting each target; the test set (seed 200) is only scored.
synth-vt-select:
    cargo run --release -p tactile -- synth visuotactile --sequences 20 --frames-per-sequence 25 --seed 250 --out data/vt-select

# Error against latency per runtime for every size of both sweeps; writes docs/bench-detector.md and docs/bench-segmenter.md with plots.
bench-paper-b:
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- bench detector --data data/vt-test-final --select data/vt-select-det --out docs/bench-detector.md --models data/det/onset-soft-mobilenet-v3-small-w0.25-80x60 data/det/onset-soft-mobilenet-v3-small-w0.5-80x60 data/det/onset-soft-mobilenet-v3-small-w0.5-120x90 data/det/onset-soft-resnet18-w0.25-80x60 data/det/onset2-mobilenet-v3-small-w0.25-80x60 data/det/onset2-mobilenet-v3-small-w0.5-80x60 data/det/onset2-mobilenet-v3-small-w0.5-120x90 data/det/onset2-mobilenet-v3-small-w0.5-160x120
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- bench detector --data data/vt-test-final --select data/vt-select-det --out docs/detector-ablation.md --models data/det/big-mobilenet-w0.5-80x60 data/det/soft-w0.5-80x60 data/det/onset-hard-w0.5-80x60 data/det/onset-soft-mobilenet-v3-small-w0.5-80x60 data/det/onset2-mobilenet-v3-small-w0.5-80x60
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- bench segmenter --data data/vt-test --select data/vt-select --out docs/bench-segmenter.md --models data/seg/unet-s48-b4 data/seg/unet-s64-b8 data/seg/unet-s96-b8

# Depth reconstruction: held-out sets at the press extremes, then three encoder sizes x two inputs into data/depth.
synth-vt-depth:
    cargo run --release -p tactile -- synth visuotactile --sequences 16 --frames-per-sequence 15 --seed 300 --press-mm 3.6,4.0 --out data/vt-depth-test

sweep-depth: synth-vt
    for spec in "tiny 96x64" "tiny 160x96" "small 96x64" "small 160x96" "medium 96x64" "medium 160x96"; do set -- $spec; cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/$1-$2 --encoder $1 --input $2 --max-epochs 6 --patience 2 --decoder-width 32; done

# Loss, head and mask-channel ablations on the tiny encoder at 160x96 (the L1 / 1x1 / RGB run is data/depth/tiny-160x96).
ablate-depth: synth-vt
    cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/ablate-mse --encoder tiny --input 160x96 --loss mse --max-epochs 6 --patience 2 --decoder-width 32
    cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/ablate-l1-grad-ssim --encoder tiny --input 160x96 --loss l1-grad-ssim --max-epochs 6 --patience 2 --decoder-width 32
    cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/ablate-custom-head --encoder tiny --input 160x96 --head custom --max-epochs 6 --patience 2 --decoder-width 32
    cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/ablate-mask --encoder tiny --input 160x96 --with-mask --max-epochs 6 --patience 2 --decoder-width 32

# The shipped depth model: the smallest meeting every target on the selection set, the tiny encoder at 96x64 with L1 + gradient + SSIM (the small one is the runner-up).
train-depth:
    cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/tiny-96x64-l1gs --encoder tiny --input 96x64 --loss l1-grad-ssim --max-epochs 12 --patience 3 --decoder-width 32
    cargo run --release -p tactile -- train depth --data data/vt-train --out data/depth/small-96x64-l1gs --encoder small --input 96x64 --loss l1-grad-ssim --max-epochs 12 --patience 3 --decoder-width 32

# docs/bench-depth.md (size sweep) and docs/depth-ablation.md (losses, heads, mask channel), with plots.
bench-depth:
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- bench depth --data data/vt-test --extreme data/vt-depth-test --select data/vt-select --out docs/bench-depth.md --models data/depth/tiny-96x64 data/depth/tiny-160x96 data/depth/small-96x64 data/depth/small-160x96 data/depth/medium-96x64 data/depth/medium-160x96 data/depth/tiny-96x64-l1gs data/depth/small-96x64-l1gs
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- bench depth --data data/vt-test --extreme data/vt-depth-test --select data/vt-select --out docs/depth-ablation.md --models data/depth/tiny-160x96 data/depth/ablate-mse data/depth/ablate-l1-grad-ssim data/depth/ablate-custom-head data/depth/ablate-mask

# docs/results.md: every shipped model's speed against its error and the pipeline's, regenerated from fresh held-out data.
report:
    eval "$(bash scripts/install-ort.sh)" && cargo run --release -p tactile -- report --real {{real}} --readme README.md
