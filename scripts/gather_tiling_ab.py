"""The post-process gathers drawn full screen against tiled (viewer/render/passes/gather_tiles.py),
frames interleaved in one process so both see the same machine load; with the hybrid
composite of the same run. Medians of ctx.finish() + CPU clock times (ms).

    python scripts/gather_tiling_ab.py living_room,thin 640x360 15

One row per scene: each gather full -> tiled, the hybrid composite, the frame ratio
hybrid/McGuire against McGuire full -> tiled, and Guertin/McGuire (both tiled).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from viewer.glcontext import create_headless  # noqa: E402
from viewer.render.renderer import Renderer  # noqa: E402
from world.loader import load_scene  # noqa: E402

GATHERS = {"mcguire": "mcguire_gather", "ue4": "ue4_gather", "guertin": "guertin_gather"}


def scene_path(name: str) -> Path:
    return Path(name) if name.endswith(".toml") else ROOT / "scenes" / f"{name}.toml"


def measure(ctx, name: str, size, frames: int) -> str:
    scene = load_scene(scene_path(name))
    r = Renderer(ctx, scene, size)
    t = scene.render.time
    gather = {(m, tl): [] for m in GATHERS for tl in (False, True)}
    frame = {key: [] for key in gather}
    frame["hybrid"], composite = [], []
    try:
        for m in (*GATHERS, "hybrid"):
            r.render(m, t)                               # warm-up: programs, numba
        for _ in range(frames):
            for m, pass_name in GATHERS.items():
                for tiled in (False, True):
                    r.pipeline(m).passes[-1].tiled = tiled
                    res = r.render(m, t, timing=True)
                    gather[(m, tiled)].append(res.pass_ms[pass_name])
                    frame[(m, tiled)].append(sum(res.pass_ms.values()))
            res = r.render("hybrid", t, timing=True)
            composite.append(res.pass_ms["hybrid_composite"])
            frame["hybrid"].append(sum(res.pass_ms.values()))
    finally:
        r.release()
    g = {k: float(np.median(v)) for k, v in gather.items()}
    f = {k: float(np.median(v)) for k, v in frame.items()}
    cells = " | ".join(f"{g[(m, False)]:.1f} -> {g[(m, True)]:.1f}" for m in GATHERS)
    return (f"| {name} {size[0]}x{size[1]} | {cells} | {float(np.median(composite)):.1f} | "
            f"{f['hybrid'] / f[('mcguire', False)]:.2f} -> {f['hybrid'] / f[('mcguire', True)]:.2f} | "
            f"{f[('guertin', True)] / f[('mcguire', True)]:.2f} |")


def main() -> int:
    scenes = sys.argv[1].split(",")
    size = tuple(int(x) for x in sys.argv[2].split("x"))
    frames = int(sys.argv[3]) if len(sys.argv) > 3 else 15
    print("| scene | McGuire gather | UE4 gather | Guertin gather | hybrid composite | "
          "hybrid/McGuire frame | Guertin/McGuire frame |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    ctx = create_headless()
    for name in scenes:
        print(measure(ctx, name, size, frames), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
