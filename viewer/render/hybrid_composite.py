"""The hybrid mode's composite: both layers blurred and combined in one resolve.

  (inputs) the layers packed for the inner loop as glsl/hybrid_layers.glsl describes:
      the front by the G-buffer (layout "hybrid"), the revealed ones by reveal_shade;
  hybrid_tilemax_x / hybrid_tilemax / hybrid_neighbormax: the largest displacement around
      each tile (viewer/render/tiles.py, McGuire's passes on the raster displacement);
  hybrid_composite -> hybrid: the time-sampled composite (glsl/hybrid_time.frag), or the
      bucketed gather (glsl/hybrid_bucket.frag) for comparison; only on the active tiles
      where the frame has tile lists (viewer/render/tile_lists.py), the sharp colour elsewhere.
"""
from __future__ import annotations

from .blur_common import max_radius_px
from .frame import Frame
from .hybrid_params import HybridParams  # noqa: F401  (registers the "hybrid" group)
from .passes import FullscreenPass
from .pool import TexSpec
from .tile_lists import tile_list
from .tiles import tile_passes

# Which noise stream of glsl/noise.glsl's hash01 jitters the time samples or taps.
JITTER_STREAM = 2
FRAGMENTS = {"time": "hybrid_time.frag", "bucket": "hybrid_bucket.frag"}


def composite_kind(frame: Frame) -> str:
    """"time" or "bucket": the `hybrid.composite` setting, "auto" resolved by whether the
    camera moves (docs/performance.md has the measurements behind the choice)."""
    kind = frame.params["hybrid"].composite
    if kind == "auto":
        return "time" if frame.scene.camera.moving else "bucket"
    return kind


class Composite(FullscreenPass):
    """The composite composite_kind picks: "time" (glsl/hybrid_time.frag) or "bucket"
    (glsl/hybrid_bucket.frag)."""
    name = "hybrid_composite"
    inputs = ("color", "hybrid_front", "hybrid_back", "hybrid_back_color", "hybrid_back2",
              "hybrid_back2_color", "hybrid_tilemax", "hybrid_neighbormax", "ray_mask_tiles")
    produces = ("hybrid",)

    def program(self, frame: Frame, vertex: str = "fullscreen.vert"):
        self.fragment = FRAGMENTS[composite_kind(frame)]
        return super().program(frame, vertex)

    def defines(self, frame: Frame):
        p = frame.params["hybrid"]
        return {"LAYERS": int(p.layers), "MAX_SEEDS": int(p.seeds),
                "JITTER_STREAM": f"{JITTER_STREAM}u"}

    def outputs(self, frame: Frame):
        return {"hybrid": TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        p = frame.params["hybrid"]
        k = max_radius_px(frame)
        tiles = tile_list(frame, "active")
        if tiles is not None:
            # Outside the active tiles nothing reaches a pixel: its sharp colour stands.
            frame.ctx.copy_framebuffer(frame.pool.framebuffer(("hybrid",)),
                                       frame.pool.framebuffer(("color",)))
        self.draw(frame, self.produces,
                  {"u_front_color": "color", "u_front": "hybrid_front",
                   "u_back_color": "hybrid_back_color", "u_back": "hybrid_back",
                   "u_back2_color": "hybrid_back2_color", "u_back2": "hybrid_back2",
                   "u_tilemax": "hybrid_tilemax", "u_neighbormax": "hybrid_neighbormax",
                   "u_mask_tiles": "ray_mask_tiles"},
                  {"u_tile": k, "u_max_disp": 2.0 * k,
                   "u_samples_min": int(p.samples_min),
                   "u_samples_max": int(max(p.samples_max, p.samples_min)),
                   "u_spacing": float(p.sample_spacing), "u_jitter": float(p.jitter),
                   "u_tolerance": float(p.tolerance), "u_iterations": int(p.iterations)},
                  tiles=tiles, clear=False)


def composite_passes() -> list:
    """The displacement tiles and the composite, after the reveal."""
    return [*tile_passes("velocity", "hybrid"), Composite()]
