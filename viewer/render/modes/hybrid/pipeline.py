"""Mode `hybrid`: Hybrid MBlur (Tan, Cui, Bhojan, SIGGRAPH 2020 poster; docs/algorithms.md 4).

Post-process blur cannot know the background a moving object hides, which its blur
partly uncovers (inner blur). The hybrid mode finds those pixels, ray-traces the true
background behind them, shades it like the raster layer, and resolves both layers:

  gbuffer (colour, hybrid_front = D, depth, id; the path's targets with segments;
          + normal for the range check)
          -> motion_tiles -> select_tiles
          (host: which tiles move, which any motion reaches) (tile_select.py)
          -> hybrid tiles (+ NeighborMax read back for the bucket along the chord)
                                                             (viewer/render/modes/hybrid/composite.py)
          -> motion_table (hybrid.curve = inverse: host, the motion table and the tiles
          that follow curves, where motion bends)   (viewer/render/modes/hybrid/inverse.py)
          -> mask_displacement (with the range check: + the edge test -> mask_edge tiles
          -> ray_mask), on the moving tiles                  (viewer/render/modes/hybrid/mask.py)
          -> reveal (CPU rays) -> reveal_shade (hybrid_back*: packed D, depth, id, colour)
                                                             (viewer/render/modes/hybrid/reveal.py)
          -> hybrid_composite (bucketed; time-sampled or split by setting), on the
          active tiles
                                                             (viewer/render/modes/hybrid/composite.py)

Parameters: the `hybrid` group (viewer/render/modes/hybrid/params.py) and the shared `blur`
limit; the pipeline holds the passes of its configuration (viewer/render/modes/hybrid/config.py:
segments, range_check, composite, curve).
Stats: masked_pixels, rays, revealed_pixels, reveal_ms (host work) and its parts.
"""
from __future__ import annotations

from viewer.render.passes.gbuffer import GBufferPass
from .composite import Composite, composite_tile_passes
from .config import HybridConfig
from viewer.render.graph.registry import mode
from viewer.render.graph.passes import Pipeline
from .inverse import MotionTable
from .mask import raymask_passes
from .reveal import reveal_passes
from viewer.render.modes.hybrid.tile_select import selection_passes


def hybrid_passes(config: HybridConfig = HybridConfig()) -> list:
    """Everything after the G-buffer (the composite's tiles early: they need only the
    G-buffer, and their host read-back then waits for little)."""
    return [*selection_passes(config.segments), *composite_tile_passes(config),
            *((MotionTable(),) if config.curve == "inverse" else ()),
            *raymask_passes(config), *reveal_passes(), Composite(config)]


def hybrid_gbuffer(config: HybridConfig = HybridConfig()) -> GBufferPass:
    """Colour and the packed front layer (D, depth, id), the path's targets; the normal
    target too only for the poster's three-step mask, whose edge test alone reads it."""
    return GBufferPass(layout="hybrid" if config.range_check else "front",
                       segments=config.segments)


@mode("hybrid", groups=("blur", "hybrid"), config=HybridConfig)
def hybrid_pipeline(config: HybridConfig = HybridConfig()) -> Pipeline:
    return Pipeline("hybrid", [hybrid_gbuffer(config), *hybrid_passes(config)],
                    output="hybrid", config=config)
