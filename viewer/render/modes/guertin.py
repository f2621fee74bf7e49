"""Mode `guertin`: Guertin, McGuire, Nowrouzezahrai 2014, "A Fast and Stable Feature-Aware
Motion Blur Filter" (HPG 2014), as fragment passes:

  gbuffer -> guertin_velocity (McGuire's half vector, clamped to [0.5, r] px)
          -> guertin_tilemax_x -> guertin_tilemax
          -> guertin_neighbormax (3x3, a diagonal tile only where it points toward the
             centre tile)                                       (viewer/render/passes/tiles.py)
          -> guertin (the reconstruction, glsl/modes/guertin_gather.frag: NeighborMax read at a
             pixel shifted along one axis, never into a diagonal tile; taps alternating
             between the neighbourhood's direction (even) and the pixel's (odd), weighed
             at their unrounded distance, with one low-discrepancy jitter; direction-
             weighted cases, centre weight N / (kappa |vC|), relative depth compare),
             drawn only on the tiles that can move (viewer/render/passes/gather_tiles.py)

r is the shared `blur.max_radius` in pixels (tile size and blur limit, as for McGuire).
With `guertin.segments` K > 1 the G-buffer writes each pixel's path and the neighbourhood
taps follow the NeighborMax winner's path, as McGuire's do (viewer/render/modes/mcguire.py).
The taps always alternate between the two directions, as the paper's Appendix A does. Its
per-tile direction variance is not computed: Appendix A's loop does not read it, and the
limit it would steer coherent neighbourhoods towards (every tap along wN) measured worse
on every scene (docs/algorithms.md 2). Departures from Appendix A, by measurement: kappa
20 (not 40), phi 15 (not 27), the middle tap left out (G3D's default).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from viewer.render.graph.params import group, param
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.passes.gather_tiles import draw_gather, gather_tiles, jitter_reach
from viewer.render.passes.gbuffer import (GBufferPass, PathConfig, path_names, path_targets,
                                          segments_param)
from viewer.render.passes.motion_params import curve_steps_param
from viewer.render.passes.half_velocity import EARLY_OUT_PX, VelocityPrep, path_bindings
from viewer.render.graph.registry import mode
from viewer.render.graph.passes import FullscreenPass, Pipeline
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.passes.tiles import tile_passes

# The tap jitter is glsl/graph/noise.glsl's interleaved gradient noise at offset TAP_NOISE (a
# low-discrepancy pattern, the paper's Halton jitter); the NeighborMax lookup shift and
# the axis it goes along are hash01 streams TILE_STREAM_X and TILE_STREAM_Y.
TAP_NOISE, TILE_STREAM_X, TILE_STREAM_Y = 3.0, 4, 5


@group("guertin")
class GuertinParams:
    samples: int = param(15, unit="taps", lo=2, hi=63,
                         help="taps N, alternating between the neighbourhood's (even, "
                              "outermost) and the pixel's direction (odd); odd N keeps "
                              "each direction's taps in pairs about X (G3D: 27)")
    gamma: float = param(1.5, unit="px", lo=0.01, hi=20.0,
                         help="px over the 0.5 px floor at which the centre direction is "
                              "the pixel's own; slower pixels sample toward the "
                              "perpendicular of the dominant motion")
    kappa: float = param(20.0, lo=1.0, hi=1000.0,
                         help="centre weight N / (kappa |vC|): larger lets more of the "
                              "neighbours in (the paper: 40, whose blur of a wide object "
                              "over a still background is too opaque: 3x 20's error)")
    eta: float = param(0.95, unit="fraction of a tap spacing", lo=0.0, hi=1.0,
                       help="tap jitter scale: 0 = fixed taps (banding), up to 1 = a "
                            "whole tap spacing either way (noise), at N = phi")
    phi: float = param(15.0, unit="taps", lo=1.0, hi=63.0,
                       help="jitter baseline: the taps shift by up to eta * phi / N tap "
                            "spacings (the paper's phi, 27 there)")
    skip_middle: bool = param(True, help="leave the middle tap (odd N: t about 0, X "
                                         "itself) to the centre weight, as McGuire 2012 "
                                         "and G3D do; the paper's Appendix A takes it")
    tile_jitter: float = param(0.25, unit="tiles", lo=0.0, hi=0.5,
                               help="largest NeighborMax lookup offset, in tiles, along one "
                                    "axis per pixel (hides tile seams as noise)")
    z_scale: float = param(1.0, unit="fraction of the nearer depth", lo=0.01, hi=10.0,
                           help="depth compare extent as a fraction of the nearer depth: "
                                "a tap that far behind counts as wholly behind")
    segments: int = segments_param()
    curve_steps: int = curve_steps_param(1)     # the published linear blur by default




@dataclass(frozen=True)
class GuertinConfig(PathConfig):
    group: ClassVar[str] = "guertin"


class Gather(FullscreenPass):
    name = "guertin_gather"
    fragment = "modes/guertin_gather.frag"
    produces = ("guertin",)

    def __init__(self, tiled: bool = True, config: GuertinConfig = GuertinConfig()):
        self.segments = config.segments
        self.tiled = tiled
        paths = path_targets(config.segments)
        tile_paths = path_names("guertin_neighbormax", config.segments)
        self.inputs = ("color", "depth", "guertin_velocity", "guertin_neighbormax", *paths,
                       *tile_paths)
        # The tiles to draw: NeighborMax read back (its path's extent where it has one).
        lookups = tile_paths or ("guertin_neighbormax",)
        self.reads_back = tuple(ReadBack(n) for n in lookups) if tiled else ()

    def defines(self, frame: Frame):
        return {"EARLY_OUT_PX": EARLY_OUT_PX, "TAP_NOISE": f"{TAP_NOISE!r}",
                "TILE_STREAM_X": f"{TILE_STREAM_X}u", "TILE_STREAM_Y": f"{TILE_STREAM_Y}u",
                "SEGMENTS": self.segments}

    def outputs(self, frame: Frame):
        return {"guertin": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        p = frame.params["guertin"]
        r = max_radius_px(frame)
        paths = path_bindings("guertin_neighbormax", self.segments)
        tile_paths = path_names("guertin_neighbormax", self.segments)
        tiles = (gather_tiles(frame, "guertin_neighbormax", slice(0, 2), r, EARLY_OUT_PX,
                              jitter_reach(p.tile_jitter, r), tile_paths)
                 if self.tiled else None)
        draw_gather(self, frame, "guertin",
                    {"u_color": "color", "u_depth": "depth", "u_velocity": "guertin_velocity",
                     "u_neighbormax": "guertin_neighbormax", **paths},
                    {"u_tile": r, "u_samples": int(p.samples), "u_gamma": float(p.gamma),
                     "u_kappa": float(p.kappa), "u_eta": float(p.eta), "u_phi": float(p.phi),
                     "u_skip_middle": bool(p.skip_middle),
                     "u_tile_jitter": float(p.tile_jitter), "u_z_scale": float(p.z_scale)},
                    tiles)


def guertin_passes(tiled: bool = True, config: GuertinConfig = GuertinConfig()) -> list:
    """The filter's passes after a G-buffer (colour, depth, velocity; the path of
    config.segments pieces) exists."""
    return [VelocityPrep("guertin_velocity"),
            *tile_passes("guertin_velocity", "guertin", segments=config.segments,
                         paths=path_targets(config.segments), diagonal_toward=True),
            Gather(tiled, config)]


@mode("guertin", groups=("blur", "guertin"), config=GuertinConfig)
def guertin_pipeline(config: GuertinConfig = GuertinConfig()) -> Pipeline:
    return Pipeline("guertin", [GBufferPass(layout="motion", segments=config.segments),
                                *guertin_passes(config=config)],
                    output="guertin", config=config)
