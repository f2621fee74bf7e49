"""Animation curves of glTF samplers, and their sampling (SCENE_FORMAT.md, glTF scenes).

Rotations are unit quaternions in world/transforms.py's (w, x, y, z) order: the reader
reorders glTF's (x, y, z, w) keys as it reads them, and normalises the keys of STEP and
LINEAR rotation samplers (CUBICSPLINE keys are tangents: their curve's value is
normalised instead).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from world import transforms as tf

INTERPOLATIONS = ("STEP", "LINEAR", "CUBICSPLINE")


@dataclass
class GltfSampler:
    times: np.ndarray               # (n,) float64, strictly increasing, finite
    values: np.ndarray              # (n, c) or (n, 3, c) for CUBICSPLINE
    interpolation: str


def sample(sampler: GltfSampler, a: float, path: str) -> np.ndarray:
    """The channel value at animation time `a`: `a` clamped to the key range, segment i
    with k_i <= a < k_(i+1) (the last one at a = k_(n-1)), STEP / LINEAR (rotations:
    shortest-arc slerp) / CUBICSPLINE (Hermite; rotations normalised)."""
    k = sampler.times
    vals = sampler.values
    cubic = sampler.interpolation == "CUBICSPLINE"
    n = k.shape[0]
    rot = path == "rotation"
    if n == 1:
        v = (vals[0, 1] if cubic else vals[0]).astype(np.float64)
        return tf.quat_normalised(v) if rot and cubic else v
    a = float(a)
    if not (a >= k[0]):                     # also NaN -> first key
        a = float(k[0])
    elif a > k[-1]:
        a = float(k[-1])
    i = int(np.searchsorted(k, a, side="right")) - 1
    i = min(max(i, 0), n - 2)
    k0, k1 = float(k[i]), float(k[i + 1])
    u = (a - k0) / (k1 - k0)
    interp = sampler.interpolation
    if interp == "STEP":
        return np.array(vals[i + 1] if a >= k[-1] else vals[i], dtype=np.float64)
    if interp == "LINEAR":
        if rot:
            return tf.slerp(vals[i], vals[i + 1], u)
        v0, v1 = vals[i].astype(np.float64), vals[i + 1].astype(np.float64)
        return v0 + u * (v1 - v0)
    # CUBICSPLINE: values[:, 0] in-tangent A, [:, 1] value V, [:, 2] out-tangent B
    d = k1 - k0
    u2, u3 = u * u, u * u * u
    v = ((2 * u3 - 3 * u2 + 1) * vals[i, 1] + d * (u3 - 2 * u2 + u) * vals[i, 2]
         + (-2 * u3 + 3 * u2) * vals[i + 1, 1] + d * (u3 - u2) * vals[i + 1, 0])
    v = np.asarray(v, dtype=np.float64)
    return tf.quat_normalised(v) if rot else v
