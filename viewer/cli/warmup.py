"""Compile the project's numba kernels into their on-disk cache ahead of the first frame.

    python -m viewer.cli.warmup

scripts/setup.sh runs this once, so that the first frame of any mode afterwards loads the
kernels from the cache (well under a second) instead of compiling them (~40 s). It renders
two tiny frames of every mode on every built-in scene, the hybrid also with the range
check: the scenes between them take every path whose argument types differ (a still and a
moving camera, the static view, static and moving hits, the post-process filters' tile
lists), so nothing is left to compile at any size (tests/test_hardening_newcomer.py
checks that rendering every mode afterwards compiles nothing). A warm cache makes this a
few seconds.
"""
from __future__ import annotations

import sys
import time

from world import jit_notice
from viewer.glcontext import create_headless
from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODES
from viewer.render.renderer import Renderer
from world.loader import builtin_scene_names, builtin_scene_path, load_scene

SIZE = (64, 36)


def variants(mode: str) -> list[ParamSet]:
    """The parameter sets whose kernels differ: the hybrid with and without the range
    check; the reference with 2 sub-frames (its kernels do not depend on how many)."""
    out = []
    for range_check in ((False, True) if mode == "hybrid" else (None,)):
        params = ParamSet()
        params.set("reference.samples", 2)
        if range_check is not None:
            params.set("hybrid.range_check", range_check)
        out.append(params)
    return out


def warm_up(size=SIZE) -> int:
    """Render the frames; the number of kernels numba compiled (cache misses)."""
    jit_notice.install()
    ctx = create_headless()
    for name in builtin_scene_names():
        scene = load_scene(builtin_scene_path(name))
        r = Renderer(ctx, scene, size)
        try:
            for mode in MODES:
                for params in variants(mode):
                    for k in range(2):
                        r.render(mode, scene.render.time + k / 60.0, params, seed=k)
        finally:
            r.release()
    ctx.release()
    return jit_notice.install().compiled


def main() -> int:
    t0 = time.perf_counter()
    n = warm_up()
    print(f"warmup: {n} kernels compiled and cached in {time.perf_counter() - t0:.0f} s "
          "(every mode's)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
