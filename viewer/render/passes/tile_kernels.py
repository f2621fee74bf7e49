"""Compiled loops (numba) for the tile lists' host side: a frame fills several lists and
dilates tile maps of a few hundred to a few thousand tiles, where numpy's per-call cost
(~5 us a call, tens of calls) outweighs the work. Same results as the numpy statements in
their docstrings (tests/test_tile_lists.py)."""
from __future__ import annotations

import numpy as np
from numba import njit

from world.conventions import flip_row

_JIT = dict(cache=True, nogil=True)
_flip_row = njit(inline="always")(flip_row)     # conventions' row flip, compiled in

# Two triangles per tile, corners as (x1?, y1?): (x0,y0) (x1,y0) (x0,y1), (x1,y0) (x1,y1) (x0,y1).
_CORNERS = ((0, 0), (1, 0), (0, 1), (1, 0), (1, 1), (0, 1))


@njit(**_JIT)
def block_quads(tiles, tile, w, h, blocks_per_row, cuts):
    """The vertex data of tile x tile quads whose pixels' records lie block-packed, block k
    (tile k) at (k % blocks_per_row, k // blocks_per_row) * tile (float32, 6 vertices a
    quad: the corner and its place in the record texture), the GL-pixel box around the
    tiles cut at the target's edge (n >= 1 for the box), and each quad's first tile.
    Consecutive tiles side by side in a row whose blocks are side by side too share a quad
    (fewer, larger triangles: merge_tiles), except across a tile k with cuts[k] (a new
    draw starts there)."""
    n = tiles.shape[0]
    data = np.empty(n * 24, np.float32)
    first = np.empty(n, np.int64)
    bx0, by0, bx1, by1 = w, h, 0, 0
    q = 0
    k = 0
    while k < n:
        e = k + 1
        while (e < n and not cuts[e] and e % blocks_per_row != 0
               and tiles[e, 1] == tiles[k, 1] and tiles[e, 0] == tiles[e - 1, 0] + 1):
            e += 1
        x0 = tiles[k, 0] * tile
        y0 = tiles[k, 1] * tile
        x1 = min((tiles[e - 1, 0] + 1) * tile, w)
        y1 = min(y0 + tile, h)
        bx0, by0, bx1, by1 = min(bx0, x0), min(by0, y0), max(bx1, x1), max(by1, y1)
        rx = (k % blocks_per_row) * tile - x0
        ry = (k // blocks_per_row) * tile - y0
        for v in range(6):
            x = x1 if _CORNERS[v][0] else x0
            y = y1 if _CORNERS[v][1] else y0
            o = (q * 6 + v) * 4
            data[o] = x
            data[o + 1] = y
            data[o + 2] = x + rx
            data[o + 3] = y + ry
        first[q] = k
        q += 1
        k = e
    return data[:q * 24], (bx0, by0, bx1, by1), first[:q]


@njit(**_JIT)
def merge_tiles(tiles):
    """The tiles (n, 2) (tx, ty) as few rectangles (m, 4) (tx0, ty0, tx1, ty1), ends
    exclusive, covering exactly the same tiles once: runs along x within a row, then runs
    with the same columns in consecutive rows joined. (llvmpipe pays per triangle and along
    every triangle's edges: 16 x 16 tile quads cost ~25% more per fragment than the same
    pixels in a few large quads.)"""
    n = tiles.shape[0]
    out = np.empty((n, 4), np.int64)
    if n == 0:
        return out
    big = max(tiles[:, 0].max(), tiles[:, 1].max()) + 2
    order = np.argsort(tiles[:, 1] * big + tiles[:, 0])
    runs = np.empty((n, 3), np.int64)             # (tx0, tx1, ty)
    r = 0
    for i in range(n):
        tx, ty = tiles[order[i], 0], tiles[order[i], 1]
        if r > 0 and runs[r - 1, 2] == ty and runs[r - 1, 1] == tx:
            runs[r - 1, 1] = tx + 1
        elif r > 0 and runs[r - 1, 2] == ty and runs[r - 1, 1] > tx:
            continue                                # a repeated tile
        else:
            runs[r, 0], runs[r, 1], runs[r, 2] = tx, tx + 1, ty
            r += 1
    big += 1
    order = np.argsort((runs[:r, 0] * big + runs[:r, 1]) * big + runs[:r, 2])
    m = 0
    for i in range(r):
        x0, x1, ty = runs[order[i], 0], runs[order[i], 1], runs[order[i], 2]
        if m > 0 and out[m - 1, 0] == x0 and out[m - 1, 2] == x1 and out[m - 1, 3] == ty:
            out[m - 1, 3] = ty + 1
        else:
            out[m, 0], out[m, 1], out[m, 2], out[m, 3] = x0, ty, x1, ty + 1
            m += 1
    return out[:m]


@njit(**_JIT)
def rect_quads(rects, tile, tile_h, w, h):
    """The vertex data of rectangles of tiles (float32 corners, 6 vertices a rectangle) and
    the GL-pixel box around them, cut at the target's edge."""
    n = rects.shape[0]
    data = np.empty(n * 12, np.float32)
    bx0, by0, bx1, by1 = w, h, 0, 0
    for k in range(n):
        x0 = rects[k, 0] * tile
        y0 = rects[k, 1] * tile_h
        x1 = min(rects[k, 2] * tile, w)
        y1 = min(rects[k, 3] * tile_h, h)
        bx0, by0, bx1, by1 = min(bx0, x0), min(by0, y0), max(bx1, x1), max(by1, y1)
        for v in range(6):
            data[(k * 6 + v) * 2] = x1 if _CORNERS[v][0] else x0
            data[(k * 6 + v) * 2 + 1] = y1 if _CORNERS[v][1] else y0
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


@njit(inline="always")
def _max_along_rows(a, r):
    """Each entry's largest value within r entries along its row, 0 past the ends."""
    th, tw = a.shape
    out = np.zeros((th, tw), a.dtype)
    for y in range(th):
        for x in range(tw):
            m = a[y, x]
            for u in range(max(0, x - r), min(tw, x + r + 1)):
                m = max(m, a[y, u])
            out[y, x] = m
    return out


@njit(**_JIT)
def square_max(a, r):
    """The largest value within r tiles (Chebyshev) of each tile, 0 past the edges, for
    a map of values >= 0 (scipy's maximum_filter(a, size=2 r + 1, mode="constant",
    cval=0)); a boolean map gives "any within r". Separable: along rows, then columns."""
    return np.ascontiguousarray(_max_along_rows(_max_along_rows(a, r).T, r).T)


@njit(**_JIT)
def pixel_tiles(ij, rows, cols, tile, height):
    """(rows, cols) boolean map, GL rows, of the tile x tile tiles holding an image pixel
    (i, j) of `ij` (row j from the top of an image `height` pixels high)."""
    out = np.zeros((rows, cols), np.bool_)
    for k in range(ij.shape[0]):
        out[_flip_row(ij[k, 1], height) // tile, ij[k, 0] // tile] = True
    return out


@njit(**_JIT)
def true_coords(selected):
    """(n, 2) int64 (x, y) of the True entries of a boolean map (rows = y), row by row
    (np.stack(np.nonzero(selected)[::-1], axis=1))."""
    th, tw = selected.shape
    out = np.empty((selected.sum(), 2), np.int64)
    k = 0
    for y in range(th):
        for x in range(tw):
            if selected[y, x]:
                out[k, 0] = x
                out[k, 1] = y
                k += 1
    return out


@njit(inline="always")
def _segment_meets_box(cx, cy, dx, dy, x0, y0, x1, y1):
    """Does the segment (cx, cy) +- (dx, dy) meet the closed box [x0, x1] x [y0, y1]?
    (slabs: the segment's parameter range inside each axis' slab, intersected)."""
    lo, hi = -1.0, 1.0
    for c, d, a, b in ((cx, dx, x0, x1), (cy, dy, y0, y1)):
        if d == 0.0:
            if c < a or c > b:
                return False
        else:
            t0, t1 = (a - c) / d, (b - c) / d
            if t0 > t1:
                t0, t1 = t1, t0
            lo, hi = max(lo, t0), min(hi, t1)
            if lo > hi:
                return False
    return True


@njit(**_JIT)
def outlines_along(boundary, todo, vn, tile, k, w, h, max_len, margin, spread=0.0):
    """FINE tiles (GL rows, `tile` px) where a tap of the composite's neighbourhood line
    may land on another object than its pixel's: the line of pixel x runs through its
    centre along vn, the NeighborMax vector (GL rows, k px tiles) of x's k-tile clamped
    to max_len, to +- |vn| / 2 (run only where |vn| / 2 > 0.5), and a tap takes the pixel
    holding its point, clamped to the screen. A tap on another object has an id boundary
    between it and x on the pixels the segment crosses, so a `boundary` tile (one holding
    a pixel whose right or upper neighbour shows another object) meets the segment: tile
    T is set when the box of T's pixel centres (per k-tile part), widened by `margin` px
    for rounding, swept along +- vn / 2, meets a boundary tile's box; a border tile's box
    runs on to infinity outward (a clamped tap). Only the tiles of `todo` are decided
    (the others read False). spread: the sine of the largest angle a line of the same
    reach may take off vn (the composite's merged own lines): every point of such a line
    lies within |vn| / 2 * spread of the segment, so the box is widened by that too."""
    rows, cols = boundary.shape
    out = np.zeros((rows, cols), np.bool_)
    big = 1e30
    for ty in range(rows):
        for tx in range(cols):
            if not todo[ty, tx]:
                continue
            x0, y0 = tx * tile, ty * tile
            x1, y1 = min(x0 + tile, w), min(y0 + tile, h)
            hit = False
            for ky in range(y0 // k, (y1 - 1) // k + 1):
                for kx in range(x0 // k, (x1 - 1) // k + 1):
                    vx, vy = vn[ky, kx, 0], vn[ky, kx, 1]
                    length = np.sqrt(vx * vx + vy * vy)
                    if hit or 0.5 * min(length, max_len) <= 0.5:
                        continue
                    s = 0.5 * min(length, max_len) / length
                    dx, dy = vx * s, vy * s
                    # The centres of T's pixels in this k-tile, widened by the margin
                    # and by the spread lines' offset.
                    e = margin + 0.5 * min(length, max_len) * spread
                    px0 = max(x0, kx * k) + 0.5 - e
                    px1 = min(x1, (kx + 1) * k) - 0.5 + e
                    py0 = max(y0, ky * k) + 0.5 - e
                    py1 = min(y1, (ky + 1) * k) - 0.5 + e
                    cx, cy = 0.5 * (px0 + px1), 0.5 * (py0 + py1)
                    hx, hy = 0.5 * (px1 - px0), 0.5 * (py1 - py0)
                    reach = int((max(abs(dx) + hx, abs(dy) + hy)) // tile) + 2
                    for by in range(max(0, ty - reach), min(rows, ty + reach + 1)):
                        for bx in range(max(0, tx - reach), min(cols, tx + reach + 1)):
                            if not boundary[by, bx]:
                                continue
                            bx0 = -big if bx == 0 else bx * tile
                            bx1 = big if bx == cols - 1 else min(bx * tile + tile, w)
                            by0 = -big if by == 0 else by * tile
                            by1 = big if by == rows - 1 else min(by * tile + tile, h)
                            if _segment_meets_box(cx, cy, dx, dy, bx0 - hx, by0 - hy,
                                                  bx1 + hx, by1 + hy):
                                hit = True
                                break
                        if hit:
                            break
            out[ty, tx] = hit
    return out


@njit(**_JIT)
def mark_tiles(pixels, rows, cols, tile):
    """(rows, cols, 2) float32, (0, 1) in the tile x tile tiles holding a pixel (i, j) of
    `pixels`, 0 elsewhere (image orientation)."""
    out = np.zeros((rows, cols, 2), np.float32)
    for k in range(pixels.shape[0]):
        out[pixels[k, 1] // tile, pixels[k, 0] // tile, 1] = 1.0
    return out


@njit(**_JIT)
def reach_boxes(reach, bw, bh, w, h, fine):
    """FINE x FINE tiles (GL rows, `fine` px, cut at the w x h screen) holding a pixel
    closer than reach[j, i] px to a pixel of box (i, j), the bw x bh px at (i bw, j bh)
    (cut at the screen too); reach < 0: no box. Distances between pixel indices: the
    nearest pixels of two boxes lie (gap x, gap y) apart, so a tile is set when
    gap_x^2 + gap_y^2 < reach^2 (numpy: that test over every box and tile)."""
    fh, fw = -(-h // fine), -(-w // fine)
    out = np.zeros((fh, fw), np.bool_)
    for j in range(reach.shape[0]):
        for i in range(reach.shape[1]):
            r = reach[j, i]
            if r < 0.0:
                continue
            ext = int(np.ceil(r))
            x0, y0 = i * bw, j * bh
            x1, y1 = min(x0 + bw, w) - 1, min(y0 + bh, h) - 1
            for v in range(max(0, y0 - ext) // fine, min(h - 1, y1 + ext) // fine + 1):
                gy = max(0, v * fine - y1, y0 - (min(v * fine + fine, h) - 1))
                for u in range(max(0, x0 - ext) // fine, min(w - 1, x1 + ext) // fine + 1):
                    gx = max(0, u * fine - x1, x0 - (min(u * fine + fine, w) - 1))
                    if gx * gx + gy * gy < r * r:
                        out[v, u] = True
    return out


@njit(**_JIT)
def tiles_in_reach(marked, tile, w, h, reach, fine):
    """FINE x FINE tiles (GL rows) whose pixels, grown by reach px on either axis and cut
    at the w x h screen, meet a `marked` tile (tile x tile px): gather_tiles.within_reach."""
    fh, fw = -(-h // fine), -(-w // fine)
    out = np.zeros((fh, fw), np.bool_)
    th, tw = marked.shape
    for v in range(fh):
        y0 = min(max(v * fine - reach, 0), h - 1) // tile
        y1 = min(max(min(v * fine + fine, h) - 1 + reach, 0), h - 1) // tile
        for u in range(fw):
            x0 = min(max(u * fine - reach, 0), w - 1) // tile
            x1 = min(max(min(u * fine + fine, w) - 1 + reach, 0), w - 1) // tile
            hit = False
            for ty in range(y0, min(y1, th - 1) + 1):
                for tx in range(x0, min(x1, tw - 1) + 1):
                    if marked[ty, tx]:
                        hit = True
            out[v, u] = hit
    return out


@njit(inline="always")
def _border_count(a, b, n):
    """How many of the border indices 0 and n - 1 lie in [a, b]."""
    return int(a <= 0 <= b) + int(n > 1 and a <= n - 1 <= b)


@njit(**_JIT)
def self_taps(off_x, off_y, run, k, w, h, fine):
    """FINE tiles (GL rows) holding a pixel X whose k-tile (k px, GL rows) runs and that
    no axis keeps every tap off: off_x[tile] says each tap leaves X's column, which holds
    for X off the first and last columns (there a tap may be clamped back onto X);
    likewise off_y for rows. An inner pixel needs one of the two, a border column's the
    rows', a border row's the columns', a corner is never safe. (McGuire's self-tap test,
    viewer/render/passes/gather_reach.py.)"""
    fh, fw = -(-h // fine), -(-w // fine)
    out = np.zeros((fh, fw), np.bool_)
    for v in range(fh):
        py0, py1 = v * fine, min(v * fine + fine, h) - 1
        for u in range(fw):
            px0, px1 = u * fine, min(u * fine + fine, w) - 1
            bad = False
            for ty in range(py0 // k, py1 // k + 1):
                ya, yb = max(py0, ty * k), min(py1, ty * k + k - 1)
                edge_y = _border_count(ya, yb, h)
                inner_y = yb - ya + 1 - edge_y > 0
                for tx in range(px0 // k, px1 // k + 1):
                    if not run[ty, tx]:
                        continue
                    xa, xb = max(px0, tx * k), min(px1, tx * k + k - 1)
                    edge_x = _border_count(xa, xb, w)
                    inner_x = xb - xa + 1 - edge_x > 0
                    ox, oy = off_x[ty, tx], off_y[ty, tx]
                    if ((inner_x and inner_y and not (ox or oy))
                            or (edge_x and inner_y and not oy)
                            or (inner_x and edge_y and not ox) or (edge_x and edge_y)):
                        bad = True
            out[v, u] = bad
    return out
