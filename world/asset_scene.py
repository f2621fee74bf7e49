"""A quick look at a glTF asset: a bare `.gltf`/`.glb` path given where a scene is expected
becomes a scene document (the dict a scene file parses to) with the asset as its one
`gltf` entry, a camera that frames its moving parts over the animation from a side that
sees them (world/quick_look.py), two lights, ambient, a neutral background, a 1/60 s
shutter and a time at which the parts move, loaded through world.loader's checks like
any scene file. docs/scene-format.md ("A glTF file as a scene") states the rules; `hmblur scene`
writes the document as TOML to edit.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from world import limits, quick_look
from world.errors import SceneError

SUFFIXES = (".gltf", ".glb")
FOV_Y = 40.0
FILL = 0.6                     # the asset's box: within the middle 60% of the frame
VIEW = quick_look.DIRECTIONS[0]      # centre -> eye: in front (+Z), right (+X), above (+Y)
FRAME_TIMES = 9                # times over the animation range that the bounds cover
SHUTTER = 1.0 / 60.0
FAR_RATIO = 1e4               # far / near at most, for what stands around the moving parts
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
    into its asset's), its time_offset and time_scale applied; None for no animation. The
    key times are float32: each is taken as the shortest decimal that reads back to it
    (1.2, not 1.2000000476837158), so the times made from them print as written."""
    chosen = instance.animations if animations is None else animations
    spans = [instance.asset.animations[i].time_span for i in chosen]
    spans = [s for s in spans if s is not None]
    if not spans:
        return None
    a0, a1 = (_float32_decimal(x) for x in (min(s[0] for s in spans), max(s[1] for s in spans)))
    return (instance.time_offset + a0 / instance.time_scale,
            instance.time_offset + a1 / instance.time_scale)


def _float32_decimal(x) -> float:
    return float(str(np.float32(x)))


def bounds(scene, times, objects=None) -> tuple[np.ndarray, np.ndarray]:
    """The world-space box (lo, hi) of every object's (or `objects`') vertices at each of
    `times`."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for t in times:
        for o in scene.objects if objects is None else objects:
            v = o.vertices_at(t)
            m = o.matrix(t)
            w = v @ m[:3, :3].T + m[:3, 3]
            lo, hi = np.minimum(lo, w.min(axis=0)), np.maximum(hi, w.max(axis=0))
    return lo, hi


def frame(doc: dict, scene) -> None:
    """Set doc's camera, lights and render time from the loaded scene (docs/scene-format.md,
    "A glTF file as a scene"). Without animation, or where nothing moves over it: the box
    of the whole asset at FRAME_TIMES times over the animation range, seen from VIEW, at
    the middle of the range (0 without animation). Else the box of the moving parts over
    those times, seen from the first of quick_look.DIRECTIONS whose view of them the static
    parts block least, at a time they move on screen (world/quick_look.py). Either way the
    camera looks at the box's centre from the nearest distance at which every corner lies
    in the middle FILL of the frame (of the document's width and height)."""
    (instance,) = scene.assets
    span = animation_range(instance)
    if span is None:
        times, t = [0.0], 0.0
    else:
        times = np.linspace(span[0], span[1], FRAME_TIMES).tolist()
        t = 0.5 * (span[0] + span[1])
    if not scene.objects:
        raise SceneError(scene.path, "", "the asset has no mesh to show")
    with np.errstate(all="ignore"):
        whole_lo, whole_hi = bounds(scene, times)
    moving = quick_look.motion(scene, times) if span is not None else None
    lo, hi = (whole_lo, whole_hi) if moving is None else (moving.lo, moving.hi)
    centre = 0.5 * (lo + hi)
    aspect = doc["render"]["width"] / doc["render"]["height"]
    if moving is None:
        back = VIEW / np.linalg.norm(VIEW)
    else:
        backs = quick_look.DIRECTIONS / np.linalg.norm(quick_look.DIRECTIONS, axis=1,
                                                       keepdims=True)
        eyes = np.array([centre + _distance(lo, hi, b, aspect)[0] * b for b in backs])
        back = backs[quick_look.pick_direction(quick_look.seen_fraction(moving, eyes))]
    distance, toward = _distance(lo, hi, back, aspect)
    cam = doc["camera"]
    cam["position"] = [_round(x) for x in centre + distance * back]
    cam["look_at"] = [_round(x) for x in centre]
    # all of the box between near and far, with room to move the camera in the viewer
    # (and the whole asset before far, so that what stands around the moving parts shows)
    depth = distance - toward
    whole = _corners(whole_lo, whole_hi) - centre
    near = max(0.1 * float(depth.min()), 1e-4 * distance)
    around = min(4.0 * float((distance - whole @ back).max()), FAR_RATIO * near,
                 limits.MAX_SCENE_NUMBER)
    cam["near"] = _round(near)
    cam["far"] = _round(max(4.0 * float(depth.max()), around))
    most = limits.MAX_SCENE_NUMBER
    if not all(abs(x) <= most for x in cam["position"] + [cam["far"]]):
        raise SceneError(scene.path, "", f"the asset spans {_span(lo, hi)} over its animation: "
                         f"a camera framing it would stand {distance:.3g} from its centre and "
                         f"see {cam['far']:.3g} deep, beyond the +-{most:g} a scene holds; place "
                         "it in a scene file with a smaller scale")
    if back[1] < 0:          # seen from below: the key light comes from below too
        key = doc["lights"][0]["direction"]
        doc["lights"][0]["direction"] = [key[0], -key[1], key[2]]
    if moving is not None:
        from world.camera import Camera
        from world.scene import CameraSpec
        spec = CameraSpec(position=np.array(cam["position"]), look_at=np.array(cam["look_at"]),
                          fov_y=FOV_Y, near=cam["near"], far=cam["far"])
        t = quick_look.pick_time(moving, Camera(spec, doc["render"]["width"],
                                                doc["render"]["height"]), SHUTTER)
    doc["render"]["time"] = _round(t)


def _span(lo: np.ndarray, hi: np.ndarray) -> str:
    return f"{[float(f'{x:.3g}') for x in lo]} to {[float(f'{x:.3g}') for x in hi]}"


def _corners(lo, hi) -> np.ndarray:
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                     for z in (lo[2], hi[2])])


def _distance(lo, hi, back, aspect) -> tuple[float, np.ndarray]:
    """(distance from the box's centre along `back` at which every corner of the box lies
    in the middle FILL of the frame, each corner's offset towards the eye)."""
    centre = 0.5 * (lo + hi)
    right = np.cross(-back, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -back)
    corners = _corners(lo, hi) - centre
    # a corner at depth (d - c.back) from the eye is inside the middle FILL of the frame
    # when |c.right| <= FILL tan(fov/2) aspect (d - c.back), and likewise for up
    tan = math.tan(math.radians(FOV_Y) / 2.0)
    toward = corners @ back
    need = np.maximum(np.abs(corners @ right) / (FILL * tan * aspect),
                      np.abs(corners @ up) / (FILL * tan)) + toward
    return max(float(need.max()), MIN_DISTANCE), toward


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
