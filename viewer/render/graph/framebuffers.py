"""The context's parking framebuffer, bound before others are released: below both the
pool and the depth set-up, which bind it."""
from __future__ import annotations

import moderngl


def park_framebuffer(ctx: moderngl.Context):
    """Bind a 1x1 framebuffer that lives as long as the context before releasing others:
    moderngl re-binds its last bound framebuffer when it creates the next one, and a
    released one would leave GL_INVALID_OPERATION behind."""
    if not isinstance(ctx.extra, dict):
        ctx.extra = {}
    fbo = ctx.extra.get("parking_fbo")
    if fbo is None:
        fbo = ctx.extra["parking_fbo"] = ctx.framebuffer([ctx.renderbuffer((1, 1))])
    fbo.use()
