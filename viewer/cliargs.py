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
from .scene_loader import load_scene


def add_scene_args(p, samples: bool = True):
    p.add_argument("scene", help="scene file (.toml) or built-in scene name")
    p.add_argument("--time", type=str, default=None, help="frame time in seconds (scene default)")
    p.add_argument("--size", type=str, default=None, help="WxH (scene default, e.g. 1280x720)")
    if samples:
        p.add_argument("--samples", type=str, default=None,
                       help="reference sub-frames (default 64; = --set reference.samples=N)")
    p.add_argument("--seed", type=str, default="0", help="seed of every jitter (default 0)")
    p.add_argument("--set", action="append", default=[], metavar="GROUP.FIELD=VALUE",
                   help="set a parameter (repeatable)")
    p.add_argument("--params", type=str, default=None,
                   help="JSON sidecar of an earlier image: reproduce its parameters, time and size")


def parse_size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text or "")
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise UserError(f"--size {text!r}: expected WIDTHxHEIGHT with positive integers, e.g. 640x360")
    return int(m.group(1)), int(m.group(2))


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
    try:
        data = json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise UserError(f"--params {path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"--params {path}: cannot read ({exc.__class__.__name__})") from None
    except json.JSONDecodeError as exc:
        raise UserError(f"--params {path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(data, dict):
        raise UserError(f"--params {path}: expected a JSON object")
    return data


CAMERA_VECTORS = ("position", "look_at", "up", "velocity", "angular_velocity")
CAMERA_NUMBERS = ("fov_y", "near", "far", "shutter")


def apply_camera(scene: Scene, data, source: str):
    """Override the scene's camera with a sidecar's (the viewer may have moved it)."""
    import numpy as np
    if not isinstance(data, dict):
        raise UserError(f"{source}: camera: expected a table")
    cam = scene.camera
    for key, value in data.items():
        if key in CAMERA_VECTORS:
            try:
                v = np.asarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                v = None
            if v is None or v.shape != (3,) or not np.all(np.isfinite(v)):
                raise UserError(f"{source}: camera.{key}: expected 3 finite numbers")
            setattr(cam, key, v)
        elif key in CAMERA_NUMBERS:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise UserError(f"{source}: camera.{key}: expected a finite number")
            setattr(cam, key, float(value))
        else:
            raise UserError(f"{source}: camera.{key}: unknown key")


def setup(args) -> Setup:
    params = ParamSet()
    side = read_sidecar(args.params) if getattr(args, "params", None) else None
    scene = load_scene(args.scene)
    size = (scene.render.width, scene.render.height)
    t = scene.render.time
    seed = 0
    if side is not None:
        params.update(side.get("params", {}), source=f"--params {args.params}")
        if "camera" in side:
            apply_camera(scene, side["camera"], f"--params {args.params}")
        if "size" in side:
            size = parse_size("x".join(str(x) for x in side["size"]))
        if "time" in side:
            t = parse_float("--params time", str(side["time"]))
        seed = parse_int("--params seed", str(side.get("seed", 0)), 0)
    if args.size is not None:
        size = parse_size(args.size)
    if args.time is not None:
        t = parse_float("--time", args.time)
    if args.seed != "0" or side is None:
        seed = parse_int("--seed", args.seed, 0)
    if getattr(args, "samples", None) is not None:
        params.set("reference.samples", str(parse_int("--samples", args.samples, 1)))
    params.apply(args.set)
    return Setup(scene, size, t, params, seed, side)


def check_output_file(path: str, flag: str = "--out") -> Path:
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if p.is_dir():
        raise UserError(f"{flag} {path}: is a directory, expected a file path")
    if not parent.is_dir():
        raise UserError(f"{flag} {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"{flag} {path}: folder {parent} is not writable")
    return p


def check_output_dir(path: str, flag: str, create: bool = True) -> Path:
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise UserError(f"{flag} {path}: exists and is not a folder")
    if not p.exists():
        if not create or not p.parent.is_dir():
            raise UserError(f"{flag} {path}: folder {p.parent} does not exist")
        if not os.access(p.parent, os.W_OK):
            raise UserError(f"{flag} {path}: folder {p.parent} is not writable")
        p.mkdir()
    if not os.access(p, os.W_OK):
        raise UserError(f"{flag} {path}: folder is not writable")
    return p
