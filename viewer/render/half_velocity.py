"""The half vector of McGuire et al. 2012, which Guertin et al. 2014 keep: v = D/2 of the
G-buffer's full displacement, its magnitude clamped to [0.5, k] px (k the tile size and blur
limit), and the gathers' early out at that 0.5 px floor."""
from __future__ import annotations

from .blur_common import max_radius_px
from .frame import Frame
from .passes import FullscreenPass
from .pool import TexSpec

# The paper's early out is |vN| <= 0.5 px + eps: the 0.5 px floor of the velocity clamp,
# plus room for its float rounding, so a neighbourhood moving at the floor stays sharp.
EARLY_OUT_PX = 0.5 + 1e-3


class VelocityPrep(FullscreenPass):
    """The half vector v = D/2, |v| clamped to [0.5, k] px (zero stays zero), into
    `output` (McGuire names it mcguire_velocity, Guertin guertin_velocity)."""
    fragment = "mcguire_velocity.frag"
    inputs = ("velocity",)

    def __init__(self, output: str = "mcguire_velocity"):
        self.name, self.produces = output, (output,)

    def outputs(self, frame: Frame):
        return {self.produces[0]: TexSpec(2, "f4")}

    def execute(self, frame: Frame):
        self.draw(frame, self.produces, {"u_displacement": "velocity"},
                  {"u_max_radius": float(max_radius_px(frame))})
