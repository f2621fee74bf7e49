"""Scripted UI actions for running the viewer without a person (`hmblur view --script`).

Two spellings of the same thing. Text, one action per line, `#` starts a comment:

    10 mode reference
    20 set blur.max_radius=0.1
    30 key P
    40 resize 400x300
    50 orbit 40 -10          # left drag by (dx, dy) pixels from the scene's centre
    60 view depth
    70 overlay compact

JSON, a list of objects with the frame and one action:

    [{"frame": 10, "mode": "reference"}, {"frame": 40, "resize": [400, 300]}]

Actions run at the start of their frame, before input is dispatched. Mouse and key actions
become input events that go through imgui first, like a person's would. Every argument is
checked when the script is read (a bad one is a one-line error, exit 2, before the window
opens); an action that fails while running (a scene file that does not load) shows in the
panel, and the run then exits 2 with that line.
"""
from __future__ import annotations

import json
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

from world.errors import UserError

# name: (number of arguments, what they are)
ACTIONS = {
    "mode": (1, "a mode name"),
    "set": (1, "group.field=value"),
    "key": (1, "a key name (P, F12, SPACE, W, ...)"),
    "resize": (1, "WxH"),
    "orbit": (2, "dx dy (pixels, left drag from the scene's centre)"),
    "pan": (2, "dx dy (pixels, right drag from the scene's centre)"),
    "drag": (5, "button x0 y0 x1 y1 (button: left, right or middle; window pixels)"),
    "zoom": (1, "wheel notches (positive: closer)"),
    "view": (1, "a buffer name, or 'output'"),
    "visual": (1, "auto, colour, depth, normal, id, velocity, tiles or scalar"),
    "time": (1, "seconds"),
    "play": (0, "nothing"),
    "pause": (0, "nothing"),
    "speed": (1, "a factor"),
    "shutter": (1, "seconds"),
    "seed": (1, "an integer"),
    "open": (1, "a scene path or built-in name"),
    "animation": (2, "a gltf entry's name and what it plays: all, none, an animation's name "
                     "or index"),
    "reset": (0, "nothing"),
    "fly": (1, "on or off"),
    "panel": (1, "on or off"),
    "overlay": (1, "full, compact or off"),
    "subframes": (1, "sub-frames per displayed frame (progressive modes)"),
    "quit": (0, "nothing"),
}


@dataclass(frozen=True)
class Action:
    frame: int
    name: str
    args: tuple[str, ...]
    where: str                         # file:line or file[index], for error messages

    def fail(self, expected: str):
        raise UserError(f"--script {self.where}: {self.name}: expected {expected}")


def _number(a: Action, text: str, what: str = "a number", lo: float | None = None) -> float:
    from viewer.cli.args import parse_float
    try:
        v = parse_float(a.name, text)
    except UserError:
        a.fail(f"{what}, got {text!r}")
    if lo is not None and v < lo:
        a.fail(f"{what} >= {lo:g}, got {text!r}")
    return v


def _integer(a: Action, text: str, lo: int) -> int:
    if not re.fullmatch(r"[+-]?\d+", text) or int(text) < lo:
        a.fail(f"an integer >= {lo}, got {text!r}")
    return int(text)


def _check_args(a: Action):
    """The action's arguments, checked as far as they can be before the window opens."""
    name, args = a.name, a.args
    if name == "mode":
        from ..render.modes import MODES
        if args[0] not in MODES:
            a.fail(f"one of {', '.join(MODES)}, got {args[0]!r}")
    elif name == "set":
        from viewer.render.graph.params import ParamSet
        from ..render import modes  # noqa: F401  (registers every mode's parameter groups)
        try:
            ParamSet().apply([args[0]])
        except UserError as exc:
            raise UserError(f"--script {a.where}: set {str(exc).removeprefix('--set ')}") from None
    elif name == "key":
        import glfw
        if not isinstance(getattr(glfw, f"KEY_{args[0].upper()}", None), int):
            a.fail(f"a GLFW key name (P, F12, SPACE, W, ...), got {args[0]!r}")
    elif name == "resize":
        from viewer.cli.args import parse_size
        try:
            parse_size(args[0], "resize")
        except UserError:
            a.fail(f"WxH with positive integers, got {args[0]!r}")
    elif name in ("orbit", "pan", "zoom", "time", "speed"):
        for v in args:
            _number(a, v)
    elif name == "shutter":
        _number(a, args[0], "seconds", lo=0.0)
    elif name == "drag":
        if args[0] not in ("left", "right", "middle"):
            a.fail(f"button left, right or middle, got {args[0]!r}")
        for v in args[1:]:
            _number(a, v, "window pixels")
    elif name == "visual":
        from viewer.render.passes.debug_view import KINDS
        if args[0] not in ("auto",) + KINDS:
            a.fail(f"auto or one of {', '.join(KINDS)}, got {args[0]!r}")
    elif name in ("fly", "panel"):
        if args[0] not in ("on", "off"):
            a.fail(f"on or off, got {args[0]!r}")
    elif name == "overlay":
        if args[0] not in ("full", "compact", "off"):
            a.fail(f"full, compact or off, got {args[0]!r}")
    elif name == "seed":
        _integer(a, args[0], 0)
    elif name == "subframes":
        _integer(a, args[0], 1)
    elif name == "open":
        from world.loader import builtin_scene_names
        if not Path(args[0]).is_file() and args[0] not in builtin_scene_names():
            a.fail(f"a scene file or built-in name ({', '.join(builtin_scene_names())}), "
                   f"got {args[0]!r}")


def _check(action: Action) -> Action:
    if action.name not in ACTIONS:
        raise UserError(f"--script {action.where}: unknown action {action.name!r} "
                        f"(known: {', '.join(ACTIONS)})")
    n, what = ACTIONS[action.name]
    if len(action.args) != n:
        action.fail(f"{n} argument(s): {what}")
    _check_args(action)
    return action


def format_help() -> str:
    """The script format, for `hmblur view --help`."""
    width = max(len(n) for n in ACTIONS)
    rows = "\n".join(f"  {n:<{width}}  {what if k else '(no arguments)'}"
                     for n, (k, what) in ACTIONS.items())
    return ("--script FILE: one action per line, 'FRAME ACTION [ARGS]' ('#' starts a "
            "comment), run at the start of frame FRAME (from 0); or a JSON list such as "
            "[{\"frame\": 10, \"mode\": \"hybrid\"}, {\"frame\": 20, \"resize\": "
            "[400, 300]}]. Actions and their arguments:\n" + rows)


def _frame(value, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise UserError(f"--script {where}: expected a frame number >= 0, got {value!r}")
    return value


def parse_text(text: str, source: str) -> list[Action]:
    out = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        words = shlex.split(line, comments=True)
        if not words:
            continue
        where = f"{source}:{lineno}"
        frame = int(words[0]) if re.fullmatch(r"\d+", words[0]) else words[0]
        if len(words) < 2:
            raise UserError(f"--script {where}: expected FRAME ACTION [ARGS...]")
        out.append(_check(Action(_frame(frame, where), words[1], tuple(words[2:]), where)))
    return out


def parse_json(data, source: str) -> list[Action]:
    if not isinstance(data, list):
        raise UserError(f"--script {source}: expected a JSON list of actions")
    out = []
    for i, item in enumerate(data):
        where = f"{source}[{i}]"
        if not isinstance(item, dict) or "frame" not in item or len(item) != 2:
            raise UserError(f"--script {where}: expected {{\"frame\": N, \"ACTION\": ARGS}}")
        frame = _frame(item["frame"], where)
        (name, value), = [(k, v) for k, v in item.items() if k != "frame"]
        if value is None or value == []:
            args = ()
        elif isinstance(value, list):
            args = tuple(str(v) for v in value)
        else:
            args = (str(value),)
        if name == "resize" and len(args) == 2:
            args = (f"{args[0]}x{args[1]}",)
        out.append(_check(Action(frame, name, args, where)))
    return out


MAX_SCRIPT_BYTES = 1 << 20      # a script of actions is a few hundred bytes


def load_script(path: str) -> list[Action]:
    from viewer.cli.args import read_user_file
    p = Path(path)
    raw = read_user_file("--script", path, MAX_SCRIPT_BYTES, "a script")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise UserError(f"--script {path}: not UTF-8 text") from None
    if text.lstrip().startswith("["):
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise UserError(f"--script {path}: not JSON ({exc.msg} at line {exc.lineno})") from None
        except (RecursionError, ValueError) as exc:
            raise UserError(f"--script {path}: not a script's JSON ({exc.__class__.__name__})") from None
        actions = parse_json(data, p.name)
    else:
        actions = parse_text(text, p.name)
    return sorted(actions, key=lambda a: a.frame)     # stable: same-frame order kept


class Timeline:
    """Script actions and the input events they expand to, by frame."""

    def __init__(self, actions: list[Action] = ()):
        self._due: dict[int, list] = {}
        for a in actions:
            self.at(a.frame, a)

    def at(self, frame: int, item):
        self._due.setdefault(frame, []).append(item)

    def due(self, frame: int) -> list:
        return self._due.pop(frame, [])
