"""The mode registry: each mode module registers its pipeline builder with `mode()`; a mode
that is not registered does not exist. Mode modules import only this; `modes.py` imports
every mode module, so MODES is complete once `viewer.render.modes` is imported."""
from __future__ import annotations

from typing import Callable

from .passes import Pipeline

MODES: dict[str, Callable[[], Pipeline]] = {}
MODE_GROUPS: dict[str, tuple[str, ...]] = {}   # parameter groups each mode uses
ORDER = ("off", "reference", "mcguire", "ue4", "guertin", "hybrid")


def mode(name: str, groups: tuple[str, ...] = (), steps: bool = True):
    """Register a mode's pipeline builder with its parameter groups. `steps`: the mode takes
    sub-exposure steps (the "motion" group, viewer/render/steps.py, run by the renderer
    around any pipeline): every real-time blur does; a sharp frame or a mode with its own
    samples over the exposure does not."""
    def register(builder):
        MODES[name] = builder
        MODE_GROUPS[name] = tuple(groups) + (("motion",) if steps else ())
        # Listed (CLI, panel, compare) in ORDER, whichever mode module is imported first.
        rank = {n: k for k, n in enumerate(ORDER)}
        for table in (MODES, MODE_GROUPS):
            items = sorted(table.items(), key=lambda kv: rank.get(kv[0], len(rank)))
            table.clear()
            table.update(items)
        return builder
    return register
