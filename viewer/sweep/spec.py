"""A sweep file (TOML) -> a checked Sweep: scenes, times, shutters, sizes, reference
samples, seeds, common parameters and variants with their grids expanded.

Every mistake is one UserError naming the sweep file and the key, the way world/loader.py
words a scene file's. Scenes are only found here (a file, a built-in or bench/example/
conformance name, a glob relative to the sweep file); they are loaded on the workers, so
that a scene that fails to load is one error row of the table, not the end of the sweep.
"""
from __future__ import annotations

import glob
import itertools
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from world.errors import UserError
from world.loader import builtin_scene_names, builtin_scene_path, describe_value
from viewer.cli.args import MAX_TIME, other_scene, parse_size
from viewer.eval.comparison import REALTIME, Variant, check_variant
from viewer.render.modes.user import parse_method
from viewer.render.modes.user.method import KINDS
from viewer.render.graph.params import ParamSet

KEYS = ("scenes", "times", "shutters", "size", "samples", "seed", "set", "variants")
VARIANT_KEYS = ("mode", "set")


@dataclass
class SceneRef:
    label: str            # the table's `scene` column
    path: Path            # the scene file


@dataclass
class SweepVariant(Variant):
    family: str = ""                                  # the [variants.NAME] it came from
    grid: dict = field(default_factory=dict)          # the grid's keys -> this one's values


@dataclass
class Sweep:
    path: Path
    scenes: list[SceneRef]
    times: list            # [None]: each scene's own [render] time
    shutters: list         # [None]: each scene camera's shutter
    sizes: list            # [None]: each scene's [render] size; else (w, h)
    samples: list[int]
    seeds: list[int]
    common: dict           # "group.field" -> value, for the reference and every variant
    variants: list[SweepVariant]

    def cells(self):
        """Every (scene, time, shutter, size, samples, seed), scenes outermost."""
        return list(itertools.product(self.scenes, self.times, self.shutters, self.sizes,
                                      self.samples, self.seeds))

    def swept(self) -> list[str]:
        """The cell parameters given more than one value (the plots' x axes)."""
        axes = {"time": self.times, "shutter": self.shutters, "size": self.sizes,
                "samples": self.samples, "seed": self.seeds}
        return [k for k, v in axes.items() if len(v) > 1]

    def grid_keys(self) -> list[str]:
        return list(dict.fromkeys(k for v in self.variants for k in v.grid))

    def set_keys(self) -> list[str]:
        return list(dict.fromkeys(k for v in self.variants for k in v.sets))


class _Checker:
    def __init__(self, path: Path):
        self.path = path

    def fail(self, key: str, expected: str):
        raise UserError(f"{self.path}: {key}: {expected}" if key else f"{self.path}: {expected}")

    def list_of(self, v, key: str, check, allow_scalar: bool):
        """A non-empty list of distinct values (or, with allow_scalar, one value)."""
        if not isinstance(v, list):
            if allow_scalar:
                return [check(v, key)]
            self.fail(key, f"expected a list, got {describe_value(v)}")
        if not v:
            self.fail(key, "expected at least one value, got an empty list")
        out = [check(x, f"{key}[{i + 1}]") for i, x in enumerate(v)]
        for i, x in enumerate(out):
            if x in out[:i]:
                self.fail(f"{key}[{i + 1}]", f"{v[i]!r} is listed twice")
        return out

    def number(self, v, key: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            self.fail(key, f"expected a finite number, got {describe_value(v)}")
        return float(v)

    def time(self, v, key: str) -> float:
        t = self.number(v, key)
        if abs(t) > MAX_TIME:
            self.fail(key, f"expected seconds within +-{MAX_TIME:g}, got {v!r}")
        return t

    def shutter(self, v, key: str) -> float:
        s = self.number(v, key)
        if s < 0:
            self.fail(key, f"expected an exposure time >= 0 s, got {v!r}")
        return s

    def integer(self, lo: int):
        def check(v, key):
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                self.fail(key, f"expected an integer >= {lo}, got {describe_value(v)}")
            return v
        return check

    def size(self, v, key: str) -> tuple[int, int]:
        if not isinstance(v, str):
            self.fail(key, f"expected \"WxH\", e.g. \"320x180\", got {describe_value(v)}")
        try:
            return parse_size(v, key)
        except UserError:
            self.fail(key, f"expected \"WxH\" with positive integers, e.g. \"320x180\", got {v!r}")

    def scene(self, v, key: str) -> list[SceneRef]:
        if not isinstance(v, str) or not v:
            self.fail(key, f"expected a scene file, a built-in name or a glob, got {describe_value(v)}")
        here = self.path.parent
        if any(c in v for c in "*?["):
            found = sorted(glob.glob(str(here / v), recursive=True))
            found = [Path(f) for f in found if Path(f).is_file()]
            if not found:
                self.fail(key, f"{v!r} matches no file (globs are relative to the sweep file)")
            return [SceneRef(_rel(p, here), p.resolve()) for p in found]
        p = here / v
        if p.is_file():
            return [SceneRef(v, p.resolve())]
        if not v.endswith(".toml") and "/" not in v:
            if v in builtin_scene_names():
                return [SceneRef(v, builtin_scene_path(v).resolve())]
            other = other_scene(v)
            if other is not None:
                return [SceneRef(v, other)]
        self.fail(key, f"{v!r}: no such scene file (relative to the sweep file) or built-in "
                  f"scene ({', '.join(builtin_scene_names())})")


def _rel(p: Path, here: Path) -> str:
    try:
        return str(p.relative_to(here))
    except ValueError:
        return str(p)


def _value_text(v) -> str:
    return str(v).lower() if isinstance(v, bool) else f"{v:g}" if isinstance(v, float) else str(v)


def grid_name(family: str, grid: dict) -> str:
    """`hybrid[curve_steps=1]`: the family and this point's grid values (a key by its field
    alone unless two grid keys share a field name)."""
    if not grid:
        return family
    fields = [k.partition(".")[2] for k in grid]
    parts = [f"{k.partition('.')[2] if fields.count(k.partition('.')[2]) == 1 else k}="
             f"{_value_text(v)}" for k, v in grid.items()]
    return f"{family}[{','.join(parts)}]"


def load_sweep(path) -> Sweep:
    path = Path(path)
    c = _Checker(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UserError(f"{path}: sweep file not found") from None
    except IsADirectoryError:
        raise UserError(f"{path}: is a folder, expected a sweep file (.toml)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"{path}: cannot read ({exc.__class__.__name__})") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: not TOML ({exc})") from None
    for k in doc:
        if k not in KEYS:
            c.fail(k, f"unknown key (expected {', '.join(KEYS)})")
    if "scenes" not in doc:
        c.fail("scenes", "required: a list of scene files, built-in names or globs")
    if "variants" not in doc:
        c.fail("variants", "required: at least one [variants.NAME] table with a mode")
    scene_lists = c.list_of(doc["scenes"], "scenes", c.scene, allow_scalar=False)
    scenes, seen = [], {}
    for i, refs in enumerate(scene_lists):
        for ref in refs:
            if ref.path in seen:
                c.fail(f"scenes[{i + 1}]", f"{ref.path} is already listed by scenes[{seen[ref.path]}]")
            seen[ref.path] = i + 1
            scenes.append(ref)
    labels = [s.label for s in scenes]
    for s in scenes:                  # a shorter label where it stays unique
        stem = s.path.stem
        if stem != s.label and sum(Path(lab).stem == stem for lab in labels) == 1:
            s.label = stem
    times = c.list_of(doc["times"], "times", c.time, False) if "times" in doc else [None]
    shutters = c.list_of(doc["shutters"], "shutters", c.shutter, False) if "shutters" in doc else [None]
    sizes = c.list_of(doc["size"], "size", c.size, True) if "size" in doc else [None]
    samples = c.list_of(doc.get("samples", ParamSet()["reference"].samples), "samples",
                        c.integer(1), True)
    seeds = c.list_of(doc.get("seed", 0), "seed", c.integer(0), True)

    common = doc.get("set", {})
    if not isinstance(common, dict):
        c.fail("set", f"expected a table {{ \"group.field\" = value }}, got {describe_value(common)}")
    probe = ParamSet()
    for key, value in common.items():
        if isinstance(value, list):
            c.fail(f"set.{key}", "expected one value (a grid belongs in a variant's set)")
        probe.set(key, value, label=f"{path}: set")
    for n in samples:
        probe.set("reference.samples", n, label=f"{path}: samples")

    table = doc["variants"]
    if not isinstance(table, dict) or not table:
        c.fail("variants", "expected one or more [variants.NAME] tables")
    variants = []
    for family, vt in table.items():
        k = f"variants.{family}"
        if not isinstance(vt, dict):
            c.fail(k, f"expected a table with mode and set, got {describe_value(vt)}")
        for key in vt:
            if key not in VARIANT_KEYS:
                c.fail(f"{k}.{key}", f"unknown key (expected {', '.join(VARIANT_KEYS)})")
        modes = f"one of {', '.join(REALTIME)}, or a user pass glsl:PATH, py:PATH:FUNCTION"
        if "mode" not in vt:
            c.fail(f"{k}.mode", f"required: {modes}")
        mode = vt["mode"]
        if not isinstance(mode, str):
            c.fail(f"{k}.mode", f"expected {modes}, got {describe_value(mode)}")
        method = None
        if mode.partition(":")[0] in KINDS:     # a user pass, its file beside the sweep file
            method = parse_method(mode, path.parent, f"{path}: {k}.mode {mode}")
            mode = method.kind
        sets = vt.get("set", {})
        if not isinstance(sets, dict):
            c.fail(f"{k}.set", f"expected a table {{ \"group.field\" = value or [values] }}, "
                   f"got {describe_value(sets)}")
        fixed, grid = {}, {}
        for key, value in sets.items():
            if isinstance(value, list):
                grid[key] = c.list_of(value, f"{k}.set.{key}", lambda x, _k: x, False)
            else:
                fixed[key] = value
        check_variant(Variant(family, mode, dict(sets), method), f"{path}: {k}", values=False)
        for values in itertools.product(*grid.values()):
            point = dict(zip(grid, values))
            v = SweepVariant(grid_name(family, point), mode, {**fixed, **point},
                             method=method, family=family, grid=point)
            v.params(probe, f"{path}: {k}.set")   # every value checked: type and range
            variants.append(v)
    names = [v.name for v in variants]
    for v in variants:
        if names.count(v.name) > 1:
            c.fail(f"variants.{v.family}", f"makes the name {v.name!r} twice")
    used = {g for v in variants for g in v.groups} | {"reference"}
    for key in common:
        group = key.partition(".")[0]
        if group not in used:
            c.fail(f"set.{key}", f"no variant's mode uses the {group} parameters")
    return Sweep(path, scenes, times, shutters, sizes, samples, seeds, common, variants)
