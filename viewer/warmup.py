"""Compile the project's numba kernels into their on-disk cache ahead of the first frame.

    python -m viewer.warmup

scripts/setup.sh runs this once, so that the first hybrid frame afterwards loads the
kernels from the cache (well under a second) instead of compiling them (~40 s). It renders
two tiny hybrid frames of every built-in scene, with the default mask and with the range
check: the scenes between them take every path whose argument types differ (a still and a
moving camera, the static view, static and moving hits), so nothing is left to compile
at any size. A warm cache makes this a few seconds.
"""
from __future__ import annotations

import sys
import time

from world import jit_notice
from .glcontext import create_headless
from .params import ParamSet
from .render.renderer import Renderer
from world.loader import builtin_scene_names, builtin_scene_path, load_scene

SIZE = (64, 36)


def warm_up(size=SIZE) -> int:
    """Render the hybrid frames; the number of kernels numba compiled (cache misses)."""
    ctx = create_headless()
    for name in builtin_scene_names():
        scene = load_scene(builtin_scene_path(name))
        r = Renderer(ctx, scene, size)
        try:
            for range_check in (False, True):
                params = ParamSet()
                params.set("hybrid.range_check", range_check)
                for k in range(2):
                    r.render("hybrid", scene.render.time + k / 60.0, params, seed=k)
        finally:
            r.release()
    ctx.release()
    return jit_notice.install().compiled


def main() -> int:
    t0 = time.perf_counter()
    n = warm_up()
    print(f"warmup: {n} kernels compiled and cached in {time.perf_counter() - t0:.0f} s",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
