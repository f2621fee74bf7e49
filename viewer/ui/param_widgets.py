"""imgui widgets generated from the parameter dataclasses (viewer/render/graph/params.py): a combo for
choices, a checkbox for booleans, a slider for a bounded number (logarithmic over wide
positive ranges), a drag for an unbounded one. Every change goes through ParamSet.set, so
the panel obeys the same ranges as `--set`."""
from __future__ import annotations

import dataclasses

from imgui_bundle import imgui

from world.errors import UserError
from viewer.render.graph.params import ParamSet

DRAG_SPEED = 0.01
LOG_RATIO = 100.0                 # hi / lo at which a slider becomes logarithmic


def widget_kind(f: dataclasses.Field) -> str:
    """Which widget a field gets: combo, checkbox, slider_int, drag_int, slider_float,
    drag_float or text."""
    meta, kind = f.metadata, type(f.default)
    if meta.get("choices") is not None:
        return "combo"
    if kind is bool:
        return "checkbox"
    bounded = meta.get("lo") is not None and meta.get("hi") is not None
    if kind is int:
        return "slider_int" if bounded else "drag_int"
    if kind is float:
        return "slider_float" if bounded else "drag_float"
    return "text"


def tooltip(f: dataclasses.Field) -> str:
    meta = f.metadata
    parts = [meta.get("help") or f.name]
    unit = f" ({meta['unit']})" if meta.get("unit") else ""
    if meta.get("lo") is not None or meta.get("hi") is not None:
        parts.append(f"range {meta.get('lo', '-inf')} .. {meta.get('hi', 'inf')}{unit}")
    elif unit:
        parts.append(f"unit: {meta['unit']}")
    if meta.get("effect", "uniform") != "uniform":
        parts.append(f"a change costs a {meta['effect']}")
    parts.append(f"default {f.default!r}")
    return "\n".join(parts)


def _log_flag(lo, hi) -> int:
    return imgui.SliderFlags_.logarithmic if lo > 0 and hi / lo >= LOG_RATIO else 0


def field_widget(params: ParamSet, group: str, f: dataclasses.Field) -> str | None:
    """Draw one field's widget; apply a change. Returns an error message or None."""
    key = f"{group}.{f.name}"
    value = getattr(params[group], f.name)
    meta = f.metadata
    label = f"{f.name}##{key}"
    kind = widget_kind(f)
    lo, hi = meta.get("lo"), meta.get("hi")
    if kind == "combo":
        choices = list(meta["choices"])
        changed, idx = imgui.combo(label, choices.index(value) if value in choices else 0,
                                   [str(c) for c in choices])
        new = choices[idx]
    elif kind == "checkbox":
        changed, new = imgui.checkbox(label, value)
    elif kind == "slider_int":
        changed, new = imgui.slider_int(label, value, int(lo), int(hi), "%d", _log_flag(lo, hi))
    elif kind == "drag_int":
        changed, new = imgui.drag_int(label, value, 0.2, int(lo if lo is not None else 0),
                                      int(hi if hi is not None else 0))
    elif kind == "slider_float":
        changed, new = imgui.slider_float(label, value, float(lo), float(hi), "%.4g",
                                          _log_flag(lo, hi))
    elif kind == "drag_float":
        changed, new = imgui.drag_float(label, value, DRAG_SPEED,
                                        float(lo if lo is not None else 0.0),
                                        float(hi if hi is not None else 0.0), "%.4g")
    else:
        changed, new = imgui.input_text(label, str(value))
    imgui.set_item_tooltip(tooltip(f))
    if not changed or new == value:
        return None
    if isinstance(new, float):
        new = float(f"{new:.6g}")     # imgui works in float32: keep sidecars readable
    try:
        params.set(key, new)
    except UserError as exc:
        return str(exc)
    return None


def group_widgets(params: ParamSet, group: str) -> list[str]:
    """Every field of one group; returns the errors of rejected changes."""
    errors = []
    for f in dataclasses.fields(params[group]):
        err = field_widget(params, group, f)
        if err:
            errors.append(err)
    return errors
