"""The half vector of McGuire et al. 2012, which Guertin et al. 2014 keep: v = D/2 of the
G-buffer's full displacement, its magnitude clamped to [0.5, k] px (k the tile size and blur
limit), the gathers' early out at that 0.5 px floor, and the path samplers of their path
gathers (glsl/passes/path.glsl)."""
from __future__ import annotations

from .blur_common import max_radius_px
from viewer.render.graph.frame import Frame
from viewer.render.graph.passes import FullscreenPass
from viewer.render.graph.pool import TexSpec

# The paper's early out is |vN| <= 0.5 px + eps: the 0.5 px floor of the velocity clamp,
# plus room for its float rounding, so a neighbourhood moving at the floor stays sharp.
EARLY_OUT_PX = 0.5 + 1e-3

# The G-buffer's path targets, and the NeighborMax winner's path as the gather reads them.
GBUFFER_PATHS = ("hybrid_path", "hybrid_path2")


def path_bindings(tile_source: str, segments: int) -> dict[str, str]:
    """A path gather's samplers for `segments` path pieces (none for one): the pixel's and
    the taps' paths, and the NeighborMax winner's (TILE_SOURCE_path, _path2)."""
    n = segments // 2
    names = {"u_path0": GBUFFER_PATHS[0], "u_path1": GBUFFER_PATHS[1],
             "u_tile_path0": tile_source + "_path", "u_tile_path1": tile_source + "_path2"}
    return {key: names[key] for key in ("u_path0", "u_tile_path0", "u_path1", "u_tile_path1")
            [:2 * n]}


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
