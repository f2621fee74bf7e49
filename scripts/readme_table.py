"""The README's performance table from docs/perf/*.json (scripts/bench_all.sh writes them):
one row per scene and size, the animated ratio beside the 640x360 rows. Prints Markdown."""
from __future__ import annotations

import json
import sys
from pathlib import Path

ROWS = [("living_room", "living_room"), ("thin", "thin"), ("basic", "basic (conformance)"),
        ("spinner", "spinner"), ("vase_pan", "vase_pan (conformance, camera moves)"),
        ("pan", "pan (camera moves)"), ("crowd", "crowd (32 movers, bench scene)"),
        ("crowd_pan", "crowd_pan (32 movers, camera moves)")]


def main(folder: str = "docs/perf") -> None:
    d = Path(folder)
    print("| scene | size | McGuire ms | UE4-style ms | hybrid ms | hybrid / McGuire "
          "| animated, 60 fps |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for name, label in ROWS:
        for size in ("640x360", "1280x720"):
            f = d / f"{name}_{size}.json"
            if not f.exists():
                continue
            r = json.loads(f.read_text())
            modes = r["modes"]

            def ms(m):
                return f"{modes[m]['frame_ms']:.1f}" if m in modes else "-"
            anim = d / f"{name}_{size}_animated.json"
            a = (f"{json.loads(anim.read_text())['ratios']['hybrid/mcguire']:.2f}"
                 if anim.exists() else "-")
            print(f"| {label} | {size} | {ms('mcguire')} | {ms('ue4')} | {ms('hybrid')} "
                  f"| {r['ratios']['hybrid/mcguire']:.2f} | {a} |")


if __name__ == "__main__":
    main(*sys.argv[1:])
