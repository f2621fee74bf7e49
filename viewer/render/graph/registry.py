"""The mode registry: each mode module registers its pipeline builder with `mode()`; a mode
that is not registered does not exist. Mode modules import only this; `modes.py` imports
every mode module, so MODES is complete once `viewer.render.modes` is imported.

A builder takes the mode's configuration: a frozen dataclass of the parameters that
change which passes run, which textures exist and which shader variants compile (e.g.
hybrid.segments, hybrid.range_check), made from a ParamSet by the mode's `config`; the
pipeline holds exactly the passes that configuration runs, and the renderer keeps one
pipeline per (mode, configuration). Every other parameter is read by the passes per frame."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from viewer.render.graph.params import ParamSet
from .passes import Pipeline


@dataclass(frozen=True)
class NoConfig:
    """A mode whose passes are the same under every parameter."""

    @classmethod
    def of(cls, params: ParamSet) -> "NoConfig":
        return cls()


MODES: dict[str, Callable[..., Pipeline]] = {}   # builder(config=default) -> Pipeline
MODE_CONFIGS: dict[str, type] = {}             # each mode's configuration class
MODE_GROUPS: dict[str, tuple[str, ...]] = {}   # parameter groups each mode uses
ORDER = ("off", "reference", "mcguire", "ue4", "guertin", "hybrid")


def mode(name: str, groups: tuple[str, ...] = (), steps: bool = True, config: type = NoConfig):
    """Register a mode's pipeline builder with its parameter groups and its configuration
    class (`config.of(params)` makes one; the builder's default argument is the default's).
    `steps`: the mode takes sub-exposure steps (the "motion" group, viewer/render/steps.py,
    run by the renderer around any pipeline): every real-time blur does; a sharp frame or
    a mode with its own samples over the exposure does not."""
    def register(builder):
        MODES[name] = builder
        MODE_CONFIGS[name] = config
        MODE_GROUPS[name] = tuple(groups) + (("motion",) if steps else ())
        # Listed (CLI, panel, compare) in ORDER, whichever mode module is imported first.
        rank = {n: k for k, n in enumerate(ORDER)}
        for table in (MODES, MODE_CONFIGS, MODE_GROUPS):
            items = sorted(table.items(), key=lambda kv: rank.get(kv[0], len(rank)))
            table.clear()
            table.update(items)
        return builder
    return register


def mode_config(name: str, params: ParamSet | None = None):
    """Mode `name`'s configuration under `params` (None: the defaults)."""
    return MODE_CONFIGS[name].of(params if params is not None else ParamSet())


def build(name: str, params: ParamSet | None = None) -> Pipeline:
    """Mode `name`'s pipeline for its configuration under `params`."""
    return MODES[name](mode_config(name, params))
