#!/usr/bin/env bash
# The README's viewer screenshots (docs/screenshots/view_*.png): the window, panel and
# overlay included, under Xvfb. Run after scripts/setup.sh (or `bash scripts/test.sh`).
set -euo pipefail
cd "$(dirname "$0")/.."
for mode in hybrid mcguire; do
  xvfb-run -a -s "-screen 0 1400x900x24" .venv/bin/hmblur view spinner --mode "$mode" \
    --frames 40 --size 960x540 --screenshot "docs/screenshots/view_$mode.png"
done
