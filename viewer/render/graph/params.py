"""Parameters as dataclasses: one definition drives `--set group.field=value`, the viewer's
panel and the JSON sidecar written beside every image.

A group is a dataclass registered with `@group("name")`; each field is made with `param()`,
whose metadata gives the range, the unit, help text and what a change costs ("uniform":
nothing, "recompile": a shader rebuild, "realloc": new textures). `describe_params` lists
them for `hmblur params`.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field, fields

from world.errors import UserError

GROUPS: dict[str, type] = {}


def group(name: str):
    def register(cls):
        cls = dataclass(cls)
        cls.group_name = name
        GROUPS[name] = cls
        return cls
    return register


def param(default, *, lo=None, hi=None, help: str = "", choices=None, effect: str = "uniform",
          unit: str = ""):
    """A parameter field. `unit`: what the number counts ("px", "m", "fraction of the image
    width", ...); empty for flags, choices and plain ratios."""
    return field(default=default, metadata=dict(lo=lo, hi=hi, help=help, choices=choices,
                                                effect=effect, unit=unit))


def _parse(kind: type, text: str, key: str):
    try:
        if kind is bool:
            low = text.strip().lower()
            if low in ("1", "true", "yes", "on"):
                return True
            if low in ("0", "false", "no", "off"):
                return False
            raise ValueError
        value = kind(text)
    except ValueError:
        raise UserError(f"--set {key}: expected {kind.__name__}, got {text!r}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise UserError(f"--set {key}: expected a finite number, got {text!r}")
    return value


def check_value(f: dataclasses.Field, value, key: str):
    meta = f.metadata
    if meta.get("choices") is not None and value not in meta["choices"]:
        raise UserError(f"--set {key}: expected one of {', '.join(map(str, meta['choices']))}, got {value!r}")
    if meta.get("lo") is not None and value < meta["lo"]:
        raise UserError(f"--set {key}: expected at least {meta['lo']}, got {value!r}")
    if meta.get("hi") is not None and value > meta["hi"]:
        raise UserError(f"--set {key}: expected at most {meta['hi']}, got {value!r}")


class ParamSet:
    """One instance of every registered group, with defaults; keys are 'group.field'."""

    def __init__(self):
        self.groups = {name: cls() for name, cls in GROUPS.items()}

    def __getitem__(self, name: str):
        return self.groups[name]

    def field(self, key: str) -> tuple[object, dataclasses.Field]:
        name, _, fname = key.partition(".")
        if name not in self.groups:
            raise UserError(f"--set {key}: unknown parameter group {name!r} "
                            f"(known: {', '.join(sorted(self.groups))})")
        inst = self.groups[name]
        for f in fields(inst):
            if f.name == fname:
                return inst, f
        raise UserError(f"--set {key}: unknown parameter {fname!r} of {name} "
                        f"(known: {', '.join(f.name for f in fields(inst))})")

    def set(self, key: str, value, label: str = "--set"):
        """Set group.field from a string (parsed) or a value; a mistake names `label`
        (the flag or file it came from) and the key."""
        if label != "--set":
            try:
                return self.set(key, value)
            except UserError as exc:
                raise UserError(f"{label}: {str(exc).removeprefix('--set ')}") from None
        inst, f = self.field(key)
        kind = type(f.default)
        if isinstance(value, str):
            value = _parse(kind, value, key)
        elif kind is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if type(value) is not kind:
            raise UserError(f"--set {key}: expected {kind.__name__}, got {value!r}")
        check_value(f, value, key)
        setattr(inst, f.name, value)

    def apply(self, assignments: list[str]):
        for text in assignments:
            key, eq, value = text.partition("=")
            if not eq:
                raise UserError(f"--set {text!r}: expected group.field=value")
            self.set(key.strip(), value.strip())

    def to_dict(self, names=None) -> dict:
        return {n: dataclasses.asdict(g) for n, g in self.groups.items()
                if names is None or n in names}

    def update(self, data: dict, source: str = "parameters"):
        if not isinstance(data, dict):
            raise UserError(f"{source}: expected a table of parameter groups")
        for name, values in data.items():
            if not isinstance(values, dict):
                raise UserError(f"{source}: {name}: expected a table of parameters")
            for fname, value in values.items():
                self.set(f"{name}.{fname}", value, label=source)


def value_range(f: dataclasses.Field) -> str:
    """The accepted values as text: choices, a closed range, a bound, or the type."""
    meta, kind = f.metadata, type(f.default)
    choices = meta.get("choices")
    if choices is not None:
        steps = {b - a for a, b in zip(choices, choices[1:])} if all(
            isinstance(c, int) and not isinstance(c, bool) for c in choices) else set()
        if len(choices) > 4 and len(steps) == 1:          # an arithmetic run: its ends
            return f"{choices[0]}, {choices[1]}, ..., {choices[-1]}"
        return "|".join(map(str, choices))
    if kind is bool:
        return "true|false"
    lo, hi = meta.get("lo"), meta.get("hi")
    if lo is not None and hi is not None:
        return f"{lo:g} .. {hi:g}"
    if lo is not None:
        return f">= {lo:g}"
    if hi is not None:
        return f"<= {hi:g}"
    return kind.__name__


def describe_params(names=None) -> list[dict]:
    """Every parameter of the groups `names` (default: all registered), in definition
    order: key, type, default, range, unit, effect, help."""
    rows = []
    for name, cls in GROUPS.items():
        if names is not None and name not in names:
            continue
        for f in fields(cls):
            rows.append({"key": f"{name}.{f.name}", "type": type(f.default).__name__,
                         "default": f.default, "range": value_range(f),
                         "unit": f.metadata.get("unit", ""),
                         "effect": f.metadata.get("effect", "uniform"),
                         "help": f.metadata.get("help", "")})
    return rows
