"""A sweep file (TOML) -> a checked Sweep: scenes, times, shutters, sizes, reference
samples, seeds, common parameters and variants with their grids expanded.

Every mistake is one UserError naming the sweep file and the key, the way world/loader.py
words a scene file's. Scenes are only found here (a file, a built-in or bench/example/
conformance name, a glob relative to the sweep file); they are loaded on the workers, so
that a scene that fails to load is one error row of the table, not the end of the sweep.
"""
from __future__ import annotations

import fnmatch
import itertools
import math
import os
import re
import stat
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from world import limits
from world.errors import UserError
from world.loader import builtin_scene_names, builtin_scene_path, describe_value
from viewer.cli.args import MAX_TIME, other_scene, parse_size, shutter_expected
from viewer.eval.comparison import MAX_NAME, REALTIME, Variant, check_capacity, check_variant
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
        self.glob_entries = [0]         # seen by every glob of the file together

    def fail(self, key: str, expected: str):
        raise UserError(f"{self.path}: {key}: {expected}" if key else f"{self.path}: {expected}")

    def list_of(self, v, key: str, check, allow_scalar: bool):
        """A non-empty list of distinct values (or, with allow_scalar, one value), at most
        limits.MAX_SWEEP_CELLS long (a longer one makes more cells than that anyway)."""
        if not isinstance(v, list):
            if allow_scalar:
                return [check(v, key)]
            self.fail(key, f"expected a list, got {describe_value(v)}")
        if not v:
            self.fail(key, "expected at least one value, got an empty list")
        if len(v) > limits.MAX_SWEEP_CELLS:
            self.fail(key, f"{len(v)} values, more than the {limits.MAX_SWEEP_CELLS} cells a "
                      "sweep may have")
        out, seen = [], set()
        for i, x in enumerate(v):
            out.append(check(x, f"{key}[{i + 1}]"))
            try:
                mark = ("value", out[-1], type(out[-1]))
                hash(mark)
            except TypeError:             # (a glob's scenes: compared by what was written)
                mark = ("text", repr(x))
            if mark in seen:
                self.fail(f"{key}[{i + 1}]", f"{x!r} is listed twice")
            seen.add(mark)
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
        expected = shutter_expected(s)
        if expected:
            self.fail(key, f"{expected}, got {v!r}")
        return s

    def integer(self, lo: int, hi: int | None = None):
        def check(v, key):
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                self.fail(key, f"expected an integer >= {lo}, got {describe_value(v)}")
            if hi is not None and v > hi:
                self.fail(key, f"expected an integer from {lo} to {hi}, got {v}")
            return v
        return check

    def size(self, v, key: str) -> tuple[int, int]:
        if not isinstance(v, str):
            self.fail(key, f"expected \"WxH\", e.g. \"320x180\", got {describe_value(v)}")
        if not re.fullmatch(r"\s*\d{1,9}\s*[xX]\s*\d{1,9}\s*", v):
            self.fail(key, f"expected \"WxH\" with positive integers, e.g. \"320x180\", got {v!r}")
        try:
            return parse_size(v, key)
        except UserError as exc:          # (zero, or past the frame limits: its words)
            self.fail(key, str(exc).removeprefix(f"{key} {v!r}: "))

    def scene(self, v, key: str) -> list[SceneRef]:
        if not isinstance(v, str) or not v:
            self.fail(key, f"expected a scene file, a built-in name or a glob, got {describe_value(v)}")
        here = self.path.parent
        if any(c in v for c in "*?["):
            found = bounded_glob(v, here, lambda expected: self.fail(key, expected),
                                 self.glob_entries)
            if not found:
                self.fail(key, f"{v!r} matches no file (globs are relative to the sweep file)")
            return [SceneRef(_rel(p, here), p.resolve()) for p in found]
        p = here / v
        kind = _file_kind(p)
        if kind == "file":
            return [SceneRef(v, p.resolve())]
        if kind is not None:
            self.fail(key, f"{v!r}: {p} is {kind}, expected a scene file (.toml, .gltf, .glb)")
        if not v.endswith(".toml") and "/" not in v:
            if v in builtin_scene_names():
                return [SceneRef(v, builtin_scene_path(v).resolve())]
            other = other_scene(v)
            if other is not None:
                return [SceneRef(v, other)]
        self.fail(key, f"{v!r}: no such scene file (relative to the sweep file) or built-in "
                  f"scene ({', '.join(builtin_scene_names())})")


def _file_kind(p: Path) -> str | None:
    """"file" for a regular file (symlinks followed), else what is there (None: nothing)."""
    try:
        mode = os.stat(p).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISREG(mode):
        return "file"
    return "a folder" if stat.S_ISDIR(mode) else "not a regular file (a device or FIFO)"


def bounded_glob(pattern: str, here: Path, fail, seen: list | None = None) -> list[Path]:
    """The regular files `pattern` names (relative to `here`, `**` for any depth of
    folders), sorted: glob's matching without its hazards. `**` never enters a symlinked
    folder (a link loop cannot make it walk for ever), hidden names match only a pattern
    part that starts with a dot, and past limits.MAX_GLOB_ENTRIES directory entries seen or
    limits.MAX_SWEEP_SCENES files matched it calls fail(expected). `seen`: a one-item list
    counting the entries, shared by the globs of one sweep file."""
    parts = Path(pattern).parts
    magic = [i for i, part in enumerate(parts) if any(c in part for c in "*?[")]
    paths = [here / Path(*parts[:magic[0]])] if magic[0] else [here]
    seen = [0] if seen is None else seen

    def entries(folder: Path):
        try:
            with os.scandir(folder) as it:
                for e in it:
                    seen[0] += 1
                    if seen[0] > limits.MAX_GLOB_ENTRIES:
                        fail(f"{pattern!r} visits more than {limits.MAX_GLOB_ENTRIES:,} "
                             "folder entries (the sweep file's globs together): narrow it")
                    yield e
        except OSError:                    # (not a folder, unreadable: matches nothing)
            return

    def below(folder: Path):
        """`folder` and every folder under it, symlinked folders not entered."""
        out, stack = [], [folder]
        while stack:
            d = stack.pop()
            out.append(d)
            stack += sorted((Path(e.path) for e in entries(d)
                             if not e.name.startswith(".") and e.is_dir(follow_symlinks=False)),
                            reverse=True)
        return out

    for k, part in enumerate(parts[magic[0]:], magic[0]):
        nxt = []
        for d in paths:
            if part == "**":
                folders = below(d)
                nxt += folders
                if k == len(parts) - 1:      # a last `**` names the files in them too
                    nxt += [Path(e.path) for f in folders for e in entries(f)
                            if not e.name.startswith(".")]
            elif any(c in part for c in "*?["):
                nxt += [Path(e.path) for e in entries(d)
                        if fnmatch.fnmatchcase(e.name, part)
                        and (part.startswith(".") or not e.name.startswith("."))]
            else:
                nxt.append(d / part)
        paths = list(dict.fromkeys(nxt))
    found = sorted((p for p in paths if _file_kind(p) == "file"), key=str)
    if len(found) > limits.MAX_SWEEP_SCENES:
        fail(f"{pattern!r} matches {len(found)} files, more than the "
             f"{limits.MAX_SWEEP_SCENES} scenes a sweep may have")
    return found


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
    kind = _file_kind(path)
    if kind is None:
        raise UserError(f"{path}: sweep file not found")
    if kind != "file":
        raise UserError(f"{path}: is {kind}, expected a sweep file (.toml)")
    try:
        with open(path, "rb") as f:
            data = f.read(limits.MAX_SWEEP_FILE_BYTES + 1)
    except OSError as exc:
        raise UserError(f"{path}: cannot read ({exc.strerror or exc.__class__.__name__})") from None
    if len(data) > limits.MAX_SWEEP_FILE_BYTES:
        raise UserError(f"{path}: holds more than the {limits.MAX_SWEEP_FILE_BYTES} bytes a "
                        "sweep file may")
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise UserError(f"{path}: expected UTF-8 text (TOML), bad byte at offset {exc.start}") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"{path}: not TOML ({exc})") from None
    except (ValueError, RecursionError) as exc:
        raise UserError(f"{path}: TOML could not be read ({type(exc).__name__})") from None
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
    seeds = c.list_of(doc.get("seed", 0), "seed", c.integer(0, limits.MAX_SEED), True)
    n_cells = math.prod(map(len, (scenes, times, shutters, sizes, samples, seeds)))
    if n_cells > limits.MAX_SWEEP_CELLS:
        c.fail("", f"{len(scenes)} scenes x {len(times)} times x {len(shutters)} shutters x "
               f"{len(sizes)} sizes x {len(samples)} sample counts x {len(seeds)} seeds are "
               f"{n_cells:,} cells, more than the {limits.MAX_SWEEP_CELLS:,} a sweep may have")

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
    variants, count = [], 0
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
        count += math.prod(map(len, grid.values()))
        if count > limits.MAX_VARIANTS:
            c.fail(k, f"makes the sweep's variants {count:,} (its grid's lists multiplied), "
                   f"more than the {limits.MAX_VARIANTS} a comparison may show")
        for values in itertools.product(*grid.values()):
            point = dict(zip(grid, values))
            v = SweepVariant(grid_name(family, point), mode, {**fixed, **point},
                             method=method, family=family, grid=point)
            if len(v.name) > MAX_NAME:
                c.fail(k, f"makes the variant name {v.name[:40]!r}... of {len(v.name)} "
                       f"characters (a file name: at most {MAX_NAME}): shorten NAME or the "
                       "grid's values")
            v.params(probe, f"{path}: {k}.set")   # every value checked: type and range
            variants.append(v)
    names = [v.name for v in variants]
    for v in variants:
        if names.count(v.name) > 1:
            c.fail(f"variants.{v.family}", f"makes the name {v.name!r} twice")
    renders = n_cells * len(variants)
    if renders > limits.MAX_SWEEP_RENDERS:
        c.fail("variants", f"{n_cells:,} cells x {len(variants)} variants are {renders:,} "
               f"renders (4 table rows each), more than the {limits.MAX_SWEEP_RENDERS:,} a "
               "sweep may have")
    for size in sizes:
        if size is not None:
            try:
                check_capacity(len(variants), size, "")
            except UserError as exc:
                c.fail("size", str(exc).removeprefix(": "))
    used = {g for v in variants for g in v.groups} | {"reference"}
    for key in common:
        group = key.partition(".")[0]
        if group not in used:
            c.fail(f"set.{key}", f"no variant's mode uses the {group} parameters")
    return Sweep(path, scenes, times, shutters, sizes, samples, seeds, common, variants)
