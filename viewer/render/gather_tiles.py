"""The post-process gathers drawn only on the tiles where they can change a pixel.

McGuire 2012, UE4-style and Guertin 2014 each end in a gather that returns the sharp
colour wherever the tile it looks up (NeighborMax, or UE4's dilated max) moves by no more
than its early-out speed. On a software rasteriser every fragment costs even when it
returns at once, so the gather reads that tile texture back (a few hundred texels), lists
the tiles whose lookup can pass the early out (grown by one tile where the lookup is
jittered into a neighbour), and draws only those, as merged rectangles
(viewer/render/tile_lists.py TileList), over a copy of the sharp colour: every other
pixel is the colour its early out would have written, so the image is the same to the
byte as a full-screen draw.
"""
from __future__ import annotations

import numpy as np

from .frame import Frame
from .tile_kernels import square_max
from .tile_lists import TileList, tile_coords

# Relative margin on the early-out speed: the host's float64 length and the shader's
# float32 one may round apart; a tile near the threshold is drawn (that changes no pixel).
MARGIN = 1e-4


def moving_lookups(vectors: np.ndarray, early_out_px: float, reach: int) -> np.ndarray:
    """Tiles (GL rows) holding a pixel whose lookup can pass the early out: the tile's own
    vector is longer than early_out_px (within MARGIN), or that of a tile up to `reach`
    tiles away (Chebyshev) that a jittered lookup can land on."""
    v = vectors.astype(np.float64)
    moving = np.hypot(v[..., 0], v[..., 1]) > early_out_px * (1.0 - MARGIN)
    return square_max(moving, reach) if reach else moving


def gather_tiles(frame: Frame, source: str, components: slice, tile: int,
                 early_out_px: float, reach: int) -> TileList | None:
    """The tiles to draw of a gather that looks `source` (tile x tile px texels) up: its
    `components` hold the vector the early out tests. None where every tile is drawn
    (the full-screen triangle then, with no copy of the colour)."""
    tex = frame.pool.get(source)
    a = np.frombuffer(tex.read(), np.float32).reshape(tex.size[1], tex.size[0], tex.components)
    moving = moving_lookups(a[..., components], early_out_px, reach)
    frame.stats[f"{source}_gather_tiles"] = int(moving.sum())
    if moving.all():
        return None
    state = frame.host.setdefault("state", {})
    key = f"gather_tiles:{source}"
    tl = state.get(key)
    if tl is None or tl.ctx is not frame.ctx:
        tl = state[key] = TileList(frame.ctx)
    tl.set(tile_coords(moving), tile, frame.size)
    return tl


def draw_gather(pass_, frame: Frame, output: str, textures: dict, uniforms: dict,
                tiles: TileList | None):
    """Draw a gather pass into `output`: full screen without tiles, else the sharp colour
    copied and the tiles drawn over it."""
    if tiles is not None:
        frame.ctx.copy_framebuffer(frame.pool.framebuffer((output,)),
                                   frame.pool.framebuffer(("color",)))
        frame.pool.mark_written((output,))
    pass_.draw(frame, (output,), textures, uniforms, tiles=tiles, clear=False)
