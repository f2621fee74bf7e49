"""Mode `mcguire`: McGuire, Hennessy, Bukowski, Osman 2012, "A Reconstruction Filter for
Plausible Motion Blur" (docs/algorithms.md section 1), as fragment passes:

  gbuffer -> mcguire_velocity (half vector, clamped to [0.5, k] px)
          -> mcguire_tilemax_x -> mcguire_tilemax -> mcguire_neighbormax (viewer/render/passes/tiles.py)
          -> mcguire (the reconstruction gather, linear colour)

k is the shared `blur.max_radius` in pixels; it is both the tile size and the blur limit.
With `mcguire.segments` K > 1 the G-buffer also writes each pixel's path (glsl/passes/path.glsl),
the tile passes carry the NeighborMax winner's path, and the gather splits its taps over
the K segments (glsl/modes/mcguire_gather.frag); K = 1 is the paper's filter.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from viewer.render.graph.params import group, param
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.passes.gather_reach import mcguire_maps
from viewer.render.passes.gather_tiles import draw_gather, gather_tiles, tile_list
from viewer.render.passes.gbuffer import (GBufferPass, PathConfig, path_names, path_targets,
                                          segments_param)
from viewer.render.passes.motion_params import curve_steps_param
from viewer.render.passes.half_velocity import EARLY_OUT_PX, VelocityPrep, path_bindings
from viewer.render.graph.registry import mode
from viewer.render.graph.passes import FullscreenPass, Pipeline
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.passes.tile_runs import FINE
from viewer.render.passes.tiles import tile_passes

# Which noise stream of glsl/graph/noise.glsl's hash01 the per-pixel tap jitter uses.
JITTER_STREAM = 1


@group("mcguire")
class McGuireParams:
    samples: int = param(15, unit="taps", choices=tuple(range(3, 64, 2)),
                         help="taps S along the neighbourhood velocity (odd; the middle "
                              "one is the centre pixel)")
    soft_z_extent: float = param(0.1, unit="m", lo=1e-4, hi=10.0,
                                 help="SOFT_Z_EXTENT in metres: the depth over which a tap "
                                      "goes from 'in front' to 'behind'")
    jitter: float = param(1.0, unit="fraction of a step", lo=0.0, hi=1.0,
                          help="per-pixel tap jitter: 0 = fixed taps (banding), "
                               "1 = the paper's j in [-0.5, 0.5) (noise)")
    centre_kappa: float = param(0.0, lo=0.0, hi=200.0,
                                help="0: the paper's centre weight 1/|V|; > 0: the authors' "
                                     "later S/(kappa |V|) (40 in G3D)")
    segments: int = segments_param()
    curve_steps: int = curve_steps_param(1)     # the published linear blur by default




@dataclass(frozen=True)
class McGuireConfig(PathConfig):
    group: ClassVar[str] = "mcguire"


class Gather(FullscreenPass):
    """The reconstruction; tiled: drawn only on the FINE tiles where a pixel's blur reaches
    and the NeighborMax lookup fails the early out, the CENTRE_ONLY variant where only
    the centre taps can weigh (viewer/render/passes/gather_reach.py), with a path on the tiles
    whose lookup fails the early out (viewer/render/passes/gather_tiles.py): the same image."""
    name = "mcguire_gather"
    fragment = "modes/mcguire_gather.frag"
    produces = ("mcguire",)

    def __init__(self, tiled: bool = True, config: McGuireConfig = McGuireConfig()):
        self.segments = config.segments
        self.tiled = tiled
        paths = path_targets(config.segments)
        tile_paths = path_names("mcguire_neighbormax", config.segments)
        # The tiles to draw come from tile textures read back: the NeighborMax path's
        # extent, or without a path NeighborMax and the TileMax strips (gather_reach.py).
        lookups = tile_paths or ("mcguire_neighbormax", "mcguire_tilemax_x")
        self.inputs = ("color", "depth", "mcguire_velocity", "mcguire_neighbormax", *paths,
                       *(lookups if tiled else tile_paths))
        self.reads_back = tuple(ReadBack(n) for n in lookups) if tiled else ()

    def defines(self, frame: Frame):
        return {"EARLY_OUT_PX": EARLY_OUT_PX, "JITTER_STREAM": f"{JITTER_STREAM}u",
                "SEGMENTS": self.segments, "CENTRE_ONLY": 0}

    def outputs(self, frame: Frame):
        return {"mcguire": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        p = frame.params["mcguire"]
        k = max_radius_px(frame)
        paths = path_bindings("mcguire_neighbormax", self.segments)
        tile_paths = path_names("mcguire_neighbormax", self.segments)
        tiles, variants = self.tiles(frame, k, p, tile_paths)
        draw_gather(self, frame, "mcguire",
                    {"u_color": "color", "u_depth": "depth", "u_velocity": "mcguire_velocity",
                     "u_neighbormax": "mcguire_neighbormax", **paths},
                    {"u_tile": k, "u_samples": int(p.samples),
                     "u_soft_z": float(p.soft_z_extent), "u_jitter": float(p.jitter),
                     "u_kappa": float(p.centre_kappa)}, tiles, variants)

    def tiles(self, frame: Frame, k: int, p, tile_paths):
        """draw_gather's tiles (None: full screen) and variants."""
        if not self.tiled:
            return None, ()
        if tile_paths:
            return gather_tiles(frame, "mcguire_neighbormax", slice(0, 2), k, EARLY_OUT_PX,
                                0, tile_paths), ()
        full, centre = mcguire_maps(frame, k, int(p.samples), float(p.jitter),
                                    float(p.centre_kappa), EARLY_OUT_PX)
        frame.stats["mcguire_gather_tiles"] = int(full.sum())
        frame.stats["mcguire_gather_centre_tiles"] = int(centre.sum())
        if full.all():
            return None, ()
        return (tile_list(frame, "mcguire", full, FINE),
                ((tile_list(frame, "mcguire_centre", centre, FINE), {"CENTRE_ONLY": 1}),))


def mcguire_passes(tiled: bool = True, config: McGuireConfig = McGuireConfig()) -> list:
    """The filter's passes after a G-buffer (colour, depth, velocity; the path of
    config.segments pieces) exists."""
    return [VelocityPrep(), *tile_passes("mcguire_velocity", "mcguire", segments=config.segments,
                                         paths=path_targets(config.segments)),
            Gather(tiled, config)]


@mode("mcguire", groups=("blur", "mcguire"), config=McGuireConfig)
def mcguire_pipeline(config: McGuireConfig = McGuireConfig()) -> Pipeline:
    return Pipeline("mcguire", [GBufferPass(layout="motion", segments=config.segments),
                                *mcguire_passes(config=config)], output="mcguire",
                    config=config)
