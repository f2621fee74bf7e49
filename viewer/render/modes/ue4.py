"""Mode `ue4`: UE4-style post-process motion blur after Jimenez 2014 (docs/algorithms.md 3.2).

G-buffer -> flatten (half vector v = D/2 clamped to the shared blur limit, packed with depth)
-> per-tile min and max velocity -> dilation by swept tile quads -> gather with paired,
oppositely jittered taps and centre-fill normalisation. Every stage writes a named pool
texture, so `--buffers` shows all of them.

Colour taps are bilinear by default, as in UE (which samples with SampleLevel), but the four
texels are fetched and weighted in the shader: the G-buffer's colour texture is
nearest-filtered and belongs to another pass, and explicit weights give the same numbers on
every driver (a hardware sampler may quantise its weights), which the tests compare against
numpy. Velocity and depth at a tap come from the texel that contains it (UE's point
sampling), so a tap within half a pixel of a silhouette mixes in the colour of the other
side under the weight of its own; `ue4.bilinear=false` takes that texel's colour instead.

With `ue4.segments` K > 1 the G-buffer also writes each pixel's path (glsl/passes/path.glsl): the
flatten's |v| is the path's half extent, the tile max and the dilation carry the max
texel's path, and the gather's taps walk the looked-up tile's path (glsl/modes/ue4_gather.frag).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from viewer.render.graph.params import group, param
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.passes.gather_reach import ue4_map
from viewer.render.passes.gather_tiles import draw_gather, gather_tiles, jitter_reach, tile_list
from viewer.render.passes.gbuffer import (GBufferPass, PathConfig, path_names, path_samplers,
                                          path_targets, segments_param)
from viewer.render.passes.motion_params import curve_steps_param
from viewer.render.passes.half_velocity import path_bindings
from viewer.render.graph.registry import mode
from viewer.render.graph.passes import FullscreenPass, Pipeline
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.passes.tile_runs import FINE


@group("ue4")
class UE4Params:
    tile: int = param(16, unit="px", lo=2, hi=64, effect="realloc",
                      help="tile size in pixels for the min/max velocity tiles")
    taps: int = param(8, unit="taps per side", lo=1, hi=32,
                      help="gather taps per side (2 x taps in all; UE's quality 4 = 8)")
    depth_scale: float = param(100.0, unit="1/m", lo=0.01, hi=1.0e6,
                               help="depth compare slope per metre: a tap within 0.5/depth_scale m "
                                    "of the centre counts half as fore-, half as background "
                                    "(UE: 1 per cm)")
    tile_jitter: float = param(0.25, unit="tiles", lo=0.0, hi=0.5,
                               help="largest tile-lookup jitter per axis, in tiles")
    tap_jitter: float = param(1.0, unit="fraction of a step", lo=0.0, hi=1.0,
                              help="per-pixel jitter of the tap pattern, as a fraction of one step "
                                   "(1 = UE; 0 = taps at step centres, banding instead of noise)")
    fast_path: bool = param(True, help="plain average where the neighbourhood moves uniformly")
    fast_ratio: float = param(0.4, unit="ratio of squared lengths", lo=0.0, hi=1.0,
                              help="fast path when |vmin|^2 > fast_ratio * |vmax|^2")
    mirror: bool = param(True, help="exchange weights within a tap pair (docs/algorithms.md 3.4)")
    bilinear: bool = param(True, help="bilinear colour taps (UE); off: the colour of the texel "
                                      "whose depth and velocity weigh the tap")
    fast_path_guard: bool = param(False,
                                  help="the dilated min also covers every tile the taps can "
                                       "read, so a moving neighbourhood beside a screen-static "
                                       "object takes the full path (UE: covering tiles only)")
    segments: int = segments_param()
    curve_steps: int = curve_steps_param(1)     # the published linear blur by default


@dataclass(frozen=True)
class UE4Config(PathConfig):
    group: ClassVar[str] = "ue4"


FLAT = TexSpec(4, "f4")           # (v.x, v.y, depth, |v|), v the clamped half vector in px


def tile_spec(frame: Frame) -> TexSpec:
    return TexSpec(4, "f4", tile=frame.params["ue4"].tile)     # (vmin.xy, vmax.xy) in px


def dilation_reach(max_px: float, tile: int) -> int:
    """Tiles per side the dilation gathers over: a swept quad reaches |v_t| + e along its
    direction and e across it, e <= 0.99 * sqrt(2), so no covered tile lies farther than
    ceil(|v_t|) + 1 tiles on either axis, with |v_t| <= max_px / tile."""
    return int(math.ceil(max_px / tile)) + 1


class Flatten(FullscreenPass):
    name = "ue4_flatten"
    fragment = "modes/ue4_flatten.frag"
    produces = ("ue4_flat",)

    def __init__(self, config: UE4Config = UE4Config()):
        self.segments = config.segments
        self.inputs = ("velocity", "depth", *path_targets(config.segments))

    def defines(self, frame):
        return {"SEGMENTS": self.segments}

    def outputs(self, frame):
        return {"ue4_flat": FLAT}

    def execute(self, frame):
        self.draw(frame, self.produces, {"u_velocity": "velocity", "u_depth": "depth",
                                         **path_samplers(path_targets(self.segments))},
                  {"u_max_px": float(max_radius_px(frame))})


class _TilePass(FullscreenPass):
    """A pass into `output` and its path targets (the path's extent carried along), at
    the ue4 tile size."""

    def __init__(self, output: str, inputs: tuple[str, ...], segments: int):
        self.segments = segments
        self.inputs = inputs
        self.produces = (output, *path_names(output, segments))

    def defines(self, frame):
        return {"SEGMENTS": self.segments}

    def outputs(self, frame):
        return {name: tile_spec(frame) for name in self.produces}


class TileMinMax(_TilePass):
    name = "ue4_tiles"
    fragment = "modes/ue4_tiles.frag"

    def __init__(self, config: UE4Config = UE4Config()):
        super().__init__("ue4_tiles", ("ue4_flat", *path_targets(config.segments)),
                         config.segments)

    def execute(self, frame):
        self.draw(frame, self.produces,
                  {"u_flat": "ue4_flat", **path_samplers(path_targets(self.segments))},
                  {"u_tile": frame.params["ue4"].tile})


class Dilate(_TilePass):
    name = "ue4_dilate"
    fragment = "modes/ue4_dilate.frag"

    def __init__(self, config: UE4Config = UE4Config()):
        super().__init__("ue4_dilated", ("ue4_tiles", *path_names("ue4_tiles", config.segments)),
                         config.segments)

    def execute(self, frame):
        p = frame.params["ue4"]
        self.draw(frame, self.produces,
                  {"u_tiles": "ue4_tiles", **path_samplers(path_names("ue4_tiles", self.segments))},
                  {"u_tile": float(p.tile), "u_reach": dilation_reach(max_radius_px(frame), p.tile),
                   "u_guard": bool(p.fast_path_guard), "u_tile_jitter": p.tile_jitter})


# The gather's early out: the looked-up tile's max velocity is under half a pixel.
EARLY_OUT_PX = 0.5


class Gather(FullscreenPass):
    """The gather; tiled: drawn only on the FINE tiles where a lookup can take the fast
    path or fail the early out and a moving pixel's taps reach (viewer/render/
    gather_reach.py), with a path on those where a lookup can fail the early out
    (viewer/render/passes/gather_tiles.py): the same image."""
    name = "ue4_gather"
    fragment = "modes/ue4_gather.frag"
    produces = ("ue4",)

    def __init__(self, tiled: bool = True, config: UE4Config = UE4Config()):
        self.segments = config.segments
        self.tiled = tiled
        self.inputs = ("color", "ue4_flat", "ue4_tiles", "ue4_dilated",
                       *path_targets(config.segments), *path_names("ue4_dilated", config.segments))
        # The tiles to draw come from the tile textures read back (tiles()).
        lookups = ("ue4_dilated",) if config.segments > 1 else ("ue4_dilated", "ue4_tiles")
        self.reads_back = tuple(ReadBack(n) for n in lookups) if tiled else ()

    def defines(self, frame):
        return {"EARLY_OUT_PX": EARLY_OUT_PX, "SEGMENTS": self.segments}

    def outputs(self, frame):
        return {"ue4": TexSpec(4, "f4")}

    def execute(self, frame):
        p = frame.params["ue4"]
        tiles = self.tiles(frame, p) if self.tiled else None
        draw_gather(self, frame, "ue4",
                    {"u_color": "color", "u_flat": "ue4_flat", "u_tiles": "ue4_dilated",
                     **path_bindings("ue4_dilated", self.segments)},
                    {"u_tile": p.tile, "u_max_px": float(max_radius_px(frame)), "u_taps": p.taps,
                     "u_depth_scale": p.depth_scale,
                     "u_tile_jitter": p.tile_jitter, "u_tap_jitter": p.tap_jitter,
                     "u_fast_path": bool(p.fast_path), "u_fast_ratio": p.fast_ratio,
                     "u_mirror": bool(p.mirror), "u_bilinear": bool(p.bilinear)}, tiles)

    def tiles(self, frame, p):
        """draw_gather's tiles (None: full screen)."""
        reach = jitter_reach(p.tile_jitter, p.tile)
        if self.segments > 1:
            return gather_tiles(frame, "ue4_dilated", slice(2, 4), p.tile, EARLY_OUT_PX, reach)
        draw = ue4_map(frame, p.tile, reach, p.taps, max_radius_px(frame), bool(p.fast_path),
                       p.fast_ratio, EARLY_OUT_PX)
        frame.stats["ue4_gather_tiles"] = int(draw.sum())
        return None if draw.all() else tile_list(frame, "ue4", draw, FINE)


def ue4_passes(tiled: bool = True, config: UE4Config = UE4Config()) -> list:
    """The post passes after the G-buffer (the path of config.segments pieces)."""
    return [Flatten(config), TileMinMax(config), Dilate(config), Gather(tiled, config)]


@mode("ue4", groups=("blur", "ue4"), config=UE4Config)
def ue4_pipeline(config: UE4Config = UE4Config()) -> Pipeline:
    return Pipeline("ue4", [GBufferPass(layout="motion", segments=config.segments),
                            *ue4_passes(config=config)], output="ue4", config=config)
