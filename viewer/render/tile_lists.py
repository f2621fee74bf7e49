"""Tile lists: run a fragment pass only on the tiles where it has work.

On a software rasteriser (llvmpipe) every fragment costs, even one that returns at once,
and most of a frame does not move. After the G-buffer, `motion_tiles` reduces the
displacement to its longest |D| per FINE x FINE tile, and flags the tiles that may hold an
id boundary (a pixel whose right or upper neighbour shows another object); the host reads
that small texture back and lists three sets of tiles (GL orientation: tile (0, 0) at the
bottom left):

  moving: a pixel there moves at least hybrid.min_speed: the ray mask's per-pixel passes
      run only there (everywhere else their answer is "not masked");
  surface: the moving tiles with an id boundary within their displacement test's reach
      (near_boundary): the test runs only there; elsewhere every probe lands on the
      pixel's own object (a moving camera: vase_pan 204 of 883 moving tiles);
  active: a surface's motion can reach the tile (within half its longest displacement,
      clamped to the blur limit, plus the composite's landing tolerance and a pixel): the
      composite runs only there; everywhere else it would return the sharp colour.

A pass given a TileList draws the list's quads (glsl/tiles.vert; adjacent tiles merged
into rectangles, which llvmpipe shades faster) with its own fragment shader instead of
the full-screen triangle; its targets are cleared first (or, for the composite, start as
a copy of the sharp colour). Without lists (synthetic tests, single
passes) every pass draws full screen: both ways give the same pixels, which
tests/test_tile_lists.py checks on real scenes.
"""
from __future__ import annotations

import math

import moderngl
import numpy as np

from .blur_common import max_radius_px
from .frame import Frame
from .gbuffer import path_targets
from .host import HostResource
from .hybrid.params import HybridParams  # noqa: F401  (registers the "hybrid" group)
from .passes import FullscreenPass, Pass
from .pool import ReadBack, TexSpec
from . import tile_kernels
from .kept import KeptSlot
from .tiles import StripSpec

FINE = 16                      # px per side of a list tile
# Extra reach (px) on top of half the displacement and the landing tolerance: the
# composite's walks floor positions to pixels, so a landing can sit a pixel further out.
MARGIN = 1.0


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
        self.box = None                # (x0, y0, x1, y1) GL pixels around the tiles
        self.vertex_shader = "tiles.vert"
        self.blocks_per_row = None

    def set(self, tiles: np.ndarray, tile: int, size: tuple[int, int],
            blocks_per_row: int | None = None, tile_h: int | None = None,
            cuts: np.ndarray | None = None):
        """tiles: (n, 2) tile coordinates (tx, ty), GL orientation, of tile x tile pixels
        (tile x tile_h where given) of a target of `size`.

        blocks_per_row: also give every vertex `in_record`, its place in a texture that
        stores tile k's pixels as a tile x tile block at (k % blocks_per_row,
        k // blocks_per_row) * tile (glsl/reveal_tiles.vert); `cuts`, the first tiles of
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
        self.vertex_shader = "reveal_tiles.vert" if blocks_per_row else "tiles.vert"
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


class TileLists:
    """Per-renderer host state: the two lists, reused frame after frame."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.moving = TileList(ctx)
        self.active = TileList(ctx)
        self.surface = TileList(ctx)   # moving, and an id boundary within the probes' reach
        self.shape = (0, 0)            # (rows, columns) of FINE tiles this frame
        self.boundary = np.zeros((0, 0), bool)   # tiles that may hold an id boundary
        self._extra: dict[str, TileList] = {}

    def extra(self, name: str) -> TileList:
        """Another list kept with these (e.g. the composite's split of the active tiles)."""
        if name not in self._extra:
            self._extra[name] = TileList(self.ctx)
        return self._extra[name]

    def release(self):
        self.moving.release()
        self.active.release()
        self.surface.release()
        for tl in self._extra.values():
            tl.release()


# The lists, kept from frame to frame (their vertex buffers reused), and this frame's.
KEPT_LISTS = KeptSlot("tile_lists", TileLists, "the hybrid's tile lists, reused")
TILE_LISTS = HostResource("tile_lists", TileLists,
                          "this frame's moving, surface and active tiles (select_tiles)")


def kept_tile_list(frame: Frame, name: str) -> TileList:
    """A TileList kept across frames under `name` (its vertex buffer reused), made the
    first time (e.g. clear_outside's "zero_tiles")."""
    slot = KeptSlot(name, TileList)
    tl = frame.kept.get(slot)
    if tl is None or tl.ctx is not frame.ctx:
        tl = frame.kept.put(slot, TileList(frame.ctx))
    return tl


def moving_tiles(longest: np.ndarray, min_speed: float) -> np.ndarray:
    """Tiles holding a pixel with |D| >= min_speed (the ray mask's own test)."""
    return longest >= _threshold(min_speed)


def _threshold(min_speed: float) -> np.float32:
    # A hair below min_speed so float rounding can only add a tile, never drop one.
    return np.float32(min_speed) * np.float32(1.0 - 1e-6)


def moving_threshold(frame: Frame) -> float:
    """The longest |D| from which a tile counts as moving (for shaders that test tiles)."""
    return float(_threshold(frame.params["hybrid"].min_speed))


def active_tiles(longest: np.ndarray, tile: int, max_disp: float, tolerance: float) -> np.ndarray:
    """Tiles that any moving surface can reach: tile T is active when some tile T' with
    longest displacement m' > 0 lies within min(m', max_disp) / 2 + tolerance + MARGIN px
    (Chebyshev gap between the tiles, a bound on the distance between their pixels)."""
    m = np.minimum(longest.astype(np.float64), max_disp)
    reach = np.where(m > 0.0, 0.5 * m + tolerance + MARGIN, -1.0)
    radius = int(math.ceil((0.5 * max_disp + tolerance + MARGIN) / tile)) + 1
    # Tiles L apart (Chebyshev) have a gap of (L - 1) tiles: each source marks the square
    # of the L whose gap it reaches.
    return tile_kernels.dilate_by_reach(reach, tile, radius)


def within_reach(sources: np.ndarray, reach, tile: int) -> np.ndarray:
    """Tiles T from which a source tile lies within reach[T] px (an array per tile, or one
    number): tiles L apart (Chebyshev) have a gap of (L - 1) tiles between their pixels,
    so the nearest source must lie L <= 1 + reach / tile away (L = 0: T itself)."""
    if not sources.any():
        return np.zeros_like(sources)
    return tile_kernels.chessboard_distance(sources) <= 1.0 + np.asarray(reach) / tile


def near_boundary(longest: np.ndarray, boundary: np.ndarray, tile: int) -> np.ndarray:
    """Tiles whose displacement test can see another object: a tile that may hold an id
    boundary lies within R = longest / 2 + 2 px (the reach of the probes X +- D/2, a half
    pixel of rounding, and the other pixel of a boundary pair). Elsewhere every probe
    lands on the pixel's own object: nothing is uncovered (and the relative-displacement
    probes, run only after an uncovering, never start)."""
    return within_reach(boundary, 0.5 * longest.astype(np.float64) + 2.0, tile)


# glsl/zero_tiles.frag's target kinds (OUTk; 0: no target at location k).
OUT_FLOAT, OUT_INT = 1, 2


class ZeroTiles(FullscreenPass):
    """Every target of a framebuffer back to 0 over a tile list (glsl/zero_tiles.frag)."""
    fragment = "zero_tiles.frag"

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


def segments(frame: Frame) -> int:
    """The hybrid's path segments this frame (glsl/path.glsl): hybrid.segments where the
    G-buffer wrote the path targets (it discards them when it writes none), else 1, the
    chord alone (passes run on buffers without a path)."""
    k = int(frame.params["hybrid"].segments)
    names = frame.pool.names()
    return k if all(n in names for n in path_targets(k)) else 1


PATH_TEXTURES = {"u_path0": "hybrid_path", "u_path1": "hybrid_path2"}


def path_textures(frame: Frame, names=PATH_TEXTURES) -> dict[str, str]:
    """The sampler bindings of the path targets this frame has (none for one segment)."""
    return dict(list(names.items())[:segments(frame) // 2])


class MotionTiles(FullscreenPass):
    name = "motion_tiles"
    fragment = "motion_tiles.frag"
    produces = ("motion_tiles_x", "motion_tiles")

    def __init__(self, segments: int = 1):
        self.inputs = ("hybrid_front", *path_targets(segments))   # D, id; the path

    def defines(self, frame: Frame):
        return {"SEGMENTS": segments(frame)}

    def outputs(self, frame: Frame):
        return {"motion_tiles_x": StripSpec(2, "f4", tile=FINE),
                "motion_tiles": TexSpec(2, "f4", tile=FINE)}

    def execute(self, frame: Frame):
        for stage, src, dst in ((0, "hybrid_front", "motion_tiles_x"),
                                (1, "motion_tiles_x", "motion_tiles")):
            paths = path_textures(frame) if stage == 0 else {}
            self.draw(frame, (dst,), {"u_source": src, **paths}, {"u_tile": FINE},
                      defines={"STAGE": stage})


class SelectTiles(Pass):
    """Host side: read `motion_tiles` back (a few thousand floats) and fill the lists."""
    name = "select_tiles"
    runs_on = "cpu"
    inputs = ("motion_tiles",)
    host_outputs = (TILE_LISTS,)
    reads_back = (ReadBack("motion_tiles"),)

    def execute(self, frame: Frame):
        lists = frame.kept.get(KEPT_LISTS)
        if lists is None or lists.ctx is not frame.ctx:
            lists = frame.kept.put(KEPT_LISTS, TileLists(frame.ctx))
        tex = frame.pool.get("motion_tiles")
        tw, th = tex.size
        both = np.frombuffer(frame.pool.read_back("motion_tiles"),
                             np.float32).reshape(th, tw, 2)   # GL rows
        longest, boundary = both[..., 0].copy(), both[..., 1] != 0
        p = frame.params["hybrid"]
        moving = moving_tiles(longest, p.min_speed)
        active = active_tiles(longest, FINE, 2.0 * max_radius_px(frame), p.tolerance)
        surface = moving & near_boundary(longest, boundary, FINE)
        lists.shape = longest.shape
        lists.longest = longest
        lists.moving_tiles = moving
        lists.surface_tiles = surface
        lists.boundary = boundary
        lists.moving.set(tile_coords(moving), FINE, frame.size)
        lists.active.set(tile_coords(active), FINE, frame.size)
        lists.surface.set(tile_coords(surface), FINE, frame.size)
        frame.host.put(TILE_LISTS, lists)
        frame.stats["tiles"] = int(tw * th)
        frame.stats["moving_tiles"] = lists.moving.count
        frame.stats["active_tiles"] = lists.active.count
        frame.stats["surface_tiles"] = lists.surface.count


def moving_strips(frame: Frame, k: int) -> TileList | None:
    """The texels of a k x 1 TileMax strip (ceil(W / k) x H) that can be nonzero: those
    whose k pixels meet a FINE tile with any displacement (longest |D| > 0, so elsewhere
    every D there is exactly 0, the strip's value), as 1 x FINE quads; None without tile
    lists."""
    lists = frame.host.get(TILE_LISTS)
    if lists is None:
        return None
    w, h = frame.size
    sw = -(-w // k)
    x0 = np.arange(sw) * k
    t0, t1 = x0 // FINE, (np.minimum(x0 + k, w) - 1) // FINE          # FINE columns met
    csum = np.concatenate([np.zeros((lists.shape[0], 1), np.int64),
                           np.cumsum(lists.longest > 0, axis=1)], axis=1)
    meets = csum[:, t1 + 1] - csum[:, t0] > 0                          # (FINE rows, strips)
    tl = lists.extra("tilemax_strips")
    tl.set(tile_coords(meets), 1, (sw, h), tile_h=FINE)
    return tl


def tile_strips(frame: Frame, tiles: np.ndarray, name: str) -> TileList:
    """The texels of a FINE x 1 strip (ceil(W / FINE) x H) under the FINE tiles `tiles`
    (GL rows), as 1 x FINE quads: the extra list `name`."""
    w, h = frame.size
    tl = frame.host[TILE_LISTS].extra(name)
    tl.set(tile_coords(tiles), 1, (-(-w // FINE), h), tile_h=FINE)
    return tl


def tile_list(frame: Frame, which: str) -> TileList | None:
    """The frame's `which` ("moving", "active" or "surface") list, or None to draw full
    screen."""
    lists = frame.host.get(TILE_LISTS)
    return getattr(lists, which) if lists is not None else None


def selection_passes(segments: int = 1) -> list:
    """motion_tiles (the path of `segments` pieces) and select_tiles."""
    return [MotionTiles(segments), SelectTiles()]
