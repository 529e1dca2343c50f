#!/usr/bin/env bash
# models/cae-synth without the pin alignment saved with it (`just
# align-cae-synth`), as data/cae-synth-unaligned: what a turned sensor costs
# without alignment, and the encoder a rotation-augmented head trains on
# (the aligned one would turn its turned copies back).
set -euo pipefail
cd "$(dirname "$0")/.."
UNALIGNED=data/cae-synth-unaligned
mkdir -p data
rm -rf "$UNALIGNED.tmp" && cp -r models/cae-synth "$UNALIGNED.tmp"
python3 - "$UNALIGNED.tmp/cae.json" <<'PY'
import json, sys
config = json.load(open(sys.argv[1]))
config["preprocess"].pop("align", None)
json.dump(config, open(sys.argv[1], "w"), indent=2)
PY
rm -rf "$UNALIGNED" && mv "$UNALIGNED.tmp" "$UNALIGNED"
