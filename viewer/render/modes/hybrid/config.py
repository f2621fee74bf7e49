"""The hybrid mode's configuration (viewer/render/graph/registry.py): the parameters that decide
which passes run, which textures exist and which shader variants compile."""
from __future__ import annotations

from dataclasses import dataclass

from viewer.render.passes.gbuffer import path_targets
from .params import HybridParams  # noqa: F401  (registers the "hybrid" group)


@dataclass(frozen=True)
class HybridConfig:
    segments: int = 1            # hybrid.segments: the path targets and every path variant
    range_check: bool = False    # hybrid.range_check: the poster's three-step mask passes
    composite: str = "bucket"    # hybrid.composite: the composite's variants and inputs
    curve: str = "steps"         # hybrid.curve: the motion table pass and inverse variant

    @classmethod
    def of(cls, params) -> "HybridConfig":
        p = params["hybrid"]
        return cls(int(p.segments), bool(p.range_check), str(p.composite), str(p.curve))

    @property
    def paths(self) -> tuple[str, ...]:
        """The G-buffer's path targets (none for one segment)."""
        return path_targets(self.segments)

    def tile_paths(self, base: str) -> tuple[str, ...]:
        """BASE's path targets carried by the tile passes (BASE_path, BASE_path2)."""
        return tuple(base + n[len("hybrid"):] for n in self.paths)

    @property
    def reads_neighbormax(self) -> bool:
        """Whether the composite's cheaper variants read NeighborMax on the host (one
        segment; along a path they read the path's extent instead; the time-sampled
        composite has none)."""
        return self.composite != "time" and self.segments == 1
