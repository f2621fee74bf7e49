"""The modes and their pipelines: importing this module imports every mode module, each of
which registers its builder with `registry.mode()` (the CLI lists exactly these)."""
from __future__ import annotations

from .gbuffer import GBufferPass
from .motion_params import MotionParams  # noqa: F401  (registers the "motion" group)
from .passes import Pipeline
from .registry import MODE_GROUPS, MODES, NoConfig, mode

__all__ = ["MODES", "MODE_GROUPS"]


@mode("off", steps=False)
def _off(config: NoConfig = NoConfig()) -> Pipeline:
    return Pipeline("off", [GBufferPass()], output="color", config=config)


# Each mode module registers itself with @mode on import (add new ones here).
from . import reference  # noqa: E402,F401
from . import mcguire  # noqa: E402,F401
from . import ue4  # noqa: E402,F401
from . import guertin  # noqa: E402,F401
from .hybrid import pipeline  # noqa: E402,F401  (the hybrid)
