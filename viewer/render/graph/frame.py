"""What one frame's passes share: the context, the pool, the scene, the camera, the time
and the exposure."""
from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from typing import Callable

import moderngl
import numpy as np

from world.camera import Camera
from world import conventions
from world.conventions import to_image
from viewer.render.graph.params import ParamSet
from viewer.render.graph.shaders import ProgramCache
from viewer.render.graph.gpu_scene import GpuScene
from .host import HostResources
from .kept import KeptState
from .pool import ResourcePool


@dataclass
class Frame:
    ctx: moderngl.Context
    pool: ResourcePool
    programs: ProgramCache
    gpu: GpuScene
    camera: Camera
    time: float
    params: ParamSet
    seed: int = 0
    timing: bool = False                       # finish() around each pass, CPU clock
    stats: dict = field(default_factory=dict)  # counters: masked pixels, rays, ...
    pass_ms: dict = field(default_factory=dict)
    # Main-thread CPU time of each timed pass (time.thread_time: Python, numba, Embree
    # calls on this thread and the driver's work here; not the waits for the GPU or
    # llvmpipe's rasteriser threads): how much of a pass is host work.
    pass_cpu_ms: dict = field(default_factory=dict)
    # This frame's host-side results, declared by the passes that make and read them
    # (viewer/render/graph/host.py).
    host: HostResources = field(default_factory=HostResources)
    # State kept across frames, the Renderer's (a frame made on its own gets its own).
    kept: KeptState = field(default_factory=KeptState)
    # What the caller asks for: every reference sub-frame's visibility, classified into
    # the evaluation regions (host resource `regions`); progress(k, n) as long passes
    # (the reference) advance.
    record_visibility: bool = False
    progress: Callable[[int, int], None] | None = None
    # GpuScene.object_matrices of this frame's objects by (id, t, t_open, t_close): the
    # camera and the objects hold still for a frame, and several passes ask.
    object_matrices: dict = field(default_factory=dict)
    # The exposure's length (s), centred on `time`: every pass reads the exposure from here,
    # never from the scene's camera, so that a sub-exposure step (viewer/render/steps.py)
    # is a frame with a shorter shutter. None: the scene camera's shutter, when made.
    shutter: float | None = None

    def __post_init__(self):
        if self.shutter is None:
            self.shutter = float(self.scene.camera.shutter)

    @property
    def scene(self):
        return self.gpu.scene

    @property
    def size(self) -> tuple[int, int]:
        return self.pool.size

    @property
    def exposure(self) -> tuple[float, float]:
        """(open, close) of this frame's exposure."""
        return self.exposure_at(self.time)

    def exposure_at(self, t: float) -> tuple[float, float]:
        """(open, close) of an exposure of this frame's shutter centred on t."""
        return conventions.exposure(t, self.shutter)

    def sample_times(self, n: int) -> np.ndarray:
        """n stratified times over this frame's exposure (conventions.sample_times)."""
        return conventions.sample_times(self.time, self.shutter, n)

    def read(self, name: str) -> np.ndarray:
        """A pool texture read back (ResourcePool.read_back: a pass must declare it) as
        numpy, image orientation (top row first), (H, W) or (H, W, C)."""
        return texture_array(self.pool.get(name), self.pool.read_back(name))

    def write(self, name: str, array: np.ndarray):
        """Upload an image-orientation array into the pool texture `name` (already allocated)."""
        self.pool.check_write((name,))
        tex = self.pool.get(name)
        a = np.asarray(array, dtype=_NP[tex.dtype])
        if a.ndim == 2:
            a = a[..., None]
        if a.shape != (tex.size[1], tex.size[0], tex.components):
            raise ValueError(f"{name}: array {a.shape} does not fit texture "
                             f"{(tex.size[1], tex.size[0], tex.components)}")
        tex.write(to_image(a).tobytes())
        self.pool.mark_written((name,))


_NP = {"f4": np.float32, "f2": np.float16, "u4": np.uint32, "u1": np.uint8, "i4": np.int32}


def read_texture(tex: moderngl.Texture) -> np.ndarray:
    """A texture as numpy, image orientation (the caller's read, after a frame)."""
    return texture_array(tex, tex.read())


def texture_array(tex: moderngl.Texture, data: bytes) -> np.ndarray:
    """`data`, the whole of `tex` read back, as numpy in image orientation."""
    w, h = tex.size
    a = np.frombuffer(data, dtype=_NP[tex.dtype]).reshape(h, w, tex.components)
    a = to_image(a)
    return a[..., 0] if tex.components == 1 else a


class PassTimer:
    """Synchronised CPU timing of a pass: ctx.finish() before and after (llvmpipe's timer
    queries report only submission time, so they are not used for the numbers we report)."""

    def __init__(self, frame: Frame, name: str):
        self.frame, self.name = frame, name
        self.t0 = self.c0 = 0.0        # the clocks when the pass began (__enter__)

    def __enter__(self):
        if self.frame.timing:
            self.frame.ctx.finish()
            self.t0 = _time.perf_counter()
            self.c0 = _time.thread_time()
        return self

    def __exit__(self, *exc):
        if self.frame.timing and exc[0] is None:
            add_cpu_ms(self.frame, self.name, self.c0)
            self.frame.ctx.finish()
            ms = (_time.perf_counter() - self.t0) * 1e3
            self.frame.pass_ms[self.name] = self.frame.pass_ms.get(self.name, 0.0) + ms


def add_cpu_ms(frame: Frame, name: str, c0: float):
    """Add the main thread's CPU time since thread_time() read c0 to pass `name`."""
    ms = (_time.thread_time() - c0) * 1e3
    frame.pass_cpu_ms[name] = frame.pass_cpu_ms.get(name, 0.0) + ms
