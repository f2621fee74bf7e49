"""Compiled loops (numba) for the hybrid's reveal on the render side: the ray mask read back
from GL as a pixel list, and the reveal's hits packed into per-tile record blocks for the
shading draw. Numpy's per-call cost (~5 us a call) over tens of thousands of rays outweighs
the work; each function does its chain in one loop (tests/test_raymask.py,
tests/test_tile_lists.py, tests/test_raytrace.py).

Compiled once per machine (cache=True) and run without the GIL (nogil=True).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from world.conventions import flip_row

_JIT = dict(cache=True, nogil=True)
_flip_row = njit(inline="always")(flip_row)     # conventions' row flip, compiled in


@njit(**_JIT)
def record_inputs(px, height, object_id, prim_id, face_offset, static_view, static_key):
    """pack_blocks' per-ray inputs in one pass: the GL pixel (gx, gy) of image pixel px
    (i, j) in an image `height` rows high, the key (1 + object id, or static_key >= 0
    where static_view), and the face row in the SurfaceTable (face_offset[object id] +
    prim id; -1 on a miss)."""
    n = px.shape[0]
    gx = np.empty(n, np.int64)
    gy = np.empty(n, np.int64)
    key = np.empty(n, np.int64)
    face = np.empty(n, np.int64)
    for k in range(n):
        gx[k] = px[k, 0]
        gy[k] = _flip_row(px[k, 1], height)
        oid = object_id[k]
        key[k] = static_key if static_key >= 0 and static_view[k] else np.int64(oid) + 1
        face[k] = face_offset[oid] + np.int64(prim_id[k]) if oid != 0 else -1
    return gx, gy, key, face


@njit(**_JIT)
def _counting_order(values, top, order):
    """`order` (a permutation of the rows) stably sorted by values[row] in [0, top)."""
    count = np.zeros(top + 1, np.int64)
    for i in range(order.shape[0]):
        count[values[order[i]] + 1] += 1
    for v in range(top):
        count[v + 1] += count[v]
    out = np.empty_like(order)
    for i in range(order.shape[0]):
        v = values[order[i]]
        out[count[v]] = order[i]
        count[v] += 1
    return out


@njit(**_JIT)
def pack_blocks(gx, gy, key, face, bary, tile_bits, row_bits):
    """Hit records in blocks (viewer/render/modes/hybrid/reveal.py layer_hits): for ray k at GL
    pixel (gx, gy) with key (1 + object id; small non-negative ints), face row and
    barycentrics, the record (max(face, 0), u, v, key) in one tile x tile block per
    (key, screen tile) holding its pixels, tile = 2^tile_bits; in the blocks of the same
    screen tile's other keys, that pixel's record is (0, 0, 0, -1), "another key's";
    everything else 0, "no ray here". Blocks are numbered in
    order of (key, tile row, tile column), 2^row_bits to a row of the record texture
    (powers of two: shifts and masks, not divisions, per pixel).
    Returns (records (rows, 2^row_bits * tile, 4) float32, each block's key, each
    block's tile (tx, ty), each key's run of blocks (key, first, count) in order)."""
    n = gx.shape[0]
    tile, per_row = 1 << tile_bits, 1 << row_bits
    cols = rows_t = top = 0
    for k in range(n):
        cols = max(cols, (gx[k] >> tile_bits) + 1)
        rows_t = max(rows_t, (gy[k] >> tile_bits) + 1)
        top = max(top, key[k])
    # The keys present, ranked: the (key, tile) table has a row per present key only.
    rank = np.full(top + 1, -1, np.int64)
    for k in range(n):
        rank[key[k]] = 0
    n_keys = 0
    for c in range(top + 1):
        if rank[c] == 0:
            rank[c] = n_keys
            n_keys += 1
    per_key = cols * rows_t
    # Each ray's cell, rank(key) * per_key + tile, and the cells present in order (block b
    # is the b-th): the rays sorted by cell, by one counting sort where the cells are few
    # for the rays, else by tile and then by key rank (a table over every key and tile of
    # the screen is ~190 k cells at 4 px tiles for crowd_pan's 13 keys and 4.5 k rays).
    cell = np.empty(n, np.int64)
    tile_of = np.empty(n, np.int64)       # (kept apart: no divisions per ray)
    rank_of = np.empty(n, np.int64)
    for k in range(n):
        tile_of[k] = (gy[k] >> tile_bits) * cols + (gx[k] >> tile_bits)
        rank_of[k] = rank[key[k]]
        cell[k] = rank_of[k] * per_key + tile_of[k]
    if n_keys * per_key <= 4 * n:         # few cells for the rays: sort by cell at once
        order = _counting_order(cell, n_keys * per_key, np.arange(n))
    else:
        order = _counting_order(rank_of, n_keys, _counting_order(tile_of, per_key, np.arange(n)))
    block = np.empty(n, np.int64)          # each ray's block
    blocks = 0
    for i in range(n):
        if i == 0 or cell[order[i]] != cell[order[i - 1]]:
            blocks += 1
        block[order[i]] = blocks - 1
    keys = np.empty(n_keys, np.int64)
    for c in range(top + 1):
        if rank[c] >= 0:
            keys[rank[c]] = c
    block_key = np.empty(blocks, np.int64)
    block_tile = np.empty((blocks, 2), np.int64)
    # The blocks of each screen tile as a linked list (several keys drawn there).
    head = np.full(per_key, -1, np.int64)
    after = np.full(blocks, -1, np.int64)
    shared = np.zeros(per_key, np.int64)
    for i in range(n):
        k = order[i]
        b = block[k]
        if i == 0 or block[order[i - 1]] != b:
            r = tile_of[k]
            block_key[b] = keys[rank_of[k]]
            block_tile[b, 0] = r % cols
            block_tile[b, 1] = r // cols
            after[b] = head[r]
            head[r] = b
            shared[r] += 1
    n_rows = (blocks + per_row - 1) >> row_bits
    records = np.zeros((n_rows * tile, per_row * tile, 4), np.float32)
    mask = tile - 1
    for k in range(n):
        b = block[k]
        ox, oy = gx[k] & mask, gy[k] & mask
        rx = ((b & (per_row - 1)) << tile_bits) + ox
        ry = ((b >> row_bits) << tile_bits) + oy
        records[ry, rx, 0] = max(face[k], 0)
        records[ry, rx, 1] = bary[k, 0]
        records[ry, rx, 2] = bary[k, 1]
        records[ry, rx, 3] = key[k]
        r = tile_of[k]
        if shared[r] > 1:
            # The tile's other keys' blocks: -1 there, "another draw's pixel".
            o = head[r]
            while o >= 0:
                if o != b:
                    records[((o >> row_bits) << tile_bits) + oy,
                            ((o & (per_row - 1)) << tile_bits) + ox, 3] = -1.0
                o = after[o]
    # The blocks are in key order: each key's blocks are one run.
    runs = np.zeros((n_keys, 3), np.int64)
    for b in range(blocks):
        r = rank[block_key[b]]
        if runs[r, 2] == 0:
            runs[r, 0], runs[r, 1] = block_key[b], b
        runs[r, 2] += 1
    return records, block_key, block_tile, runs


@njit(**_JIT)
def nonzero_pixels(gl_rows, i0, j0):
    """The nonzero pixels of a window read back from GL (rows bottom-up) in image order
    (rows top-down, then columns): their image coordinates (i, j), with (i0, j0) the
    window's top-left image pixel, and their values. No flipped copy; a first pass counts
    each row's pixels (a branch-free sum that vectorises), the second reads only the rows
    holding any, and in them tests runs of 8 pixels at once (one OR, one branch), then
    reads only the runs holding any: the mask is mostly 0, in bands. The OR is written
    out and the pixels' helper inlined: numba compiles a loop for either into slower code."""
    h, w = gl_rows.shape
    per_row = np.zeros(h, np.int64)
    for y in range(h):
        c = 0
        for x in range(w):
            c += gl_rows[y, x] != 0
        per_row[y] = c
    count = per_row.sum()
    ij = np.empty((count, 2), np.int64)
    values = np.empty(count, gl_rows.dtype)
    k = 0
    whole = w - w % 8
    for r in range(h):
        y = _flip_row(r, h)
        if per_row[y] == 0:
            continue
        row = gl_rows[y]
        for x0 in range(0, whole, 8):
            if (row[x0] | row[x0 + 1] | row[x0 + 2] | row[x0 + 3] | row[x0 + 4]
                    | row[x0 + 5] | row[x0 + 6] | row[x0 + 7]) == 0:
                continue
            k = _take_nonzero(row, x0, x0 + 8, r + j0, i0, ij, values, k)
        k = _take_nonzero(row, whole, w, r + j0, i0, ij, values, k)
    return ij, values


@njit(inline="always")
def _take_nonzero(row, x0, x1, j, i0, ij, values, k):
    """nonzero_pixels' pixels of row[x0:x1] (image row j) from entry k on; the next k."""
    for x in range(x0, x1):
        v = row[x]
        if v != 0:
            ij[k, 0] = x + i0
            ij[k, 1] = j
            values[k] = v
            k += 1
    return k
