"""The hybrid mode's ray mask (docs/algorithms.md 4.1-4.2): which pixels get a ray.

By default (hybrid.range_check off) the mask is the pixels whose hidden background shows
at some time of the exposure, written as ray_mask by the displacement test's pass alone
(STEP 3): probes along half the displacement relative to the background, which the probes
along half the pixel's own displacement find (glsl/modes/hybrid/raymask_displacement.frag). With a
still background that is the poster's displacement test; under a moving camera it marks
only the band the relative motion uncovers (a small part of the pixels the poster's test
marks). With hybrid.range_check on, the paper's three steps (a little better inner blur
for many more rays: docs/performance.md, "Quality for time"), adapted to the contract's
centred exposure, in two fragment passes (the first two steps read nothing but the
pixel's own neighbourhood):

  mask_displacement (+ mask_relative): a moving pixel whose displaced position, looking
      both ways along half its displacement (and half the relative displacement to the
      background seen there), lands on a different, farther object;
  mask_edge (same pass, + mask_edge_probe): the survivors where a Sobel kernel on log
      depth or normal exceeds a threshold (the moving silhouettes);
  ray_mask: every moving pixel with an edge pixel of its own object within reach along
      its displacement; holds the pixel's object id where masked, 0 elsewhere.

mask_edge_near (per 16 x 16 tile, which objects have an edge within a tile of it, and the
largest reach of those edges) lets the range check skip, exactly, a search whose probes
all lie far from its own object's edges, and bound the others.

Where most tiles move (a moving camera: reach_test), survivors and edges are few among
them, so three exact shortcuts pay for their read-backs: the edge test runs only on the
tiles holding a survivor, the range check only on the tiles with an edge within reach
or a survivor, and there it first reads the own-object bits of every tile in reach
(mask_edge_reach) and returns at once where there are none.
"""
from __future__ import annotations

import numpy as np

from viewer.render.passes.blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.graph.host import HostResource
from .config import HybridConfig
from .inverse import (INVERSE_TILES, LOOKUP_DEFINES, MASK_CHECKS, MOTION_TABLE, curved_tiles,
                      lookup_uniforms)
from viewer.render.graph.passes import FullscreenPass
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.passes.tile_runs import FINE, tile_coords, within_reach
from viewer.render.modes.hybrid.tile_select import TILE_LISTS, path_textures, tile_list, tile_strips
from viewer.render.passes.tiles import StripSpec

MASK = TexSpec(1, "u1")
RAY_MASK = TexSpec(1, "u4")         # own object id where masked
RELATIVE = TexSpec(2, "f4")
EDGE_PROBE = TexSpec(2, "f4")       # (half |relative D|, object id) at edge pixels, else 0
REACH_TEST_FRACTION = 0.5           # of the tiles moving, from which reach_test holds
# FINE tile maps (GL rows) from the surface tests, for the range check's passes; None
# where the frame's mask path does not make them.
PROBE_TILES = HostResource("edge_probe_tiles", np.ndarray,
                           "tiles where mask_edge_probe was written (None: unknown)", optional=True)
SURVIVOR_TILES = HostResource("survivor_tiles", np.ndarray,
                              "tiles holding a displacement-test survivor (reach_test only)",
                              optional=True)


class SurfaceTests(FullscreenPass):
    """The displacement test and, on its survivors, the edge test, in one pass
    (glsl/modes/hybrid/raymask_displacement.frag, STEP 0); also mask_edge_probe, what the range check
    reads per probe. Where the camera moves (reach_test), the survivors of the first lie
    in few of the moving tiles (vase_pan: 60 of 883), so the two run apart: STEP 1 on the
    moving tiles, the tiles holding a survivor read back (glsl/modes/hybrid/mask_any.frag), STEP 2
    (the Sobel kernel) on those alone."""
    name = "mask_displacement"
    fragment = "modes/hybrid/raymask_displacement.frag"
    host_inputs = (TILE_LISTS,)

    def __init__(self, config: HybridConfig = HybridConfig()):
        """Without the range check (config.range_check off) the displacement test alone,
        written as ray_mask; with it the targets of the three steps' first two."""
        self._any = AnyTiles()
        self.range_check = config.range_check
        self.segments = config.segments
        self.inverse = config.curve == "inverse"
        if self.range_check:
            self.inputs = ("hybrid_front", "normal", *config.paths)
            self.produces = RANGE_TARGETS
            self.host_outputs = (PROBE_TILES, SURVIVOR_TILES)
            self.reads_back = (ReadBack("mask_survivors", "most tiles moving"),)
        else:
            self.inputs, self.produces = ("hybrid_front", *config.paths), ("ray_mask",)
        if self.inverse:
            self.inputs += (MOTION_TABLE,)
            self.host_inputs = (TILE_LISTS, INVERSE_TILES)

    def defines(self, frame: Frame):
        return {"SEGMENTS": self.segments}

    def outputs(self, frame: Frame):
        specs = {"mask_displacement": MASK, "mask_relative": RELATIVE, "mask_edge": MASK,
                 "mask_edge_probe": EDGE_PROBE,
                 "mask_survivors_x": StripSpec(1, "u1", tile=FINE),
                 "mask_survivors": TexSpec(1, "u1", tile=FINE), "ray_mask": RAY_MASK}
        return {n: specs[n] for n in self.produces}

    def execute(self, frame: Frame):
        p = frame.params["hybrid"]
        # Only where an id boundary lies within the probes' reach can a probe see another
        # object (tile_select.near_boundary); elsewhere the targets keep their clear value,
        # the answer there (mask_relative aside: read only at survivors).
        tiles = tile_list(frame, "surface")
        first = {"u_min_speed": float(p.min_speed),
                 "u_depth_threshold": float(p.depth_threshold)}
        second = {"u_edge_depth": float(p.edge_depth), "u_edge_normal": float(p.edge_normal)}
        if not self.range_check:
            # The mask is the displacement test's survivors, written as ray_mask at once;
            # where the composite follows curves, also each moving pixel whose own mover
            # leaves it at some time (a reversal, an arc: what the chord misses).
            textures = {"u_front": "hybrid_front", **path_textures(self.segments)}
            # (inverse.py: every tile a mover reaches over the exposure, whatever its chord)
            curved = curved_tiles(frame) if self.inverse else None
            if curved is None:
                return self.draw(frame, ("ray_mask",), textures, first, tiles=tiles,
                                 defines={"STEP": 3})
            lists = frame.host[TILE_LISTS]
            rest = lists.extra("mask_straight")
            rest.set(tile_coords(lists.surface_tiles & ~curved), FINE, frame.size)
            self.draw(frame, ("ray_mask",), textures, first, tiles=rest, defines={"STEP": 3})
            tl = lists.extra("mask_curved")
            tl.set(tile_coords(curved), FINE, frame.size)
            return self.draw(frame, ("ray_mask",), {**textures, "u_table": MOTION_TABLE},
                             {**first, **lookup_uniforms(frame),
                              "u_max_disp": 2.0 * max_radius_px(frame)}, tiles=tl,
                             defines={"STEP": 3, "INVERSE_CHECKS": MASK_CHECKS,
                                      **LOOKUP_DEFINES}, clear=False)
        if not reach_test(frame):
            # Where the edge outputs were written (EdgeIdTiles).
            frame.host.put(PROBE_TILES, None if tiles is None
                           else frame.host[TILE_LISTS].surface_tiles)
            frame.host.put(SURVIVOR_TILES, None)
            return self.draw(frame, self.produces[:4],
                             {"u_front": "hybrid_front", "u_normal": "normal",
                              **path_textures(self.segments)},
                             {**first, **second}, tiles=tiles, defines={"STEP": 0})
        self.draw(frame, ("mask_displacement", "mask_relative"),
                  {"u_front": "hybrid_front", **path_textures(self.segments)}, first, tiles=tiles,
                  defines={"STEP": 1})
        survivors = self._any.tiles(frame, "mask_displacement", "mask_survivors")
        lists = frame.host[TILE_LISTS]
        tl = lists.extra("survivors")
        tl.set(tile_coords(survivors), FINE, frame.size)
        frame.stats["survivor_tiles"] = tl.count
        frame.host.put(SURVIVOR_TILES, survivors)
        frame.host.put(PROBE_TILES, survivors)
        self.draw(frame, ("mask_edge", "mask_edge_probe"),
                  {"u_front": "hybrid_front", "u_normal": "normal",
                   "u_displacement_mask": "mask_displacement", "u_relative": "mask_relative"},
                  second, tiles=tl, defines={"STEP": 2})


# SurfaceTests' targets with the range check (ray_mask last: written without it too).
RANGE_TARGETS = ("mask_displacement", "mask_relative", "mask_edge", "mask_edge_probe",
                 "mask_survivors_x", "mask_survivors", "ray_mask")


class AnyTiles(FullscreenPass):
    """Which FINE tiles of a uint mask hold a nonzero texel, read back (glsl/modes/hybrid/mask_any.frag:
    SOURCE -> NAME_x strip -> NAME), as a GL-rows boolean map."""
    fragment = "modes/hybrid/mask_any.frag"

    def tiles(self, frame: Frame, source: str, name: str) -> np.ndarray:
        for stage, src, dst in ((0, source, name + "_x"), (1, name + "_x", name)):
            self.draw(frame, (dst,), {"u_source": src}, {"u_tile": FINE},
                      defines={"STAGE": stage})
        tex = frame.pool.get(name)
        return np.frombuffer(frame.pool.read_back(name),
                             np.uint8).reshape(tex.size[1], tex.size[0]) != 0


def reach_tiles(frame: Frame) -> int:
    """Tiles (Chebyshev) within which the range check's probes stay: they lie at most k px
    (the blur limit) from their pixel, so within ceil(k / FINE) + 1 tiles of its tile."""
    return -(-max_radius_px(frame) // FINE) + 1


def edge_tiles(frame: Frame) -> np.ndarray:
    """Which FINE tiles (GL rows) hold a ray-mask edge: mask_edge_ids read back, for the
    range check's tile list under a moving camera."""
    ids = frame.pool.get("mask_edge_ids")
    data = np.frombuffer(frame.pool.read_back("mask_edge_ids"), np.uint32)
    return data.reshape(ids.size[1], ids.size[0], -1)[..., 0] != 0


def reach_test(frame: Frame) -> bool:
    """Whether most tiles move (a moving camera), so that the mask passes take the
    shortcuts of the module's docstring: worth their read-backs and extra reductions there
    (a large share of the mask passes' time saved), not where few tiles move (the reach reductions
    would cost more than they save). Exact either way."""
    moving = tile_list(frame, "moving")
    if moving is None:
        return False
    tiles = frame.host[TILE_LISTS].shape
    return moving.count > REACH_TEST_FRACTION * tiles[0] * tiles[1]


class EdgeIdTiles(FullscreenPass):
    """Per FINE tile, a bitmask of the objects (id mod 32) with edge pixels there and the
    largest reach of those edges, then spread to the 3x3 tiles around
    (glsl/modes/hybrid/edge_ids.frag): mask_edge_near."""
    name = "mask_edge_near"
    fragment = "modes/hybrid/edge_ids.frag"
    inputs = ("mask_edge_probe",)
    produces = ("mask_edge_ids_x", "mask_edge_ids", "mask_edge_near", "mask_edge_reach_x",
                "mask_edge_reach")
    host_inputs = (TILE_LISTS, PROBE_TILES)

    def outputs(self, frame: Frame):
        return {"mask_edge_ids_x": StripSpec(2, "u4", tile=FINE),
                "mask_edge_ids": TexSpec(2, "u4", tile=FINE),
                "mask_edge_near": TexSpec(2, "u4", tile=FINE),
                "mask_edge_reach_x": TexSpec(2, "u4", tile=FINE),
                "mask_edge_reach": TexSpec(2, "u4", tile=FINE)}

    def execute(self, frame: Frame):
        uniforms = {"u_tile": FINE, "u_radius": reach_tiles(frame)}
        # The edge test wrote mask_edge_probe only on some tiles (SurfaceTests: the surface
        # tiles, or under a moving camera those holding a survivor), 0 elsewhere: the
        # first step reads only their strips, the rest of the strip is 0.
        written = frame.host.get(PROBE_TILES)
        strips = None if written is None else tile_strips(frame, written, "edge_strips")
        first = dict(uniforms)
        if strips is not None:
            first["u_viewport"] = tuple(float(x) for x in strips.size)
        self.draw(frame, ("mask_edge_ids_x",), {"u_probe": "mask_edge_probe"}, first,
                  tiles=strips, defines={"STAGE": 0})
        steps = [(1, {"u_source": "mask_edge_ids_x"}, "mask_edge_ids"),
                 (2, {"u_source": "mask_edge_ids"}, "mask_edge_near")]
        if reach_test(frame):
            steps += [(3, {"u_source": "mask_edge_ids"}, "mask_edge_reach_x"),
                      (4, {"u_source": "mask_edge_reach_x"}, "mask_edge_reach")]
        for stage, textures, out in steps:
            self.draw(frame, (out,), textures, uniforms, defines={"STAGE": stage})


class RangeCheck(FullscreenPass):
    name = "ray_mask"
    fragment = "modes/hybrid/raymask_range.frag"
    inputs = ("mask_displacement", "mask_edge_probe", "mask_edge_ids", "mask_edge_near",
              "mask_edge_reach", "hybrid_front")
    produces = ("ray_mask",)
    host_inputs = (TILE_LISTS, SURVIVOR_TILES)
    reads_back = (ReadBack("mask_edge_ids", "most tiles moving"),)

    def defines(self, frame: Frame):
        # The tile size as a constant: a division by a uniform runs lane by lane on
        # llvmpipe, here in the coarse look's loop.
        return {"REACH_TEST": int(reach_test(frame)), "FINE": FINE}

    def outputs(self, frame: Frame):
        return {"ray_mask": RAY_MASK}

    def execute(self, frame: Frame):
        p = frame.params["hybrid"]
        tiles = tile_list(frame, "moving")
        if reach_test(frame):
            # Only the moving tiles with an edge within their search's reach, or a
            # survivor of the displacement test (masked as it is): the rest would find
            # nothing. A search walks min(k, relative_reach |D| / 2) px each way from its
            # pixel, and its probes land within half a pixel: tile T reaches
            # R_T = min(k, relative_reach * longest_T / 2) + 1 px.
            lists = frame.host[TILE_LISTS]
            reach = np.minimum(float(max_radius_px(frame)),
                               0.5 * float(p.relative_reach) * lists.longest.astype(np.float64))
            in_reach = within_reach(edge_tiles(frame), reach + 1.0, FINE)
            keep = lists.moving_tiles & (in_reach | frame.host[SURVIVOR_TILES])
            tiles = lists.extra("range_check")
            tiles.set(tile_coords(keep), FINE, frame.size)
            frame.stats["range_tiles"] = tiles.count
        self.draw(frame, self.produces,
                  {"u_displacement_mask": "mask_displacement", "u_edge_probe": "mask_edge_probe",
                   "u_front": "hybrid_front",
                   "u_edge_near": "mask_edge_near", "u_edge_reach": "mask_edge_reach"},
                  {"u_min_speed": float(p.min_speed),
                   "u_relative_reach": float(p.relative_reach),
                   "u_max_reach": float(max_radius_px(frame))},
                  tiles=tiles)


def raymask_passes(config: HybridConfig = HybridConfig()) -> list:
    """The mask passes of `config`: the displacement test alone, or with the range check
    the three steps and their tile summaries (after a G-buffer with normals)."""
    if not config.range_check:
        return [SurfaceTests(config)]
    return [SurfaceTests(config), EdgeIdTiles(), RangeCheck()]
