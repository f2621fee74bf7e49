"""Draw any pool texture, by name, into a framebuffer: the viewer's buffer view.

One shader (glsl/passes/debug_view.frag) holds every visualisation; which one is used follows the
buffer's name and format with the same rules as `viewer.io.visualize.visualise` (the CLI's
`--buffers` pictures), so a buffer looks the same in the window and in a dump. Ranges that
depend on the data (depth's log range, the longest velocity, a mask's largest value) are
measured from the texture itself on the host.
"""
from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from world.conventions import BACKGROUND_DEPTH, glsl_defines
from viewer.render.graph.shaders import ProgramCache
from viewer.render.graph.frame import read_texture
from viewer.render.graph.gpu_scene import set_uniform
from viewer.render.graph.pool import ResourcePool, TexSpec

KINDS = ("colour", "depth", "normal", "id", "velocity", "tiles", "scalar")
# moderngl's u1/u2/u4 and i1/i2/i4 are integer formats (usampler/isampler); f1, f2, f4 float.
SOURCE_UINT, SOURCE_INT = 1, 2      # SOURCE_TYPE codes; 0 float or normalised
_SOURCE_TYPE = {"u1": SOURCE_UINT, "u2": SOURCE_UINT, "u4": SOURCE_UINT,
                "i1": SOURCE_INT, "i2": SOURCE_INT, "i4": SOURCE_INT}


def view_defines(dtype: str) -> dict:
    """glsl/passes/debug_view.frag's defines: the source's sampler type and the codes of
    SOURCE_TYPE and of u_kind (KIND_<NAME>: the index in KINDS)."""
    return {"SOURCE_TYPE": _SOURCE_TYPE.get(dtype, 0), "SOURCE_UINT": SOURCE_UINT,
            "SOURCE_INT": SOURCE_INT, **{f"KIND_{k.upper()}": i for i, k in enumerate(KINDS)}}


def auto_kind(name: str, spec: TexSpec, dtype: str | None = None) -> tuple[str, int]:
    """(visualisation, first channel) for a buffer, from its name and format."""
    dtype = dtype or spec.dtype
    base = name.rsplit("_", 1)[-1] if name.startswith("sub_") else name
    words = base.split("_")
    if dtype == "u4" or "id" in words:
        return "id", 0
    if "depth" in base:
        return "depth", 0
    if "normal" in base:
        return "normal", 0
    if any(w.startswith("path") for w in words):    # path offsets, two points a texel
        return "velocity", 0
    if spec.tile > 1 and spec.components >= 2:      # per-tile vectors; of 4, the max in .zw
        return "tiles", 2 if spec.components == 4 else 0
    if spec.components == 2:
        return "velocity", 0
    if spec.components == 4 and ("tile" in base or "neighbor" in base or "max" in base):
        return "velocity", 2
    if spec.components >= 3:
        return "colour", 0
    return "scalar", 0


@dataclass
class ViewSettings:
    """How the buffer view shows a texture; "auto" picks from the name and format."""
    kind: str = "auto"
    channel: int | None = None        # None: the automatic choice
    gain: float = 1.0                 # colour only: multiplier (a progressive mean's n / k)
    scale: float | None = None        # velocity/tiles/scalar full scale; None: the data's max


def data_range(kind: str, a: np.ndarray, channel: int = 0) -> tuple[float, float]:
    """What the visualisation normalises by, measured as visualize.py does."""
    a = a if a.ndim == 3 else a[..., None]
    if kind == "depth":
        d = a[..., 0].astype(np.float64)
        hit = d < BACKGROUND_DEPTH * 0.5
        if not hit.any():
            return 0.0, 1.0
        ld = np.log(np.maximum(d[hit], 1e-6))
        return float(ld.min()), float(ld.max())
    if kind in ("velocity", "tiles"):
        v = np.nan_to_num(a[..., channel:channel + 2].astype(np.float64))
        mag = np.hypot(v[..., 0], v[..., 1]) if v.shape[-1] == 2 else np.abs(v[..., 0])
        return 0.0, max(float(mag.max()), 1e-6)
    if kind == "scalar":
        x = np.nan_to_num(a[..., min(channel, a.shape[-1] - 1)].astype(np.float64))
        return 0.0, max(float(np.abs(x).max()), 1e-12)
    return 0.0, 1.0


class DebugView:
    """Draws pool textures with glsl/passes/debug_view.frag; programs come from the renderer's cache."""

    def __init__(self, programs: ProgramCache):
        self.programs = programs

    def resolve(self, pool: ResourcePool, name: str, settings: ViewSettings) -> tuple[str, int]:
        tex = pool.get(name)
        kind, channel = auto_kind(name, pool.spec(name), tex.dtype)
        if settings.kind != "auto":
            kind = settings.kind
        if settings.channel is not None:
            channel = settings.channel
        return kind, max(0, min(channel, tex.components - 1))

    def draw(self, target: moderngl.Framebuffer, pool: ResourcePool, name: str,
             settings: ViewSettings | None = None, dest: tuple[int, int, int, int] | None = None) -> str:
        """Draw pool texture `name` into `dest` (x, y, w, h; default: all of `target`).
        Returns the visualisation used."""
        settings = settings or ViewSettings()
        if settings.kind not in KINDS + ("auto",):
            raise ValueError(f"buffer view: unknown visualisation {settings.kind!r}")
        tex = pool.get(name)
        kind, channel = self.resolve(pool, name, settings)
        ctx = target.ctx
        prog = self.programs.get("graph/fullscreen.vert", "passes/debug_view.frag",
                                 {**glsl_defines(), **view_defines(tex.dtype)})
        dest = dest or (0, 0) + tuple(target.size)
        lo, hi = 0.0, 1.0
        gain = settings.gain
        if kind == "depth":
            lo, hi = data_range(kind, read_texture(tex))
        elif kind in ("velocity", "tiles", "scalar"):
            full = settings.scale or data_range(kind, read_texture(tex), channel)[1]
            gain = 1.0 / max(full, 1e-12)
        tex.use(0)
        set_uniform(prog, "u_src", 0)
        set_uniform(prog, "u_kind", KINDS.index(kind))
        set_uniform(prog, "u_dest", tuple(float(x) for x in dest))
        set_uniform(prog, "u_channel", int(channel))
        set_uniform(prog, "u_gain", float(gain))
        set_uniform(prog, "u_log_range", (float(lo), float(hi)))
        set_uniform(prog, "u_tile", int(pool.spec(name).tile))
        target.use()
        target.viewport = dest
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        self.programs.empty_vao(prog).render(moderngl.TRIANGLES, vertices=3)
        return kind
