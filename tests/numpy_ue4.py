"""Numpy reference of the UE4-style motion blur, written from docs/algorithms.md 3.2 and 3.4 (not
from the shaders), for tests/test_ue4.py.

Arrays are in GL orientation: a[y, x] with row 0 at the BOTTOM, so that velocities (y up)
and row indices agree; tests flip with conventions.to_image when they upload or read. Pixel
(x, y) has its centre at window point (x + 0.5, y + 0.5). Everything is float32, as on the
GPU, so comparisons can be tight.
"""
from __future__ import annotations

import numpy as np

F = np.float32


def ign(px, py, offset: float, seed: int = 0) -> np.ndarray:
    """Interleaved gradient noise of glsl/graph/noise.glsl at window points (px, py)."""
    a, b = F(F(offset) * F(5.588238)), F(F(seed % 1024) * F(7.13))
    x = (F(px) + a) + b          # the GLSL's order of additions
    y = (F(py) + a) + b
    d = x * F(0.06711056) + y * F(0.00583715)
    d = d - np.floor(d)
    n = F(52.9829189) * d
    return (n - np.floor(n)).astype(F)


def flatten(velocity, depth, max_px: float) -> np.ndarray:
    """(v.x, v.y, depth, |v|) with v = D/2, its length clamped to max_px."""
    v = F(0.5) * np.asarray(velocity, F)
    length = np.sqrt(np.sum(v * v, axis=-1))
    over = length > max_px
    scale = np.where(over, F(max_px) / np.where(over, length, F(1)), F(1)).astype(F)
    v = v * scale[..., None]
    length = np.where(over, F(max_px), length)
    return np.concatenate([v, np.asarray(depth, F)[..., None], length[..., None]], axis=-1)


def tile_minmax(flat, k: int) -> np.ndarray:
    """Per k x k tile (border tiles partial): (vmin.xy, vmax.xy) of least and greatest
    stored length; the first in scan order (rows upward, columns rightward) wins ties."""
    h, w = flat.shape[:2]
    th, tw = -(-h // k), -(-w // k)
    out = np.zeros((th, tw, 4), F)
    for ty in range(th):
        for tx in range(tw):
            block = flat[ty * k:(ty + 1) * k, tx * k:(tx + 1) * k].reshape(-1, 4)
            lengths = block[:, 3]
            i_min = int(np.argmin(lengths))          # argmin/argmax: first occurrence
            out[ty, tx, :2] = block[i_min, :2]
            if lengths.max() > 0:
                out[ty, tx, 2:] = block[int(np.argmax(lengths)), :2]
    return out


def covers(n_vmax, offset, tile: float) -> bool:
    """Does the quad swept by tile n (max velocity n_vmax, px) cover the tile at `offset`
    (m - n, in tiles)?"""
    l2 = float(np.dot(n_vmax, n_vmax))
    if l2 < 0.25:
        return offset[0] == 0 and offset[1] == 0
    length = np.sqrt(l2)
    d = np.asarray(n_vmax, np.float64) / length
    e = 0.99 * (abs(d[0]) + abs(d[1]))
    along = abs(offset[0] * d[0] + offset[1] * d[1])
    across = abs(-offset[0] * d[1] + offset[1] * d[0])
    return along < length / tile + e and across < e


def dilate(tiles, tile: int, reach: int, guard: bool = False,
           tile_jitter: float = 0.25) -> np.ndarray:
    """Min-of-mins and max-of-maxes (by length) over the tiles whose swept quad covers each
    tile, searched within +-reach tiles; the first in scan order wins ties. With `guard`,
    the min also runs over the square of ceil(|vmax| / tile + tile_jitter) tiles about the
    tile: every tile that a tap from a pixel looking this tile up can read."""
    th, tw = tiles.shape[:2]
    out = np.zeros_like(tiles)
    for my in range(th):
        for mx in range(tw):
            lmin, lmax = np.inf, 0.0
            for ny in range(max(0, my - reach), min(th, my + reach + 1)):
                for nx in range(max(0, mx - reach), min(tw, mx + reach + 1)):
                    t = tiles[ny, nx]
                    if not covers(t[2:], (mx - nx, my - ny), tile):
                        continue
                    n2, l2 = float(np.dot(t[:2], t[:2])), float(np.dot(t[2:], t[2:]))
                    if n2 < lmin:
                        lmin, out[my, mx, :2] = n2, t[:2]
                    if l2 > lmax:
                        lmax, out[my, mx, 2:] = l2, t[2:]
            if guard:
                r = int(np.ceil(np.sqrt(lmax) / tile + tile_jitter))
                for ny in range(max(0, my - r), min(th, my + r + 1)):
                    for nx in range(max(0, mx - r), min(tw, mx + r + 1)):
                        t = tiles[ny, nx]
                        n2 = float(np.dot(t[:2], t[:2]))
                        if n2 < lmin:
                            lmin, out[my, mx, :2] = n2, t[:2]
    return out


def bilinear(color, px, py) -> np.ndarray:
    """Bilinear colour at window points (px, py) already inside [0.5, size - 0.5]."""
    h, w = color.shape[:2]
    qx, qy = px - F(0.5), py - F(0.5)
    x0, y0 = np.floor(qx).astype(int), np.floor(qy).astype(int)
    fx, fy = (qx - x0).astype(F)[..., None], (qy - y0).astype(F)[..., None]
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    bottom = color[y0, x0] * (1 - fx) + color[y0, x1] * fx
    top = color[y1, x0] * (1 - fx) + color[y1, x1] * fx
    return bottom * (1 - fy) + top * fy


def gather(color, flat, dilated, tile: int, taps: int = 8, depth_scale: float = 100.0,
           tile_jitter: float = 0.25, tap_jitter: float = 1.0, fast_path: bool = True,
           fast_ratio: float = 0.4, mirror: bool = True, bilinear_taps: bool = True,
           seed: int = 0) -> np.ndarray:
    """The gather of docs/algorithms.md 3.2(c) at every pixel, vectorised over pixels."""
    color = np.asarray(color, F)[..., :3]
    h, w = color.shape[:2]
    th, tw = dilated.shape[:2]
    X = (np.arange(w, dtype=F) + F(0.5))[None, :].repeat(h, 0)
    Y = (np.arange(h, dtype=F) + F(0.5))[:, None].repeat(w, 1)

    # tile lookup, jittered by up to tile_jitter tiles per axis
    jx, jy = ign(X, Y, 1.0, seed) - F(0.5), ign(X, Y, 2.0, seed) - F(0.5)
    tx = np.clip(np.floor(X / F(tile) + F(2 * tile_jitter) * jx).astype(int), 0, tw - 1)
    ty = np.clip(np.floor(Y / F(tile) + F(2 * tile_jitter) * jy).astype(int), 0, th - 1)
    t = dilated[ty, tx]
    vmin, vmax = t[..., :2], t[..., 2:]
    lmax2 = np.sum(vmax * vmax, axis=-1)
    skip = lmax2 < 0.25
    fast = fast_path & ~skip & (np.sum(vmin * vmin, axis=-1) > F(fast_ratio) * lmax2)

    K = F(taps)
    j = F(tap_jitter) * (ign(X, Y, 0.0, seed) - F(0.5))
    px_to_step = K / np.sqrt(np.where(skip, F(1), lmax2))
    centre = flat
    acc = np.zeros_like(color)
    plain = np.zeros_like(color)
    wsum = np.zeros((h, w), F)

    def tap(o, sign):
        px = np.clip(X + sign * (o / K) * vmax[..., 0], F(0.5), F(w - 0.5))
        py = np.clip(Y + sign * (o / K) * vmax[..., 1], F(0.5), F(h - 0.5))
        iy, ix = np.floor(py).astype(int), np.floor(px).astype(int)
        f = flat[iy, ix]
        dz = f[..., 2] - centre[..., 2]
        bg = np.clip(F(0.5) + F(depth_scale) * dz, 0, 1)
        fg = np.clip(F(0.5) - F(depth_scale) * dz, 0, 1)
        edge = np.maximum(o - F(1), F(0))
        spread_centre = np.clip(px_to_step * centre[..., 3] - edge, 0, 1)
        spread_tap = np.clip(px_to_step * f[..., 3] - edge, 0, 1)
        c = bilinear(color, px, py) if bilinear_taps else color[iy, ix]
        return c, f, bg * spread_centre + fg * spread_tap

    for i in range(taps):
        op, om = F(i + 0.5) + j, F(i + 0.5) - j
        c0, f0, w0 = tap(op, F(1))
        c1, f1, w1 = tap(om, F(-1))
        if mirror:
            far0, fast1 = f0[..., 2] > f1[..., 2], f1[..., 3] > f0[..., 3]
            w0, w1 = np.where(far0 & fast1, w1, w0), np.where(~far0 & ~fast1, w0, w1)
        acc += w0[..., None] * c0 + w1[..., None] * c1
        wsum += w0 + w1
        plain += c0 + c1

    full = acc / (2 * K) + (1 - wsum / (2 * K))[..., None] * color
    out = np.where(fast[..., None], plain / (2 * K), full)
    return np.where(skip[..., None], color, out).astype(F)


def box_coverage(x, lo: float, hi: float, radius: float) -> np.ndarray:
    """Fraction of the exposure during which an interval [lo, hi), moving by 2*radius px
    centred on the frame time (box shutter), covers the points x."""
    x = np.asarray(x, np.float64)
    # covered while lo + s <= x < hi + s, s uniform in [-radius, radius]
    a = np.clip(x - hi, -radius, radius)
    b = np.clip(x - lo, -radius, radius)
    return (b - a) / (2 * radius)
