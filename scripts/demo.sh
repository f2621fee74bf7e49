#!/usr/bin/env bash
# The main job: set up (scripts/setup.sh), then render the demo comparison of the built-in
# living room headless into out/demo (strip.png, metrics.md, metrics.json, every mode's PNG).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
exec .venv/bin/hmblur compare living_room --size 640x360 --out out/demo "$@"
