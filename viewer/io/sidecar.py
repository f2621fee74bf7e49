"""The JSON sidecar written beside every image and video: what reproduces it (scene,
mode, time, size, seed, parameters, camera), where it was made (device, version) and the
frame's counters. `hmblur shot`, `video`, the viewer's captures and recordings and the
sweep's cells all write it from here."""
from __future__ import annotations

from pathlib import Path

from viewer.cli import args as cliargs
from viewer.glcontext import device_name
from viewer.render.modes import MODE_GROUPS

FIRST_FRAME_NOTE = ("the times and *_ms counters in stats are those of the first frame of a "
                    "fresh renderer: shader compiles, texture allocation and the ray "
                    "tracer's scene build are included; 'hmblur bench' reports warm medians")


def version() -> str:
    """The project's version: pyproject.toml at the top of a source checkout, else the
    installed distribution's."""
    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    try:
        import tomllib
        return tomllib.loads(pyproject.read_text())["project"]["version"]
    except (OSError, KeyError, ValueError):
        from importlib.metadata import PackageNotFoundError, version as dist_version
        try:
            return dist_version("hybrid-mblur")
        except PackageNotFoundError:
            return "unknown"


def camera_dict(spec) -> dict:
    return spec.to_dict()


def sidecar(s: cliargs.Setup, mode: str, result, ctx, scene_arg: str,
            first_frame: bool = False, ms: float | None = None,
            groups: tuple[str, ...] | None = None) -> dict:
    """The JSON beside an image. `first_frame`: the stats are a fresh renderer's first
    frame (set-up costs included), said so in "timing"; `ms`: the render's wall time;
    `groups`: the parameter groups written (default: the mode's; a user pass's own)."""
    timing = {"first_frame": first_frame}
    if first_frame:
        timing["note"] = FIRST_FRAME_NOTE
    if ms is not None:
        timing["render_ms"] = ms
    return {
        **cliargs.scene_source(scene_arg),
        **({"animations": dict(s.animations)} if s.animations else {}),
        "scene_name": s.scene.name,
        "mode": mode,
        "time": s.time,
        "size": list(s.size),
        "seed": s.seed,
        "params": s.params.to_dict(MODE_GROUPS.get(mode, ()) if groups is None else groups),
        "camera": camera_dict(s.scene.camera),
        "device": device_name(ctx),
        "stats": result.stats,
        "timing": timing,
    }
