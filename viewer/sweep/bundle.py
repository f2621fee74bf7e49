"""A scene file and every file it references, as bytes, so that a worker without the
sweep's disk can rebuild them in a folder of its own and load the scene from there.

References are found by reading the TOML (scene format v1.2; a bare .gltf/.glb scene is
its own asset): `mesh = "file"`, image textures' `path`, glTF entries' `gltf = "file"`;
inside those, an OBJ's `mtllib` and the material's texture maps, a .gltf's external `uri`s
(buffers, images) and a .glb's JSON chunk's. Each one passes the loader's asset-file rule
(world/assets.py, asset_file: inside the scene's folder or the built-in assets, a regular
file, within its size limit) before it is opened, and is read through a descriptor that is
checked again (a file swapped for a FIFO after the check cannot make a read hang). The
bytes of every bundle of a sweep together stay within limits.MAX_SWEEP_BYTES, counted
before each file is read. A reference that breaks the rule makes the bundle's `error` (the
loader's own words): the scene's cells are error rows, and no worker receives it. A
reference that names no file is left out: the worker's loader reports it.

Everything sits under the common folder of the files, so every relative path resolves
after the rebuild as before. A worker writes its copies under its temp dir, in the
sweep's own folder (`hmblur-sweep-RUN`), which the sweep removes when it ends.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import struct
import tempfile
import tomllib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from urllib.parse import unquote, urlsplit

from world import limits
from world.assets import asset_file
from world.errors import SceneError, UserError
from world.regular_file import Grew, NotRegular, TooLarge, read_regular

COPIES_PREFIX = "hmblur-sweep-"
MAX_GLTF_BYTES = limits.MAX_GLTF_FILE_BYTES


@dataclass(frozen=True)
class Bundle:
    entry: str                 # the scene file, relative to the bundle's root
    files: tuple               # ((relative path, bytes), ...) sorted by path
    origin: str                # the root folder on the machine that made it (for messages)
    error: str | None = None   # why the scene cannot be sent (then `files` is empty)

    @cached_property
    def digest(self) -> str:
        """sha256 over every path and its bytes: what a cell's result depends on."""
        h = hashlib.sha256()
        for rel, data in self.files:
            h.update(rel.encode() + b"\0" + len(data).to_bytes(8, "little") + data)
        h.update(b"entry\0" + self.entry.encode())
        if self.error is not None:
            h.update(b"error\0" + self.error.encode())
        return h.hexdigest()

    @property
    def size(self) -> int:
        return sum(len(data) for _, data in self.files)


class Budget:
    """The bytes the bundles of one sweep may hold together (limits.MAX_SWEEP_BYTES)."""

    def __init__(self, where: str, limit: int = limits.MAX_SWEEP_BYTES):
        self.where, self.limit, self.used = where, limit, 0

    def take(self, n: int, path: Path):
        if self.used + n > self.limit:
            raise UserError(f"{self.where}: the scene files and the files they name come to "
                            f"more than the {self.limit >> 20} MiB a sweep sends to its "
                            f"workers (at {path}, {n} bytes): sweep fewer or smaller scenes")
        self.used += n


def scene_bundle(scene: Path, budget: Budget | None = None) -> Bundle:
    scene = Path(os.path.realpath(scene))
    budget = budget or Budget(str(scene))
    found: dict[Path, bytes] = {}
    bare = scene.suffix.lower() in (".gltf", ".glb")
    try:
        cap = MAX_GLTF_BYTES if bare else limits.MAX_SCENE_BYTES
        found[scene] = _read(scene, cap, budget, lambda e: SceneError(scene, "", e))
        if bare:
            _add_gltf(found, scene, scene, "", budget)
        else:
            for key, rel, what in scene_references(found[scene]):
                cap = limits.MAX_IMAGE_BYTES if what == "image" else limits.MAX_MESH_BYTES
                real = asset_file(scene, rel, key, what, cap)
                if real in found:
                    continue
                found[real] = _read(real, cap, budget, lambda e, k=key: SceneError(scene, k, e))
                if what == "glTF":
                    _add_gltf(found, scene, real, key, budget)
                elif what == "mesh" and real.suffix.lower() == ".obj":
                    _add_obj(found, scene, real, key, budget)
    except SceneError as exc:
        return Bundle(scene.name, (), str(scene.parent), str(exc))
    root = Path(os.path.commonpath([str(p.parent) for p in found]))
    files = tuple(sorted((str(p.relative_to(root)), data) for p, data in found.items()))
    return Bundle(str(scene.relative_to(root)), files, str(root))


def _read(real: Path, cap: int, budget: Budget, error) -> bytes:
    """The bytes of a file asset_file accepted, through a descriptor opened without
    blocking and checked again (a regular file of at most `cap` bytes), counted against
    the sweep's budget before they are read. `error(expected)` makes the exception."""
    try:
        return read_regular(real, cap, lambda size: budget.take(size, real))
    except FileNotFoundError:
        raise error(f"file not found: {real}") from None
    except NotRegular:
        raise error(f"{real} is not a regular file (a folder, device or FIFO)") from None
    except TooLarge as e:
        raise error(f"{real} holds {e.size} bytes, more than the {cap} a scene may load") from None
    except Grew:
        raise error(f"{real} grew while it was read") from None
    except OSError as e:
        raise error(f"{real} cannot be read ({e.strerror or e})") from None


def scene_references(data: bytes) -> list[tuple[str, str, str]]:
    """(key, path as written, kind) of every file a scene file names: meshes, image
    textures, glTF entries; the key as the loader's errors name it."""
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError, ValueError, RecursionError):
        return []                         # the worker's loader says what is wrong
    out = []
    objects = doc.get("objects", [])
    for i, obj in enumerate(objects if isinstance(objects, list) else [], 1):
        if not isinstance(obj, dict):
            continue
        name = obj.get("name", f"object{i}")
        k = f"objects[{i}] ({name})" if isinstance(name, str) else f"objects[{i}]"
        for key, what in (("mesh", "mesh"), ("gltf", "glTF")):
            if isinstance(obj.get(key), str):
                out.append((f"{k}.{key}", obj[key], what))
        material = obj.get("material")
        texture = material.get("texture") if isinstance(material, dict) else None
        if isinstance(texture, dict) and isinstance(texture.get("path"), str):
            out.append((f"{k}.material.texture.path", texture["path"], "image"))
    return out


def _add_gltf(found: dict, scene: Path, path: Path, key: str, budget: Budget):
    """A glTF file's external buffers and images, by the same rule from its folder."""
    data = found[path]
    doc = _glb_json(data) if path.suffix.lower() == ".glb" else _json(data)
    if not isinstance(doc, dict):
        return                            # the worker's loader says what is wrong
    for section in ("buffers", "images"):
        items = doc.get(section)
        for j, item in enumerate(items if isinstance(items, list) else []):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:") or urlsplit(uri).scheme:
                continue
            where = f"{key}: " if key else ""
            k = f"{where}{path.name}: {section}[{j}].uri"
            real = asset_file(scene, unquote(uri), k, "glTF " + section[:-1], MAX_GLTF_BYTES,
                              base=path.parent)
            if real not in found:
                found[real] = _read(real, MAX_GLTF_BYTES, budget,
                                    lambda e, k=k: SceneError(scene, k, e))


def _add_obj(found: dict, scene: Path, path: Path, key: str, budget: Budget):
    """An OBJ's material libraries and their texture maps, by the same rule."""
    for name in _words_after(found[path], (b"mtllib",)):
        k = f"{key}: {path.name}: mtllib"
        mtl = asset_file(scene, name, k, "material library", limits.MAX_MESH_BYTES,
                         base=path.parent)
        if mtl in found:
            continue
        found[mtl] = _read(mtl, limits.MAX_MESH_BYTES, budget, lambda e: SceneError(scene, k, e))
        for tex in _words_after(found[mtl], (b"map_Kd", b"map_Ka", b"map_Ks", b"map_Bump",
                                             b"map_d", b"bump")):
            kt = f"{key}: {mtl.name}: texture map"
            real = asset_file(scene, tex, kt, "image", limits.MAX_IMAGE_BYTES, base=mtl.parent)
            if real not in found:
                found[real] = _read(real, limits.MAX_IMAGE_BYTES, budget,
                                    lambda e: SceneError(scene, kt, e))


def _json(data: bytes):
    try:
        return json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None


def _glb_json(data: bytes):
    """The JSON chunk of a binary glTF (header 12 bytes, then length, type "JSON")."""
    if len(data) < 20 or data[:4] != b"glTF":
        return None
    length, kind = struct.unpack_from("<I4s", data, 12)
    return _json(data[20:20 + length]) if kind == b"JSON" else None


def _words_after(data: bytes, keywords) -> list[str]:
    """The file named after a keyword at the start of a line (the last word: map options
    such as `-s 1 1 1` come before the name)."""
    out = []
    for line in data.splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] in keywords:
            out.append(words[-1].decode("utf-8", "replace"))
    return out


# --- the worker's copies ------------------------------------------------------------------

def copies_folder(run: str) -> Path:
    """This machine's folder for one sweep's copies (`run`: the sweep's own token)."""
    return Path(tempfile.gettempdir()) / f"{COPIES_PREFIX}{run}"


def copy_root(bundle: Bundle, run: str) -> Path:
    return copies_folder(run) / bundle.digest[:24]


def materialise(bundle: Bundle, run: str) -> Path:
    """The bundle's files under this machine's copies folder of the sweep, in a folder
    named by their digest (made once per machine: written to a private folder, then
    renamed into place, so a second worker on the same machine finds it whole or not at
    all); the scene's path."""
    root = copy_root(bundle, run)
    if not root.is_dir():
        root.parent.mkdir(mode=0o700, exist_ok=True)
        stage = Path(tempfile.mkdtemp(prefix=".stage-", dir=root.parent))
        for rel, data in bundle.files:
            p = stage / rel
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(data)
        try:
            os.rename(stage, root)
        except OSError:                  # another worker got there first: theirs is whole
            shutil.rmtree(stage, ignore_errors=True)
    return root / bundle.entry


def remove_copies(run: str):
    """This machine's copies of the sweep `run`, all of them (at the sweep's end)."""
    shutil.rmtree(copies_folder(run), ignore_errors=True)


def unplace(text: str, bundle: Bundle, run: str) -> str:
    """An error as the user's own files would give it: the worker's copy's folder replaced
    by the folder the bundle was made from."""
    origin = bundle.origin.rstrip(os.sep) or os.sep
    root = copy_root(bundle, run)
    for r in dict.fromkeys([str(root), os.path.realpath(root)]):   # (a temp dir via a link)
        text = text.replace(r + os.sep, origin.rstrip(os.sep) + os.sep).replace(r, origin)
    return text
