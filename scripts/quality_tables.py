"""Image-quality tables: `hmblur compare` on the built-in and conformance scenes, FLIP per
region against the reference, written between markers in docs/quality.md and README.md.

    python scripts/quality_tables.py             # render (out/quality/), then write tables
    python scripts/quality_tables.py --tables    # write the tables from out/quality/ only

Every figure comes from the metrics.json that `hmblur compare` writes: a cell reads
whole image / inner blur / outer blur FLIP (regions as compare defines them).
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "out" / "quality"
SIZE = "640x360"
CONFORMANCE = ROOT / "tests" / "conformance"

# (label, scene argument)
SCENES = [("living_room", "living_room"), ("fan", "fan"), ("spinner", "spinner"), ("thin", "thin"),
          ("pan", "pan"), ("wheel", "wheel"), ("rover", "rover"),
          ("basic", str(CONFORMANCE / "basic.toml")),
          ("vase_pan", str(CONFORMANCE / "vase_pan.toml")),
          ("keys_arc", str(CONFORMANCE / "keys_arc.toml")),
          ("shapes", str(CONFORMANCE / "shapes.toml")),
          ("turning_car", "turning_car"),
          ("gltf_box", str(CONFORMANCE / "gltf" / "gltf_box.toml")),
          ("gltf_skin", str(CONFORMANCE / "gltf" / "gltf_skin.toml"))]
# Curved motion, on the scenes whose motion bends: the hybrid's default (curve steps:
# 2 sub-frames where the paths bend), the linear hybrid (one chord, one frame), inverse
# motion (one frame along each point's curve), the linear hybrid with 2 path segments,
# and every real-time mode with 4 sub-exposure steps.
CURVED_SCENES = ("fan", "spinner", "wheel", "keys_arc", "turning_car")
ORDER = ("off", "mcguire", "ue4", "guertin", "hybrid")
LABELS = {"mcguire": "McGuire 2012", "ue4": "UE4-style", "guertin": "Guertin 2014"}
LINEAR = ["--set", "hybrid.curve_steps=1"]
VARIANTS = {"linear": ("linear", ["--modes", "hybrid", *LINEAR]),
            "inverse": ("inverse", ["--modes", "hybrid", "--set", "hybrid.curve=inverse"]),
            "2 segments": ("seg2", ["--modes", "hybrid", "--set", "hybrid.segments=2", *LINEAR]),
            "4 steps": ("steps4", ["--set", "motion.steps=4"])}


def run_compare(label: str, scene: str, tag: str = "", extra=()) -> Path:
    out = OUT / (label + (f"_{tag}" if tag else ""))
    cmd = [sys.executable, "-m", "viewer", "compare", scene, "--size", SIZE, "--out", str(out),
           *extra]
    print(" ".join(cmd[2:]), file=sys.stderr)
    subprocess.run(cmd, check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    return out


def metrics(folder: Path) -> dict:
    return json.loads((folder / "metrics.json").read_text())["metrics"]


def cell(m: dict) -> str:
    def f(x):
        return f"{x:.4f}".lstrip("0") if x < 0.1 else f"{x:.3f}".lstrip("0")
    return "/".join(f(m[r]["flip"]) if m[r]["pixels"] else "-" for r in ("all", "inner", "outer"))


def modes_table() -> str:
    first = metrics(OUT / SCENES[0][0])
    modes = sorted((m for m in first if m != "reference"),
                   key=lambda m: ORDER.index(m) if m in ORDER else len(ORDER))
    lines = ["| scene | " + " | ".join(LABELS.get(m, m) for m in modes) + " |",
             "|---|" + "---|" * len(modes)]
    for label, _ in SCENES:
        m = metrics(OUT / label)
        lines.append(f"| {label} | " + " | ".join(cell(m[k]) if k in m else "-" for k in modes) + " |")
    return "\n".join(lines)


def curved_table() -> str:
    lines = ["| scene | hybrid, linear (one chord) | hybrid (default: curve steps) | "
             "hybrid, inverse motion | hybrid, linear, 2 segments | McGuire, 4 steps | "
             "UE4-style, 4 steps | hybrid, 4 steps |", "|---|---|---|---|---|---|---|---|"]
    for label in CURVED_SCENES:
        default = metrics(OUT / label)["hybrid"]
        linear = metrics(OUT / f"{label}_linear")["hybrid"]
        inverse = metrics(OUT / f"{label}_inverse")["hybrid"]
        seg2 = metrics(OUT / f"{label}_seg2")["hybrid"]
        steps = metrics(OUT / f"{label}_steps4")
        lines.append(f"| {label} | {cell(linear)} | {cell(default)} | {cell(inverse)} | "
                     f"{cell(seg2)} | {cell(steps['mcguire'])} | {cell(steps['ue4'])} | "
                     f"{cell(steps['hybrid'])} |")
    return "\n".join(lines)


def fill(path: Path, name: str, text: str):
    """Replace the block between <!-- quality:NAME --> and <!-- /quality:NAME -->."""
    if not path.exists():
        return
    src = path.read_text()
    pat = re.compile(rf"(<!-- quality:{name} -->\n).*?(<!-- /quality:{name} -->)", re.S)
    if not pat.search(src):
        return
    path.write_text(pat.sub(lambda m: m.group(1) + text + "\n" + m.group(2), src))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tables", action="store_true", help="only write the tables from out/quality/")
    args = ap.parse_args()
    if not args.tables:
        for label, scene in SCENES:
            run_compare(label, scene)
        for label, scene in SCENES:
            if label in CURVED_SCENES:
                for tag, extra in VARIANTS.values():
                    run_compare(label, scene, tag, extra)
    modes, curved = modes_table(), curved_table()
    for path in (ROOT / "README.md", ROOT / "docs" / "quality.md"):
        fill(path, "modes", modes)
        fill(path, "curved", curved)
    print(modes + "\n\n" + curved)
    return 0


if __name__ == "__main__":
    sys.exit(main())
