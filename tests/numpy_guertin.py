"""A numpy statement of Guertin, McGuire, Nowrouzezahrai 2014 (HPG 2014, Appendix A),
the oracle for the GLSL passes of mode `guertin`.

Same conventions as tests/numpy_mcguire.py (GL orientation, row 0 at the bottom, positive
linear depth), whose velocity clamp, TileMax, noise and weight shapes the paper keeps.
Float32 wherever rounding picks a discrete outcome (which pixel a tap or a lookup lands on).
"""
from __future__ import annotations

import numpy as np

import numpy_mcguire as nm
from numpy_mcguire import F32, cone, cylinder, hash01, radius
from numpy_ue4 import ign


# ---- NeighborMax with the diagonal rule --------------------------------------------------------

def toward_centre(dx: int, dy: int, v: np.ndarray) -> bool:
    """A diagonal neighbour at offset o = (dx, dy) counts only where dot(v, -o) > 0."""
    return not (dx and dy) or -(v[0] * F32(dx) + v[1] * F32(dy)) > 0


def neighbormax(tiles: np.ndarray) -> np.ndarray:
    """McGuire's NeighborMax with the diagonal rule."""
    return nm.neighbormax(tiles, toward_centre)


# ---- reconstruction ---------------------------------------------------------------------------

def front(depth_a, depth_b, z_scale=1.0):
    """A in front of B: 1 when nearer, 0 once A lies z_scale * min(A, B) behind B."""
    return np.clip(1.0 - (depth_a - depth_b) / (z_scale * np.minimum(depth_a, depth_b)),
                   0.0, 1.0)


def direction(v):
    """v / |v|, 0 where v = 0."""
    n = np.hypot(v[..., 0], v[..., 1])
    return np.where(n[..., None] > 0, v / np.where(n > 0, n, 1.0)[..., None], 0.0)


def centre_direction(vn, vc, gamma):
    """wC: the perpendicular of wN on vC's side, blended toward vC's own direction as |vC|
    rises from 0.5 px to 0.5 + gamma px."""
    wn = direction(vn)
    wp = np.stack([-wn[..., 1], wn[..., 0]], -1)
    flip = (wp * vc).sum(-1) < 0
    wp = np.where(flip[..., None], -wp, wp)
    s = np.clip((np.hypot(vc[..., 0], vc[..., 1]) - 0.5) / gamma, 0.0, 1.0)[..., None]
    return direction(wp + s * (direction(vc) - wp))


def lookup_offset(xs, ys, k, tile_jitter, seed, streams):
    """The NeighborMax lookup offset (ox, oy) in px, float32: a shift of up to tile_jitter
    * k px (stream streams[0]) along x or along y (stream streams[1] below 1/2: x), never
    both, so the tile read is this pixel's or an axis neighbour, never a diagonal one."""
    shift = (F32(tile_jitter) * F32(k)
             * (F32(2.0) * hash01(xs, ys, seed, streams[0]).astype(F32) - F32(1.0))).astype(F32)
    along_x = hash01(xs, ys, seed, streams[1]) < 0.5
    zero = np.zeros_like(shift)
    return np.where(along_x, shift, zero), np.where(along_x, zero, shift)


def lookup_tiles(xs, ys, w, h, k, tile_jitter, seed, streams):
    """The tile each pixel reads NeighborMax from: the pixel offset by lookup_offset,
    clamped to the screen, integer-divided by k. Also `ambiguous`, where the offset pixel
    lies within 1e-4 px of a pixel boundary."""
    ox, oy = lookup_offset(xs, ys, k, tile_jitter, seed, streams)
    px = xs.astype(F32) + F32(0.5) + ox
    py = ys.astype(F32) + F32(0.5) + oy
    amb = np.zeros(xs.shape, bool)
    qx, qy = nm.tap_pixel(px, py, w, h, amb, np.bool_(tile_jitter > 0), margin=1e-4)
    return qx // k, qy // k, amb


def tap_jitter(xs, ys, samples, eta, phi, seed, noise):
    """The per-pixel tap shift in tap spacings, float32: eta * phi / N * (2 ign - 1)."""
    j = F32(2.0) * ign(xs, ys, noise, seed) - F32(1.0)
    return (F32(eta) * F32(phi) / F32(samples) * j).astype(F32)


def tap_t(i: int, samples: int, j):
    """Tap i's t in (-1, 1) (beyond it where the jitter passes a spacing), float32."""
    return (F32(-1.0) + F32(2.0) * (F32(i) + F32(1.0) + j) / F32(samples + 1)).astype(F32)


def taps(samples: int, skip_middle: bool):
    """(i, along wN) per tap: even taps along the neighbourhood direction, odd ones along
    the centre direction (Appendix A); the middle one left out where skip_middle, N odd."""
    middle = (samples - 1) // 2 if skip_middle and samples % 2 else -1
    return [(i, i % 2 == 0) for i in range(samples) if i != middle]


def gather(color, depth, v, nmax, k: int, samples=15, gamma=1.5, kappa=40.0, eta=0.95,
           phi=15.0, skip_middle=True, tile_jitter=0.25, z_scale=1.0, seed=0,
           streams=(3.0, 4, 5), early_out=0.5 + 1e-3):
    """The reconstruction at every pixel: (out (H, W, 3) float64, ambiguous (H, W) bool),
    ambiguous where a tap or the lookup lies within 1e-3 px of a rounding boundary.
    streams: the tap jitter's noise offset, the lookup shift's and its axis's streams."""
    color = np.asarray(color, np.float64)[..., :3]
    h, w = depth.shape
    ys, xs = np.mgrid[0:h, 0:w]
    tx, ty, ambiguous = lookup_tiles(xs, ys, w, h, k, tile_jitter, seed, streams[1:])
    vn32 = nmax[ty, tx].astype(F32)
    ln32 = np.hypot(vn32[..., 0], vn32[..., 1]).astype(F32)
    still = ln32 <= early_out
    vn = vn32.astype(np.float64)
    vc = v.astype(np.float64)
    wn = direction(vn)
    wc = centre_direction(vn, vc, gamma)
    rc = radius(vc)
    zc = depth.astype(np.float64)
    total = samples / (kappa * rc)
    acc = total[..., None] * color
    j = tap_jitter(xs, ys, samples, eta, phi, seed, streams[0])
    vdir = direction(v.astype(np.float64))
    for i, along_n in taps(samples, skip_middle):
        t = tap_t(i, samples, j)
        d = wn if along_n else wc
        d32 = d.astype(F32)
        step = (t * ln32).astype(F32)
        px = xs.astype(F32) + F32(0.5) + step * d32[..., 0]
        py = ys.astype(F32) + F32(0.5) + step * d32[..., 1]
        sx, sy = nm.tap_pixel(px, py, w, h, ambiguous, ~still)
        dist = np.abs(t.astype(np.float64)) * ln32   # T = |t| |vN|, unrounded (the paper's)
        rs = rc[sy, sx]
        zs = zc[sy, sx]
        wa = np.abs((wc * d).sum(-1))
        wb = np.abs((vdir[sy, sx] * d).sum(-1))
        a = (front(zs, zc, z_scale) * cone(dist, rs) * wb
             + front(zc, zs, z_scale) * cone(dist, rc) * wa
             + 2.0 * cylinder(dist, np.minimum(rs, rc)) * np.maximum(wa, wb))
        total = total + a
        acc = acc + a[..., None] * color[sy, sx]
    out = np.where(still[..., None], color, acc / total[..., None])
    return out, ambiguous


def guertin(color, depth, displacement, k: int, **kw):
    return nm.whole_filter(gather, neighbormax, color, depth, displacement, k, **kw)
