"""Compiled loops (numba) for the tile lists' host side: a frame fills several lists and
dilates tile maps of a few hundred to a few thousand tiles, where numpy's per-call cost
(~5 us a call, tens of calls) outweighs the work. Same results as the numpy statements in
their docstrings (tests/test_tile_lists.py)."""
from __future__ import annotations

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True)

# Two triangles per tile, corners as (x1?, y1?): (x0,y0) (x1,y0) (x0,y1), (x1,y0) (x1,y1) (x0,y1).
_CORNERS = ((0, 0), (1, 0), (0, 1), (1, 0), (1, 1), (0, 1))


@njit(**_JIT)
def tile_quads(tiles, tile, tile_h, w, h, blocks_per_row):
    """The vertex data of tile x tile_h quads (float32, 6 vertices a tile: the corner, and
    where blocks_per_row > 0 also the corner's place in a block-packed record texture,
    block k at (k % blocks_per_row, k // blocks_per_row) * tile) and the GL-pixel box
    (x0, y0, x1, y1) around the tiles, cut at the target's edge (n >= 1 for the box)."""
    n = tiles.shape[0]
    stride = 4 if blocks_per_row > 0 else 2
    data = np.empty(n * 6 * stride, np.float32)
    bx0, by0, bx1, by1 = w, h, 0, 0
    for k in range(n):
        x0 = tiles[k, 0] * tile
        y0 = tiles[k, 1] * tile_h
        x1 = min(x0 + tile, w)
        y1 = min(y0 + tile_h, h)
        bx0, by0, bx1, by1 = min(bx0, x0), min(by0, y0), max(bx1, x1), max(by1, y1)
        rx = (k % blocks_per_row) * tile - x0 if blocks_per_row > 0 else 0
        ry = (k // blocks_per_row) * tile - y0 if blocks_per_row > 0 else 0
        for v in range(6):
            x = x1 if _CORNERS[v][0] else x0
            y = y1 if _CORNERS[v][1] else y0
            o = (k * 6 + v) * stride
            data[o] = x
            data[o + 1] = y
            if blocks_per_row > 0:
                data[o + 2] = x + rx
                data[o + 3] = y + ry
    return data, (bx0, by0, bx1, by1)


@njit(**_JIT)
def dilate_by_reach(reach, tile, radius):
    """Tiles within reach of a source: tile (y, x) is set when some tile with reach r >= 0
    (px) lies L <= min(floor(r / tile) + 1, radius) tiles away (Chebyshev), i.e. the gap
    between them, (L - 1) tiles, is within r (L = 0: the source itself)."""
    th, tw = reach.shape
    out = np.zeros((th, tw), np.bool_)
    for y in range(th):
        for x in range(tw):
            r = reach[y, x]
            if r < 0:
                continue
            level = min(int(r // tile) + 1, radius)
            for v in range(max(0, y - level), min(th, y + level + 1)):
                for u in range(max(0, x - level), min(tw, x + level + 1)):
                    out[v, u] = True
    return out


@njit(**_JIT)
def chessboard_distance(sources):
    """Per tile, the Chebyshev distance (in tiles) to the nearest True tile of `sources`
    (0 on one; a large number where there is none): two raster passes of an 8-neighbour
    chamfer, exact for this metric (scipy's distance_transform_cdt on ~sources)."""
    th, tw = sources.shape
    big = th + tw + 1
    d = np.empty((th, tw), np.int64)
    for y in range(th):
        for x in range(tw):
            if sources[y, x]:
                d[y, x] = 0
                continue
            m = big
            if y > 0:
                m = min(m, d[y - 1, x] + 1)
                if x > 0:
                    m = min(m, d[y - 1, x - 1] + 1)
                if x + 1 < tw:
                    m = min(m, d[y - 1, x + 1] + 1)
            if x > 0:
                m = min(m, d[y, x - 1] + 1)
            d[y, x] = m
    for y in range(th - 1, -1, -1):
        for x in range(tw - 1, -1, -1):
            m = d[y, x]
            if y + 1 < th:
                m = min(m, d[y + 1, x] + 1)
                if x > 0:
                    m = min(m, d[y + 1, x - 1] + 1)
                if x + 1 < tw:
                    m = min(m, d[y + 1, x + 1] + 1)
            if x + 1 < tw:
                m = min(m, d[y, x + 1] + 1)
            d[y, x] = m
    return d
