"""The depth test's convention, in one place: reversed Z in a 32-bit float depth buffer
where the driver can (GL 4.5 or ARB_clip_control), the standard mapping in the default
24-bit buffer elsewhere.

Why: the standard projection stores about 1 - near / d, so with a small `near` and
surfaces far away the window depth rounds to 1 in 24 bits (near 1e-4, a wall at 2000 m:
it vanishes; boxes 30 m apart at 1000 m: the farther shows through). Reversed Z stores
about near / d in a float, whose relative precision (~1e-7) holds at every distance.
moderngl exposes neither glClipControl nor a float depth attachment, so both are made
through the GL library itself (ctypes, the context current): the clip control once per
context, the float storage by re-specifying moderngl's depth texture.
"""
from __future__ import annotations

import ctypes
import ctypes.util

import moderngl
import numpy as np

from viewer.render.graph.framebuffers import park_framebuffer

GL_LOWER_LEFT, GL_ZERO_TO_ONE = 0x8CA1, 0x935F
GL_TEXTURE_2D, GL_DEPTH_COMPONENT32F = 0x0DE1, 0x8CAC
GL_DEPTH_COMPONENT, GL_FLOAT = 0x1902, 0x1406

_GL = None


def _gl():
    """The GL library whose entry points dispatch to the current context (GLVND's
    libOpenGL, else libGL), or None."""
    global _GL
    if _GL is None:
        _GL = False
        for name in ("OpenGL", "GL"):
            path = ctypes.util.find_library(name)
            try:
                lib = ctypes.CDLL(path or f"lib{name}.so.{0 if name == 'OpenGL' else 1}")
                lib.glClipControl, lib.glTexImage2D, lib.glBindTexture   # all present?
            except (OSError, AttributeError):
                continue
            _GL = lib
            break
    return _GL or None


def reversed_z(ctx: moderngl.Context) -> bool:
    """Whether `ctx` draws with reversed Z (clip control [0, 1] set; asked once a context,
    the answer kept on it)."""
    if not isinstance(ctx.extra, dict):
        ctx.extra = {}
    known = ctx.extra.get("reversed_z")
    if known is not None:
        return known
    ok = (ctx.version_code >= 450 or "GL_ARB_clip_control" in ctx.extensions) \
        and _gl() is not None
    if ok:
        _gl().glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)
        ok = ctx.error == "GL_NO_ERROR" and _clips_below_zero(ctx)
    ctx.extra["reversed_z"] = ok
    return ok


def _clips_below_zero(ctx: moderngl.Context) -> bool:
    """Whether the clip control took effect in `ctx` (the library's entry point may reach
    another context or none): a point at clip z = -w/2 is drawn under GL's default [-1, 1]
    depth range and clipped under [0, 1]."""
    prog = ctx.program(
        vertex_shader="#version 330 core\nvoid main() { gl_Position = vec4(0, 0, -0.5, 1); }",
        fragment_shader="#version 330 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }")
    vao = ctx.vertex_array(prog, [])
    try:
        park_framebuffer(ctx)                     # a 1x1 target that lives with ctx
        fbo = ctx.extra["parking_fbo"]
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        vao.render(moderngl.POINTS, vertices=1)
        return fbo.read(components=4)[0] == 0
    finally:
        vao.release()
        prog.release()


def depth_texture(ctx: moderngl.Context, size: tuple[int, int]) -> moderngl.Texture:
    """A depth attachment: 32-bit float under reversed Z, moderngl's 24-bit otherwise."""
    tex = ctx.depth_texture(size)
    if reversed_z(ctx):
        gl = _gl()
        ctx.error                                    # (start from a clean slate)
        gl.glBindTexture(GL_TEXTURE_2D, tex.glo)
        gl.glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, size[0], size[1], 0,
                        GL_DEPTH_COMPONENT, GL_FLOAT, None)
        gl.glBindTexture(GL_TEXTURE_2D, 0)
        if ctx.error != "GL_NO_ERROR":
            raise RuntimeError("could not make a 32-bit float depth buffer")
    return tex


def projection(ctx: moderngl.Context, standard: np.ndarray, near: float, far: float
               ) -> np.ndarray:
    """The projection the rasteriser draws with: `standard` (OpenGL's, clip z in [-w, w])
    or, under reversed Z, the same with clip z = near (far - d) / (far - near) for view
    depth d: 1 at near, 0 at far, and clipping still exactly at near and far (0 <= z <= w
    with clip control [0, 1])."""
    if not reversed_z(ctx):
        return standard
    p = standard.copy()
    p[2, :] = (0.0, 0.0, near / (far - near), near * far / (far - near))
    return p


def clear_value(ctx: moderngl.Context) -> float:
    return 0.0 if reversed_z(ctx) else 1.0


def nearer(ctx: moderngl.Context) -> str:
    """The depth function that keeps the nearer fragment."""
    return ">" if reversed_z(ctx) else "<"
