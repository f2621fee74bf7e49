"""Conventions that several modules must agree on, stated once.

Pixel centres: pixel (i, j) of a written image (column i from the left, row j from the
top) samples the ray through (i + 0.5, j + 0.5). GL framebuffers are bottom-up, images are
top-down: `flip_row` maps a row index between the two and `to_image` applies the same map
to a whole array; every row flip goes through one of them (the compiled kernels inline
flip_row).

Object ids: object k of the scene file (1-based, file order) is written as k into an
unsigned integer target cleared to 0, so 0 means "background" with no offset.

Velocity: the G-buffer's velocity is the full screen-space displacement of the surface
point over the exposure, `p(t + shutter/2) - p(t - shutter/2)`, in pixels of the
framebuffer, in GL window axes (x to the right, y UP). The filters blur from -v/2 to +v/2.

Exposure: the frame at time t with shutter s integrates [t - s/2, t + s/2] (centred on
t); N stratified times over it are t - s/2 + (k + 0.5) s/N, k = 0 .. N-1 (the reference's
sharp sub-frames, the sub-exposure steps' centres).

Depth: linear view depth (distance along the camera's forward axis, positive, metres).
Pixels that hit nothing get BACKGROUND_DEPTH, finite so that differences stay finite.
"""
from __future__ import annotations

import numpy as np

BACKGROUND_DEPTH = 1.0e9


def flip_row(y, height):
    """GL row y (from the bottom) of a `height`-row framebuffer -> image row (from the
    top), and back: the flip is its own inverse. Plain arithmetic, so numba compiles it."""
    return height - 1 - y


def to_image(gl_rows: np.ndarray) -> np.ndarray:
    """GL bottom-up rows -> image top-down rows (and back): flip_row on the first axis,
    row k of the result being row flip_row(k, height) of the input."""
    return np.ascontiguousarray(gl_rows[::-1])


def pixel_centres_ndc(i, j, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """NDC (x right, y up) of the centre of image pixel (i, j), j counted from the top."""
    x = (np.asarray(i, dtype=np.float64) + 0.5) / width * 2.0 - 1.0
    y = 1.0 - (np.asarray(j, dtype=np.float64) + 0.5) / height * 2.0
    return x, y


def exposure(t: float, shutter: float) -> tuple[float, float]:
    """(open, close) of the exposure of the frame at time t."""
    return t - 0.5 * shutter, t + 0.5 * shutter


def sample_times(t: float, shutter: float, n: int) -> np.ndarray:
    """The n stratified times t - s/2 + (k + 0.5) s / n, k = 0 .. n-1."""
    return t - 0.5 * shutter + (np.arange(n) + 0.5) * shutter / n


def glsl_defines() -> dict[str, str]:
    """Constants that GLSL needs from here, injected as #defines (never written twice)."""
    return {"BACKGROUND_DEPTH": f"{BACKGROUND_DEPTH:.1f}"}
