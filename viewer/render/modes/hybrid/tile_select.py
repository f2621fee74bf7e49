"""The hybrid's tile selection: which tiles each of its passes runs on.

Most of a frame does not move. After the G-buffer, `motion_tiles` reduces the
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

The lists are TileLists (viewer/render/passes/tile_runs.py); without them (synthetic
tests, single passes) every pass draws full screen: both ways give the same pixels, which
tests/test_tile_lists.py checks on real scenes.
"""
from __future__ import annotations

import math

import moderngl
import numpy as np

from viewer.render.graph.frame import Frame
from viewer.render.graph.host import HostResource
from viewer.render.graph.kept import KeptSlot
from viewer.render.graph.passes import FullscreenPass, Pass
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.modes.hybrid.params import HybridParams  # noqa: F401  (registers the "hybrid" group)
from viewer.render.passes import tile_kernels
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.passes.gbuffer import path_samplers, path_targets
from viewer.render.passes.tile_runs import FINE, TileList, tile_coords, within_reach
from viewer.render.passes.tiles import StripSpec

# Extra reach (px) on top of half the displacement and the landing tolerance: the
# composite's walks floor positions to pixels, so a landing can sit a pixel further out.
MARGIN = 1.0


class TileLists:
    """Per-renderer host state: the tile lists and this frame's tile maps, reused frame
    after frame."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.moving = TileList(ctx)
        self.active = TileList(ctx)
        self.surface = TileList(ctx)   # moving, and an id boundary within the probes' reach
        self.shape = (0, 0)            # (rows, columns) of FINE tiles this frame
        # This frame's FINE tile maps (GL rows): the longest displacement (px), the moving
        # tiles, those of `surface`, and the tiles that may hold an id boundary.
        self.longest = np.zeros((0, 0), np.float32)
        self.moving_tiles = np.zeros((0, 0), bool)
        self.surface_tiles = np.zeros((0, 0), bool)
        self.boundary = np.zeros((0, 0), bool)
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


def moving_tiles(longest: np.ndarray, min_speed: float) -> np.ndarray:
    """Tiles holding a pixel with |D| >= min_speed (the ray mask's own test)."""
    return longest >= _threshold(min_speed)


def _threshold(min_speed: float) -> np.float32:
    # A hair below min_speed so float rounding can only add a tile, never drop one.
    return np.float32(min_speed) * np.float32(1.0 - 1e-6)


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


def near_boundary(longest: np.ndarray, boundary: np.ndarray, tile: int) -> np.ndarray:
    """Tiles whose displacement test can see another object: a tile that may hold an id
    boundary lies within R = longest / 2 + 2 px (the reach of the probes X +- D/2, a half
    pixel of rounding, and the other pixel of a boundary pair). Elsewhere every probe
    lands on the pixel's own object: nothing is uncovered (and the relative-displacement
    probes, run only after an uncovering, never start)."""
    return within_reach(boundary, 0.5 * longest.astype(np.float64) + 2.0, tile)


PATH_TEXTURES = path_samplers(path_targets(4))


def path_textures(segments: int, names=PATH_TEXTURES) -> dict[str, str]:
    """The sampler bindings of the path targets this frame has (none for one segment)."""
    return dict(list(names.items())[:segments // 2])


class MotionTiles(FullscreenPass):
    name = "motion_tiles"
    fragment = "modes/hybrid/motion_tiles.frag"
    produces = ("motion_tiles_x", "motion_tiles")

    def __init__(self, segments: int = 1):
        self.segments = segments
        self.inputs = ("hybrid_front", *path_targets(segments))   # D, id; the path

    def defines(self, frame: Frame):
        return {"SEGMENTS": self.segments}

    def outputs(self, frame: Frame):
        return {"motion_tiles_x": StripSpec(2, "f4", tile=FINE),
                "motion_tiles": TexSpec(2, "f4", tile=FINE)}

    def execute(self, frame: Frame):
        for stage, src, dst in ((0, "hybrid_front", "motion_tiles_x"),
                                (1, "motion_tiles_x", "motion_tiles")):
            paths = path_textures(self.segments) if stage == 0 else {}
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
        lists = frame.kept.get_or_make(KEPT_LISTS, lambda: TileLists(frame.ctx),
                                       lambda kept: kept.ctx is frame.ctx)
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
