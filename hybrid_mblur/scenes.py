"""Scenes for the API: a scene file (.toml), a built-in name or a bare glTF asset, loaded
as `hmblur` loads them (viewer/cli/args.py: the same checks, the same one-line errors)."""
from __future__ import annotations

from os import PathLike

from world.loader import builtin_scene_names
from world.scene import Scene
from viewer.cli.args import load

__all__ = ["Scene", "load_scene", "builtin_scenes"]


def load_scene(source: str | PathLike, animations: dict | None = None) -> Scene:
    """The scene `source` names: a scene file (.toml, docs/scene-format.md), a glTF asset
    (.gltf, .glb: framed, lit and played) or a built-in name (builtin_scenes()).
    `animations`: {gltf entry name: "all", "none", an animation's name or index}. A mistake
    raises world.errors.UserError, whose text names the file and the key."""
    return load(str(source), animations)


def builtin_scenes() -> list[str]:
    """The names of the scenes that come with the program."""
    return list(builtin_scene_names())
