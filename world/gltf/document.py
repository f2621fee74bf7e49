"""GltfError and typed access to a glTF document's JSON: every mistake a GltfError of one
line naming the item (`accessors[3].count: ...`; the scene loader prefixes file and entry).
"""
from __future__ import annotations

import json
import math

import numpy as np

from world import limits


class GltfError(Exception):
    """One line saying what is wrong with the asset, naming the item (no file prefix).
    Line breaks that come with names or paths from the asset are escaped."""

    def __init__(self, message: str = ""):
        super().__init__(str(message).replace("\r", "\\r").replace("\n", "\\n"))


REQUIRED = object()


def fail(msg: str):
    raise GltfError(msg)


def is_int(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def is_num(v) -> bool:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:                      # an integer beyond float range
        return False


def obj(v, where: str) -> dict:
    if not isinstance(v, dict):
        fail(f"{where}: expected a JSON object")
    return v


def integer(o: dict, key: str, where: str, default=REQUIRED, lo: int = 0, hi: int | None = None):
    v = o.get(key, default)
    if v is REQUIRED:
        fail(f"{where}: missing {key}")
    if v is default and default is None:
        return None
    if not is_int(v) or v < lo or (hi is not None and v > hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        fail(f"{where}.{key}: expected an integer {rng}, got {show(v)}")
    return v


def ref(o: dict, key: str, where: str, items, name: str, required=False):
    """An index into the top-level array `name` (length len(items))."""
    if key not in o:
        if required:
            fail(f"{where}: missing {key}")
        return None
    v = o[key]
    if not is_int(v) or not 0 <= v < len(items):
        fail(f"{where}.{key}: {show(v)} is not an index of {name} ({len(items)} entries)")
    return v


def array(o: dict, key: str, where: str, required=False) -> list:
    if key not in o:
        if required:
            fail(f"{where}: missing {key}")
        return []
    v = o[key]
    if not isinstance(v, list):
        fail(f"{where}.{key}: expected an array")
    if len(v) > limits.MAX_GLTF_ITEMS:
        fail(f"{where}.{key}: {len(v)} entries, more than the limit of {limits.MAX_GLTF_ITEMS}")
    return v


def numbers(o: dict, key: str, where: str, n: int, default,
            bound: float = limits.MAX_SCENE_NUMBER) -> np.ndarray:
    """n numbers, each finite and within +-bound (the shaders' float32 keeps 7 digits)."""
    if key not in o:
        return np.array(default, dtype=np.float64)
    v = o[key]
    if not isinstance(v, list) or len(v) != n or not all(is_num(x) and abs(x) <= bound for x in v):
        fail(f"{where}.{key}: expected {n} finite numbers within +-{bound:g}, got {show(v)}")
    return np.array(v, dtype=np.float64)


def within(a: np.ndarray, where: str, what: str = "values",
           bound: float = limits.MAX_SCENE_NUMBER) -> np.ndarray:
    """`a` (an accessor's elements along the first axis), unless an element holds a value
    that is not finite or lies beyond +-bound."""
    bad = ~(np.abs(a) <= bound)               # (NaN compares false)
    if bad.any():
        k = int(np.nonzero(bad.reshape(len(a), -1).any(axis=1))[0][0])
        v = float(a.reshape(len(a), -1)[k][bad.reshape(len(a), -1)[k]][0])
        if not np.isfinite(v):
            fail(f"{where}: non-finite {what} (element {k}: {v!r})")
        fail(f"{where}: {what} within +-{bound:g} expected, element {k} holds {v:.7g}")
    return a


def name(o: dict, where: str, default: str) -> str:
    """The item's name (`default` where it has none), of at most limits.MAX_NAME_CHARS."""
    v = o.get("name")
    if not isinstance(v, str) or not v:
        return default
    if len(v) > limits.MAX_NAME_CHARS:
        fail(f"{where}.name: {len(v)} characters, more than the limit of {limits.MAX_NAME_CHARS}")
    return v


def string(o: dict, key: str, where: str, default=None):
    v = o.get(key, default)
    if v is not default and not isinstance(v, str):
        fail(f"{where}.{key}: expected a string")
    return v


def show(v) -> str:
    s = json.dumps(v) if not isinstance(v, float) or math.isfinite(v) else repr(v)
    return s if len(s) <= 40 else s[:37] + "..."


def kept(cache: dict, key, make):
    """cache[key], made by make() the first time it is asked for."""
    if key not in cache:
        cache[key] = make()
    return cache[key]
