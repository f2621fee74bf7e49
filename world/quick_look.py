"""What a bare asset's quick look (world/asset_scene.py) looks at: the parts that move over
the animation, a direction from which static parts of the asset do not hide them, and a
time at which they move on screen (docs/scene-format.md, "A glTF file as a scene").

The parts that move are the objects whose vertices (skinned ones posed) change between
the sampled times. The direction is the first of DIRECTIONS, in order, whose view of the
moving parts (probe points on them, at every sampled time) the asset's static triangles
block least, within SEEN_SLACK of the best, by casting the rays with Embree. The time is
the sample nearest the middle of the animation at which the moving parts move on screen
at least MIDDLE_SHARE as fast as at the sample where they move most.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Centre -> eye directions tried, in order of preference: from above (front right first,
# the view of an asset without hidden moving parts), then level, then from below.
DIRECTIONS = np.array([
    [0.6, 0.45, 1.0], [-0.6, 0.45, 1.0], [0.6, 0.45, -1.0], [-0.6, 0.45, -1.0],
    [0.3, 0.15, 1.0], [1.0, 0.15, -0.3], [-0.3, 0.15, -1.0], [-1.0, 0.15, 0.3],
    [0.6, -0.45, 1.0], [-0.6, -0.45, 1.0], [0.6, -0.45, -1.0], [-0.6, -0.45, -1.0],
])
SEEN_SLACK = 0.05      # a later direction wins only when it sees more than this more
PROBES = 512           # probe points on the moving parts (spread over their vertices)
MOVED = 1e-5           # of a part's box diagonal: a part whose vertices move less is still
MIDDLE_SHARE = 0.5     # of the most screen motion: a time that moves less is passed over


@dataclass
class Motion:
    """The moving objects of a scene over `times`: their world box, each one's probe
    vertex indices, and the static objects (the occluders)."""
    times: np.ndarray
    moving: list                 # [(SceneObject, probe vertex indices)]
    static: list                 # [SceneObject]
    lo: np.ndarray               # the moving parts' box over the times
    hi: np.ndarray

    def probes(self, t: float) -> np.ndarray:
        """World positions of the probe vertices at time t, (n, 3)."""
        return np.concatenate([_world(o, t, idx) for o, idx in self.moving])


def _world(o, t: float, idx=None) -> np.ndarray:
    v = o.vertices_at(t)
    if idx is not None:
        v = v[idx]
    m = o.matrix(t)
    return v @ m[:3, :3].T + m[:3, 3]


def motion(scene, times) -> Motion | None:
    """The parts of `scene` that move over `times` (None where nothing moves)."""
    moving, static = [], []
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for o in scene.objects:
        if not o.moving:
            static.append(o)
            continue
        first = _world(o, times[0])
        olo, ohi, moved = first.min(axis=0), first.max(axis=0), 0.0
        for t in times[1:]:
            w = _world(o, t)
            moved = max(moved, float(np.abs(w - first).max()))
            olo, ohi = np.minimum(olo, w.min(axis=0)), np.maximum(ohi, w.max(axis=0))
        if moved > MOVED * float(np.linalg.norm(ohi - olo)):
            moving.append(o)
            lo, hi = np.minimum(lo, olo), np.maximum(hi, ohi)
        else:
            static.append(o)
    if not moving:
        return None
    counts = np.array([len(o.vertices_at(times[0])) for o in moving])
    share = np.maximum(1, np.round(PROBES * counts / counts.sum())).astype(int)
    picked = [(o, np.unique(np.linspace(0, n - 1, min(n, k)).round().astype(np.int64)))
              for o, n, k in zip(moving, counts, share)]
    return Motion(np.asarray(times, np.float64), picked, static, lo, hi)


def seen_fraction(m: Motion, eyes: np.ndarray) -> np.ndarray:
    """For each eye (k, 3), the fraction of the probe points at every sampled time that no
    static triangle of the asset hides from it."""
    points = np.concatenate([m.probes(t) for t in m.times])
    tris = [_world(o, float(m.times[0]))[o.mesh.faces] for o in m.static]
    tris = [t for t in tris if len(t)]
    if not tris:
        return np.ones(len(eyes))
    from embreex import rtcore as rtc
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh
    device = rtc.EmbreeDevice()
    es = rtcs.EmbreeScene(device)
    TriangleMesh(es, np.ascontiguousarray(np.concatenate(tris), np.float32))
    out = []
    for eye in eyes:
        d = points - eye
        length = np.linalg.norm(d, axis=1)
        ok = length > 0
        dirs = np.where(ok[:, None], d / np.where(ok, length, 1.0)[:, None], [0.0, 0.0, 1.0])
        origins = np.broadcast_to(eye, points.shape)
        # a hit short of the point (less a sliver, for a point on a face the static part
        # touches) hides it
        far = np.maximum(length * (1.0 - 1e-4) - 1e-6, 0.0)
        geom = es.run(np.ascontiguousarray(origins, np.float32),
                      np.ascontiguousarray(dirs, np.float32),
                      dists=np.array(far, np.float32), output=1)["geomID"]
        out.append(float(np.mean(geom < 0)))
    return np.array(out)


def pick_direction(scores: np.ndarray) -> int:
    """The first direction that sees within SEEN_SLACK of the best."""
    return int(np.flatnonzero(scores >= scores.max() - SEEN_SLACK)[0])


def pick_time(m: Motion, camera, shutter: float) -> float:
    """The sample time nearest the middle (the middle itself first, then the earlier of
    two as near) at which the moving parts' mean screen motion over the shutter is at
    least MIDDLE_SHARE of the most at any interior sample. The ends are left out: a looped
    animation that does not end where it began jumps there."""
    times = m.times
    mid = len(times) // 2
    inner = list(range(1, len(times) - 1)) or [mid]
    pixels = []
    for k in inner:
        t = float(times[k])
        a, da = camera.project(t, m.probes(t - 0.5 * shutter))
        b, db = camera.project(t, m.probes(t + 0.5 * shutter))
        front = (da > 0) & (db > 0)
        pixels.append(float(np.linalg.norm(b - a, axis=1)[front].mean()) if front.any() else 0.0)
    pixels = np.array(pixels)
    moving = [k for k, p in zip(inner, pixels) if p >= MIDDLE_SHARE * pixels.max()]
    return float(times[min(moving, key=lambda k: (abs(k - mid), k))])
