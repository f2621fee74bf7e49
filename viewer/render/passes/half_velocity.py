"""The half vector of McGuire et al. 2012, which Guertin et al. 2014 keep: v = D/2 of the
G-buffer's full displacement, its magnitude clamped to [0.5, k] px (k the tile size and blur
limit), the gathers' early out at that 0.5 px floor, and the path samplers of their path
gathers (glsl/passes/path.glsl)."""
from __future__ import annotations

from .blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.graph.passes import FullscreenPass
from viewer.render.graph.pool import TexSpec
from viewer.render.passes.gbuffer import path_names, path_targets

# The paper's early out is |vN| <= 0.5 px + eps: the 0.5 px floor of the velocity clamp,
# plus room for its float rounding, so a neighbourhood moving at the floor stays sharp.
EARLY_OUT_PX = 0.5 + 1e-3

def path_bindings(tile_source: str, segments: int) -> dict[str, str]:
    """A path gather's samplers for `segments` path pieces (none for one): the pixel's and
    the taps' paths (the G-buffer's), and the NeighborMax winner's (TILE_SOURCE_path,
    _path2)."""
    own, tile = path_targets(segments), path_names(tile_source, segments)
    return {key: name for j in range(len(own))
            for key, name in ((f"u_path{j}", own[j]), (f"u_tile_path{j}", tile[j]))}


class VelocityPrep(FullscreenPass):
    """The half vector v = D/2, |v| clamped to [0.5, k] px (zero stays zero), into
    `output` (McGuire names it mcguire_velocity, Guertin guertin_velocity)."""
    fragment = "passes/mcguire_velocity.frag"
    inputs = ("velocity",)

    def __init__(self, output: str = "mcguire_velocity"):
        self.name, self.produces = output, (output,)

    def outputs(self, frame: Frame):
        return {self.produces[0]: TexSpec(2, "f4")}

    def execute(self, frame: Frame):
        self.draw(frame, self.produces, {"u_displacement": "velocity"},
                  {"u_max_radius": float(max_radius_px(frame))})
