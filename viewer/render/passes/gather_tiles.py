"""The post-process gathers drawn only on the tiles where they can change a pixel.

McGuire 2012, UE4-style and Guertin 2014 each end in a gather that returns the sharp
colour wherever the tile it looks up (NeighborMax, or UE4's dilated max) moves by no more
than its early-out speed. On a software rasteriser every fragment costs even when it
returns at once, so the gather reads that tile texture back (a few hundred texels), lists
the tiles whose lookup can pass the early out (or, where the lookup is jittered, the
FINE tiles within the jitter's reach of one), and draws only those, as merged rectangles
(tile_runs.py TileList), over a copy of the sharp colour: every other
pixel is the colour its early out would have written, so the image is the same to the
byte as a full-screen draw. Guertin's gather and the gathers along a path take these
tiles; McGuire's and UE4's along a straight motion take finer ones, within the reach of
a moving pixel (viewer/render/passes/gather_reach.py), drawn the same way.
"""
from __future__ import annotations

import math

import numpy as np

from viewer.render.passes import tile_kernels
from viewer.render.graph.frame import Frame
from viewer.render.passes.tile_runs import FINE, TileList, kept_tile_list, tile_coords

# Relative margin on the early-out speed: the host's float64 length and the shader's
# float32 one may round apart; a tile near the threshold is drawn (that changes no pixel).
MARGIN = 1e-4


def moving_lookups(vectors: np.ndarray, early_out_px: float) -> np.ndarray:
    """Lookup tiles (GL rows) whose vector is longer than early_out_px (within MARGIN)."""
    v = np.asarray(vectors, np.float64)
    return np.hypot(v[..., 0], v[..., 1]) > early_out_px * (1.0 - MARGIN)


def within_reach(moving: np.ndarray, tile: int, size: tuple[int, int], reach_px: int,
                 fine: int = FINE) -> np.ndarray:
    """FINE x FINE tiles (GL rows) holding a pixel that can look up a `moving` tile (tile
    x tile px) from up to reach_px px away on either axis: a FINE tile's pixels, grown by
    reach_px and cut at the screen's edge, meet a moving tile (tile_kernels.tiles_in_reach)."""
    w, h = size
    return tile_kernels.tiles_in_reach(np.ascontiguousarray(moving, np.bool_), tile, w, h,
                                       reach_px, fine)


def half_extents(frame: Frame, paths: tuple[str, ...]) -> np.ndarray:
    """Half the path extent (glsl/passes/path.glsl path_extent) of each texel of the path
    targets `paths` (two points a texel each), as an (H, W, 2) vector (extent, 0), the
    length the early out of a path gather tests."""
    points = []
    for name in paths:
        tex = frame.pool.get(name)
        points.append(np.frombuffer(frame.pool.read_back(name), np.float32)
                      .reshape(tex.size[1], tex.size[0], 2, 2).astype(np.float64))
    o = np.concatenate(points, axis=2)
    half = np.sqrt((o * o).sum(-1).max(-1))
    return np.stack([half, np.zeros_like(half)], axis=-1)


def read_tiles(frame: Frame, name: str) -> np.ndarray:
    """A small pool texture read back: (rows, columns, components) float32, GL rows."""
    tex = frame.pool.get(name)
    return np.frombuffer(frame.pool.read_back(name), np.float32).reshape(tex.size[1], tex.size[0],
                                                         tex.components)


def tile_list(frame: Frame, name: str, selected: np.ndarray, tile: int) -> TileList:
    """The tiles of `selected` (GL rows, tile x tile px) as the kept list `name`."""
    tl = kept_tile_list(frame, f"gather_tiles:{name}")
    tl.set(tile_coords(selected), tile, frame.size)
    return tl


def gather_tiles(frame: Frame, source: str, components: slice, tile: int,
                 early_out_px: float, reach_px: int,
                 paths: tuple[str, ...] = ()) -> TileList | None:
    """The tiles to draw of a gather that looks `source` (tile x tile px texels) up, from
    up to reach_px px away where the lookup is jittered: its `components` hold the
    vector the early out tests. The lookup's own tiles where reach_px is 0, FINE tiles
    otherwise (a tile's worth of reach would draw a ring of whole k x k tiles around
    every moving one). `paths`: `source`'s path targets, whose half extent the early out
    tests instead where given (a gather along a path). None where every pixel may pass
    the early out (the full-screen triangle then, with no copy of the colour)."""
    vectors = (half_extents(frame, paths) if paths
               else read_tiles(frame, source)[..., components])
    moving = moving_lookups(vectors, early_out_px)
    if reach_px > 0:
        moving, tile = within_reach(moving, tile, frame.size, reach_px), FINE
    frame.stats[f"{source}_gather_tiles"] = int(moving.sum())
    return None if moving.all() else tile_list(frame, source, moving, tile)


def jitter_reach(tile_jitter: float, tile: int) -> int:
    """Pixels (per axis) a lookup offset by up to tile_jitter tiles can land from its
    pixel: the offset, rounded up, plus one for the rounding to a pixel."""
    return int(math.ceil(tile_jitter * tile)) + 1 if tile_jitter > 0.0 else 0


def draw_gather(pass_, frame: Frame, output: str, textures: dict, uniforms: dict,
                tiles: TileList | None, variants: tuple = ()):
    """Draw a gather pass into `output`: full screen without tiles, else the sharp colour
    copied and the tiles drawn over it; `variants`: (TileList, defines) pairs drawn over
    it too, each its tiles with the shader variant of those defines."""
    if tiles is None:
        pass_.draw(frame, (output,), textures, uniforms, clear=False)
        return
    frame.ctx.copy_framebuffer(frame.pool.framebuffer((output,)),
                               frame.pool.framebuffer(("color",), read=True))
    frame.pool.mark_written((output,))
    for tl, defines in ((tiles, None), *variants):
        pass_.draw(frame, (output,), textures, uniforms, tiles=tl, clear=False,
                   defines=defines)
