"""A numpy statement of McGuire et al. 2012 (docs/algorithms.md 1.1-1.4), the oracle for the GLSL
passes.

Arrays are in GL orientation: row 0 is the BOTTOM row, index [y, x], velocities in GL
window axes (x right, y up), the same frame the fragment shaders see through
gl_FragCoord. Tests flip with world.conventions.to_image when reading or writing frames.
Depth is positive linear view depth (larger = farther).

Float32 is used wherever the rounding decides a discrete outcome (which tap pixel, which
vector is longer), so those outcomes follow the shader's arithmetic.
"""
from __future__ import annotations

import numpy as np

F32 = np.float32


# ---- 1.1 velocity setup --------------------------------------------------------------------

def clamp_velocity(displacement: np.ndarray, k: float) -> np.ndarray:
    """v = D/2 with |v| clamped to [0.5, k]; v = 0 exactly where D = 0. (H, W, 2)."""
    q = 0.5 * np.asarray(displacement, dtype=np.float64)
    mag = np.hypot(q[..., 0], q[..., 1])
    moving = mag > 0.0
    scale = np.where(moving, np.clip(mag, 0.5, k) / np.where(moving, mag, 1.0), 0.0)
    return (q * scale[..., None]).astype(F32)


# ---- 1.2, 1.3 tiles ------------------------------------------------------------------------

def _longest(vectors: np.ndarray) -> np.ndarray:
    """The first vector of the largest squared length (float32, as compared in GLSL)."""
    v = vectors.astype(F32)
    m2 = v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1]
    return v[int(np.argmax(m2))]       # argmax keeps the first of equal maxima


def tilemax_x(v: np.ndarray, k: int) -> np.ndarray:
    """The k x 1 step: (H, ceil(W/k), 2), tile column tx covering x in [tx k, tx k + k)."""
    h, w = v.shape[:2]
    tw = -(-w // k)
    out = np.zeros((h, tw, 2), F32)
    for y in range(h):
        for tx in range(tw):
            out[y, tx] = _longest(v[y, tx * k:(tx + 1) * k])
    return out


def tilemax_y(strip: np.ndarray, k: int) -> np.ndarray:
    """The 1 x k step on the strip: (ceil(H/k), ceil(W/k), 2)."""
    h, tw = strip.shape[:2]
    th = -(-h // k)
    out = np.zeros((th, tw, 2), F32)
    for ty in range(th):
        for tx in range(tw):
            out[ty, tx] = _longest(strip[ty * k:(ty + 1) * k, tx])
    return out


def tilemax(v: np.ndarray, k: int) -> np.ndarray:
    return tilemax_y(tilemax_x(v, k), k)


def neighbormax(tiles: np.ndarray, accept=None) -> np.ndarray:
    """Largest of the 3x3 tiles around each tile; the centre is first, so it wins ties.
    accept(dx, dy, v): whether the neighbour at offset (dx, dy) with vector v counts."""
    th, tw = tiles.shape[:2]
    out = np.zeros_like(tiles, dtype=F32)
    for ty in range(th):
        for tx in range(tw):
            cand = [tiles[ty, tx]]
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    y, x = ty + dy, tx + dx
                    if 0 <= y < th and 0 <= x < tw and (
                            accept is None or accept(dx, dy, tiles[y, x].astype(F32))):
                        cand.append(tiles[y, x])
            out[ty, tx] = _longest(np.array(cand))
    return out


# ---- noise (a port of glsl/graph/noise.glsl hash01) ------------------------------------------------

def hash01(x, y, seed: int, stream: int) -> np.ndarray:
    """lowbias32 of the pixel, seed and stream, in [0, 1), bit for bit as in GLSL."""
    with np.errstate(over="ignore"):
        u = np.uint32
        h = (np.asarray(x).astype(u) * u(73856093)) ^ (np.asarray(y).astype(u) * u(19349663)) \
            ^ (u(seed & 0xFFFFFFFF) + u(stream) * u(83492791))
        h = h ^ (h >> u(16))
        h = h * u(0x7FEB352D)
        h = h ^ (h >> u(15))
        h = h * u(0x846CA68B)
        h = h ^ (h >> u(16))
    return (h >> u(8)).astype(np.float64) / 16777216.0


# ---- 1.4 reconstruction --------------------------------------------------------------------

def cone(dist, r):
    return np.clip(1.0 - dist / r, 0.0, 1.0)


def smoothstep(e0, e1, x):
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def cylinder(dist, r):
    return 1.0 - smoothstep(0.95 * r, 1.05 * r, dist)


def front(depth_a, depth_b, soft_z):
    """A in front of B, positive depth: 1 when nearer or within ~soft_z, 0 when farther."""
    return np.clip(1.0 - (depth_a - depth_b) / soft_z, 0.0, 1.0)


def radius(v):
    return np.maximum(np.hypot(v[..., 0], v[..., 1]), 0.5)


def tap_offsets(samples: int, j):
    """t_i for i = 0..S-1 without the middle one, per pixel: (S-1, ...) float32."""
    j = np.asarray(j, F32)
    s1 = F32(samples + 1)
    ts = [F32(-1.0) + F32(2.0) * (F32(i) + j + F32(1.0)) / s1
          for i in range(samples) if i != (samples - 1) // 2]
    return np.array(ts, F32)


def tap_pixel(px, py, w: int, h: int, ambiguous, where, margin: float = 1e-3):
    """The pixel holding the float32 point (px, py), clamped to the w x h screen; marks
    `ambiguous` (in place) where `where` and the point lies within `margin` px of a pixel
    edge, where float32 in the shader and here may round to different pixels."""
    for p in (px, py):
        frac = p.astype(np.float64) - np.floor(p)
        ambiguous |= (np.minimum(frac, 1.0 - frac) < margin) & where
    return (np.clip(np.floor(px).astype(int), 0, w - 1),
            np.clip(np.floor(py).astype(int), 0, h - 1))


def gather(color, depth, v, nmax, k: int, samples: int = 15, soft_z: float = 0.1,
           jitter: float = 1.0, seed: int = 0, stream: int = 1, kappa: float = 0.0,
           early_out: float = 0.5 + 1e-3):
    """The reconstruction at every pixel.

    Returns (out (H, W, 3) float64, ambiguous (H, W) bool): `ambiguous` marks pixels with a
    tap within 1e-3 px of a rounding boundary, where float32 in the shader and here may
    pick different pixels."""
    color = np.asarray(color, np.float64)[..., :3]
    h, w = depth.shape
    ys, xs = np.mgrid[0:h, 0:w]
    vn = nmax[ys // k, xs // k].astype(F32)
    still = np.hypot(vn[..., 0], vn[..., 1]) <= early_out
    rx = radius(v.astype(np.float64))
    zx = depth.astype(np.float64)
    wsum = (samples / (kappa * rx)) if kappa > 0 else 1.0 / rx
    acc = wsum[..., None] * color
    j = (F32(jitter) * (hash01(xs, ys, seed, stream) - 0.5).astype(F32)).astype(F32)
    ambiguous = np.zeros((h, w), bool)
    for t in tap_offsets(samples, j):
        px = xs.astype(F32) + F32(0.5) + t * vn[..., 0]
        py = ys.astype(F32) + F32(0.5) + t * vn[..., 1]
        yx, yy = tap_pixel(px, py, w, h, ambiguous, ~still)
        dist = np.hypot(yx - xs, yy - ys)
        zy = zx[yy, yx]
        ry = rx[yy, yx]
        a = (front(zy, zx, soft_z) * cone(dist, ry)
             + front(zx, zy, soft_z) * cone(dist, rx)
             + 2.0 * cylinder(dist, ry) * cylinder(dist, rx))
        wsum = wsum + a
        acc = acc + a[..., None] * color[yy, yx]
    out = np.where(still[..., None], color, acc / wsum[..., None])
    return out, ambiguous


def whole_filter(gather, neighbormax, color, depth, displacement, k: int, **kw):
    """A filter of this family from G-buffer colour, depth and full displacement (GL
    orientation): the clamped half vector, TileMax, `neighbormax`, then `gather`."""
    v = clamp_velocity(displacement, k)
    return gather(color, depth, v, neighbormax(tilemax(v, k)), k, **kw)


def mcguire(color, depth, displacement, k: int, **kw):
    return whole_filter(gather, neighbormax, color, depth, displacement, k, **kw)
