"""Scene files (docs/scene-format.md) -> `world.scene.Scene`, with every mistake a SceneError.

`load_scene` takes a path to a TOML file or the name of a built-in scene in `scenes/`.
Validation is strict and happens here, once: the renderers may trust a loaded Scene.
Whatever the document holds, the loader raises nothing but SceneError, and each message
names the file, the dotted key and what was expected. Array entries are numbered from 1
in file order (`objects[2]` is the object with id 2, with its name beside it;
`camera.keys[1]` the camera's first key).

Primitive parameters that the format leaves out are left out of the trimesh call too, so
trimesh's own defaults apply (sphere radius 1, subdivisions 3; cylinder and revolve
sections). A cylinder needs `radius` and `height` because trimesh does. Sizes are capped
(subdivisions <= 7, sections <= 10000, frames <= 16384 px, and world/limits.py: numbers,
triangles, files, texture pixels) so that a typo cannot hang the program or exhaust memory;
each is checked before the work it bounds.
"""
from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import trimesh

import scenes

from world import asset_scene, images, limits
from world.assets import asset_file
from world.errors import SceneError
from world.scene import (INTERPOLATIONS, CameraKeys, CameraSpec, Light, Material, Mesh, ObjectKeys,
                    Placement, RenderDefaults, Scene, SceneObject, Texture)

PRIMITIVES = ("box", "sphere", "cylinder", "revolve")
SHADINGS = ("smooth", "flat")
TEXTURE_KEYS = {
    "checker": ("kind", "size", "albedo2"),
    "stripes": ("kind", "axis", "size", "albedo2"),
    "image": ("kind", "path"),
}
MAX_SUBDIVISIONS = 7
MAX_SECTIONS = 10000
MAX_FRAME_SIZE = limits.MAX_FRAME_SIZE
NUMBERING = "objects[k], lights[k] and keys[k] count from 1 in file order"
# What a keyed object or camera must not also have: its pose comes from the keys.
OBJECT_UNKEYED = ("position", "rotation", "scale", "velocity", "angular_velocity")
CAMERA_UNKEYED = ("position", "look_at", "velocity", "angular_velocity")


# ---------------------------------------------------------------- built-in scenes

def builtin_dir() -> Path:
    return Path(scenes.__file__).resolve().parent


def builtin_scene_names() -> list[str]:
    return sorted(p.stem for p in builtin_dir().glob("*.toml"))


def builtin_scene_path(name: str) -> Path:
    path = builtin_dir() / f"{name}.toml"
    if name not in builtin_scene_names():
        raise SceneError(name, "", "no such scene file or built-in scene; built-in scenes: "
                         + ", ".join(builtin_scene_names()))
    return path


def load_scene(source, animations: dict | None = None) -> Scene:
    """A scene from a TOML path, or from a built-in name (no ".toml", not an existing path).
    `animations`: {gltf entry name: "all", "none", an animation's name or index}, each
    replacing the `animation` key of the entries of that name (the viewer's choice, kept
    in sidecars)."""
    path = Path(source)
    if not _is_file(path):
        if isinstance(source, str) and not source.endswith(".toml") and not _exists(path):
            path = builtin_scene_path(source)
        elif _exists(path):
            raise SceneError(path, "", "not a regular file")
        else:
            raise SceneError(path, "", "file not found")
    if asset_scene.is_asset(path):      # a bare glTF asset: a scene made around it
        return load_asset(path, animations)[0]
    if not animations:
        return _out_of_memory_said(path, _Loader(path).load)
    loader = _Loader(path)
    return _out_of_memory_said(path, lambda: _Loader(
        path, document=choose_animations(loader.parse(), animations, path)).load())


def load_asset(path, animations: dict | None = None) -> tuple[Scene, dict]:
    """(Scene, the scene document it was loaded from) of a bare .gltf/.glb file
    (world.asset_scene; docs/scene-format.md, "A glTF file as a scene"); `animations` as
    for load_scene (the framing follows the animations chosen)."""
    path = Path(path)
    choose = (lambda doc: choose_animations(doc, animations, path)) if animations else None
    return _out_of_memory_said(path, lambda: asset_scene.load_asset_scene(path, _Loader,
                                                                         choose))


def choose_animations(doc: dict, animations: dict, path) -> dict:
    """`doc` with the `animation` of each gltf entry named in `animations` replaced (the
    values are checked as the file's are, when the entry loads); a name that is no gltf
    entry's is a SceneError."""
    if not isinstance(animations, dict) or len(animations) > limits.MAX_OBJECTS:
        raise SceneError(path, "animations", "expected a table of at most "
                         f"{limits.MAX_OBJECTS} gltf entry names")
    entries = doc.get("objects") if isinstance(doc, dict) else None
    if not isinstance(entries, list):
        entries = []
    found = set()
    chosen = []
    for number, t in enumerate(entries, 1):
        if isinstance(t, dict) and "gltf" in t:
            name = t.get("name", f"object{number}")
            if isinstance(name, str) and name in animations:
                t = {**t, "animation": animations[name]}
                found.add(name)
        chosen.append(t)
    missing = [n for n in animations if n not in found]
    if missing:
        raise SceneError(path, "animations", f"no gltf entry named {str(missing[0])[:80]!r}")
    return {**doc, "objects": chosen}


def _out_of_memory_said(path, load):
    """load(), with a MemoryError a SceneError naming the scene file (the files a scene
    names say so themselves, with their key, where they are read)."""
    try:
        return load()
    except MemoryError:
        raise SceneError(path, "", "out of memory while loading the scene") from None


def _is_file(p: Path) -> bool:
    try:
        return p.is_file()
    except (OSError, ValueError):
        return False


def _exists(p: Path) -> bool:
    try:
        return p.exists()
    except (OSError, ValueError):
        return False


# ---------------------------------------------------------------- value checks

def describe_value(v) -> str:
    """A TOML value as an error names it: its kind and a short view of it."""
    if isinstance(v, bool):
        return f"the boolean {str(v).lower()}"
    if isinstance(v, (int, float)):
        return f"the number {v!r}"
    if isinstance(v, str):
        return f"the string {v[:40]!r}"
    if isinstance(v, list):
        return f"an array of {len(v)}"
    if isinstance(v, dict):
        return "a table"
    return f"a {type(v).__name__}"


def _normalised(d: np.ndarray) -> np.ndarray | None:
    """d / |d|, or None where |d| is zero, underflows or overflows (as numpy computes it,
    so that the camera, which normalises the same way, never divides by 0 or inf)."""
    with np.errstate(all="ignore"):
        n = np.linalg.norm(d)
        u = d / n
    if not (np.isfinite(n) and n > 0 and np.all(np.isfinite(u))):
        return None
    return u


def _join(prefix: str, key: str) -> str:
    return f"{prefix}.{key}" if prefix else key


class _Loader:
    def __init__(self, path: Path, document: dict | None = None):
        self.path = path
        self.document = document        # a scene document made elsewhere, else the file's
        self.triangles = 0          # of the meshes built so far (limits.MAX_TRIANGLES)
        self.images = images.SceneImages()      # the scene's decoded images, each once
        # Every earlier object and glTF node by name, for `parent` (v1.2).
        self.named: dict[str, list] = {}

    def fail(self, key: str, expected: str):
        if "[" in key:
            expected += f" ({NUMBERING})"
        raise SceneError(self.path, key, expected)

    # -- scalars and vectors

    def number(self, v, key: str, bound: float = limits.MAX_SCENE_NUMBER,
               what: str = "a number") -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(key, f"expected a number, got {describe_value(v)}")
        try:
            x = float(v)
        except OverflowError:
            x = math.inf
        if not math.isfinite(x):
            self.fail(key, f"expected a finite number, got {describe_value(v)}")
        if abs(x) > bound:                        # (float32 in the shaders)
            self.fail(key, f"expected {what} within +-{bound:g}, got {x!r}")
        return x

    def integer(self, v, key: str) -> int:
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(key, f"expected an integer, got {describe_value(v)}")
        return v

    def string(self, v, key: str) -> str:
        if not isinstance(v, str):
            self.fail(key, f"expected a string, got {describe_value(v)}")
        return v

    def name(self, v, key: str) -> str:
        s = self.string(v, key)
        if len(s) > limits.MAX_NAME_CHARS:
            self.fail(key, f"expected a name of at most {limits.MAX_NAME_CHARS} characters, "
                      f"got {len(s)}")
        return s

    def table(self, v, key: str, allowed) -> dict:
        if not isinstance(v, dict):
            self.fail(key, f"expected a table, got {describe_value(v)}")
        for k in v:
            if k not in allowed:
                self.fail(_join(key, k), "unknown key; allowed here: " + ", ".join(allowed))
        return v

    def require(self, t: dict, k: str, prefix: str, what: str = "a value"):
        if k not in t:
            self.fail(_join(prefix, k), f"required key is missing ({what})")
        return t[k]

    def vec3(self, v, key: str) -> np.ndarray:
        if not isinstance(v, list) or len(v) != 3:
            self.fail(key, f"expected an array of 3 numbers, got {describe_value(v)}")
        return np.array([self.number(x, f"{key}[{i}]") for i, x in enumerate(v)],
                        dtype=np.float64)

    def colour(self, v, key: str) -> np.ndarray:
        c = self.vec3(v, key)
        if np.any(c < 0):
            self.fail(key, f"expected colour components >= 0, got {c.tolist()}")
        return c

    def positive(self, v, key: str) -> float:
        x = self.number(v, key)
        if x <= 0:
            self.fail(key, f"expected a number > 0, got {x!r}")
        return x

    def non_negative(self, v, key: str) -> float:
        x = self.number(v, key)
        if x < 0:
            self.fail(key, f"expected a number >= 0, got {x!r}")
        return x

    def int_in(self, v, key: str, lo: int, hi: int) -> int:
        n = self.integer(v, key)
        if not lo <= n <= hi:
            self.fail(key, f"expected an integer from {lo} to {hi}, got {n}")
        return n

    def array_of_tables(self, v, key: str) -> list:
        if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
            self.fail(key, f"expected an array of tables ([[{key}]]), got {describe_value(v)}")
        return v

    def at_most(self, v: list, key: str, most: int) -> list:
        if len(v) > most:
            self.fail(key, f"expected at most {most} entries, got {len(v)}")
        return v

    def unit(self, v, key: str) -> np.ndarray:
        n = _normalised(self.vec3(v, key))
        if n is None:
            self.fail(key, f"expected a non-zero vector, got {v}")
        return n

    # -- the document

    def load(self) -> Scene:
        doc = self.parse() if self.document is None else self.document
        self.table(doc, "", ("name", "background", "ambient", "camera", "render", "lights",
                             "objects"))
        name = self.name(doc.get("name", self.path.stem), "name")
        background = self.colour(doc.get("background", [0, 0, 0]), "background")
        ambient = self.colour(doc.get("ambient", [0, 0, 0]), "ambient")
        camera = self.camera(self.require(doc, "camera", "", "a [camera] table"))
        render = self.render(doc.get("render", {}))
        lights = [self.light(t, f"lights[{i}]")
                  for i, t in enumerate(self.at_most(self.array_of_tables(
                      doc.get("lights", []), "lights"), "lights", limits.MAX_LIGHTS), 1)]
        objects, assets = [], []
        entries = self.at_most(self.array_of_tables(doc.get("objects", []), "objects"),
                               "objects", limits.MAX_OBJECTS)
        for i, t in enumerate(entries, 1):
            if "gltf" in t:
                from world import gltf_entry     # (pygltflib only for scenes that use it)
                instance, made = gltf_entry.load_entry(self, t, i, len(objects) + 1)
                assets.append(instance)
                for node in instance.nodes:
                    self.named.setdefault(node.name, []).append(node)
            else:
                made = [self.object(t, i, len(objects) + 1)]
                self.named.setdefault(made[0].name, []).append(made[0])
            objects.extend(made)
            if len(objects) > limits.MAX_OBJECTS:
                self.fail(f"objects[{i}]", f"the scene's objects (glTF mesh nodes included) "
                          f"pass {limits.MAX_OBJECTS}")
        return Scene(name=name, path=self.path, camera=camera, background=background,
                     ambient=ambient, render=render, lights=lights, objects=objects,
                     assets=assets)

    def parse(self) -> dict:
        try:
            size = self.path.stat().st_size
        except OSError as e:
            self.fail("", f"cannot read the file ({e.strerror or e})")
        if size > limits.MAX_SCENE_BYTES:
            self.fail("", f"the file holds {size} bytes, more than the "
                      f"{limits.MAX_SCENE_BYTES} a scene file may")
        try:
            text = self.path.read_bytes().decode("utf-8")
        except OSError as e:
            self.fail("", f"cannot read the file ({e.strerror or e})")
        except UnicodeDecodeError as e:
            self.fail("", f"expected UTF-8 text (TOML), bad byte at offset {e.start}")
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            self.fail("", f"TOML syntax error: {e}")
        except (ValueError, RecursionError) as e:
            self.fail("", f"TOML could not be read: {type(e).__name__}: {e}")

    def camera(self, v) -> CameraSpec:
        k = "camera"
        t = self.table(v, k, ("position", "look_at", "up", "fov_y", "near", "far", "shutter",
                              "velocity", "angular_velocity", "interpolation", "keys"))
        interpolation = self.keyed(t, k, CAMERA_UNKEYED)
        fov_y = self.number(self.require(t, "fov_y", k, "degrees"), "camera.fov_y")
        if not 0 < fov_y < 180:
            self.fail("camera.fov_y", f"expected degrees strictly between 0 and 180, got {fov_y!r}")
        up = self.vec3(t.get("up", [0, 1, 0]), "camera.up")
        self.unit(up.tolist(), "camera.up")
        near = self.positive(t.get("near", 0.05), "camera.near")
        far = self.number(t.get("far", 100.0), "camera.far")
        if not far > near:
            self.fail("camera.far", f"expected a number > near ({near!r}), got {far!r}")
        shutter = self.non_negative(t.get("shutter", 0.0), "camera.shutter")
        if interpolation is not None:
            keys = self.camera_keys(t["keys"], up, interpolation)
            return CameraSpec(position=keys.positions[0].copy(), look_at=keys.look_ats[0].copy(),
                              fov_y=fov_y, up=up, near=near, far=far, shutter=shutter,
                              keys=keys)
        position = self.vec3(self.require(t, "position", k, "3 numbers"), "camera.position")
        look_at = self.vec3(self.require(t, "look_at", k, "3 numbers"), "camera.look_at")
        self.view(position, look_at, up, k)
        return CameraSpec(
            position=position, look_at=look_at, fov_y=fov_y,
            up=up, near=near, far=far,
            shutter=shutter,
            velocity=self.vec3(t.get("velocity", [0, 0, 0]), "camera.velocity"),
            angular_velocity=self.vec3(t.get("angular_velocity", [0, 0, 0]),
                                       "camera.angular_velocity"))

    def view(self, position, look_at, up, k: str):
        """A view direction exists (look_at apart from position) and up is not along it."""
        up_unit = self.unit(up.tolist(), f"{k}.up")
        with np.errstate(all="ignore"):
            fwd = look_at - position
        fwd_unit = _normalised(fwd)
        if fwd_unit is None:
            self.fail(f"{k}.look_at", f"expected a point distinct from {k}.position "
                      f"{position.tolist()} (at a finite distance), got {look_at.tolist()}")
        if np.linalg.norm(np.cross(fwd_unit, up_unit)) < 1e-6:
            self.fail(f"{k}.up", "expected a vector not parallel to the view direction "
                      f"(look_at - position = {fwd.tolist()})")

    # -- keyed motion (v1.1)

    def keyed(self, t: dict, k: str, unkeyed) -> str | None:
        """The interpolation of a table with `keys` (None: not keyed), after the checks of
        which keys exclude which."""
        if "keys" not in t:
            if "interpolation" in t:
                self.fail(f"{k}.interpolation", "allowed only together with keys "
                          f"([[{k.split(' ')[0].split('[')[0]}.keys]])")
            return None
        for other in unkeyed:
            if other in t:
                self.fail(f"{k}.{other}", "not allowed together with keys (a keyed pose comes "
                          f"from the keys: put it in each key, or drop {k}.keys)")
        interpolation = self.string(t.get("interpolation", "linear"), f"{k}.interpolation")
        if interpolation not in INTERPOLATIONS:
            self.fail(f"{k}.interpolation", f"expected \"linear\" or \"smooth\", got "
                      f"{interpolation!r}")
        keys = t["keys"]
        if not isinstance(keys, list) or not all(isinstance(x, dict) for x in keys):
            self.fail(f"{k}.keys", f"expected an array of key tables ([[keys]]), got "
                      f"{describe_value(keys)}")
        if not keys:
            self.fail(f"{k}.keys", "expected at least one key")
        return interpolation

    def key_times(self, keys: list, k: str, allowed) -> np.ndarray:
        """Each key table checked against `allowed`, and the keys' strictly increasing times."""
        times = []
        for j, key in enumerate(keys, 1):
            kk = f"{k}.keys[{j}]"
            self.table(key, kk, allowed)
            tj = self.number(self.require(key, "time", kk, "seconds"), f"{kk}.time")
            if times and not tj > times[-1]:
                self.fail(f"{kk}.time", f"expected a time greater than keys[{j - 1}]'s "
                          f"({times[-1]!r}): key times increase strictly, got {tj!r}")
            times.append(tj)
        return np.array(times, dtype=np.float64)

    def object_keys(self, keys: list, k: str, interpolation: str) -> ObjectKeys:
        times = self.key_times(keys, k, ("time", "position", "rotation", "scale"))
        pos, rot, sc = [], [], []
        for j, key in enumerate(keys, 1):
            kk = f"{k}.keys[{j}]"
            pos.append(self.vec3(key.get("position", [0, 0, 0]), f"{kk}.position"))
            rot.append(self.vec3(key.get("rotation", [0, 0, 0]), f"{kk}.rotation"))
            sc.append(self.scale(key.get("scale", 1.0), f"{kk}.scale"))
        return ObjectKeys(times, np.array(pos), np.array(rot), np.array(sc), interpolation)

    def camera_keys(self, keys: list, up: np.ndarray, interpolation: str) -> CameraKeys:
        k = "camera"
        times = self.key_times(keys, k, ("time", "position", "look_at", "up"))
        pos, look, ups = [], [], []
        for j, key in enumerate(keys, 1):
            kk = f"{k}.keys[{j}]"
            pos.append(self.vec3(self.require(key, "position", kk, "3 numbers: every camera "
                                              "key has its eye"), f"{kk}.position"))
            look.append(self.vec3(self.require(key, "look_at", kk, "3 numbers: every camera "
                                               "key has its look-at point"), f"{kk}.look_at"))
            ups.append(self.vec3(key["up"], f"{kk}.up") if "up" in key else up.copy())
            self.view(pos[-1], look[-1], ups[-1], kk)
        return CameraKeys(times, np.array(pos), np.array(look), np.array(ups), interpolation)

    def render(self, v) -> RenderDefaults:
        t = self.table(v, "render", ("width", "height", "time"))
        width = self.int_in(t.get("width", 1280), "render.width", 1, MAX_FRAME_SIZE)
        height = self.int_in(t.get("height", 720), "render.height", 1, MAX_FRAME_SIZE)
        if width * height > limits.MAX_FRAME_PIXELS:
            self.fail("render", f"expected at most {limits.MAX_FRAME_PIXELS} pixels "
                      f"(e.g. 2560x1600), got {width}x{height}")
        # the bound of --time (world/limits.py)
        time = self.number(t.get("time", 0.0), "render.time", limits.MAX_TIME, "seconds")
        return RenderDefaults(width=width, height=height, time=time)

    def light(self, t: dict, k: str) -> Light:
        self.table(t, k, ("direction", "color"))
        direction = self.unit(self.require(t, "direction", k, "3 numbers, the direction the "
                                           "light travels"), f"{k}.direction")
        return Light(direction=direction, color=self.colour(t.get("color", [1, 1, 1]),
                                                            f"{k}.color"))

    def entry_key(self, t: dict, number: int) -> str:
        """How errors name objects entry `number`: objects[k] (name)."""
        k = f"objects[{number}]"
        name = t.get("name", f"object{number}")
        return f"{k} ({name})" if isinstance(name, str) and len(name) <= limits.MAX_NAME_CHARS else k

    def object(self, t: dict, number: int, oid: int) -> SceneObject:
        k = self.entry_key(t, number)
        name = t.get("name", f"object{number}")
        self.table(t, k, ("name", "mesh", "position", "rotation", "scale", "shading",
                          "material", "velocity", "angular_velocity", "interpolation", "keys",
                          "parent"))
        name = self.name(name, f"{k}.name")
        placement = self.placement(t, k)
        mesh_value = self.require(t, "mesh", k, "a file path or a primitive table")
        mesh = self.mesh(mesh_value, f"{k}.mesh")
        default_shading = "flat" if isinstance(mesh_value, dict) and "box" in mesh_value \
            else "smooth"
        shading = self.string(t.get("shading", default_shading), f"{k}.shading")
        if shading not in SHADINGS:
            self.fail(f"{k}.shading", f"expected \"smooth\" or \"flat\", got {shading!r}")
        material = self.material(t.get("material", {}), f"{k}.material", mesh)
        return SceneObject(name=name, id=oid, mesh=mesh, material=material, shading=shading,
                           parent=self.parent(t, k), **placement)

    def placement(self, t: dict, k: str) -> dict:
        """An object's own pose: position, rotation, scale, velocities, or keys (then the
        pose fields hold the first key's), as Placement's fields."""
        interpolation = self.keyed(t, k, OBJECT_UNKEYED)
        if interpolation is not None:
            keys = self.object_keys(t["keys"], k, interpolation)
            return dict(position=keys.positions[0].copy(), rotation=keys.rotations[0].copy(),
                        scale=keys.scales[0].copy(), keys=keys)
        return dict(
            position=self.vec3(t.get("position", [0, 0, 0]), f"{k}.position"),
            rotation=self.vec3(t.get("rotation", [0, 0, 0]), f"{k}.rotation"),
            scale=self.scale(t.get("scale", 1.0), f"{k}.scale"),
            velocity=self.vec3(t.get("velocity", [0, 0, 0]), f"{k}.velocity"),
            angular_velocity=self.vec3(t.get("angular_velocity", [0, 0, 0]),
                                       f"{k}.angular_velocity"))

    def parent(self, t: dict, k: str):
        """The node named by `parent` (v1.2): exactly one earlier object or glTF node
        (`entry/<node name>`) of that name; None without the key."""
        if "parent" not in t:
            return None
        name = self.string(t["parent"], f"{k}.parent")
        found = self.named.get(name, [])
        if not found:
            self.fail(f"{k}.parent", f"expected the name of an earlier object or glTF node "
                      f"(entry/<node name>), got {name!r}: none before this object has it")
        if len(found) > 1:
            self.fail(f"{k}.parent", f"{name!r} names {len(found)} earlier objects or nodes; "
                      "a parent's name must be unique")
        return found[0]

    def scale(self, v, key: str) -> np.ndarray:
        if isinstance(v, list):
            scale = self.vec3(v, key)
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            scale = np.full(3, self.number(v, key))
        else:
            self.fail(key, f"expected a number or 3 numbers, got {describe_value(v)}")
        if np.any(scale == 0):
            self.fail(key, f"expected non-zero scale factors, got {scale.tolist()}")
        return scale

    def material(self, v, k: str, mesh: Mesh) -> Material:
        t = self.table(v, k, ("albedo", "specular", "shininess", "texture"))
        texture = None
        if "texture" in t:
            texture = self.texture(t["texture"], f"{k}.texture", mesh)
        return Material(
            albedo=self.colour(t.get("albedo", [0.8, 0.8, 0.8]), f"{k}.albedo"),
            specular=self.non_negative(t.get("specular", 0.0), f"{k}.specular"),
            shininess=self.non_negative(t.get("shininess", 32.0), f"{k}.shininess"),
            texture=texture)

    def texture(self, v, k: str, mesh: Mesh) -> Texture:
        if not isinstance(v, dict):
            self.fail(k, f"expected a table, got {describe_value(v)}")
        kind = self.string(self.require(v, "kind", k, "\"checker\", \"stripes\" or \"image\""),
                           f"{k}.kind")
        if kind not in TEXTURE_KEYS:
            self.fail(f"{k}.kind", f"expected \"checker\", \"stripes\" or \"image\", got {kind!r}")
        self.table(v, k, TEXTURE_KEYS[kind])
        if kind == "image":
            if mesh.uv is None:
                self.fail(k, "an image texture needs a mesh with UVs (texture coordinates); "
                          "this mesh has none (primitives never do)")
            rel = self.string(self.require(v, "path", k, "an image file"), f"{k}.path")
            path = self.file(rel, f"{k}.path", "image")
            try:
                return self.images.texture(self.images.from_file(path), path)
            except images.ImageError as e:
                self.fail(f"{k}.path", f"{path}: {e}")
        axis = 0
        if kind == "stripes":
            axis = self.integer(self.require(v, "axis", k, "0, 1 or 2"), f"{k}.axis")
            if axis not in (0, 1, 2):
                self.fail(f"{k}.axis", f"expected 0, 1 or 2 (x, y, z), got {axis}")
        size = self.positive(self.require(v, "size", k, "a cell size > 0"), f"{k}.size")
        albedo2 = self.colour(self.require(v, "albedo2", k, "a linear RGB colour"),
                              f"{k}.albedo2")
        return Texture(kind=kind, size=size, axis=axis, albedo2=albedo2)

    # -- files

    def file(self, rel: str, key: str, what: str) -> Path:
        """world.assets.asset_file's rule: inside the scene's folder, a regular file,
        within the size limit of its kind."""
        cap = limits.MAX_IMAGE_BYTES if what == "image" else limits.MAX_MESH_BYTES
        return asset_file(self.path, rel, key, what, cap)

    # -- meshes

    def mesh(self, v, k: str) -> Mesh:
        if isinstance(v, str):
            path = self.file(v, k, "mesh")
            try:
                # A raw read first: processing silently drops NaN vertices, which should
                # be reported, not hidden.
                raw = trimesh.load(str(path), force="mesh", process=False)
                if not np.all(np.isfinite(np.asarray(raw.vertices, dtype=np.float64))):
                    self.fail(k, f"expected finite vertex coordinates, {path} has NaN or inf")
                tm = trimesh.load(str(path), force="mesh")
            except SceneError:
                raise
            except MemoryError:
                self.fail(k, f"{path}: out of memory reading the mesh")
            except Exception:        # trimesh raises many types for bad files
                self.fail(k, f"expected a readable mesh file (.obj, .ply, .stl, .glb, .off), "
                          f"{path} could not be read as one (damaged, cut short, or another "
                          "kind of file)")
            return self.mesh_arrays(tm, k, str(path))
        if not isinstance(v, dict):
            self.fail(k, f"expected a file path or a primitive table ({', '.join(PRIMITIVES)}), "
                      f"got {describe_value(v)}")
        kinds = [p for p in PRIMITIVES if p in v]
        unknown = [key for key in v if key not in PRIMITIVES and key != "sections"]
        if unknown:
            self.fail(f"{k}.{unknown[0]}", f"unknown key; expected one of "
                      f"{', '.join(PRIMITIVES)} (and sections with revolve)")
        if len(kinds) != 1:
            self.fail(k, f"expected exactly one of {', '.join(PRIMITIVES)}, got "
                      f"{', '.join(kinds) or 'none'}")
        kind = kinds[0]
        self.table(v, k, (kind, "sections") if kind == "revolve" else (kind,))
        pk = f"{k}.{kind}"
        p = v[kind]
        try:
            if kind == "box":
                ext = self.vec3(p, pk)
                if np.any(ext <= 0):
                    self.fail(pk, f"expected extents > 0, got {ext.tolist()}")
                tm = trimesh.creation.box(extents=ext.tolist())
            elif kind == "sphere":
                t = self.table(p, pk, ("radius", "subdivisions"))
                args = {}
                if "subdivisions" in t:
                    args["subdivisions"] = self.int_in(t["subdivisions"], f"{pk}.subdivisions",
                                                       0, MAX_SUBDIVISIONS)
                if "radius" in t:
                    args["radius"] = self.positive(t["radius"], f"{pk}.radius")
                tm = trimesh.creation.icosphere(**args)
            elif kind == "cylinder":
                t = self.table(p, pk, ("radius", "height", "sections"))
                args = {"radius": self.positive(self.require(t, "radius", pk, "a number > 0"),
                                                f"{pk}.radius"),
                        "height": self.positive(self.require(t, "height", pk, "a number > 0"),
                                                f"{pk}.height")}
                if "sections" in t:
                    args["sections"] = self.int_in(t["sections"], f"{pk}.sections", 3,
                                                   MAX_SECTIONS)
                tm = trimesh.creation.cylinder(**args)
            else:
                points = self.profile(p, pk)
                args = {}
                if "sections" in v:
                    args["sections"] = self.int_in(v["sections"], f"{k}.sections", 3,
                                                   MAX_SECTIONS)
                self.budget(2 * len(points) * args.get("sections", 32), pk)
                tm = trimesh.creation.revolve(linestring=points, **args)
        except SceneError:
            raise
        except Exception as e:   # a parameter set that trimesh itself rejects
            self.fail(pk, f"trimesh could not build this {kind}: {type(e).__name__}: {e}")
        return self.mesh_arrays(tm, pk, f"the {kind}")

    def profile(self, v, k: str) -> np.ndarray:
        if not isinstance(v, list) or len(v) < 2:
            self.fail(k, f"expected an array of at least 2 [r, z] points, got {describe_value(v)}")
        pts = []
        for i, p in enumerate(v):
            if not isinstance(p, list) or len(p) != 2:
                self.fail(f"{k}[{i}]", f"expected an [r, z] pair, got {describe_value(p)}")
            r, z = self.number(p[0], f"{k}[{i}][0]"), self.number(p[1], f"{k}[{i}][1]")
            if r < 0:
                self.fail(f"{k}[{i}][0]", f"expected a radius >= 0, got {r!r}")
            pts.append((r, z))
        return np.array(pts, dtype=np.float64)

    def budget(self, triangles: int, k: str):
        """Count a mesh's triangles (an upper estimate before it is built) against the
        scene's limits.MAX_TRIANGLES, all meshes together."""
        used = self.triangles
        if used + triangles > limits.MAX_TRIANGLES:
            self.fail(k, f"{triangles} triangles here would make the scene's "
                      f"{used + triangles}, more than the {limits.MAX_TRIANGLES} it may hold")

    def mesh_arrays(self, tm, k: str, what: str) -> Mesh:
        if not isinstance(tm, trimesh.Trimesh) or len(tm.faces) == 0 or len(tm.vertices) == 0:
            self.fail(k, f"expected a mesh with triangles, {what} has none")
        self.budget(len(tm.faces), k)
        self.triangles += len(tm.faces)
        try:
            with np.errstate(all="ignore"):
                vertices = np.array(tm.vertices, dtype=np.float64)
                faces = np.array(tm.faces, dtype=np.int64)
                vn = np.array(tm.vertex_normals, dtype=np.float64)
                fn = np.array(tm.face_normals, dtype=np.float64)
        except Exception as e:   # trimesh failing on degenerate geometry
            self.fail(k, f"expected a valid mesh, trimesh failed on {what}: "
                      f"{type(e).__name__}: {e}")
        if not np.all(np.isfinite(vertices)):
            self.fail(k, f"expected finite vertex coordinates, {what} has NaN or inf")
        if not (np.all(np.isfinite(vn)) and np.all(np.isfinite(fn))):
            self.fail(k, f"expected a mesh with finite normals, {what} is degenerate")
        uv = getattr(tm.visual, "uv", None)
        if uv is not None:
            uv = np.array(uv, dtype=np.float64)
            if uv.shape != (len(vertices), 2) or not np.all(np.isfinite(uv)):
                self.fail(k, f"expected one finite (u, v) per vertex, {what} has UVs of shape "
                          f"{uv.shape} for {len(vertices)} vertices")
        return Mesh(vertices=vertices, faces=faces, vertex_normals=vn, face_normals=fn, uv=uv)


def check_camera(data: dict, source: str) -> CameraSpec:
    """A camera table ([camera], docs/scene-format.md) from elsewhere than a scene file (an
    image's sidecar), checked as a scene file's is; errors name `source`."""
    return _Loader(Path(source)).camera(data)


def merge_camera(spec: CameraSpec, data: dict, source: str) -> CameraSpec:
    """`spec` with the fields of a camera table `data` (a sidecar's) laid over it, checked
    as a scene file's camera is: a keyed `data` replaces spec's pose and velocities, an
    unkeyed one spec's keys."""
    merged = spec.to_dict()
    if "keys" in data:
        for k in CAMERA_UNKEYED:
            merged.pop(k, None)
    elif any(k in data for k in CAMERA_UNKEYED) and "keys" in merged:
        merged.pop("keys")
        merged.pop("interpolation", None)
        merged.setdefault("position", spec.position.tolist())
        merged.setdefault("look_at", spec.look_at.tolist())
    merged.update(data)
    return check_camera(merged, source)


__all__ = ["load_scene", "load_asset", "builtin_scene_names", "builtin_scene_path", "check_camera",
           "merge_camera"]
