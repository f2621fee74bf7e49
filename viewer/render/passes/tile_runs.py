"""Tile lists: run a fragment pass only on the tiles where it has work.

On a software rasteriser (llvmpipe) every fragment costs, even one that returns at once.
A pass given a TileList draws the list's quads (glsl/passes/tiles.vert; adjacent tiles merged
into rectangles, which llvmpipe shades faster) with its own fragment shader instead of
the full-screen triangle; its targets are cleared first outside the tiles (or, for a
composite or gather, start as a copy of the sharp colour). Without lists (synthetic
tests, single passes) every pass draws full screen: both ways give the same pixels.
Which tiles a mode lists is the mode's (the hybrid: modes/hybrid/tile_select.py; the
gathers: passes/gather_tiles.py).
"""
from __future__ import annotations

import moderngl
import numpy as np

from viewer.render.graph.frame import Frame
from viewer.render.graph.kept import KeptSlot
from viewer.render.graph.passes import FullscreenPass
from viewer.render.passes import tile_kernels

FINE = 16                      # px per side of a list tile


class TileList:
    """The quads of a set of tiles in one vertex buffer (grown, never shrunk), and one
    vertex array per program that draws them."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.buffer: moderngl.Buffer | None = None
        self.vaos: dict[int, moderngl.VertexArray] = {}
        self.count = 0                 # tiles in the current list
        self.quads = 0                 # quads drawn: one per tile, or merged rectangles
        self.tiles = np.zeros((0, 2), np.int64)
        self.tile = self.tile_h = FINE  # tile width and height in px
        self.size = (0, 0)             # the target's size
        self.box = None                # (x0, y0, x1, y1) GL pixels around the tiles
        self.quad_first = None         # block-mapped lists: each tile's first quad
        self.vertex_shader = "passes/tiles.vert"
        self.blocks_per_row = None

    def set(self, tiles: np.ndarray, tile: int, size: tuple[int, int],
            blocks_per_row: int | None = None, tile_h: int | None = None,
            cuts: np.ndarray | None = None):
        """tiles: (n, 2) tile coordinates (tx, ty), GL orientation, of tile x tile pixels
        (tile x tile_h where given) of a target of `size`.

        blocks_per_row: also give every vertex `in_record`, its place in a texture that
        stores tile k's pixels as a tile x tile block at (k % blocks_per_row,
        k // blocks_per_row) * tile (glsl/passes/reveal_tiles.vert); `cuts`, the first tiles of
        the runs drawn apart (part())."""
        self.tiles = np.ascontiguousarray(tiles, np.int64).reshape(-1, 2)
        self.count = len(self.tiles)
        w, h = size
        self.tile, self.tile_h, self.size = tile, tile_h or tile, size
        if blocks_per_row:
            cut = np.zeros(self.count, np.bool_)
            if cuts is not None:
                cut[np.asarray(cuts, np.int64)[np.asarray(cuts) < self.count]] = True
            data, box, self.quad_first = tile_kernels.block_quads(
                self.tiles, tile, w, h, blocks_per_row, cut)
        else:
            rects = tile_kernels.merge_tiles(self.tiles)
            data, box = tile_kernels.rect_quads(rects, tile, self.tile_h, w, h)
            self.quad_first = None
        self.quads = len(data) // (24 if blocks_per_row else 12)
        self.box = tuple(int(b) for b in box) if self.count else None
        if blocks_per_row != self.blocks_per_row:
            self._release_buffer()                      # the vertex layout changes
        self.blocks_per_row = blocks_per_row
        self.vertex_shader = "passes/reveal_tiles.vert" if blocks_per_row else "passes/tiles.vert"
        nbytes = max(data.nbytes, 4)
        if self.buffer is None or self.buffer.size < nbytes:
            self._release_buffer()
            self.buffer = self.ctx.buffer(reserve=max(nbytes, 1 << 14))
        if data.nbytes:
            self.buffer.write(data.tobytes())

    def render(self, prog: moderngl.Program, first: int = 0, count: int | None = None):
        """Draw quads first .. first + count - 1 (default: all) with `prog`: tiles of a
        block-mapped list, merged rectangles (tile_kernels.merge_tiles) of another."""
        count = self.quads - first if count is None else count
        if count <= 0:
            return
        vao = self.vaos.get(prog.glo)
        if vao is None:
            if not self.blocks_per_row:
                layout = (self.buffer, "2f", "in_corner")
            elif prog.get("in_record", None) is not None:
                layout = (self.buffer, "2f 2f", "in_corner", "in_record")
            else:
                layout = (self.buffer, "2f 8x", "in_corner")
            vao = self.vaos[prog.glo] = self.ctx.vertex_array(prog, [layout])
        vao.render(moderngl.TRIANGLES, vertices=6 * count, first=6 * first)

    def part(self, first: int, count: int) -> "TileRange":
        """Tiles first .. first + count - 1 of this (block-mapped) list, drawable like a
        list."""
        if not self.blocks_per_row:
            raise ValueError("TileList.part: only a block-mapped list draws runs apart")
        q0, q1 = np.searchsorted(self.quad_first, (first, first + count))
        if count and self.quad_first[q0] != first:
            raise ValueError(f"TileList.part: tile {first} is not a cut given to set()")
        return TileRange(self, first, count, int(q0), int(q1 - q0))

    def _release_buffer(self):
        for v in self.vaos.values():
            v.release()
        self.vaos.clear()
        if self.buffer is not None:
            self.buffer.release()
            self.buffer = None

    def release(self):
        self._release_buffer()

    def clear_outside(self, frame: Frame, outputs: tuple[str, ...]):
        """clear_outside for these tiles: what FullscreenPass.draw calls before it draws
        them (the pass framework sits below this module and takes the tiles as an object)."""
        clear_outside(frame, outputs, self)


class TileRange:
    """A run of a TileList's tiles (what FullscreenPass.draw needs: render and box)."""

    def __init__(self, tiles: TileList, first: int, count: int, quad: int, quads: int):
        self.tiles, self.first, self.count = tiles, first, count
        self.quad, self.quads = quad, quads
        self.vertex_shader = tiles.vertex_shader
        t = tiles.tiles[first:first + count]
        self.box = tiles.box if count == 0 else _box(t, tiles.tile, tiles.size)

    def render(self, prog: moderngl.Program):
        self.tiles.render(prog, self.quad, self.quads)


def _box(tiles: np.ndarray, tile: int, size) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) GL pixels around tiles (n >= 1), cut at the screen's edge."""
    lo = tiles.min(axis=0) * tile
    hi = np.minimum((tiles.max(axis=0) + 1) * tile, size)
    return int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])


def kept_tile_list(frame: Frame, name: str) -> TileList:
    """A TileList kept across frames under `name` (its vertex buffer reused), made the
    first time (e.g. clear_outside's "zero_tiles")."""
    return frame.kept.get_or_make(KeptSlot(name, TileList), lambda: TileList(frame.ctx),
                                  lambda tl: tl.ctx is frame.ctx)


def within_reach(sources: np.ndarray, reach, tile: int) -> np.ndarray:
    """Tiles T from which a source tile lies within reach[T] px (an array per tile, or one
    number): tiles L apart (Chebyshev) have a gap of (L - 1) tiles between their pixels,
    so the nearest source must lie L <= 1 + reach / tile away (L = 0: T itself)."""
    if not sources.any():
        return np.zeros_like(sources)
    return tile_kernels.chessboard_distance(sources) <= 1.0 + np.asarray(reach) / tile


# glsl/passes/zero_tiles.frag's target kinds (OUTk; 0: no target at location k).
OUT_FLOAT, OUT_INT = 1, 2


class ZeroTiles(FullscreenPass):
    """Every target of a framebuffer back to 0 over a tile list (glsl/passes/zero_tiles.frag)."""
    fragment = "passes/zero_tiles.frag"

    def defines(self, frame: Frame):
        return {"OUT_FLOAT": OUT_FLOAT, "OUT_INT": OUT_INT}

    def zero(self, frame: Frame, outputs: tuple[str, ...], tiles: TileList):
        # moderngl's u* and i* formats are integer targets; OUTk 0: no target k.
        kinds = [OUT_INT if frame.pool.spec(n).dtype[0] in "ui" else OUT_FLOAT
                 for n in outputs]
        self.draw(frame, outputs, {}, {"u_viewport": tuple(float(x) for x in tiles.size)},
                  tiles=tiles, clear=False,            # (a strip's size, not the frame's)
                  defines={f"OUT{k}": kinds[k] if k < len(kinds) else 0 for k in range(4)})


_ZERO = ZeroTiles()


def clear_outside(frame: Frame, outputs: tuple[str, ...], tiles: TileList):
    """Before a pass draws `tiles`, writing every texel of them in `outputs`: zero what
    the targets hold outside them. Where a tiled pass of the same geometry wrote them
    last, that is its tiles not drawn again, zeroed tile by tile in one draw (nothing
    when the tiles repeat); otherwise the box written since the last clear."""
    stale = frame.pool.stale_tiles(outputs, tiles)
    if stale is None:
        frame.pool.clear(outputs)
        return
    if stale.any():
        tl = kept_tile_list(frame, "zero_tiles")
        tl.set(tile_coords(stale), tiles.tile, tiles.size, tile_h=tiles.tile_h)
        _ZERO.zero(frame, outputs, tl)


def tile_coords(selected: np.ndarray) -> np.ndarray:
    """(n, 2) (tx, ty) of the True entries of a GL-orientation (rows = ty) tile map."""
    return tile_kernels.true_coords(np.ascontiguousarray(selected, np.bool_))
