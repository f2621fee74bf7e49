"""A TOML writer for scene documents (the shape world.loader reads): top-level keys with
values, tables of values, arrays of tables of values. Values are strings, booleans,
integers, finite floats, arrays of values and inline tables of values. Floats are written
with repr, so a document read back with tomllib is equal to the one written.
"""
from __future__ import annotations

import math
import re

_BARE = re.compile(r"[A-Za-z0-9_-]+")


def key(k: str) -> str:
    return k if _BARE.fullmatch(k) else string(k)


def string(s: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in s:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"TOML scene documents hold finite numbers only, got {v!r}")
        return repr(v)
    if isinstance(v, str):
        return string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items()) + " }" \
            if v else "{}"
    raise TypeError(f"no TOML value for {type(v).__name__}")


def _is_table_array(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def dumps(doc: dict, header: str = "") -> str:
    """The document as TOML text: plain keys first, then [tables], then [[arrays]] (a
    table's own values only; nested tables inside them are written inline). `header`: comment
    lines put first (each line prefixed with "# ")."""
    lines = [f"# {line}".rstrip() for line in header.splitlines()]
    plain = {k: v for k, v in doc.items() if not isinstance(v, dict) and not _is_table_array(v)}
    for k, v in plain.items():
        lines.append(f"{key(k)} = {value(v)}")
    for k, v in doc.items():
        if isinstance(v, dict):
            lines += ["", f"[{key(k)}]"] + [f"{key(a)} = {value(b)}" for a, b in v.items()]
    for k, v in doc.items():
        if _is_table_array(v):
            for t in v:
                lines += ["", f"[[{key(k)}]]"] + [f"{key(a)} = {value(b)}" for a, b in t.items()]
    return "\n".join(lines) + "\n"
