"""Per-pass timing for the overlay, and rendering a mode with it.

Software GL (llvmpipe, softpipe, SwiftShader) answers GL timer queries with the time the
commands were submitted, not run, so there the passes are timed on the CPU clock with
ctx.finish() around each (frame.PassTimer). Where the driver is a real GPU, GL_TIME_ELAPSED
queries time the passes without stalling the CPU between them.
"""
from __future__ import annotations

import time
from contextlib import contextmanager

import moderngl

from viewer.render.graph.params import ParamSet
from viewer.render.graph.frame import Frame, PassTimer, add_cpu_ms
from viewer.render.renderer import Renderer

SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "swiftshader", "software rasterizer", "swrast")


def gpu_timers_truthful(ctx: moderngl.Context) -> bool:
    renderer = str(ctx.info.get("GL_RENDERER", "")).lower()
    return not any(name in renderer for name in SOFTWARE_RENDERERS)


def describe(method: str) -> str:
    """One line for the overlay: how the pass times were measured."""
    return {"cpu": "CPU clock + ctx.finish()", "gpu": "GPU timer queries"}[method]


class PassClock:
    def __init__(self, ctx: moderngl.Context, method: str | None = None):
        self.ctx = ctx
        self.method = method or ("gpu" if gpu_timers_truthful(ctx) else "cpu")
        self._queries: dict[str, moderngl.Query] = {}

    def frame(self, renderer: Renderer, t: float, params: ParamSet, seed: int) -> Frame:
        return renderer.frame(t, params, seed, timing=self.method == "cpu")

    @contextmanager
    def measure(self, frame: Frame, name: str):
        """Time the work inside into frame.pass_ms[name] (added up if repeated), and the
        main thread's CPU time in it into frame.pass_cpu_ms[name]."""
        if self.method == "cpu":
            with PassTimer(frame, name):
                yield
            return
        q = self._queries.get(name)
        if q is None:
            q = self._queries[name] = self.ctx.query(time=True)
        c0 = time.thread_time()
        with q:
            yield
        add_cpu_ms(frame, name, c0)
        frame.pass_ms[name] = frame.pass_ms.get(name, 0.0) + q.elapsed / 1e6

    def render(self, renderer: Renderer, mode: str, t: float, params: ParamSet, seed: int) -> Frame:
        """Run every pass of `mode`, as its sub-exposure steps where set (the image stays
        on the GPU, in the pool)."""
        def make_frame(tk, shutter, seed_k):
            return renderer.frame(tk, params, seed_k, timing=self.method == "cpu",
                                  shutter=shutter)
        return renderer.run(mode, t, params, seed, make_frame, measure=self.measure)

    # Queries are kept, one per pass name, for the context's lifetime: moderngl 5 has no
    # Query.release(), and reusing them keeps the count bounded.
