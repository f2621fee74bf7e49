"""Arguments shared by the subcommands, and turning them into a scene, size, time and
parameters (every mistake a one-line UserError)."""
from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

from .errors import UserError
from .params import ParamSet
from .scene import Scene
from .scene_loader import load_scene, merge_camera


def add_scene_args(p, samples: bool = True):
    p.add_argument("scene", help="scene file (.toml) or built-in scene name")
    p.add_argument("--time", type=str, default=None, help="frame time in seconds (scene default)")
    p.add_argument("--size", type=str, default=None, help="WxH (scene default, e.g. 1280x720)")
    if samples:
        p.add_argument("--samples", type=str, default=None,
                       help="reference sub-frames (default 64; = --set reference.samples=N)")
    p.add_argument("--seed", type=str, default=None,
                   help="seed of every jitter (default 0, or the --params file's)")
    p.add_argument("--set", action="append", default=[], metavar="GROUP.FIELD=VALUE",
                   help="set a parameter (repeatable)")
    p.add_argument("--params", type=str, default=None,
                   help="JSON sidecar of an earlier image: reproduce its parameters, time and size")


def parse_size(text: str, flag: str = "--size") -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text or "")
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise UserError(f"{flag} {text!r}: expected WIDTHxHEIGHT with positive integers, e.g. 640x360")
    return int(m.group(1)), int(m.group(2))


# The largest |frame time| taken, seconds: past it the float32 transforms of p + v t lose
# every digit of a frame's motion (and far past it overflow).
MAX_TIME = 1e6


def parse_time(flag: str, text: str) -> float:
    t = parse_float(flag, text)
    if abs(t) > MAX_TIME:
        raise UserError(f"{flag} {text!r}: expected seconds within +-{MAX_TIME:g}")
    return t


def parse_float(flag: str, text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise UserError(f"{flag} {text!r}: expected a number") from None
    if not math.isfinite(v):
        raise UserError(f"{flag} {text!r}: expected a finite number")
    return v


def parse_int(flag: str, text: str, lo: int) -> int:
    try:
        v = int(text)
    except ValueError:
        raise UserError(f"{flag} {text!r}: expected an integer") from None
    if v < lo:
        raise UserError(f"{flag} {text!r}: expected an integer >= {lo}")
    return v


@dataclass
class Setup:
    scene: Scene
    size: tuple[int, int]
    time: float
    params: ParamSet
    seed: int
    sidecar: dict | None = None


def read_sidecar(path: str) -> dict:
    """An earlier output's JSON (an image's sidecar, compare's metrics.json, a bench
    report): anything with a table of parameters."""
    try:
        data = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise UserError(f"--params {path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"--params {path}: cannot read ({exc.__class__.__name__})") from None
    except json.JSONDecodeError as exc:
        raise UserError(f"--params {path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(data, dict) or not isinstance(data.get("params"), dict):
        raise UserError(f"--params {path}: expected the JSON sidecar of an hmblur image "
                        "(an object with a \"params\" table)")
    return data


def apply_camera(scene: Scene, data, source: str):
    """Override the scene's camera with a sidecar's (the viewer may have moved it), checked
    as the scene file's camera is (scene_loader.merge_camera)."""
    if not isinstance(data, dict):
        raise UserError(f"{source}: camera: expected a table")
    scene.camera = merge_camera(scene.camera, data, source)


def sidecar_size(value, source: str) -> tuple[int, int]:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(x, int) and not isinstance(x, bool) and x >= 1 for x in value)):
        raise UserError(f"{source}: size: expected [width, height], positive integers, "
                        f"got {value!r}")
    return value[0], value[1]


def setup(args) -> Setup:
    params = ParamSet()
    side = read_sidecar(args.params) if getattr(args, "params", None) else None
    scene = load_scene(args.scene)
    size = (scene.render.width, scene.render.height)
    t = scene.render.time
    seed = 0
    if side is not None:
        src = f"--params {args.params}"
        made_for = side.get("scene_name", side.get("scene"))
        if isinstance(made_for, str) and made_for not in (scene.name, args.scene):
            raise UserError(f"{src}: made for scene {made_for!r}, not {scene.name!r}")
        params.update(side["params"], source=src)
        if "camera" in side:
            apply_camera(scene, side["camera"], src)
        if "size" in side:
            size = sidecar_size(side["size"], src)
        if "time" in side:
            t = parse_time(f"{src}: time", str(side["time"]))
        seed = parse_int(f"{src}: seed", str(side.get("seed", 0)), 0)
    if args.size is not None:
        size = parse_size(args.size)
    if args.time is not None:
        t = parse_time("--time", args.time)
    if args.seed is not None:
        seed = parse_int("--seed", args.seed, 0)
    if getattr(args, "samples", None) is not None:
        params.set("reference.samples", str(parse_int("--samples", args.samples, 1)),
                   label="--samples")
    params.apply(args.set)
    return Setup(scene, size, t, params, seed, side)


def parse_modes(flag: str, text: str, available: list[str]) -> list[str]:
    """A comma-separated list of modes, each of `available`, at least one, none twice."""
    modes = [m.strip() for m in text.split(",") if m.strip()]
    if not modes:
        raise UserError(f"{flag} {text!r}: expected one or more of {', '.join(available)}")
    for m in modes:
        if m not in available:
            raise UserError(f"{flag} {text}: {m!r} is not one of {', '.join(available)}")
        if modes.count(m) > 1:
            raise UserError(f"{flag} {text}: {m!r} is listed twice")
    return modes


def check_output_file(path: str, flag: str = "--out") -> Path:
    """A file path that can be written: not a folder, not a device or pipe (renaming over
    one would replace it), in a folder that exists."""
    if not path:
        raise UserError(f"{flag} '': expected a file path")
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if p.is_dir() or path.endswith(("/", os.sep)):
        raise UserError(f"{flag} {path}: is a directory, expected a file path")
    if p.exists() and not p.is_file():
        raise UserError(f"{flag} {path}: exists and is not a regular file")
    if parent.exists() and not parent.is_dir():
        raise UserError(f"{flag} {path}: {parent} is not a folder")
    if not parent.is_dir():
        raise UserError(f"{flag} {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"{flag} {path}: folder {parent} is not writable")
    return p


def check_output_dir(path: str, flag: str, create: bool = True) -> Path:
    """A folder to write into: an existing one, or with `create` one whose parent exists
    (made only when the outputs are written: imageio.OutputSet)."""
    if not path:
        raise UserError(f"{flag} '': expected a folder path")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise UserError(f"{flag} {path}: exists and is not a folder")
    if not p.exists():
        if not create:
            raise UserError(f"{flag} {path}: folder does not exist")
        if not p.parent.is_dir():
            raise UserError(f"{flag} {path}: folder {p.parent} does not exist")
        if not os.access(p.parent, os.W_OK):
            raise UserError(f"{flag} {path}: folder {p.parent} is not writable")
        return p
    if not os.access(p, os.W_OK):
        raise UserError(f"{flag} {path}: folder is not writable")
    return p
