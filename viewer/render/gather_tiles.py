"""The post-process gathers drawn only on the tiles where they can change a pixel.

McGuire 2012, UE4-style and Guertin 2014 each end in a gather that returns the sharp
colour wherever the tile it looks up (NeighborMax, or UE4's dilated max) moves by no more
than its early-out speed. On a software rasteriser every fragment costs even when it
returns at once, so the gather reads that tile texture back (a few hundred texels), lists
the tiles whose lookup can pass the early out (or, where the lookup is jittered, the
FINE tiles within the jitter's reach of one), and draws only those, as merged rectangles
(viewer/render/tile_lists.py TileList), over a copy of the sharp colour: every other
pixel is the colour its early out would have written, so the image is the same to the
byte as a full-screen draw.
"""
from __future__ import annotations

import math

import numpy as np

from .frame import Frame
from .tile_lists import FINE, TileList, kept_tile_list, tile_coords

# Relative margin on the early-out speed: the host's float64 length and the shader's
# float32 one may round apart; a tile near the threshold is drawn (that changes no pixel).
MARGIN = 1e-4


def moving_lookups(vectors: np.ndarray, early_out_px: float) -> np.ndarray:
    """Lookup tiles (GL rows) whose vector is longer than early_out_px (within MARGIN)."""
    v = vectors.astype(np.float64)
    return np.hypot(v[..., 0], v[..., 1]) > early_out_px * (1.0 - MARGIN)


def within_reach(moving: np.ndarray, tile: int, size: tuple[int, int], reach_px: int,
                 fine: int = FINE) -> np.ndarray:
    """FINE x FINE tiles (GL rows) holding a pixel that can look up a `moving` tile (tile
    x tile px) from up to reach_px px away on either axis: a FINE tile's pixels, grown by
    reach_px and cut at the screen's edge, meet a moving tile (2-D prefix sums)."""
    w, h = size

    def spans(n_px):
        p0 = np.arange(-(-n_px // fine)) * fine
        lo = np.clip(p0 - reach_px, 0, n_px - 1) // tile
        hi = np.clip(np.minimum(p0 + fine, n_px) - 1 + reach_px, 0, n_px - 1) // tile
        return lo, hi

    (x0, x1), (y0, y1) = spans(w), spans(h)
    csum = np.zeros((moving.shape[0] + 1, moving.shape[1] + 1), np.int64)
    csum[1:, 1:] = moving.cumsum(0).cumsum(1)
    y0, y1, x0, x1 = y0[:, None], y1[:, None] + 1, x0[None, :], x1[None, :] + 1
    return csum[y1, x1] - csum[y0, x1] - csum[y1, x0] + csum[y0, x0] > 0


def gather_tiles(frame: Frame, source: str, components: slice, tile: int,
                 early_out_px: float, reach_px: int) -> TileList | None:
    """The tiles to draw of a gather that looks `source` (tile x tile px texels) up, from
    up to reach_px px away where the lookup is jittered: its `components` hold the
    vector the early out tests. The lookup's own tiles where reach_px is 0, FINE tiles
    otherwise (a tile's worth of reach would draw a ring of whole k x k tiles around
    every moving one). None where every pixel may pass the early out (the full-screen
    triangle then, with no copy of the colour)."""
    tex = frame.pool.get(source)
    a = np.frombuffer(tex.read(), np.float32).reshape(tex.size[1], tex.size[0], tex.components)
    moving = moving_lookups(a[..., components], early_out_px)
    if reach_px > 0:
        moving, tile = within_reach(moving, tile, frame.size, reach_px), FINE
    frame.stats[f"{source}_gather_tiles"] = int(moving.sum())
    if moving.all():
        return None
    tl = kept_tile_list(frame, f"gather_tiles:{source}")
    tl.set(tile_coords(moving), tile, frame.size)
    return tl


def jitter_reach(tile_jitter: float, tile: int) -> int:
    """Pixels (per axis) a lookup offset by up to tile_jitter tiles can land from its
    pixel: the offset, rounded up, plus one for the rounding to a pixel."""
    return int(math.ceil(tile_jitter * tile)) + 1 if tile_jitter > 0.0 else 0


def draw_gather(pass_, frame: Frame, output: str, textures: dict, uniforms: dict,
                tiles: TileList | None):
    """Draw a gather pass into `output`: full screen without tiles, else the sharp colour
    copied and the tiles drawn over it."""
    if tiles is not None:
        frame.ctx.copy_framebuffer(frame.pool.framebuffer((output,)),
                                   frame.pool.framebuffer(("color",)))
        frame.pool.mark_written((output,))
    pass_.draw(frame, (output,), textures, uniforms, tiles=tiles, clear=False)
