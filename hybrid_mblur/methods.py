"""User blur passes for the API: a GLSL fragment shader file, a Python file's function, or a
Python callable, to register with a Renderer beside the built-in modes
(viewer/render/modes/user/; docs/api.md says what a pass reads and writes).

A method file is code that runs, with your rights: load only files you would run."""
from __future__ import annotations

from os import PathLike
from pathlib import Path
from typing import Callable

from viewer.render.modes.user import BlurInputs, UserPass, parse_method
from viewer.render.modes.user.method import from_callable

__all__ = ["BlurInputs", "UserPass", "glsl_pass", "py_pass", "as_method"]


def glsl_pass(path: str | PathLike) -> UserPass:
    """A fragment shader file (`#version 330 core`, the samplers and uniforms of
    docs/api.md, writing `out vec4 out_color`); compiled when registered."""
    return parse_method(f"glsl:{Path(path)}")


def py_pass(source: str | PathLike | Callable, function: str | None = None) -> UserPass:
    """A Python function `f(inputs: BlurInputs) -> (H, W, 3) float array`: a callable
    (it runs in this process only), or the function named `function` in the file `source`
    (its top level runs now; the file's bytes travel to a sweep's workers)."""
    if callable(source):
        return from_callable(source, function)
    if function is None:
        raise TypeError("py_pass(path, function): the function's name is needed with a file")
    return parse_method(f"py:{Path(source)}:{function}")


def as_method(method: UserPass | str | Callable) -> UserPass:
    """A method from a UserPass, a `glsl:PATH` / `py:PATH:FUNCTION` text or a callable."""
    if isinstance(method, UserPass):
        return method
    if isinstance(method, str):
        return parse_method(method)
    return py_pass(method)
