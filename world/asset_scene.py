"""A quick look at a glTF asset: a bare `.gltf`/`.glb` path given where a scene is expected
becomes a scene document (the dict a scene file parses to) with the asset as its one
`gltf` entry, a camera that frames it over its animation, two lights, ambient, a neutral
background and a 1/60 s shutter, loaded through world.loader's checks like any scene
file. docs/scene-format.md ("A glTF file as a scene") states the rules; `hmblur scene`
writes the document as TOML to edit.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from world.errors import SceneError

SUFFIXES = (".gltf", ".glb")
FOV_Y = 40.0
FILL = 0.6                     # the asset's box: within the middle 60% of the frame
VIEW = np.array([0.6, 0.45, 1.0])   # centre -> eye: in front (+Z), right (+X), above (+Y)
FRAME_TIMES = 9                # times over the animation range that the bounds cover
SHUTTER = 1.0 / 60.0
MIN_DISTANCE = 1e-3            # m: an asset with no extent is still looked at from somewhere
BACKGROUND = [0.3, 0.31, 0.33]
AMBIENT = [0.18, 0.18, 0.2]
LIGHTS = [{"direction": [0.45, -1.0, -0.55], "color": [0.85, 0.83, 0.8]},    # key: above left
          {"direction": [-0.8, -0.25, 0.3], "color": [0.25, 0.26, 0.3]}]    # fill: right


def is_asset(path: Path) -> bool:
    return path.suffix.lower() in SUFFIXES


def base_document(path: Path) -> dict:
    """Everything but the framing: the camera is a placeholder until frame() sets it."""
    return {
        "name": path.stem,
        "background": list(BACKGROUND),
        "ambient": list(AMBIENT),
        "camera": {"position": [0.0, 0.0, 1.0], "look_at": [0.0, 0.0, 0.0], "fov_y": FOV_Y,
                   "shutter": SHUTTER},
        "render": {"width": 1280, "height": 720, "time": 0.0},
        "lights": [dict(light) for light in LIGHTS],
        "objects": [{"name": path.stem, "gltf": path.name, "loop": True}],
    }


def animation_range(instance, animations=None) -> tuple[float, float] | None:
    """[A0, A1] in scene time of the animations an entry plays (or of `animations`, indices
    into its asset's), its time_offset and time_scale applied; None for no animation."""
    chosen = instance.animations if animations is None else animations
    spans = [instance.asset.animations[i].time_span for i in chosen]
    spans = [s for s in spans if s is not None]
    if not spans:
        return None
    a0, a1 = min(s[0] for s in spans), max(s[1] for s in spans)
    return (instance.time_offset + a0 / instance.time_scale,
            instance.time_offset + a1 / instance.time_scale)


def bounds(scene, times) -> tuple[np.ndarray, np.ndarray]:
    """The world-space box (lo, hi) of every object's vertices at each of `times`."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for t in times:
        for o in scene.objects:
            v = o.vertices_at(t)
            m = o.matrix(t)
            w = v @ m[:3, :3].T + m[:3, 3]
            lo, hi = np.minimum(lo, w.min(axis=0)), np.maximum(hi, w.max(axis=0))
    return lo, hi


def frame(doc: dict, scene) -> None:
    """Set doc's camera and render time from the loaded scene: the render time is the middle
    of the animation range (0 without animation); the camera looks at the centre of the box
    that holds the asset at FRAME_TIMES times over that range, from direction VIEW, from the
    nearest distance at which every corner of the box lies in the middle FILL of the frame
    (of the document's width and height)."""
    (instance,) = scene.assets
    span = animation_range(instance)
    if span is None:
        times, t = [0.0], 0.0
    else:
        times = np.linspace(span[0], span[1], FRAME_TIMES).tolist()
        t = 0.5 * (span[0] + span[1])
    if not scene.objects:
        raise SceneError(scene.path, "", "the asset has no mesh to show")
    lo, hi = bounds(scene, times)
    centre = 0.5 * (lo + hi)
    back = VIEW / np.linalg.norm(VIEW)                       # from the centre to the eye
    right = np.cross(-back, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -back)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])]) - centre
    # a corner at depth (d - c.back) from the eye is inside the middle FILL of the frame
    # when |c.right| <= FILL tan(fov/2) aspect (d - c.back), and likewise for up
    tan = math.tan(math.radians(FOV_Y) / 2.0)
    aspect = doc["render"]["width"] / doc["render"]["height"]
    toward = corners @ back
    need = np.maximum(np.abs(corners @ right) / (FILL * tan * aspect),
                      np.abs(corners @ up) / (FILL * tan)) + toward
    distance = max(float(need.max()), MIN_DISTANCE)
    depth = distance - toward
    cam = doc["camera"]
    cam["position"] = [_round(x) for x in centre + distance * back]
    cam["look_at"] = [_round(x) for x in centre]
    # all of the box between near and far, with room to move the camera in the viewer
    cam["near"] = _round(max(0.1 * float(depth.min()), 1e-4 * distance))
    cam["far"] = _round(4.0 * float(depth.max()))
    doc["render"]["time"] = _round(t)


def _round(x: float) -> float:
    """8 significant digits: the written file stays readable (the scene is made from the
    rounded values, so the file loads back to it exactly)."""
    return float(f"{float(x):.8g}")


def load_asset_scene(path: Path, loader_class, choose=None):
    """(Scene, document) of a bare asset path. `loader_class` is world.loader._Loader;
    `choose(doc)`, if given, returns the document with the entry's animation chosen."""
    doc = base_document(path)
    if choose is not None:
        doc = choose(doc)
    loader = loader_class(path, document=doc)
    scene = loader.load()
    frame(doc, scene)
    scene.camera = loader.camera(doc["camera"])
    scene.render = loader.render(doc["render"])
    return scene, doc
