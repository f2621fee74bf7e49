"""A naive gather along each pixel's own motion, in numpy (an example of a user blur pass,
docs/api.md; the same filter as naive_gather.frag beside it): the mean of TAPS colours
spaced evenly along the pixel's half displacement v = D/2 on both sides, |v| clamped to
the blur limit k.

    hmblur compare living_room --variant mine=py:docs/examples/numpy_gather.py:gather
"""
import numpy as np

TAPS = 9


def gather(inputs):
    """inputs: hybrid_mblur.BlurInputs (arrays in image orientation, vectors in GL axes:
    x to the right, y up). Returns (H, W, 3) float linear RGB."""
    color, k = inputs.color, np.float32(inputs.tile)
    h, w = color.shape[:2]
    rows, cols = np.mgrid[0:h, 0:w]
    x = cols.astype(np.float32)
    y = (h - 1 - rows).astype(np.float32)        # GL row: counted from the bottom
    v = np.float32(0.5) * inputs.velocity
    length = np.sqrt(v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1])
    scale = np.where(length > k, k / np.maximum(length, np.float32(1e-30)), np.float32(1))
    v = v * scale[..., None]
    total = np.zeros_like(color)
    for i in range(TAPS):
        t = np.float32(-1.0 + 2.0 * i / (TAPS - 1))
        tx = np.clip(np.floor(x + np.float32(0.5) + t * v[..., 0]), 0, w - 1).astype(int)
        ty = np.clip(np.floor(y + np.float32(0.5) + t * v[..., 1]), 0, h - 1).astype(int)
        total += color[h - 1 - ty, tx]
    return total / np.float32(TAPS)
