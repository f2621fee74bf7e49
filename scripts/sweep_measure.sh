#!/usr/bin/env bash
# The figures of docs/sweeps.md ("Measured"): the sweep of docs/sweeps/methods.toml with 1
# and 2 local workers and on a scheduler with two workers started by hand (loopback), then
# the faults: a worker killed mid-cell, the sweep interrupted and run again, a bad scene
# among good ones; and two cells from `hmblur compare`. Writes under out/sweep-measure/.
# Usage: bash scripts/sweep_measure.sh   (from the repository root, set up by scripts/setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
DASK=${DASK:-$(dirname "$PY")/dask}
SWEEP=docs/sweeps/methods.toml
M=out/sweep-measure
rm -rf "$M"
mkdir -p "$M"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"     # workers import this tree

wall() {   # wall NAME CMD...: run, keep stderr, print seconds
    local t0=$(date +%s%N)
    "${@:2}" > "$M/$1.stdout" 2> "$M/$1.stderr"
    echo "$1: $(( ($(date +%s%N) - t0) / 1000000 )) ms (load average after: $(cut -d" " -f1-3 /proc/loadavg))"
}
cells() { ls "$1/cells" 2>/dev/null | wc -l; }
check() {  # check DIR: the table's cells, rows, repeated rows, failed cells
    "$PY" - "$1" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(f"{sys.argv[1]}/table.csv")))
keys = [(r["scene"], r["time"], r["shutter"], r["size"], r["variant"], r["region"]) for r in rows]
print(f"{sys.argv[1]}: {len({r['cell'] for r in rows})} cells, {len(rows)} rows, "
      f"{len(keys) - len(set(keys))} repeated, {sum(1 for r in rows if r['error'])} error rows")
EOF
}

echo "== wall time (18 cells x 5 variants, 320x180, 64 sub-frames)"
wall w1 "$PY" -m viewer sweep $SWEEP --out $M/w1 --workers 1
wall w2 "$PY" -m viewer sweep $SWEEP --out $M/w2 --workers 2
"$DASK" scheduler --host 127.0.0.1 --port 8786 --no-dashboard > $M/scheduler.log 2>&1 &
SCHED=$!
sleep 3
"$DASK" worker tcp://127.0.0.1:8786 --nthreads 1 --no-dashboard > $M/worker1.log 2>&1 &
W1=$!
"$DASK" worker tcp://127.0.0.1:8786 --nthreads 1 --no-dashboard > $M/worker2.log 2>&1 &
W2=$!
sleep 5
wall sched "$PY" -m viewer sweep $SWEEP --out $M/sched --scheduler tcp://127.0.0.1:8786
kill $W1 $W2; wait $W1 $W2 2>/dev/null || true
kill $SCHED; wait $SCHED 2>/dev/null || true
for d in w1 w2 sched; do
    check $M/$d
    echo "$d: $(grep -E 'peak memory' $M/$d/summary.md)"
    cmp -s $M/w1/table.csv $M/$d/table.csv && echo "$d: table.csv identical to w1's"
done

echo "== a worker killed (kill -9) during a cell"
"$PY" -m viewer sweep $SWEEP --out $M/kill --workers 2 > $M/kill.stdout 2> $M/kill.stderr &
MAIN=$!
until [ "$(cells $M/kill)" -ge 2 ]; do sleep 0.2; done
VICTIM=$(pgrep -P $MAIN -f spawn_main | head -1)
kill -9 "$VICTIM"
echo "killed worker $VICTIM after $(cells $M/kill) cells"
wait $MAIN
check $M/kill
grep -E '^- (engine|cells run now|peak memory)' $M/kill/summary.md
cmp -s $M/w1/table.csv $M/kill/table.csv && echo "kill: table.csv identical to w1's"

for SIG in INT TERM; do
    echo "== interrupted (SIG$SIG) after 5 cells, and run again"
    D=$M/int-$SIG
    set -m          # job control: a background job does not ignore SIGINT
    "$PY" -m viewer sweep $SWEEP --out $D --workers 2 > $D.1.stdout 2> $D.1.stderr &
    MAIN=$!
    set +m
    until [ "$(cells $D)" -ge 5 ]; do sleep 0.2; done
    kill -$SIG $MAIN
    wait $MAIN && echo "exit 0" || echo "exit $?"
    tail -1 $D.1.stderr
    echo "left $(cells $D) cell files, $(find $D -name '*.tmp' | wc -l) temporary files, table: $(ls $D/table.csv 2>/dev/null || echo none)"
    "$PY" -m viewer sweep $SWEEP --out $D --workers 2 > $D.2.stdout 2> $D.2.stderr
    grep -E '^- (cells run now|cells from earlier runs)' $D/summary.md
    check $D
    cmp -s $M/w1/table.csv $D/table.csv && echo "table.csv identical to w1's"
done

echo "== a bad scene among good ones"
mkdir -p $M/bad
printf '[camera]\nposition = [0, 1, 4]\nlook_at = [0, 0, 0]\nfov_y = 45.0\n[[objects]]\nmesh = { box = [1.0, -1.0, 1.0] }\n' > $M/bad/broken.toml
sed -e 's/^scenes = \[/scenes = ["broken.toml", /' -e 's/^shutters = .*/shutters = [0.04]/' $SWEEP > $M/bad/sweep.toml
"$PY" -m viewer sweep $M/bad/sweep.toml --out $M/bad/out --workers 2 > $M/bad.stdout 2> $M/bad.stderr
check $M/bad/out
grep -A2 '## Failed cells' $M/bad/out/summary.md | tail -1

echo "== two cells from hmblur compare"
for cell in "spinner 0.08" "living_room 0.02"; do
    set -- $cell
    "$PY" -m viewer compare $1 --size 320x180 --shutter $2 --modes mcguire,ue4,guertin,hybrid \
        --variant hybrid_linear=hybrid:hybrid.curve_steps=1 --out $M/compare-$1-$2 > /dev/null 2>&1
    "$PY" - "$M" "$1" "$2" <<'EOF'
import csv, json, sys
m, scene, shutter = sys.argv[1], sys.argv[2], float(sys.argv[3])
got = json.load(open(f"{m}/compare-{scene}-{sys.argv[3]}/metrics.json"))["metrics"]
rows = [r for r in csv.DictReader(open(f"{m}/w1/table.csv"))
        if r["scene"] == scene and float(r["shutter"]) == shutter]
same = all(float(r[k]) == float(got[r["variant"]][r["region"]][k])
           for r in rows for k in ("flip", "psnr", "ssim"))
print(f"compare {scene} shutter {shutter}: {len(rows)} rows, every number equal: {same}")
for v in got:
    a = got[v]["all"]; i = got[v]["inner"]
    print(f"  {v}: FLIP all {a['flip']:.4f} inner {i['flip']:.4f}, PSNR all {float(a['psnr']):.2f}")
EOF
done
