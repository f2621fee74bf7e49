"""A scene file and every file it references, as bytes, so that a worker without the
sweep's disk can rebuild them in a folder of its own and load the scene from there.

References are found by reading the TOML (scene format v1.2; a bare .gltf/.glb scene is
its own asset): `mesh = "file"`, image
textures' `path`, glTF entries' `gltf = "file"`; inside those, an OBJ's `mtllib` and the
material's texture maps, a .gltf's external `uri`s (buffers, images) and a .glb's JSON
chunk's. A reference that is missing or unreadable is left out: the worker's loader then
reports it as the scene's error, one row of the table. Everything sits under the common
folder of the files, so every relative path resolves after the rebuild as before.
"""
from __future__ import annotations

import hashlib
import json
import os
import struct
import tempfile
import tomllib
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote


@dataclass(frozen=True)
class Bundle:
    entry: str                 # the scene file, relative to the bundle's root
    files: tuple               # ((relative path, bytes), ...) sorted by path
    origin: str                # the root folder on the machine that made it (for messages)

    @property
    def digest(self) -> str:
        """sha256 over every path and its bytes: what a cell's result depends on."""
        h = hashlib.sha256()
        for rel, data in self.files:
            h.update(rel.encode() + b"\0" + len(data).to_bytes(8, "little") + data)
        h.update(b"entry\0" + self.entry.encode())
        return h.hexdigest()


def scene_bundle(scene: Path) -> Bundle:
    scene = Path(scene).resolve()
    found: dict[Path, bytes] = {}
    _add_asset(found, scene)          # (a bare .gltf/.glb scene brings its uris' files)
    if scene.suffix.lower() not in (".gltf", ".glb"):
        for ref in scene_references(scene, found.get(scene, b"")):
            _add_asset(found, ref)
    root = Path(os.path.commonpath([str(p.parent) for p in found] or [str(scene.parent)]))
    files = tuple(sorted((str(p.relative_to(root)), data) for p, data in found.items()))
    return Bundle(str(scene.relative_to(root)), files, str(root))


def _add(found: dict, path: Path) -> bool:
    path = path.resolve()
    if path in found:
        return False
    try:
        found[path] = path.read_bytes()
    except OSError:
        return False
    return True


def scene_references(scene: Path, data: bytes) -> list[Path]:
    """The files a scene file names (mesh, image texture, glTF entry), resolved."""
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError):
        return []                         # the worker's loader says what is wrong
    out = []
    objects = doc.get("objects", [])
    for obj in objects if isinstance(objects, list) else []:
        if not isinstance(obj, dict):
            continue
        for key in ("mesh", "gltf"):
            if isinstance(obj.get(key), str):
                out.append(scene.parent / obj[key])
        material = obj.get("material")
        texture = material.get("texture") if isinstance(material, dict) else None
        if isinstance(texture, dict) and isinstance(texture.get("path"), str):
            out.append(scene.parent / texture["path"])
    return out


def _add_asset(found: dict, path: Path):
    """An asset and, for the formats that name other files, those too."""
    if not _add(found, path) or not path.is_file():
        return
    data = found[path.resolve()]
    suffix = path.suffix.lower()
    if suffix == ".gltf":
        _gltf_uris(found, path, _json(data))
    elif suffix == ".glb":
        _gltf_uris(found, path, _glb_json(data))
    elif suffix == ".obj":
        for name in _words_after(data, (b"mtllib",)):
            mtl = path.parent / name
            if _add(found, mtl):
                for tex in _words_after(found[mtl.resolve()], (b"map_Kd", b"map_Ka", b"map_Ks",
                                                               b"map_Bump", b"map_d", b"bump")):
                    _add(found, mtl.parent / tex)


def _gltf_uris(found: dict, path: Path, doc):
    if not isinstance(doc, dict):
        return
    for section in ("buffers", "images"):
        items = doc.get(section)
        for item in items if isinstance(items, list) else []:
            uri = item.get("uri") if isinstance(item, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:") and "://" not in uri:
                _add(found, path.parent / unquote(uri))


def _json(data: bytes):
    try:
        return json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
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


def materialise(bundle: Bundle) -> Path:
    """The bundle's files under a folder of this machine's temp dir named by its digest
    (made once per machine: written to a private folder, then renamed into place, so a
    second worker on the same machine finds it whole or not at all); the scene's path."""
    root = copy_root(bundle)
    if not root.is_dir():
        stage = Path(tempfile.mkdtemp(prefix=".hmblur-sweep-", dir=root.parent))
        for rel, data in bundle.files:
            p = stage / rel
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_bytes(data)
        try:
            os.rename(stage, root)
        except OSError:                  # another worker got there first: theirs is whole
            _remove_tree(stage)
    return root / bundle.entry


def copy_root(bundle: Bundle) -> Path:
    return Path(tempfile.gettempdir()) / f"hmblur-sweep-{bundle.digest[:24]}"


def _remove_tree(path: Path):
    for p in sorted(path.rglob("*"), key=lambda q: len(q.parts), reverse=True):
        p.rmdir() if p.is_dir() else p.unlink()
    path.rmdir()
