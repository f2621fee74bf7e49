"""Mode `hybrid`: Hybrid MBlur (Tan, Cui, Bhojan, SIGGRAPH 2020 poster; docs/algorithms.md 4).

Post-process blur cannot know the background a moving object hides, which its blur
partly uncovers (inner blur). The hybrid mode finds those pixels, ray-traces the true
background behind them, shades it like the raster layer, and resolves both layers:

  gbuffer (colour, hybrid_front = D, depth, id; + normal for the range check)
          -> motion_tiles -> select_tiles
          (host: which tiles move, which any motion reaches) (viewer/render/tile_lists.py)
          -> hybrid tiles (+ NeighborMax read back)      (viewer/render/hybrid/composite.py)
          -> mask_displacement (+ the edge test) -> mask_edge tiles -> ray_mask (+ tiles),
          on the moving tiles                                (viewer/render/hybrid/mask.py)
          -> reveal (CPU rays) -> reveal_shade (hybrid_back*: packed D, depth, id, colour)
                                                             (viewer/render/hybrid/reveal.py)
          -> hybrid_composite (bucketed; time-sampled or split by setting), on the
          active tiles
                                                             (viewer/render/hybrid/composite.py)

Parameters: the `hybrid` group (viewer/render/hybrid/params.py) and the shared `blur` limit.
Stats: masked_pixels, rays, revealed_pixels, reveal_ms (host work) and its parts.
"""
from __future__ import annotations

from ..gbuffer import SEGMENT_CHOICES, GBufferPass
from .composite import Composite, composite_tile_passes
from .params import HybridParams  # noqa: F401  (registers the "hybrid" group)
from ..registry import mode
from ..passes import Pipeline
from .mask import raymask_passes
from .reveal import reveal_passes
from ..tile_lists import selection_passes


def hybrid_passes() -> list:
    """Everything after the G-buffer (the composite's tiles early: they need only the
    G-buffer, and their host read-back then waits for little)."""
    return [*selection_passes(), *composite_tile_passes(), *raymask_passes(),
            *reveal_passes(), Composite()]


class HybridGBuffer(GBufferPass):
    """Colour and the packed front layer (D, depth, id); the normal target too only for
    the poster's three-step mask (hybrid.range_check), whose edge test alone reads it."""

    def __init__(self):
        super().__init__(layout="hybrid")
        self.produces = self.targets("hybrid", max(SEGMENT_CHOICES))

    def layout(self, frame) -> str:
        return "hybrid" if frame.params["hybrid"].range_check else "front"

    def segments(self, frame) -> int:
        return int(frame.params["hybrid"].segments)


@mode("hybrid", groups=("blur", "hybrid"))
def hybrid_pipeline() -> Pipeline:
    return Pipeline("hybrid", [HybridGBuffer(), *hybrid_passes()], output="hybrid")
