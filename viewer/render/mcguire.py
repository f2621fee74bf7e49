"""Mode `mcguire`: McGuire, Hennessy, Bukowski, Osman 2012, "A Reconstruction Filter for
Plausible Motion Blur" (ALGORITHMS.md section 1), as fragment passes:

  gbuffer -> mcguire_velocity (half vector, clamped to [0.5, k] px)
          -> mcguire_tilemax_x -> mcguire_tilemax -> mcguire_neighbormax (viewer/render/tiles.py)
          -> mcguire (the reconstruction gather, linear colour)

k is the shared `blur.max_radius` in pixels; it is both the tile size and the blur limit.
"""
from __future__ import annotations

from ..params import group, param
from .blur_common import max_radius_px
from .frame import Frame
from .gbuffer import GBufferPass
from .registry import mode
from .passes import FullscreenPass, Pipeline
from .pool import TexSpec
from .tiles import tile_passes

# The paper's early out is |vN| <= 0.5 px + eps: the 0.5 px floor of the velocity clamp,
# plus room for its float rounding, so a neighbourhood moving at the floor stays sharp.
EARLY_OUT_PX = 0.5 + 1e-3
# Which noise stream of glsl/noise.glsl's hash01 the per-pixel tap jitter uses.
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


class VelocityPrep(FullscreenPass):
    name = "mcguire_velocity"
    fragment = "mcguire_velocity.frag"
    inputs = ("velocity",)
    produces = ("mcguire_velocity",)

    def outputs(self, frame: Frame):
        return {"mcguire_velocity": TexSpec(2, "f4")}

    def execute(self, frame: Frame):
        self.draw(frame, self.produces, {"u_displacement": "velocity"},
                  {"u_max_radius": float(max_radius_px(frame))})


class Gather(FullscreenPass):
    name = "mcguire_gather"
    fragment = "mcguire_gather.frag"
    inputs = ("color", "depth", "mcguire_velocity", "mcguire_neighbormax")
    produces = ("mcguire",)

    def defines(self, frame: Frame):
        return {"EARLY_OUT_PX": EARLY_OUT_PX, "JITTER_STREAM": f"{JITTER_STREAM}u"}

    def outputs(self, frame: Frame):
        return {"mcguire": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        p = frame.params["mcguire"]
        self.draw(frame, self.produces,
                  {"u_color": "color", "u_depth": "depth", "u_velocity": "mcguire_velocity",
                   "u_neighbormax": "mcguire_neighbormax"},
                  {"u_tile": max_radius_px(frame), "u_samples": int(p.samples),
                   "u_soft_z": float(p.soft_z_extent), "u_jitter": float(p.jitter),
                   "u_kappa": float(p.centre_kappa)})


def mcguire_passes() -> list:
    """The filter's passes after a G-buffer (colour, depth, velocity) exists."""
    return [VelocityPrep(), *tile_passes("mcguire_velocity", "mcguire"), Gather()]


@mode("mcguire", groups=("blur", "mcguire"))
def mcguire_pipeline() -> Pipeline:
    return Pipeline("mcguire", [GBufferPass(layout="motion"), *mcguire_passes()], output="mcguire")
