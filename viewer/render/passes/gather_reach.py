"""The FINE tiles on which a gather can give a pixel other bits than its own colour, for
McGuire 2012 and UE4-style along a straight motion (one segment): finer than the tiles
whose lookup fails the early out (viewer/render/passes/gather_tiles.py), and the same image.

McGuire (glsl/modes/mcguire_gather.frag). A still pixel X (v = 0, so rX = 0.5) weighs a tap Y
off itself (|Y - X| >= 1 px) by front * cone(d, rY) + front * cone(d, 0.5) +
2 cyl(d, rY) cyl(d, 0.5): the last two are exactly 0 past 0.525 px, the first past rY =
max(|vY|, 0.5). So where no pixel Y lies closer than |vY| (a dilation of the k x 1
TileMax strips, already computed, by their longest |v|) every tap off X adds exactly
0 and the result is sum(w c) / sum(w) over the centre and the taps that land on X
itself, each of weight 4, the colour c: 2c / 2 = c exactly when none lands there (and
the centre weight 1/rX = 2, i.e. mcguire.centre_kappa = 0), while 6c / 6 and the like
round (a byte of the PNG can move). A tap lands on X when |t vN| < 0.5 on both axes, for
|t| >= (2 - jitter) / (S + 1), or when it is clamped back onto X at the screen's edge. So
such tiles are either copied (no tap can land on X) or drawn with the CENTRE_ONLY variant,
which adds the same weights for the taps landing on X and reads no tap. (A moving pixel's
own tile is always drawn: it lies within its own reach.)

UE4 (glsl/modes/ue4_gather.frag). A still pixel (|v| = 0) weighs a tap o steps out by the
tap's spread, clamp(K |vY| / |vmax| - max(o - 1, 0), 0, 1): nonzero only when the tap
point lies within |vY| + |vmax| / K of X, the pixel Y holding it a further sqrt(1/2) px
away. Where no pixel reaches X that far (a dilation of the tile min/max tiles by their
longest |v| + k / K + sqrt(1/2)), every weight is 0 and the result is 0 / 2K + (1 - 0) c
= c exactly; the fast path (a plain average) is drawn wherever a lookup can take it.

Guertin 2014 keeps the lookup tiles: its centre weight N / (kappa rC) (0.75 at the
defaults) and direction weights round c / (sum of weights) off c even where no tap off X
weighs anything, so no copy is exact there.
"""
from __future__ import annotations

import math

import numpy as np

from viewer.render.passes import tile_kernels
from viewer.render.graph.frame import Frame
from .gather_tiles import moving_lookups, read_tiles, within_reach
from viewer.render.passes.tile_runs import FINE

# A pixel's own reach is widened by this fraction and these px: the host's float64
# lengths against the shader's float32 ones (a tile drawn too many changes no pixel).
REACH_REL, REACH_PX = 1e-4, 1e-2
# A tap leaves the pixel's column when |t v| > 0.5 px by this much (float positions).
SELF_MARGIN_PX = 1e-3


def reached(reach: np.ndarray, box_w: int, box_h: int, size: tuple[int, int]) -> np.ndarray:
    """FINE tiles (GL rows) with a pixel closer than reach[j, i] px to a pixel of the
    box_w x box_h px box (i, j); reach < 0: none (tile_kernels.reach_boxes)."""
    w, h = size
    return tile_kernels.reach_boxes(np.ascontiguousarray(reach, np.float64), box_w, box_h,
                                    w, h, FINE)


def reach_of(lengths: np.ndarray, floor: float, extra: float) -> np.ndarray:
    """Per box with longest |v| > 0: max(|v|, floor) + extra, widened; -1 for still boxes."""
    lengths = np.asarray(lengths, np.float64)
    r = (np.maximum(lengths, floor) + extra) * (1.0 + REACH_REL) + REACH_PX
    return np.where(lengths > 0.0, r, -1.0)


def lengths(vectors: np.ndarray) -> np.ndarray:
    v = np.asarray(vectors, np.float64)
    return np.hypot(v[..., 0], v[..., 1])


def self_tap_tiles(nm: np.ndarray, run: np.ndarray, k: int, size: tuple[int, int],
                   samples: int, jitter: float) -> np.ndarray:
    """FINE tiles (GL rows) holding a pixel whose McGuire lookup (k-tile of `nm`, GL rows)
    runs (`run`) and a tap of which may land on the pixel itself: tap t reads
    clamp(floor(X + 0.5 + t vN)), |t| >= (2 - jitter) / (S + 1) off the middle, so it
    leaves X's column when |t vN.x| > 0.5, unless X is in the first or last column (a tap
    clamped back onto it), likewise for rows (tile_kernels.self_taps)."""
    t_min = (2.0 - jitter) / (samples + 1)
    off = np.abs(np.asarray(nm, np.float64)) * t_min > 0.5 + SELF_MARGIN_PX
    return tile_kernels.self_taps(off[..., 0].copy(), off[..., 1].copy(),
                                  np.ascontiguousarray(run), k, size[0], size[1], FINE)


def mcguire_maps(frame: Frame, k: int, samples: int, jitter: float, kappa: float,
                 early_out_px: float) -> tuple[np.ndarray, np.ndarray]:
    """McGuire's FINE tiles to draw (GL rows): those a moving pixel's blur reaches, where
    the lookup runs (the full gather), and those of the rest where the lookup runs and a
    tap may land on the pixel itself, or the centre weight is not 2 (kappa > 0): the
    CENTRE_ONLY variant. Everywhere else the gather's result is the pixel's colour."""
    nm = read_tiles(frame, "mcguire_neighbormax")[..., :2]
    run = moving_lookups(nm, early_out_px)
    run_fine = within_reach(run, k, frame.size, 0)
    strips = read_tiles(frame, "mcguire_tilemax_x")[..., :2]      # k x 1 px boxes
    near = reached(reach_of(lengths(strips), 0.5, 0.0), k, 1, frame.size)
    rest = run_fine & ~near
    if kappa == 0.0:
        rest &= self_tap_tiles(nm, run, k, frame.size, samples, jitter)
    return run_fine & near, rest


def ue4_map(frame: Frame, tile: int, jitter_px: int, taps: int, k: int, fast_path: bool,
            fast_ratio: float, early_out_px: float) -> np.ndarray:
    """UE4-style's FINE tiles to draw (GL rows): where a lookup within the jitter's reach
    can take the fast path, and where one runs and a moving pixel reaches."""
    dilated = read_tiles(frame, "ue4_dilated").astype(np.float64)
    run = moving_lookups(dilated[..., 2:4], early_out_px)
    vmax = read_tiles(frame, "ue4_tiles")[..., 2:4]
    near = reached(reach_of(lengths(vmax), 0.0, k / taps + math.sqrt(0.5)), tile, tile,
                   frame.size)
    draw = within_reach(run, tile, frame.size, jitter_px) & near
    if fast_path:
        lmin2 = (dilated[..., 0:2] ** 2).sum(-1)
        lmax2 = (dilated[..., 2:4] ** 2).sum(-1)
        draw |= within_reach(run & (lmin2 >= fast_ratio * lmax2 * (1.0 - REACH_REL)),
                             tile, frame.size, jitter_px)
    return draw
