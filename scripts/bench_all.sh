#!/usr/bin/env bash
# The benchmark set of docs/performance.md: every real-time mode on the built-in and the
# conformance scenes at 640x360 and 1280x720, JSON into docs/perf/, then the tables
# regenerated in place (scripts/perf_tables.py).
# About 2-7 minutes on 2 cores. Run after scripts/setup.sh (or `bash scripts/test.sh`).
set -euo pipefail
cd "$(dirname "$0")/.."
H=.venv/bin/hmblur
out=docs/perf
mkdir -p "$out"
C=tests/conformance
B=scenes/bench      # bench-only scenes: many moving objects (crowd), and with camera motion
$H bench living_room --size 640x360 --frames 30 --speeds 0.25,0.5,1,2 --json $out/living_room_640x360.json
$H bench living_room --size 1280x720 --frames 12 --speeds 0.5,1,2 --json $out/living_room_1280x720.json
$H bench spinner --size 640x360 --frames 15 --speeds 0.25,0.5,1,2 --json $out/spinner_640x360.json
for s in fan thin pan wheel rover $C/basic.toml $C/keys_arc.toml $C/vase_pan.toml $B/crowd.toml $B/crowd_pan.toml; do
  n=$(basename "$s" .toml)
  $H bench "$s" --size 640x360 --frames 15 --json "$out/${n}_640x360.json"
done
for s in spinner pan $C/basic.toml $C/vase_pan.toml $B/crowd.toml $B/crowd_pan.toml; do
  n=$(basename "$s" .toml)
  $H bench "$s" --size 1280x720 --frames 8 --modes mcguire,hybrid --json "$out/${n}_1280x720.json"
done
# The same frames in an animation (frame k at t + k / 60 s after the frame before it):
# nothing kept from the last frame (tiles, clears) is then the same as in the timed one.
for s in living_room fan spinner thin pan wheel rover $C/basic.toml $C/vase_pan.toml $B/crowd.toml $B/crowd_pan.toml; do
  n=$(basename "$s" .toml)
  $H bench "$s" --size 640x360 --frames 15 --modes mcguire,hybrid --animate 60 \
    --json "$out/${n}_640x360_animated.json"
done
# The tables between the <!-- perf:NAME --> markers of docs/performance.md (and README.md)
.venv/bin/python scripts/perf_tables.py
.venv/bin/python scripts/readme_table.py "$out"      # the README's table, printed
