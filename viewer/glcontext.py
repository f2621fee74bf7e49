"""Headless GL: an EGL standalone context for the CLI and tests (the viewer makes its own)."""
from __future__ import annotations

import moderngl

from world.errors import UserError

REQUIRED_GL = 330


def create_headless() -> moderngl.Context:
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=REQUIRED_GL)
    except Exception as exc:  # the driver's own words are appended, on one line
        detail = " ".join(str(exc).split())
        raise UserError(
            "no OpenGL 3.3 context through EGL: install an EGL driver (Debian: "
            f"apt-get install libegl1 libgl1-mesa-dri) or a GPU driver ({detail})") from None
    return ctx


def device_name(ctx: moderngl.Context) -> str:
    return f"{ctx.info['GL_RENDERER']} / {ctx.info['GL_VERSION']}"
