"""Where a file a scene names (a mesh, an image texture, a glTF asset and its buffers and
images) may live, in one rule (docs/scene-format.md, "Asset files"): checked before the
file is opened, every mistake a SceneError naming the key."""
from __future__ import annotations

import os
import stat
from pathlib import Path

import scenes

from world.errors import SceneError


def builtin_assets() -> Path:
    """The assets that come with the program (scenes/assets)."""
    return Path(os.path.realpath(Path(scenes.__file__).parent / "assets"))


def allowed_roots(scene_path) -> tuple[Path, Path]:
    """The folders a scene file may name files in (real paths): its own folder and the
    built-in assets."""
    return (Path(os.path.realpath(Path(scene_path).parent)), builtin_assets())


def within(real: Path, root: Path) -> bool:
    """Whether the real path `real` is `root` or lies below it."""
    return real == root or root in real.parents


def asset_file(scene_path, rel, key: str, what: str, max_bytes: int, base=None) -> Path:
    """The file `rel` names, as its real path (symlinks resolved): relative to `base` (the
    scene file's folder by default; a glTF file's folder for its buffers and images), or
    absolute. It must resolve inside the scene file's folder (or below it) or inside the
    built-in assets, be a regular file (not a device, FIFO or folder) and hold at most
    `max_bytes`. Errors name the scene file `scene_path` and `key`."""
    scene_path = Path(scene_path)

    def fail(expected: str):
        raise SceneError(scene_path, key, expected)

    if not isinstance(rel, str) or not rel or "\0" in rel:
        fail(f"expected the path of a {what} file, got {rel!r}")
    folder = Path(base) if base is not None else scene_path.parent
    real = Path(os.path.realpath(folder / rel))
    roots = allowed_roots(scene_path)
    if not any(within(real, r) for r in roots):
        fail(f"{what} file {rel} resolves to {real}, outside the scene file's folder "
             f"{roots[0]} and the built-in assets: a scene names files in its own folder "
             "or below it")
    try:
        st = os.stat(real)
    except FileNotFoundError:
        fail(f"{what} file not found: {real}")
    except OSError as e:
        fail(f"{what} file {real} cannot be read ({e.strerror or e})")
    if not stat.S_ISREG(st.st_mode):
        fail(f"{what} file {real} is not a regular file (a folder, device or FIFO)")
    if st.st_size > max_bytes:
        fail(f"{what} file {real} holds {st.st_size} bytes, more than the {max_bytes} "
             "a scene may load")
    return real
