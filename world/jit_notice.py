"""One line on stderr before numba compiles the project's kernels, with the expected wait.

The kernels (`raytrace/kernels.py`, `viewer/render/passes/tile_kernels.py`,
`viewer/render/modes/hybrid/reveal_kernels.py`, the camera's rays in `world/camera.py`) are
compiled on the first hybrid frame and cached on disk beside their modules
(`__pycache__`), so a later process loads them in well under a second; `scripts/setup.sh`
compiles them ahead (`python -m viewer.cli.warmup`). Where the cache is cold anyway (an install that skipped
the set-up, or kernels just edited), the user sees why the first frame waits. numba fires
its "numba:compile" event only on a cache miss, so a warm cache prints nothing.
"""
from __future__ import annotations

import sys

from numba.core import event

EXPECTED_S = 40          # seconds the notice announces: the whole set on one core
PACKAGES = ("world.", "viewer.", "raytrace.")


class CompileNotice(event.Listener):
    """Prints the notice at the first compile of a kernel of PACKAGES (once a process) and
    counts them."""

    def __init__(self, stream=None):
        self.stream = stream
        self.compiled = 0

    def on_start(self, ev):
        func = getattr(ev.data["dispatcher"], "py_func", None)
        if not getattr(func, "__module__", "").startswith(PACKAGES):
            return
        self.compiled += 1
        if self.compiled == 1:
            print(f"hmblur: compiling the ray-tracing kernels, once (about {EXPECTED_S} s; "
                  f"cached on disk for later runs)", file=self.stream or sys.stderr,
                  flush=True)

    def on_end(self, ev):
        pass


_NOTICE = CompileNotice()
_installed = False


def install() -> CompileNotice:
    """Register the notice with numba (once a process): the CLI and the warm-up call this
    before any work; importing a kernel module registers nothing."""
    global _installed
    if not _installed:
        event.register("numba:compile", _NOTICE)
        _installed = True
    return _NOTICE
