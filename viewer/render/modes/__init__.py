"""The modes and their pipelines: importing this module imports every mode module, each of
which registers its builder with `registry.mode()` (the CLI lists exactly these)."""
from __future__ import annotations

from viewer.render.passes.gbuffer import GBufferPass
from viewer.render.passes.motion_params import MotionParams  # noqa: F401  (registers the "motion" group)
from viewer.render.graph.passes import Pipeline
from viewer.render.graph.registry import MODE_GROUPS, MODES, NoConfig, mode

__all__ = ["MODES", "MODE_GROUPS"]


@mode("off", steps=False)
def _off(config: NoConfig = NoConfig()) -> Pipeline:
    return Pipeline("off", [GBufferPass()], output="color", config=config)


# Each mode module registers itself with @mode on import (add new ones here).
from viewer.render.modes import reference  # noqa: E402,F401
from viewer.render.modes import mcguire  # noqa: E402,F401
from viewer.render.modes import ue4  # noqa: E402,F401
from viewer.render.modes import guertin  # noqa: E402,F401
from viewer.render.modes.hybrid import pipeline  # noqa: E402,F401  (the hybrid)
