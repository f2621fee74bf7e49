"""Shared fixtures: one EGL context for the whole run (checked for GL errors around every
test that uses it), and frames over synthetic buffers for single-pass tests.

Locally, GL tests are skipped with a reason when no EGL context can be made; under CI
(CI=true) a missing context is a failure, never a silent skip.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
CONFORMANCE = Path(__file__).resolve().parent / "conformance"

_ctx = None


def _context():
    global _ctx
    if _ctx is None:
        from viewer.glcontext import create_headless
        from world.errors import UserError
        try:
            _ctx = create_headless()
        except UserError as exc:
            if os.environ.get("CI"):
                raise
            pytest.skip(f"no EGL context: {exc}")
    # Current again: a command run in-process (`main(["shot", ...])`) makes its own
    # context current, and GL calls on this one would then go to that one.
    _ctx.__enter__()
    return _ctx


@pytest.fixture
def ctx():
    c = _context()
    assert c.error == "GL_NO_ERROR"
    yield c
    assert c.error == "GL_NO_ERROR"


def scene_from(tmp_path, text, name="s"):
    """A scene loaded from TOML text (indented as a triple-quoted string in a test)."""
    import textwrap
    from world.loader import load_scene
    p = tmp_path / f"{name}.toml"
    p.write_text(textwrap.dedent(text))
    return load_scene(p)


def srgb_to_linear(srgb) -> np.ndarray:
    """sRGB values in [0, 1] -> linear, in float64: the sRGB decoding written out, the
    oracle for world/images.py's."""
    c = np.asarray(srgb, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


def srgb8_to_linear(srgb8) -> np.ndarray:
    """uint8 sRGB -> float32 linear (the sRGB decoding, in float64): the inverse of
    imageio.linear_to_srgb8, for tests that start from 8-bit pictures."""
    return srgb_to_linear(np.asarray(srgb8, dtype=np.float64) / 255.0).astype(np.float32)


def empty_scene(shutter: float = 0.04):
    from world.scene import CameraSpec, Scene
    cam = CameraSpec(position=np.array([0.0, 0.0, 5.0]), look_at=np.zeros(3), fov_y=45.0,
                     shutter=shutter)
    return Scene("synthetic", None, cam)


@pytest.fixture
def synthetic_frame(ctx):
    """make(size, params=None, seed=0) -> a Frame over an empty scene; upload buffers with
    frame.pool.texture(name, spec) then frame.write(name, array) (image orientation)."""
    from world.camera import Camera
    from viewer.render.graph.params import ParamSet
    from viewer.render.graph.frame import Frame
    from viewer.render.graph.gpu_scene import GpuScene
    from viewer.render.graph.pool import ResourcePool
    from viewer.render.graph.shaders import ProgramCache
    made = []

    def make(size, params=None, seed=0, scene=None):
        scene = scene or empty_scene()
        pool = ResourcePool(ctx)
        pool.resize(size)
        programs = ProgramCache(ctx)
        gpu = GpuScene(ctx, scene)
        made.append((pool, programs, gpu))
        return Frame(ctx, pool, programs, gpu, Camera(scene.camera, *size), 0.0,
                     params or ParamSet(), seed=seed)

    yield make
    for pool, programs, gpu in made:
        pool.release(), programs.clear(), gpu.release()


def default_signals():
    """preexec_fn of a child that must end on a signal: SIGINT, SIGTERM and SIGHUP at their
    defaults whatever the suite was started under (a background job ignores SIGINT,
    nohup SIGHUP, and a child inherits that)."""
    import signal
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
