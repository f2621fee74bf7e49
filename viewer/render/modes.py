"""The modes and their pipelines. Each mode module registers a builder with `mode()`; a
mode that is not registered does not exist (the CLI lists exactly these)."""
from __future__ import annotations

from typing import Callable

from .gbuffer import GBufferPass
from .passes import Pipeline

MODES: dict[str, Callable[[], Pipeline]] = {}
MODE_GROUPS: dict[str, tuple[str, ...]] = {}   # parameter groups each mode uses


def mode(name: str, groups: tuple[str, ...] = ()):
    def register(builder):
        MODES[name] = builder
        MODE_GROUPS[name] = groups
        return builder
    return register


@mode("off")
def _off() -> Pipeline:
    return Pipeline("off", [GBufferPass()], output="color")


# Each mode module registers itself with @mode on import (add new ones here).
from . import reference  # noqa: E402,F401
from . import mcguire  # noqa: E402,F401
from . import ue4  # noqa: E402,F401
from . import guertin  # noqa: E402,F401
from . import hybrid  # noqa: E402,F401
