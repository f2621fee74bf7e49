"""Viewable 8-bit pictures of raw buffers (for `--buffers` dumps), chosen by buffer kind."""
from __future__ import annotations

import numpy as np

from world.conventions import BACKGROUND_DEPTH
from .imageio import linear_to_srgb8


def colour_wheel(v: np.ndarray, scale: float | None = None) -> np.ndarray:
    """Velocity (H, W, 2) as colour: hue = direction (GL axes), value = length / scale."""
    mag = np.hypot(v[..., 0], v[..., 1])
    scale = scale or max(float(mag.max()), 1e-6)
    hue = (np.arctan2(v[..., 1], v[..., 0]) / (2 * np.pi)) % 1.0
    val = np.clip(mag / scale, 0.0, 1.0)
    k = (hue[..., None] * 6.0 + np.array([5.0, 3.0, 1.0])) % 6.0
    rgb = val[..., None] * (1.0 - np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0))
    return (rgb * 255.0 + 0.5).astype(np.uint8)


def id_colours(ids: np.ndarray) -> np.ndarray:
    """Distinct colours per id (0 = black), the same for every run."""
    h = (ids.astype(np.uint64) * np.uint64(2654435761)) & np.uint64(0xFFFFFF)
    rgb = np.stack([(h >> np.uint64(s)) & np.uint64(255) for s in (16, 8, 0)], -1).astype(np.uint8)
    rgb[ids == 0] = 0
    return rgb | np.where(ids[..., None] == 0, 0, 64).astype(np.uint8)


def depth_grey(d: np.ndarray) -> np.ndarray:
    hit = d < BACKGROUND_DEPTH * 0.5
    if not hit.any():
        return np.zeros(d.shape, np.uint8)
    ld = np.log(np.maximum(d, 1e-6))
    lo, hi = ld[hit].min(), ld[hit].max()
    g = 1.0 - (ld - lo) / max(hi - lo, 1e-6)
    return np.where(hit, g * 220 + 35, 0).clip(0, 255).astype(np.uint8)


def scalar_grey(a: np.ndarray) -> np.ndarray:
    a = np.nan_to_num(a.astype(np.float64))
    hi = max(float(np.abs(a).max()), 1e-12)
    return (np.abs(a) / hi * 255 + 0.5).astype(np.uint8)


def visualise(name: str, a: np.ndarray) -> np.ndarray:
    """Pick a visualisation from the buffer's name and shape."""
    base = name.rsplit("_", 1)[-1] if name.startswith("sub_") else name
    if a.dtype == np.uint32 or "id" in base.split("_"):
        return id_colours(a if a.ndim == 2 else a[..., 0])
    if "depth" in base:
        return depth_grey(a if a.ndim == 2 else a[..., 0])
    if "normal" in base:
        n = a[..., :3].astype(np.float64)
        return ((n * 0.5 + 0.5).clip(0, 1) * 255 + 0.5).astype(np.uint8)
    if a.ndim == 3 and a.shape[2] == 2:
        return colour_wheel(a.astype(np.float64))
    if a.ndim == 3 and a.shape[2] == 4 and any(w.startswith("path") for w in base.split("_")):
        return colour_wheel(a[..., :2].astype(np.float64))      # the first point's offset
    if a.ndim == 3 and a.shape[2] == 4 and ("tile" in base or "neighbor" in base or "max" in base):
        return colour_wheel(a[..., 2:4].astype(np.float64))
    if a.ndim == 3 and a.shape[2] >= 3:
        return linear_to_srgb8(a[..., :3])
    return scalar_grey(a if a.ndim == 2 else a[..., 0])
