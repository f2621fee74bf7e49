"""Arguments shared by the subcommands, and turning them into a scene, size, time and
parameters (every mistake a one-line UserError)."""
from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

from world import limits
from world.errors import SceneError, UserError
from world.regular_file import Grew, NotRegular, TooLarge, read_regular
from viewer.render.graph.params import ParamSet
from world.scene import Scene
from world.loader import (builtin_dir, builtin_scene_names, builtin_scene_path,
                           load_scene, merge_camera)

# Scene files beside the built-in ones that are not built-in names: the bench scenes, the
# examples and (in a source checkout) the conformance scenes.
OTHER_SCENE_DIRS = ("bench", "examples", "../tests/conformance")


def other_scene(name: str) -> Path | None:
    """The file a scene name that is not built-in most likely means, if there is one."""
    for folder in OTHER_SCENE_DIRS:
        path = (builtin_dir() / folder / f"{name}.toml").resolve()
        if path.is_file():
            return path
    return None


def load(source: str, animations: dict | None = None):
    """load_scene, with the file named when `source` is the name of a bench, example or
    conformance scene rather than a built-in one."""
    try:
        return load_scene(source, animations)
    except SceneError as exc:
        path = None if Path(source).exists() or source.endswith(".toml") else other_scene(source)
        if path is None:
            raise
        try:
            shown = path.relative_to(Path.cwd())
        except ValueError:
            shown = path
        raise UserError(f"{exc}; {source!r} is the scene file {shown}") from None


# What every render command (shot, compare, bench, video, view) takes, beside its own
# flags; bench renders no reference, so it takes no --samples (docs: README, "Commands").
SCENE_FLAGS = ("--time", "--size", "--samples", "--seed", "--shutter", "--set", "--params")


def add_scene_args(p, samples: bool = True, scene_help: str | None = None,
                   time_help: str = "frame time in seconds (default: the scene's [render] "
                                    "time)", time_aliases: tuple = ()):
    p.add_argument("scene", nargs="?", default=None, metavar="SCENE",
                   help=scene_help or "scene file (.toml), glTF asset (.gltf, .glb) or built-in "
                        "scene name; may be left out with --params (the sidecar's scene)")
    p.add_argument("--time", *time_aliases, dest="time", type=str, default=None, metavar="T",
                   help=time_help)
    p.add_argument("--size", type=str, default=None, metavar="WxH",
                   help="image size (default: the scene's [render] size, else 1280x720)")
    if samples:
        p.add_argument("--samples", type=str, default=None, metavar="N",
                       help="reference sub-frames (default 64; = --set reference.samples=N)")
    p.add_argument("--seed", type=str, default=None, metavar="N",
                   help="seed of every jitter (default 0, or the --params file's)")
    p.add_argument("--shutter", type=str, default=None, metavar="S",
                   help="exposure time in seconds, replacing the scene camera's (and the "
                        "--params file's)")
    p.add_argument("--set", action="append", default=[], metavar="GROUP.FIELD=VALUE",
                   help="set a parameter (repeatable; 'hmblur params' lists them)")
    p.add_argument("--params", type=str, default=None, metavar="FILE.json",
                   help="JSON sidecar of an earlier output: reproduce its scene, parameters, "
                        "time, size, seed and camera (flags given beside it win)")


def check_shutter_read(shutter: str | None, modes, what: str = ""):
    """--shutter where every mode rendered is `off` (the sharp frame at t, no exposure)
    would change nothing: one line."""
    if shutter is not None and modes and all(m == "off" for m in modes):
        raise UserError(f"--shutter {shutter}: mode off draws the sharp frame at the frame "
                        f"time, with no exposure{what}")


def check_samples_read(samples: str | None, modes, what: str = ""):
    """--samples where the reference is not rendered would change nothing: one line."""
    if samples is not None and "reference" not in modes:
        which = f"mode {modes[0]}" if len(modes) == 1 else "modes " + ", ".join(modes)
        raise UserError(f"--samples {samples}: only the reference mode takes sub-frames, "
                        f"not {which}{what}")


def scene_source(arg: str) -> dict:
    """Where a scene came from, for a sidecar: the file's absolute path (so `--params`
    finds it from any folder) and, for a built-in scene, its name."""
    path = Path(arg)
    if not path.is_file() and not arg.endswith(".toml") and arg in builtin_scene_names():
        return {"scene": str(builtin_scene_path(arg)), "scene_builtin": arg}
    return {"scene": str(path.resolve())}


def sidecar_scene(side: dict, params_path: str) -> str:
    """The scene an earlier output was made from (SCENE left out beside --params): its
    built-in name, else its path (absolute; an older relative one is tried from the
    current folder, then from the sidecar's)."""
    src = f"--params {params_path}"
    name = side.get("scene_builtin")
    if isinstance(name, str) and name in builtin_scene_names():
        return name
    path = side.get("scene")
    if not isinstance(path, str) or not path:
        raise UserError(f"{src}: names no scene: give SCENE")
    for candidate in (Path(path), Path(params_path).parent / path):
        if candidate.is_file():
            return str(candidate)
    if path in builtin_scene_names():         # a sidecar that stored the name only
        return path
    raise UserError(f"{src}: its scene {path} is not found: give SCENE")


def check_set_groups(assignments: list[str], modes, mode_groups: dict, flag: str = "--set"):
    """A `--set` for a parameter group none of the rendered `modes` reads is a mistake (it
    would change nothing): one line naming the modes that do read it."""
    used = {g for m in modes for g in mode_groups.get(m, ())}
    for text in assignments:
        group = text.partition("=")[0].strip().partition(".")[0]
        if group not in used:
            readers = [m for m, gs in mode_groups.items() if group in gs]
            which = f"mode {modes[0]}" if len(modes) == 1 else "modes " + ", ".join(modes)
            raise UserError(f"{flag} {text}: {which} does not use the {group} parameters "
                            f"(used by {', '.join(readers) or 'no mode'})")


def parse_size(text: str, flag: str = "--size") -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d{1,9})\s*[xX]\s*(\d{1,9})\s*", text or "")
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise UserError(f"{flag} {text!r}: expected WIDTHxHEIGHT with positive integers, e.g. 640x360")
    return check_size(int(m.group(1)), int(m.group(2)), f"{flag} {text!r}")


def check_size(w: int, h: int, where: str) -> tuple[int, int]:
    """An image size within limits.MAX_FRAME_SIZE a side and MAX_FRAME_PIXELS in all."""
    if max(w, h) > limits.MAX_FRAME_SIZE or w * h > limits.MAX_FRAME_PIXELS:
        raise UserError(f"{where}: {w}x{h} is too large: at most {limits.MAX_FRAME_SIZE} px "
                        f"a side and {limits.MAX_FRAME_PIXELS} pixels (e.g. 2560x1600)")
    return w, h


MAX_TIME = limits.MAX_TIME


def parse_time(flag: str, text: str) -> float:
    t = parse_float(flag, text)
    if abs(t) > MAX_TIME:
        raise UserError(f"{flag} {text!r}: expected seconds within +-{MAX_TIME:g}")
    return t


def parse_float(flag: str, text: str) -> float:
    try:
        v = float(text)
    except (ValueError, OverflowError):
        raise UserError(f"{flag} {text!r}: expected a number") from None
    if not math.isfinite(v):
        raise UserError(f"{flag} {text!r}: expected a finite number")
    return v


def parse_int(flag: str, text: str, lo: int, hi: int | None = None) -> int:
    text = str(text)
    if len(text) > 40:                     # (int() of thousands of digits is slow, or refused)
        raise UserError(f"{flag} {text[:20]!r}...: expected an integer of at most 40 characters")
    try:
        v = int(text)
    except ValueError:
        raise UserError(f"{flag} {text!r}: expected an integer") from None
    if v < lo:
        raise UserError(f"{flag} {text!r}: expected an integer >= {lo}")
    if hi is not None and v > hi:
        raise UserError(f"{flag} {text!r}: expected an integer from {lo} to {hi}")
    return v


def parse_fps(flag: str, text: str) -> float:
    """Frames per second within limits.MIN_FPS..MAX_FPS."""
    v = parse_float(flag, text)
    if not limits.MIN_FPS <= v <= limits.MAX_FPS:
        raise UserError(f"{flag} {text!r}: expected frames per second from "
                        f"{limits.MIN_FPS:g} to {limits.MAX_FPS:g}")
    return v


def parse_seed(flag: str, text: str) -> int:
    return parse_int(flag, text, 0, limits.MAX_SEED)


def shutter_expected(s: float) -> str | None:
    """What is wrong with `s` as an exposure time (the bound a scene file's camera.shutter
    has: a scene number >= 0), or None: one rule for --shutter and a sweep's shutters."""
    if not 0 <= s <= limits.MAX_SHUTTER:
        return f"expected an exposure time from 0 to {limits.MAX_SHUTTER:g} s"
    return None


def parse_shutter(flag: str, text: str) -> float:
    """An exposure time in seconds, within the bounds a scene file's camera.shutter has."""
    s = parse_float(flag, text)
    expected = shutter_expected(s)
    if expected:
        raise UserError(f"{flag} {text!r}: {expected}")
    return s


@dataclass
class Setup:
    scene: Scene
    size: tuple[int, int]
    time: float
    params: ParamSet
    seed: int
    sidecar: dict | None = None
    animations: dict | None = None     # {gltf entry: animation} chosen in the viewer


def read_sidecar(path: str) -> dict:
    """An earlier output's JSON (an image's sidecar, compare's metrics.json, a bench
    report): anything with a table of parameters. A regular file of at most
    limits.MAX_PARAMS_BYTES, checked before reading (not a device, FIFO or folder)."""
    raw = read_user_file("--params", path, limits.MAX_PARAMS_BYTES, "a sidecar")
    try:
        data = json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError:
        raise UserError(f"--params {path}: not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise UserError(f"--params {path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    except RecursionError:
        raise UserError(f"--params {path}: JSON nested too deeply to be a sidecar") from None
    except ValueError as exc:               # an integer of more digits than Python converts
        raise UserError(f"--params {path}: not a sidecar's JSON ({exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("params"), dict):
        raise UserError(f"--params {path}: expected the JSON sidecar of an hmblur image "
                        "(an object with a \"params\" table)")
    return data


def apply_camera(scene: Scene, data, source: str):
    """Override the scene's camera with a sidecar's (the viewer may have moved it), checked
    as the scene file's camera is (world.loader.merge_camera)."""
    if not isinstance(data, dict):
        raise UserError(f"{source}: camera: expected a table")
    scene.camera = merge_camera(scene.camera, data, source)


def sidecar_size(value, source: str) -> tuple[int, int]:
    if (not isinstance(value, list) or len(value) != 2
            or not all(isinstance(x, int) and not isinstance(x, bool) and x >= 1 for x in value)):
        raise UserError(f"{source}: size: expected [width, height], positive integers, "
                        f"got {str(value)[:60]}")
    return check_size(value[0], value[1], f"{source}: size")


def read_user_file(flag: str, path: str, max_bytes: int, what: str) -> bytes:
    """The bytes of a file a flag names: a regular file (not a device, FIFO or folder,
    refused before any read) of at most `max_bytes`; else one line naming the flag."""
    try:
        return read_regular(path, max_bytes)
    except FileNotFoundError:
        raise UserError(f"{flag} {path}: file not found") from None
    except NotRegular as exc:
        raise UserError(f"{flag} {path}: {exc}") from None
    except (TooLarge, Grew):
        raise UserError(f"{flag} {path}: larger than {max_bytes} bytes: not {what}") from None
    except (OSError, ValueError) as exc:
        raise UserError(f"{flag} {path}: cannot read "
                        f"({getattr(exc, 'strerror', None) or exc.__class__.__name__})") from None


def setup(args) -> Setup:
    params = ParamSet()
    side = read_sidecar(args.params) if getattr(args, "params", None) else None
    if args.scene is None:
        if side is None:
            raise UserError("SCENE: expected a scene file (.toml), a glTF asset (.gltf, .glb) "
                            "or a built-in name ("
                            + ", ".join(builtin_scene_names()) + "), or --params FILE.json")
        args.scene = sidecar_scene(side, args.params)
    animations = None
    if side is not None and "animations" in side:
        animations = sidecar_animations(side["animations"], f"--params {args.params}")
    try:
        scene = load(args.scene, animations)
    except SceneError as exc:
        if animations is None:
            raise
        load(args.scene)                   # (the scene's own mistake, named as such)
        raise UserError(f"--params {args.params}: animations: {exc}") from None
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
        seed = parse_seed(f"{src}: seed", str(side.get("seed", 0)))
    if args.size is not None:
        size = parse_size(args.size)
    if args.time is not None:
        t = parse_time("--time", args.time)
    if args.seed is not None:
        seed = parse_seed("--seed", args.seed)
    if getattr(args, "shutter", None) is not None:
        scene.camera.shutter = parse_shutter("--shutter", args.shutter)
    if getattr(args, "samples", None) is not None:
        params.set("reference.samples", str(parse_int("--samples", args.samples, 1)),
                   label="--samples")
    params.apply(args.set)
    return Setup(scene, size, t, params, seed, side, animations)


def sidecar_animations(value, source: str) -> dict:
    """A sidecar's "animations" (the viewer's choice per gltf entry): a table of entry
    names to "all", "none", an animation's name or index; what they name is checked when
    the scene loads."""
    if (not isinstance(value, dict) or len(value) > limits.MAX_OBJECTS
            or not all(isinstance(v, (str, int)) and not isinstance(v, bool)
                       for v in value.values())):
        raise UserError(f"{source}: animations: expected a table of gltf entry names to "
                        "\"all\", \"none\", an animation's name or index")
    return value


# What `shot` and `view` render when no mode is given: the blur this project is about.
DEFAULT_MODE = "hybrid"


def add_mode_arg(p, modes, user: bool = False):
    """--mode, for a command that renders one of `modes` (shot, view); `user`: or a user's
    blur pass (docs/api.md)."""
    p.add_argument("--mode", default=None,
                   help=f"one of: {', '.join(modes)}"
                        + (", or a user's blur pass glsl:PATH or py:PATH:FUNCTION "
                           "(docs/api.md)" if user else "")
                        + f" (default: {DEFAULT_MODE}, or the --params file's)")


def pick_mode(flag: str | None, sidecar: dict | None, modes) -> str:
    """--mode, else the --params file's mode, else DEFAULT_MODE: one of `modes`."""
    mode = flag if flag is not None else (sidecar or {}).get("mode")
    mode = str(mode) if mode is not None else DEFAULT_MODE
    if mode not in modes:
        raise UserError(f"--mode {mode}: expected one of {', '.join(modes)}")
    return mode


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


def _existing_ancestor(p: Path) -> Path:
    """The nearest folder above `p` (or `p` itself) that exists: where missing folders
    would be made."""
    p = p.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def _check_can_make(folder: Path, flag: str, path: str):
    """`folder` exists and is writable, or can be made (with its missing parents)."""
    base = _existing_ancestor(folder)
    if not base.is_dir():
        raise UserError(f"{flag} {path}: {base} is not a folder")
    if not os.access(base, os.W_OK):
        raise UserError(f"{flag} {path}: folder {base} is not writable")


def check_output_file(path: str, flag: str = "--out", suffix: str | None = None) -> Path:
    """A file path that can be written: not a folder, not a device or pipe (renaming over
    one would replace it), in a folder that exists or can be made (missing folders are
    made when the outputs are written: imageio.OutputSet). `suffix`: the one extension
    accepted (".png": only PNG is written, and `x.png` -> `x.json` then never collides)."""
    if not path:
        raise UserError(f"{flag} '': expected a file path")
    p = Path(path)
    if p.is_dir() or path.endswith(("/", os.sep)):
        raise UserError(f"{flag} {path}: is a directory, expected a file path")
    if suffix is not None and p.suffix != suffix:
        raise UserError(f"{flag} {path}: expected a path ending in {suffix} "
                        f"(only {suffix[1:].upper()} is written)")
    if p.exists() and not p.is_file():
        raise UserError(f"{flag} {path}: exists and is not a regular file")
    _check_can_make(p.parent if str(p.parent) else Path("."), flag, path)
    return p


def check_output_dir(path: str, flag: str, create: bool = True) -> Path:
    """A folder to write into: an existing one, or with `create` one that can be made with
    its missing parents (made only when the outputs are written: imageio.OutputSet)."""
    if not path:
        raise UserError(f"{flag} '': expected a folder path")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise UserError(f"{flag} {path}: exists and is not a folder")
    if not p.exists():
        if not create:
            raise UserError(f"{flag} {path}: folder does not exist")
        _check_can_make(p, flag, path)
        return p
    if not os.access(p, os.W_OK):
        raise UserError(f"{flag} {path}: folder is not writable")
    return p
