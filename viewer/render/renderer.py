"""The render core's front door: a scene, a size and a context in; images and named
buffers out. The caller owns the context (EGL for the CLI and tests, GLFW for the viewer)."""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import moderngl
import numpy as np

from world.camera import Camera
from world.conventions import exposure
from world.path_bend import screen_bend
from world.errors import UserError
from viewer.render.graph.params import ParamSet
from world.scene import Scene
from viewer.render.graph.shaders import ProgramCache
from viewer.render.graph.allocator import keep_freed_memory
from viewer.render.graph.frame import Frame, PassTimer
from viewer.render.graph.gpu_scene import GpuScene
from viewer.render.graph.host import HostResources
from viewer.render.graph.kept import KeptState
from .modes import MODE_GROUPS, MODES
from .modes.user import USER_GROUPS, UserPass, user_pipeline
from .modes.user.pipeline import compile_glsl
from viewer.render.graph.registry import mode_config
from viewer.render.graph.pool import ResourcePool
from viewer.render.steps import (BEND, SCENE_POSE, SUM, MakeFrame, Measure, run_steps,
                                 step_count, sub_exposures)


@dataclass
class RenderResult:
    mode: str
    image: np.ndarray                    # linear RGB float32, (H, W, 3), top row first
    stats: dict = field(default_factory=dict)
    pass_ms: dict = field(default_factory=dict)
    host: HostResources = field(default_factory=HostResources)   # e.g. reference.REGIONS


class Renderer:
    def __init__(self, ctx: moderngl.Context, scene: Scene, size: tuple[int, int]):
        self.ctx, self.scene = ctx, scene
        keep_freed_memory()          # frame-sized host arrays reused, not re-faulted
        w, h = self._check_size(size)
        self.programs = ProgramCache(ctx)
        self.gpu = GpuScene(ctx, scene)
        self.pool = ResourcePool(ctx)
        self.pool.resize((w, h))
        self.camera = Camera(scene.camera, w, h)     # resize() makes it again
        self._pipelines: dict = {}
        self.methods: dict[str, UserPass] = {}   # user blur passes, by the name they run as
        self.kept = KeptState()          # state kept across frames (e.g. the ray tracer)
        self.made: list[str] = []        # the textures the last frame made, in order

    def _check_size(self, size):
        w, h = int(size[0]), int(size[1])
        limit = min(self.ctx.info["GL_MAX_TEXTURE_SIZE"], *self.ctx.info["GL_MAX_VIEWPORT_DIMS"])
        if not (1 <= w <= limit and 1 <= h <= limit):
            raise UserError(f"--size {w}x{h}: expected 1 to {limit} pixels per side (GL limit)")
        return w, h

    def resize(self, size: tuple[int, int]):
        w, h = self._check_size(size)
        self.pool.resize((w, h))
        self.camera = Camera(self.scene.camera, w, h)

    @property
    def size(self) -> tuple[int, int]:
        return self.pool.size

    def add_method(self, name: str, method: UserPass):
        """Register a user's blur pass to render as `name` (viewer/render/modes/user/),
        beside the modes; a shader is compiled now, so that a mistake in it stops the
        caller before any frame. A name may be registered again (the latest method runs)."""
        if name in MODES:
            raise UserError(f"method {name} ({method.spec}): {name} is a built-in mode; "
                            "give the method another name")
        if method.kind == "glsl":
            compile_glsl(self.programs, method, name)
        self.methods[name] = method

    def groups(self, mode: str) -> tuple[str, ...]:
        """The parameter groups `mode` (or a user pass registered under that name) reads."""
        return USER_GROUPS if mode in self.methods else MODE_GROUPS.get(mode, ())

    def pipeline(self, mode: str, params: ParamSet | None = None):
        """`mode`'s pipeline for its configuration under `params` (None: the defaults),
        built once per (mode, configuration) (viewer/render/graph/registry.py); a user
        pass's once per (name, method)."""
        if mode in self.methods:
            key = (mode, self.methods[mode])
            if key not in self._pipelines:
                self._pipelines[key] = user_pipeline(mode, self.methods[mode])
            return self._pipelines[key]
        if mode not in MODES:
            known = [*MODES, *self.methods]
            raise UserError(f"--mode {mode}: expected one of {', '.join(known)}")
        key = (mode, mode_config(mode, params))
        if key not in self._pipelines:
            self._pipelines[key] = MODES[mode](key[1])
        return self._pipelines[key]

    def frame(self, t: float, params: ParamSet, seed: int = 0, timing: bool = False,
              shutter: float | None = None, record_visibility: bool = False,
              progress=None) -> Frame:
        """A frame at t; `shutter` None: the scene camera's (read now, as the viewer may
        change it between frames). The frame shares the renderer's kept state."""
        return Frame(self.ctx, self.pool, self.programs, self.gpu, self.camera, float(t),
                     params, seed=seed, timing=timing, kept=self.kept, shutter=shutter,
                     record_visibility=record_visibility, progress=progress)

    def run(self, mode: str, t: float, params: ParamSet, seed: int, make_frame: MakeFrame,
            measure: Measure = PassTimer) -> Frame:
        """The frame at t of `mode`, as its sub-exposure steps (viewer/render/steps.py):
        `make_frame(time, shutter, seed)` makes each sub-frame, Pipeline.run runs the
        mode's passes on it, each inside `measure(frame, name)`, and the accumulation."""
        shutter = float(self.scene.camera.shutter)
        bend = {}

        def measure_bend() -> float:
            t0, c0 = time.perf_counter(), time.thread_time()
            bend["px"] = screen_bend(self.scene, self.camera, float(t), shutter)
            bend["ms"] = (time.perf_counter() - t0) * 1e3
            bend["cpu_ms"] = (time.thread_time() - c0) * 1e3
            return bend["px"]
        n = step_count(mode, params, shutter, measure_bend, self.groups(mode))
        pose = self._pose(float(t), shutter, n) if self.scene.assets else None
        pipeline = self.pipeline(mode, params)
        self.pool.begin()
        frame = run_steps(make_frame, pipeline, float(t), shutter, seed, n, measure)
        self.made = [n for n in (*pipeline.textures(), SUM) if n in self.pool.made]
        if pose is not None:   # (host work before the first pass: reported as one of them)
            frame.pass_ms[SCENE_POSE], frame.pass_cpu_ms[SCENE_POSE] = pose[:2]
            frame.stats["skinned_vertices"] = pose[2]
        if bend:         # (host work before the first pass: reported as one of them)
            frame.stats["bend_px"] = bend["px"]
            frame.pass_ms[BEND] = bend["ms"]
            frame.pass_cpu_ms[BEND] = bend["cpu_ms"]
        return frame

    def _pose(self, t: float, shutter: float, steps: int):
        """The glTF entries' poses (node matrices, skinned vertices) at the frame's times
        (each sub-frame's t and shutter ends), evaluated once: (ms, CPU ms, vertices)."""
        t0, c0 = time.perf_counter(), time.thread_time()
        times = set()
        for tk, sk, _ in sub_exposures(t, shutter, 0, steps):
            times.update((tk, *exposure(tk, sk)))
        n = self.scene.pose(sorted(times))
        return (time.perf_counter() - t0) * 1e3, (time.thread_time() - c0) * 1e3, n

    def render(self, mode: str, t: float, params: ParamSet | None = None, seed: int = 0,
               timing: bool = False, record_visibility: bool = False,
               read_image: bool = True, progress=None) -> RenderResult:
        """`progress(k, n)` is called as long passes (the reference) advance."""
        params = params or ParamSet()
        pipe = self.pipeline(mode, params)

        def make_frame(tk, shutter, seed_k):
            return self.frame(tk, params, seed_k, timing, shutter=shutter,
                              record_visibility=record_visibility, progress=progress)
        frame = self.run(mode, t, params, seed, make_frame)
        image = frame.read(pipe.output)[..., :3].copy() if read_image else None
        return RenderResult(mode, image, frame.stats, frame.pass_ms, frame.host)

    def output_name(self, mode: str) -> str:
        return self.pipeline(mode).output         # (the same under every configuration)

    def buffers(self) -> dict[str, np.ndarray]:
        """Every texture the last frame made, image orientation, in pipeline order (the
        pool may also hold textures of other modes and configurations run before)."""
        from viewer.render.graph.frame import read_texture
        return {n: read_texture(self.pool.get(n)) for n in self.made}

    def release(self):
        self.kept.release()
        self.pool.release()
        self.programs.clear()
        self.gpu.release()
