"""What each design for bending motion costs and gives: the hybrid linear (one chord),
with curve steps (sub-frames where the paths bend, the default), following each point's
curve by inverse motion (`hybrid.curve=inverse`), with 2 path segments in one run, and
time-interleaved sub-frames (a prototype: scripts/interleaved_subframes.py); whole-image
and inner-blur FLIP (`hmblur compare`) and ms per frame against McGuire's (`hmblur
bench`, the same run), at 640x360.

    python scripts/curve_designs.py              # measure (out/curve_designs/), write the table
    python scripts/curve_designs.py --table      # write the table from out/curve_designs/ only
    python scripts/curve_designs.py --bench      # time again (no compare), write the table

The table goes between the markers <!-- curve:designs --> in docs/performance.md
("Bending motion: what each design costs and gives"), and to stdout.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "curve_designs"
DOC = ROOT / "docs" / "performance.md"
MARK = "curve:designs"
SIZE = "640x360"
CONF = ROOT / "tests" / "conformance"
SCENES = [("fan", "fan"), ("wheel", "wheel"), ("spinner", "spinner"),
          ("keys_arc", str(CONF / "keys_arc.toml")), ("rover", "rover"),
          ("basic", str(CONF / "basic.toml")), ("thin", "thin"), ("turning_car", "turning_car"),
          ("shapes", str(CONF / "shapes.toml")), ("living_room", "living_room"), ("pan", "pan")]
# (label, --set values): curve_steps=1 turns the sub-frames off
VARIANTS = [("linear", ["hybrid.curve_steps=1"]),
            ("curve steps 2", []),
            ("inverse", ["hybrid.curve=inverse"]),
            ("segments 2", ["hybrid.curve_steps=1", "hybrid.segments=2"])]
PROTOTYPE = "interleaved 2"            # scripts/interleaved_subframes.py, --k 2


def hmblur(*args):
    subprocess.run([sys.executable, "-m", "viewer.commands.main", *args], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL)


def measure(scene_label, scene, frames, compare=True):
    out = OUT / scene_label
    spec = [f"v{k}=hybrid:" + ",".join(s) if s else f"v{k}=hybrid"
            for k, (_, s) in enumerate(VARIANTS)]
    if compare:
        hmblur("compare", scene, "--out", str(out), "--size", SIZE, "--modes", "off",
               *sum((["--variant", v] for v in spec), []))
    for k, (_, sets) in enumerate(VARIANTS):
        hmblur("bench", scene, "--size", SIZE, "--modes", "mcguire,hybrid", "--frames",
               str(frames), "--json", str(out / f"bench{k}.json"),
               *sum((["--set", s] for s in sets), []))
    subprocess.run([sys.executable, str(ROOT / "scripts" / "interleaved_subframes.py"), scene,
                    "--k", "2", "--json", str(out / "interleaved.json")], cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL)


def table() -> str:
    labels = [v for v, _ in VARIANTS] + [PROTOTYPE]
    head = ("| scene | " + " | ".join(f"{v} FLIP whole / inner" for v in labels)
            + " | " + " | ".join(f"{v}: ms / McGuire (ratio)" for v in labels) + " |")
    rows = [head, "| --- |" + " ---: |" * (2 * len(labels))]
    for label, _ in SCENES:
        out = OUT / label
        if not all((out / f).exists() for f in
                   ["metrics.json", *(f"bench{k}.json" for k in range(len(VARIANTS)))]):
            continue
        m = json.loads((out / "metrics.json").read_text())
        flip = {(v, r): x["flip"] for v, regions in m["metrics"].items()
                for r, x in regions.items()}
        cells, times = [], []
        for k, _ in enumerate(VARIANTS):
            cells.append(f"{flip[(f'v{k}', 'all')]:.4f} / {flip.get((f'v{k}', 'inner'), float('nan')):.3f}")
            b = json.loads((out / f"bench{k}.json").read_text())
            h, g = frame_ms(b, "hybrid"), frame_ms(b, "mcguire")
            times.append(f"{h:.1f} / {g:.1f} ({h / g:.2f}x)")
        proto = out / "interleaved.json"
        if proto.exists():
            p = json.loads(proto.read_text())
            cells.append(f"{p['flip']['all']:.4f} / {p['flip']['inner']:.3f}")
            times.append(f"{p['frame_ms']:.1f} / {p['mcguire_ms']:.1f} "
                         f"({p['frame_ms'] / p['mcguire_ms']:.2f}x)")
        else:
            cells.append("-")
            times.append("-")
        rows.append(f"| {label} | " + " | ".join(cells) + " | " + " | ".join(times) + " |")
    return "\n".join(rows)


def frame_ms(bench: dict, mode: str) -> float:
    return float(bench["modes"][mode]["frame_ms"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--table", action="store_true", help="write the table from OUT only")
    ap.add_argument("--bench", action="store_true", help="time again, keep the FLIP figures")
    ap.add_argument("--frames", type=int, default=15)
    ap.add_argument("--scenes", default=None, help="comma-separated labels (default all)")
    a = ap.parse_args()
    if not a.table:
        want = a.scenes.split(",") if a.scenes else None
        for label, scene in SCENES:
            if want is None or label in want:
                measure(label, scene, a.frames, compare=not a.bench)
    text = table()
    doc = DOC.read_text()
    pattern = re.compile(rf"(<!-- {MARK} -->\n).*?(<!-- /{MARK} -->)", re.S)
    if not pattern.search(doc):
        sys.exit(f"{DOC}: no <!-- {MARK} --> markers")
    DOC.write_text(pattern.sub(lambda m: m.group(1) + text + "\n" + m.group(2), doc))
    print(text)


if __name__ == "__main__":
    main()
