"""How far motion strays from a straight, uniform screen path over an exposure.

Every real-time blur reads one chord per pixel, p(t_close) - p(t_open), and spreads the
pixel uniformly along it. A path that turns (rotation), speeds up or slows down
(approach, acceleration) or reverses (a bounce) departs from that. The measure here is,
over the surface points that can be seen, the largest distance in pixels between a
point's projected position at a time inside the exposure and where uniform motion along
its chord would put it then: zero for motion that is straight and uniform on screen, the
sagitta r (1 - cos(theta / 2)) for a point turning by theta on a circle of r px, half the
way out for a path that goes out and comes back.

A sub-exposure of 1/N of the exposure strays about 1/N^2 as far (a smooth path is about
a parabola over a short interval), which is how viewer/render/steps.py turns the measure
into a step count.
"""
from __future__ import annotations

import numpy as np

from world import conventions
from world.camera import Camera
from world.scene import Scene

# Fractions of the exposure at which the paths are sampled: the ends and three inside
# (the middle is the frame time, where a reversal at the frame time turns back).
FRACTIONS = np.linspace(0.0, 1.0, 5)
# Vertices looked at per object, at most (every n-th one beyond): the measure bounds a
# smooth function of the surface point, which a few hundred points sample well.
MAX_POINTS = 128
# Points whose frame-time position lies this far outside the image (px) still count:
# their blur can reach into it.
MARGIN_PX = 64.0
# Paths reaching farther than this from the image (px) at a sampled time are left out:
# every blur clamps them to its limit, and float64 rounding out there (1e20 px at 1e21 m/s)
# would exceed a pixel.
FAR_PX = 1e7


def object_points(obj, t: float = 0.0) -> np.ndarray:
    """At most MAX_POINTS of the object's vertices at time t, homogeneous (4, n): a rigid
    mesh's kept on the object (a frame asks once per mode and step count), a skinned
    mesh's from its pose at t."""
    if obj.skin is not None:
        v = obj.skin.points(t, max(1, -(-len(obj.mesh.vertices) // MAX_POINTS)))
        return np.vstack([v.T, np.ones(len(v))])
    if obj.bend_points is None or obj.bend_points[0] is not obj.mesh:
        v = np.asarray(obj.mesh.vertices, dtype=np.float64)
        v = v[::max(1, -(-len(v) // MAX_POINTS))]
        obj.bend_points = (obj.mesh, np.vstack([v.T, np.ones(len(v))]))
    return obj.bend_points[1]


def screen_bend(scene: Scene, camera: Camera, t: float, shutter: float) -> float:
    """The largest departure (px, at the camera's image size) of a visible surface point's
    screen path over [t - shutter/2, t + shutter/2] from uniform motion along its chord
    (module doc). Points behind the near plane at any sampled time are left out (their
    projection is not a position); so are points far outside the image at time t and
    paths that reach past FAR_PX."""
    camera_moves = scene.camera.moving
    objects = [o for o in scene.objects if camera_moves or o.moving]
    bends = object_bends(scene, camera, t, shutter, objects)
    return float(bends.max()) if len(bends) else 0.0


def object_bends(scene: Scene, camera: Camera, t: float, shutter: float,
                 objects: list) -> np.ndarray:
    """screen_bend's measure for each of `objects` on its own (px; 0 for an object none of
    whose points count)."""
    with np.errstate(all="ignore"):          # (absurd speeds overflow: left out below)
        return _object_bends(scene, camera, t, shutter, objects)


def _object_bends(scene: Scene, camera: Camera, t: float, shutter: float,
                  objects: list) -> np.ndarray:
    bends = np.zeros(len(objects))
    if shutter <= 0.0 or not objects:
        return bends
    t_open, t_close = conventions.exposure(t, shutter)
    times = t_open + FRACTIONS * (t_close - t_open)
    points = [object_points(o) for o in objects]
    local = np.concatenate(points, axis=1)                      # (4, n) all objects'
    owner = np.repeat(np.arange(len(objects)), [p.shape[1] for p in points])
    skinned = any(o.skin is not None for o in objects)
    # clip = P V(t) M(t) p per point, its object's matrix at each time (a skinned mesh's
    # points posed at that time too); clip w is the view depth (GL perspective)
    clip = np.empty((len(times), 4, local.shape[1]))
    for i, ti in enumerate(times):
        vp = camera.projection() @ camera.view(float(ti))
        mats = np.stack([vp @ o.matrix(float(ti)) for o in objects])
        if skinned:
            local = np.concatenate([object_points(o, float(ti)) for o in objects], axis=1)
        clip[i] = np.einsum("nij,jn->in", mats[owner], local)
    depth = clip[:, 3]
    size = np.array([camera.width, camera.height], dtype=np.float64)[:, None]
    win = (clip[:, :2] / np.where(depth > 0.0, depth, 1.0)[:, None] * 0.5 + 0.5) * size
    middle = win[len(times) // 2]
    seen = ((depth > scene.camera.near).all(axis=0)
            & (middle >= -MARGIN_PX).all(axis=0) & (middle <= size + MARGIN_PX).all(axis=0)
            & (np.abs(win) < FAR_PX).all(axis=(0, 1)))
    if not seen.any():
        return bends
    w = win[:, :, seen]
    chord = w[0] + FRACTIONS[:, None, None] * (w[-1] - w[0])
    stray = np.sqrt(((w - chord) ** 2).sum(axis=1)).max(axis=0)
    np.maximum.at(bends, owner[seen], stray)
    return bends
