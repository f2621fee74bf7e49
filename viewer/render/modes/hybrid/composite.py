"""The hybrid mode's composite: both layers blurred and combined in one resolve.

  (inputs) the layers packed for the inner loop as glsl/modes/hybrid/hybrid_layers.glsl describes:
      the front by the G-buffer (layout "hybrid"), the revealed ones by reveal_shade;
  hybrid_tilemax_x / hybrid_tilemax / hybrid_neighbormax: the largest displacement around
      each tile (viewer/render/passes/tiles.py, McGuire's passes on the raster displacement);
  hybrid_composite -> hybrid: the bucketed gather (glsl/modes/hybrid/hybrid_bucket.frag, the default),
      the time-sampled composite (glsl/modes/hybrid/hybrid_time.frag), or "split" between them; only on
      the active tiles where the frame has tile lists (tile_select.py), the
      sharp colour elsewhere. The bucketed gather is compiled per class of tile, since
      llvmpipe pays for a branch in a loop even where no pixel takes it, and for both
      sides where the pixels of an 8-wide group disagree: with the revealed layer's line
      only where a pixel is masked, without the own line where nothing moves, and without
      the neighbourhood's line where no silhouette is in reach.
"""
from __future__ import annotations

import math

import numpy as np

from viewer.render.passes.blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.graph.host import HostResource
from .config import HybridConfig
from viewer.render.graph.passes import FullscreenPass, Pass
from viewer.render.graph.pool import ReadBack, TexSpec
from .inverse import (CANDIDATES, INVERSE_TILES, LOOKUP_DEFINES, MAX_CANDIDATES, MOTION_TABLE,
                      curved_tiles, lookup_uniforms)
from .reveal import MASKED_PIXELS
from viewer.render.passes.tile_kernels import mark_tiles, outlines_along, pixel_tiles, square_max
from viewer.render.passes.tile_runs import FINE, tile_coords, within_reach
from viewer.render.modes.hybrid.tile_select import TILE_LISTS, moving_strips, path_textures, tile_list
from viewer.render.passes.tiles import tile_passes

# Which noise stream of glsl/graph/noise.glsl's hash01 jitters the time samples or taps.
JITTER_STREAM = 2
# outlines_along's widening of the tiles' pixel centres: float rounding of a tap's point
# (float32 on the GPU: ~1e-5 px over the longest line).
OUTLINE_MARGIN_PX = 0.05
# The bucketed composite merges the own line with the neighbourhood's where their
# directions lie within this angle (glsl/modes/hybrid/hybrid_bucket.frag MERGE_COS): one line's taps
# instead of two under a camera pan, whose surfaces all move about the same way (pan:
# 95% of pixels within 6 degrees of their NeighborMax vector). The merged own lines stray
# off the neighbourhood's direction by up to the angle's sine times their reach, which
# near_outlines adds to its margin. A wider angle merges no more under a pan but blurs
# worse where the camera turns fast (curved paths); a narrower one merges less under a
# pan and costs its time.
MERGE_ANGLE_DEG = 7.0
MERGE_COS = math.cos(math.radians(MERGE_ANGLE_DEG))
MERGE_SPREAD = math.sin(math.radians(MERGE_ANGLE_DEG))
FRAGMENTS = {"time": "modes/hybrid/hybrid_time.frag", "bucket": "modes/hybrid/hybrid_bucket.frag",
             "inverse": "modes/hybrid/hybrid_inverse.frag"}
NEIGHBORMAX = HostResource("neighbormax", np.ndarray,
                           "hybrid_neighbormax read back (GL rows), for near_outlines")


def near_outlines(frame: Frame, todo: np.ndarray, segments: int) -> np.ndarray:
    """FINE tiles (GL rows) where a tap of the neighbourhood's line, or of an own line
    merged with it, can land on another object than its pixel's: all of them without
    tile lists. The line runs along the pixel's NeighborMax vector (read back: a few
    hundred floats), a merged own line within MERGE_ANGLE_DEG of it and no farther, so a
    tile is near an outline only where a boundary tile (motion_tiles' flag) lies along
    that line within its reach (tile_kernels.outlines_along: a camera pan's horizontal
    lines miss the outlines above and below). Elsewhere every tap lands on the pixel's own
    object, and the buckets of other objects stay empty: the SIMPLE variant, which skips
    them, gives the same image. Decided for the tiles of `todo` only."""
    lists = frame.host.get(TILE_LISTS)
    if lists is None or lists.boundary.shape != todo.shape:
        return np.ones(todo.shape, bool)
    if segments > 1:
        return todo & within_reach(lists.boundary, path_reach(frame, todo.shape, segments), FINE)
    vn = frame.host.get(NEIGHBORMAX)
    if vn is None:                      # (not read back: the composite run on its own)
        vn = read_neighbormax(frame)
    k = max_radius_px(frame)
    return outlines_along(lists.boundary, todo, vn, FINE, k, frame.size[0], frame.size[1],
                          2.0 * k, OUTLINE_MARGIN_PX, MERGE_SPREAD)


def path_reach(frame: Frame, shape: tuple[int, int], segments: int) -> np.ndarray:
    """Per FINE tile (GL rows), how far (px) from its pixels the taps of a neighbourhood
    path can land: half the largest NeighborMax path extent (clamped to the blur limit)
    over the k-tiles it meets, plus rounding and the other pixel of a boundary pair. A
    path bends, so this bounds it in every direction (glsl/modes/hybrid/hybrid_bucket.frag)."""
    k = max_radius_px(frame)
    w, h = frame.size
    points = []
    for name in ("hybrid_neighbormax_path", "hybrid_neighbormax_path2")[:segments // 2]:
        tex = frame.pool.get(name)
        points.append(np.frombuffer(frame.pool.read_back(name),
                                    np.float32).reshape(tex.size[1], tex.size[0], 2, 2))
    o = np.concatenate(points, axis=2).astype(np.float64)
    extent = np.minimum(2.0 * np.sqrt((o * o).sum(-1).max(-1)), 2.0 * k)
    reach = 0.5 * extent + OUTLINE_MARGIN_PX + 1.0
    per_pixel = np.repeat(np.repeat(reach, k, axis=0)[:h], k, axis=1)[:, :w]
    rows, cols = shape
    padded = np.zeros((rows * FINE, cols * FINE))
    padded[:h, :w] = per_pixel
    return padded.reshape(rows, FINE, cols, FINE).max(axis=(1, 3))


def read_neighbormax(frame: Frame) -> np.ndarray:
    """hybrid_neighbormax on the host (GL rows): a few hundred floats."""
    tex = frame.pool.get("hybrid_neighbormax")
    return np.frombuffer(frame.pool.read_back("hybrid_neighbormax"),
                         np.float32).reshape(tex.size[1], tex.size[0], 2)


class ReadNeighborMax(Pass):
    """Host side: hybrid_neighbormax read back for near_outlines, right after it is drawn
    (the hybrid runs the tile passes before the ray mask), so a GPU driver waits only for
    those passes, not for the reveal's, as a read in the composite would."""
    name = "hybrid_neighbormax_read"
    runs_on = "cpu"
    inputs = ("hybrid_neighbormax",)
    host_outputs = (NEIGHBORMAX,)
    reads_back = (ReadBack("hybrid_neighbormax"),)

    def execute(self, frame: Frame):
        frame.host.put(NEIGHBORMAX, read_neighbormax(frame))


def composite_kind(frame: Frame) -> str:
    """"bucket", "time" or "split" (the time-sampled composite on the tiles near the ray
    mask, the bucket on the other active tiles): the `hybrid.composite` setting."""
    return frame.params["hybrid"].composite


# Tiles around the masked ones that get the time-sampled composite in "split": one tile
# blurs as well as the blur limit's whole reach (pan, vase_pan) in less time; none
# leaves the outer blur as the bucket's.
SPLIT_REACH = 1
# Tiles whose longest |D| is below this get the OWN_STILL variant: half of
# glsl/modes/hybrid/hybrid_bucket.frag's "own surface moves" test (dot(D, D) >= 1e-6, |D| >= 1e-3 px),
# so float rounding cannot put a pixel on the wrong side.
STILL_PX = 5e-4


def split_tiles(active: np.ndarray, masked_ij: np.ndarray, height: int, reach: int):
    """(time, bucket) boolean tile maps (GL rows): the active tiles within `reach` tiles
    (Chebyshev) of a tile holding a masked pixel, and the other active tiles."""
    near = pixel_tiles(np.asarray(masked_ij, np.int64).reshape(-1, 2), *active.shape, FINE,
                       height)
    if reach:
        near = square_max(near, reach)
    return active & near, active & ~near


MASK_TILES = "ray_mask_tiles"


def mask_tiles(pixels: np.ndarray, size: tuple[int, int], tile: int) -> np.ndarray:
    """Per tile x tile tile (image orientation), (0, 1 if it holds a masked pixel): the
    ray mask's tile summary, for the time-sampled composite."""
    w, h = size
    return mark_tiles(pixels, -(-h // tile), -(-w // tile), tile)


def write_mask_tiles(frame: Frame):
    """ray_mask_tiles (k px tiles), which only the time-sampled composite reads, made
    where it runs, from the pixels the reveal read back; a composite run on its own (no
    reveal) reads what its caller wrote there."""
    k = max_radius_px(frame)
    frame.pool.texture(MASK_TILES, TexSpec(2, "f4", tile=k))
    pixels = frame.host.get(MASKED_PIXELS)
    if pixels is not None:
        frame.write(MASK_TILES, mask_tiles(pixels, frame.size, k))


class Composite(FullscreenPass):
    """The composite composite_kind picks: "time" (glsl/modes/hybrid/hybrid_time.frag), "bucket"
    (glsl/modes/hybrid/hybrid_bucket.frag), or "split" between them by tiles."""
    name = "hybrid_composite"
    fragment = FRAGMENTS["time"]        # (each draw names its own: _draw)

    def __init__(self, config: HybridConfig = HybridConfig()):
        self.segments = config.segments
        self.inverse = config.curve == "inverse"
        tile_paths = config.tile_paths("hybrid_neighbormax")
        self.inputs = ("color", "hybrid_front", "hybrid_back", "hybrid_back_color",
                       "hybrid_tilemax", "hybrid_neighbormax", *config.paths, *tile_paths,
                       *((MOTION_TABLE, CANDIDATES) if self.inverse else ()))
        # ray_mask_tiles: made where the time-sampled composite draws
        self.produces = ("hybrid",) + ((MASK_TILES,) if config.composite != "bucket" else ())
        self.host_inputs = (TILE_LISTS, MASKED_PIXELS,
                            *((NEIGHBORMAX,) if config.reads_neighbormax else ()),
                            *((INVERSE_TILES,) if self.inverse else ()))
        # The bucket's tiles near no outline: along a path, from the path's extent read
        # back (path_reach); along the chord, from NEIGHBORMAX.
        self.reads_back = (tuple(ReadBack(n) for n in tile_paths)
                           if config.composite != "time" else ())

    def defines(self, frame: Frame):
        p = frame.params["hybrid"]
        return {"MAX_SEEDS": int(p.seeds), "SEGMENTS": self.segments,
                "JITTER_STREAM": f"{JITTER_STREAM}u", "MERGE_COS": repr(MERGE_COS)}

    def outputs(self, frame: Frame):
        return {"hybrid": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        kind = composite_kind(frame)
        tiles = tile_list(frame, "active")
        lists = frame.host.get(TILE_LISTS)
        if tiles is not None and tiles.count < lists.shape[0] * lists.shape[1]:
            # Outside the active tiles nothing reaches a pixel: its sharp colour stands.
            # (Where every tile is active, as under a moving camera, the draws below
            # write every pixel.)
            frame.ctx.copy_framebuffer(frame.pool.framebuffer(("hybrid",)),
                                       frame.pool.framebuffer(("color",), read=True))
        if tiles is None:                      # (no tile lists: a pass run on its own)
            return self._draw(frame, "time" if kind == "split" else kind, tiles)
        active = np.zeros(lists.shape, bool)
        active[tiles.tiles[:, 1], tiles.tiles[:, 0]] = True
        curved = self._curves(frame)
        if curved is not None:
            active &= ~curved
            if kind == "time":
                tiles = lists.extra("time_straight")
                tiles.set(tile_coords(active), FINE, frame.size)
        if kind == "time":
            return self._draw(frame, kind, tiles)
        masked = frame.host.get(MASKED_PIXELS, np.zeros((0, 2), int))
        # Only tiles holding a masked pixel have a revealed layer to blur (line 3); in
        # tiles where nothing moves (own D < 1e-3 px) the own surface needs no line.
        if kind == "split":
            near, plain = split_tiles(active, masked, frame.size[1], SPLIT_REACH)
            first = ("time", near, 1, 0, 0)
            frame.stats["time_tiles"] = int(near.sum())
        else:
            revealed, plain = split_tiles(active, masked, frame.size[1], 0)
            first = ("bucket", revealed, 1, 0, 0)
        # Where no other object lies within the lines' reach, the neighbourhood's line is
        # needed only where it is the own line (SIMPLE).
        still = plain & (lists.longest < STILL_PX)
        moving = plain & ~still
        simple = moving & ~near_outlines(frame, moving, self.segments)
        parts = (first, ("bucket", moving & ~simple, 0, 0, 0), ("bucket", simple, 0, 0, 1),
                 ("bucket", still, 0, 1, 0))
        for which, selected, back, own_still, single in parts:
            tl = lists.extra(f"{which}{back}{own_still}{single}")
            tl.set(tile_coords(selected), FINE, frame.size)
            self._draw(frame, which, tl, back, own_still, single)
        frame.stats["simple_tiles"] = int(simple.sum())

    def _curves(self, frame: Frame) -> np.ndarray | None:
        """The inverse-motion composite (glsl/modes/hybrid/hybrid_inverse.frag) on the
        tiles the movers reach over the exposure (inverse.py; a mover that comes back
        within it has a short chord, and its tiles need not be active); returns those
        tiles, or None where the configuration does not follow curves or nothing bends."""
        curved = curved_tiles(frame) if self.inverse else None
        if curved is None:
            return None
        tl = frame.host.get(TILE_LISTS).extra("inverse")
        tl.set(tile_coords(curved), FINE, frame.size)
        self.draw(frame, ("hybrid",),
                  {"u_front_color": "color", "u_front": "hybrid_front",
                   "u_back_color": "hybrid_back_color", "u_back": "hybrid_back",
                   "u_table": MOTION_TABLE, "u_candidates": CANDIDATES,
                   "u_neighbormax": "hybrid_neighbormax"},
                  {**lookup_uniforms(frame),
                   "u_samples": int(frame.params["hybrid"].time_samples),
                   "u_spacing": float(frame.params["hybrid"].sample_spacing),
                   "u_tile": max_radius_px(frame),
                   "u_camera_moves": bool(frame.scene.camera.moving),
                   "u_max_disp": 2.0 * max_radius_px(frame)},
                  tiles=tl, clear=False, fragment=FRAGMENTS["inverse"],
                  defines={**LOOKUP_DEFINES, "MAX_CANDIDATES": MAX_CANDIDATES,
                           "FINE_TILE": FINE})
        frame.stats["inverse_drawn_tiles"] = int(curved.sum())
        return curved

    def _draw(self, frame: Frame, kind: str, tiles, back: int = 1, own_still: int = 0,
              simple: int = 0):
        p = frame.params["hybrid"]
        k = max_radius_px(frame)
        textures = {"u_front_color": "color", "u_front": "hybrid_front",
                    "u_back_color": "hybrid_back_color", "u_back": "hybrid_back",
                    "u_tilemax": "hybrid_tilemax", "u_neighbormax": "hybrid_neighbormax",
                    **path_textures(self.segments),
                    **path_textures(self.segments, {"u_neighbormax_path0": "hybrid_neighbormax_path",
                                            "u_neighbormax_path1": "hybrid_neighbormax_path2"})}
        if kind == "time":
            write_mask_tiles(frame)
            textures["u_mask_tiles"] = MASK_TILES
        self.draw(frame, ("hybrid",), textures,
                  {"u_tile": k, "u_max_disp": 2.0 * k,
                   "u_samples_min": int(p.samples_min),
                   "u_samples_max": int(max(p.samples_max, p.samples_min)),
                   "u_spacing": float(p.sample_spacing), "u_jitter": float(p.jitter),
                   "u_tolerance": float(p.tolerance), "u_iterations": int(p.iterations)},
                  tiles=tiles, clear=False, fragment=FRAGMENTS[kind],
                  defines={"BACK_LAYER": back, "OWN_STILL": own_still, "SIMPLE": simple})


def composite_tile_passes(config: HybridConfig = HybridConfig()) -> list:
    """The raster displacement's tiles for the composite (and NeighborMax on the host,
    where the composite reads it): they need only the G-buffer and the tile lists."""
    return [*tile_passes("hybrid_front", "hybrid", select_x=moving_strips, segments=config.segments,
                         paths=config.paths, select_reads=(TILE_LISTS,)),
            *((ReadNeighborMax(),) if config.reads_neighbormax else ())]
