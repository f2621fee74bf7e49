"""Nearest-hit ray casting against a scene whose objects move, with Embree and no rebuilds.

embreex has no instancing, no transforms and no refit, so the geometry is split once:
every static object goes into one world-space Embree scene (one geometry each, so the
geometry index names the object), and every moving object gets its own Embree scene in
its local mesh coordinates. At time t a ray is carried into a moving object's space by
the inverse of M(t); the direction is NOT renormalised, so Embree's hit parameter is
still the distance along the unit world direction. Only the rays that meet the moving
object's world box at t (a slab test on the mesh's local box carried by M(t)) go into its
scene. The nearest valid hit over all the scenes wins.

A ray must pass its own object (the masked pixel's surface). A moving one is simply not
traced, nor the objects that move rigidly with it (its children that do not move on their
own, its parents'). A static one lives in the shared static scene, so the ray is traced instead in an
"exclusion scene", the static objects but that one, built the first time a ray needs it
(static geometry only, so once per scene, within a triangle budget); past the budget, or
where asked, the ray restarts just past each hit on its own object.

embreex's `run` starts every ray at tnear = 0 and takes no tnear, so a ray that must
start further along (a restart past an excluded static object, a near plane, a deeper
layer) has its origin moved forward instead, and the offset is added back to the
distance it reports.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from embreex import rtcore as rtc
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh

from world.scene import Scene, SceneObject
from world import transforms as tf
from world.transforms import box_corners

from . import kernels
from .attributes import SurfaceTable
from .workers import run_all

# Triangles that the exclusion scenes of one RayScene may hold together: a static scene of
# 100 k triangles gets ~10 of them (Embree's BVH ~ 100 bytes a triangle: ~100 MB).
EXCLUSION_BUDGET = 1_000_000
# Rays in one Embree call (or in the exclusion scenes' calls of one intersect() together)
# from which they are split over the worker threads: below, handing work to a thread costs
# more than it saves (on 2 cores, tens of thousands of rays gain, a few thousand lose).
PARALLEL_RAYS = 8192


class StaticHits:
    """Per pixel of one view, the nearest static hit of its primary ray, once traced."""

    def __init__(self, key, size: int):
        self.key = key
        self.known = np.zeros(size, dtype=bool)
        self.object_id = np.zeros(size, dtype=np.uint32)
        self.prim_id = np.full(size, -1, dtype=np.int32)
        self.u = np.zeros(size, dtype=np.float32)
        self.v = np.zeros(size, dtype=np.float32)
        self.distance = np.full(size, np.inf)


@dataclass
class Hits:
    """Nearest hit of each ray.

    Barycentrics are Embree's: the hit point is (1 - u - v) * V0 + u * V1 + v * V2 where
    V0, V1, V2 are the vertices of `Mesh.faces[prim_id]` in that order.
    """
    object_id: np.ndarray      # (n,) uint32, 0 = miss
    prim_id: np.ndarray        # (n,) int32, face index in the object's Mesh.faces; -1 = miss
    u: np.ndarray              # (n,) float32
    v: np.ndarray              # (n,) float32
    distance: np.ndarray       # (n,) float64, world units along the unit direction; inf = miss
    restarts: int = 0          # rays re-issued past an excluded static object
    unresolved: int = 0        # rays still on their excluded static object after max_restarts
    queries: int = 0           # Embree ray queries issued (one ray into one Embree scene)
    # (n,) bool: the hit is the view's kept static hit (intersect's `view`): the first static
    # surface along the pixel's primary ray, what a raster of the static objects shows there.
    from_view: np.ndarray | None = None


@dataclass
class RayBatch:
    """The rays of one RayScene.intersect call and their nearest hits so far: what each of
    its stages (the moving objects, the exclusion scenes, the view's kept static hits, the
    static scene) reads and narrows. Every hit array is (n,) and updated in place."""
    o: np.ndarray              # (n, 3) float64 origins
    d: np.ndarray              # (n, 3) float64 directions
    excl: np.ndarray           # (n,) uint32: the object each ray must pass (0: none)
    start: np.ndarray          # (n,) float64: tnear, from o along d
    limit: np.ndarray          # (n,) float64: tfar
    from_eye: bool             # every ray starts at o[0] (primary rays)
    shared: bool               # ... and at tnear 0: one point to carry into a mover's space
    o32: np.ndarray            # Embree's rays: origins moved to tnear, float32
    d32: np.ndarray
    inv_d: np.ndarray          # 1 / d, for the box tests
    object_id: np.ndarray      # (n,) uint32, 0 = no hit yet
    prim_id: np.ndarray        # (n,) int32
    u: np.ndarray              # (n,) float32
    v: np.ndarray              # (n,) float32
    best: np.ndarray           # (n,) float64: the nearest hit so far bounds every later query
    from_view: np.ndarray      # (n,) bool: the hit is the view's kept static hit
    queries: int = 0
    restarts: int = 0
    unresolved: int = 0

    @classmethod
    def of(cls, origins, dirs, exclude_ids=None, tnear=None, tfar=None) -> "RayBatch":
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.asarray(dirs, dtype=np.float64).reshape(-1, 3)
        n = len(o)
        excl = (np.zeros(n, dtype=np.uint32) if exclude_ids is None
                else np.asarray(exclude_ids, dtype=np.uint32).reshape(n))
        start = np.zeros(n) if tnear is None else np.asarray(tnear, dtype=np.float64).reshape(n)
        limit = np.full(n, np.inf) if tfar is None else np.asarray(tfar, dtype=np.float64).reshape(n)
        # The box test takes [start, best] along the rays from their own origins, not
        # from o32 (Embree's origins, moved to tnear). Primary rays share the eye
        # (Camera.rays broadcasts it: stride 0): box-test from one point, and without a
        # tnear carry one point into each object's space, not n.
        from_eye = n > 1 and (o.strides[0] == 0 or bool((o == o[0]).all()))
        o32, d32, inv_d = kernels.ray_arrays(o, d, start, from_eye)
        return cls(o, d, excl, start, limit, from_eye, from_eye and tnear is None, o32, d32,
                   inv_d, object_id=np.zeros(n, dtype=np.uint32),
                   prim_id=np.full(n, -1, dtype=np.int32), u=np.zeros(n, dtype=np.float32),
                   v=np.zeros(n, dtype=np.float32), best=limit.copy(),
                   from_view=np.zeros(n, dtype=bool))

    @property
    def n(self) -> int:
        return len(self.o)

    def merge(self, rows, r: dict, ids: np.ndarray, start=None, object_id: int = -1):
        """Take Embree's hits `r` of `rows` (None: all rays) nearer than the best so far;
        ids: geomID + 1 -> object id, or object_id >= 0 for every hit (a mover's scene).
        start: where the rays of `r` began (default: tnear)."""
        kernels.merge_hits(np.arange(self.n) if rows is None else rows, r["geomID"],
                           r["primID"], r["u"], r["v"], r["tfar"],
                           self.start if start is None else start, self.best, self.object_id,
                           self.prim_id, self.u, self.v, ids, object_id)

    def hits(self) -> Hits:
        distance = np.where(self.object_id != 0, self.best, np.inf)
        return Hits(self.object_id, self.prim_id, self.u, self.v, distance, self.restarts,
                    self.unresolved, self.queries, self.from_view)


def transform_points(m: np.ndarray, p: np.ndarray, w: float = 1.0) -> np.ndarray:
    """Rows of p (n, 3) through the 4x4 m (column vectors), in p's dtype, column by
    column: no BLAS (OpenBLAS spreads an (n, 3) x (3, 3) product over its threads, ten
    times slower on a busy machine) and no (n, 3, 3) temporaries (einsum, broadcasting)."""
    m = m.astype(p.dtype)
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    out = np.empty_like(p)
    for i in range(3):
        out[:, i] = m[i, 0] * x + m[i, 1] * y + m[i, 2] * z + w * m[i, 3]
    return out


def transform_vectors(m: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Rows of p (n, 3) through the upper 3x3 of m (directions: no translation)."""
    return transform_points(m, p, 0.0)


@dataclass
class Poses:
    """The moving objects (RayScene.moving, in order) at one time t."""
    lo: np.ndarray        # (m, 3) float64: world box at t, padded (for the box test)
    hi: np.ndarray
    inv: np.ndarray       # (m, 4, 4) float32: M(t)^-1
    rotate: np.ndarray    # (m,) bool: M(t)^-1 turns or scales (else directions stay)


_NO_IDS = np.zeros(1, np.uint32)     # (merge_hits' table where a mover names every hit)

# Moving objects from which the box tests take their rays from a RowIndex: building it
# (~0.1 ms for 30 k rays) costs what ~10 box tests over every ray cost.
ROW_INDEX_MOVERS = 8


class RowIndex:
    """Primary rays from one eye in image row order: the key -(d . up) / (d . forward)
    (the tangent of the ray's angle below the view direction) runs monotonically with the
    row, so the rays that can meet a box lie in one contiguous span, found by bisection:
    those whose key lies within the keys of the box's corners (the key is a ratio of
    linear functions, so over a box wholly in front of the eye its extremes are at
    corners). A box not wholly in front spans every ray."""

    ROUNDING = 1e-9

    def __init__(self, eye, key, forward, up):
        self.eye, self.key, self.forward, self.up = eye, key, forward, up

    @classmethod
    def of(cls, eye, d, forward, up) -> "RowIndex | None":
        """The index of rays d (n, 3) from `eye`, None where there is none (a ray not in
        front of the eye, rays not in image row order). Within a row the key is one value
        up to rounding (~1e-16): rows in order, and the running maximum (within ROUNDING
        of the key, far inside spans' pad) to bisect (kernels.row_keys)."""
        fwd, up = np.asarray(forward, np.float64), np.asarray(up, np.float64)
        key, sign = kernels.row_keys(np.ascontiguousarray(d, np.float64), fwd, up,
                                     cls.ROUNDING)
        if sign == 0.0:
            return None
        return cls(np.asarray(eye, np.float64), key, fwd, sign * up)

    def spans(self, lo, hi) -> np.ndarray:
        """(m, 2) [first, end) ray spans of m boxes [lo, hi] ((m, 3) each), all at once;
        the float rounding of the rays' keys padded by 1e-6 relative (kernels.row_spans)."""
        return kernels.row_spans(self.key, self.eye, self.forward, self.up,
                                 np.ascontiguousarray(lo, np.float64),
                                 np.ascontiguousarray(hi, np.float64), 1e-6)


def _embree_run(scene: rtcs.EmbreeScene, origins: np.ndarray, dirs: np.ndarray,
                tfar: np.ndarray, threads: int = 1) -> dict:
    """Embree's nearest hits (run(..., output=1)); with threads > 1 and PARALLEL_RAYS rays
    or more, in parts of at least half that many side by side (the rays are independent)."""
    n = len(origins)
    k = min(threads, n // (PARALLEL_RAYS // 2))
    if k > 1:
        b = np.linspace(0, n, k + 1).astype(np.int64)
        parts = run_all([lambda a=a, e=e: _embree_run(scene, origins[a:e], dirs[a:e], tfar[a:e])
                         for a, e in zip(b[:-1], b[1:])], list(np.diff(b)), k, "embree")
        return {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    # run() writes the hit distances into `dists` in place: always hand it a fresh array.
    return scene.run(np.ascontiguousarray(origins, dtype=np.float32),
                     np.ascontiguousarray(dirs, dtype=np.float32),
                     dists=np.array(tfar, dtype=np.float32), output=1)



def body_of(obj) -> int:
    """The rigid body a moving object belongs to: the nearest of it and its parents that
    moves on its own (keys, velocities, a skin, a glTF node's animation), or the topmost
    placement; objects with the same body keep their relative pose at every time. (Under
    a moving camera their parallax within one exposure is neglected.)"""
    node = obj
    while (getattr(node, "skin", None) is None and not getattr(node, "own_moving", True)
           and getattr(node, "parent", None) is not None):
        node = node.parent
    return id(node)

class RayScene:
    """The Embree side of one loaded scene: built once, traced at any time t."""

    def __init__(self, scene: Scene, restart_eps: float = 1e-5,
                 exclusion_budget: int = EXCLUSION_BUDGET):
        """exclusion_budget: triangles all exclusion scenes may hold together (0: pass
        static own objects by restarts only)."""
        self.scene = scene
        self.exclusion_budget = int(exclusion_budget)
        self._without: dict[int, tuple[rtcs.EmbreeScene, np.ndarray] | None] = {}
        self._without_triangles = 0
        # A restart moves the origin past the excluded hit by restart_eps * (1 + |p|_max):
        # about a hundred float32 ulps of the hit point's coordinates, so the same face
        # is not found again, and far thinner than any wall of a real mesh.
        self.restart_eps = float(restart_eps)
        self.objects: dict[int, SceneObject] = {o.id: o for o in scene.objects}
        self.surfaces = SurfaceTable(self.objects)     # hit attributes, raytrace/attributes.py
        self._device = rtc.EmbreeDevice()

        static = [o for o in scene.objects if not o.moving and len(o.mesh.faces)]
        self.static_ids = np.array([o.id for o in static], dtype=np.uint32)  # geomID -> id
        # geomID + 1 -> object id, with geomID -1 (a miss) -> 0.
        self._id_of = np.concatenate([np.zeros(1, np.uint32), self.static_ids])
        self._is_static = np.zeros(max([o.id for o in scene.objects], default=0) + 1, bool)
        self._is_static[self.static_ids] = True
        self.cull = True      # the world-box test before each moving object (tests: off)
        # World-space triangles of each static object (its matrix does not depend on t).
        self._static_meshes = {
            o.id: (transform_points(o.matrix(0.0), np.asarray(o.mesh.vertices, np.float64))
                   .astype(np.float32), o.mesh.faces.astype(np.int32)) for o in static}
        self._static = self._static_scene(self.static_ids) if static else None

        self._static_hits: StaticHits | None = None
        self.moving: list[tuple[SceneObject, rtcs.EmbreeScene]] = []
        built: dict[int, rtcs.EmbreeScene] = {}     # a mesh shared by rigid movers: one scene
        for o in scene.objects:
            if o.moving and len(o.mesh.faces):
                if o.skin is None and id(o.mesh) in built:
                    es = built[id(o.mesh)]
                else:
                    es = self._mesh_scene(o.vertices_at(0.0), o.mesh.faces)
                    if o.skin is None:
                        built[id(o.mesh)] = es
                self.moving.append((o, es))
        # A skinned mover's scene holds its mesh posed at one time: rebuilt for each new t
        # (embreex has no refit), the time it takes counted in skin_ms.
        self._skinned = [k for k, (o, _) in enumerate(self.moving) if o.skin is not None]
        self._skin_time = tuple(self.moving[k][0].skin.stamp(0.0) for k in self._skinned)
        self.skin_ms, self.skin_builds = 0.0, 0
        # The corners of each moving mesh's local bounding box: at time t their world
        # box culls the rays that cannot hit the object before any Embree call.
        self._moving_ids = np.array([o.id for o, _ in self.moving], np.uint32)
        # A ray passes every mover of its own object's rigid body (body_of), not just that
        # object: what moves with it cannot be uncovered by its motion (a wheel under a
        # car's body would be revealed as the background). _body maps an object id to its
        # body's first mover's id (itself where it moves alone, and for static objects).
        self._body = np.arange(max((o.id for o in scene.objects), default=0) + 1,
                               dtype=np.uint32)
        first: dict[int, int] = {}
        for o, _ in self.moving:
            self._body[o.id] = first.setdefault(body_of(o), o.id)
        self._moving_bodies = self._body[self._moving_ids]
        self._corners = np.array([box_corners(o.vertices_at(0.0)) for o, _ in self.moving]
                                 ).reshape(-1, 8, 3)
        self._pose_cache: tuple | None = None

    def _mesh_scene(self, vertices: np.ndarray, faces: np.ndarray) -> rtcs.EmbreeScene:
        es = rtcs.EmbreeScene(self._device)
        TriangleMesh(es, np.asarray(vertices, np.float32), faces.astype(np.int32))
        return es

    def pose_skins(self, t: float):
        """The skinned movers' scenes and boxes posed at time t (kept while t holds)."""
        if not self._skinned:
            return
        stamp = tuple(self.moving[k][0].skin.stamp(t) for k in self._skinned)
        if stamp == self._skin_time:
            return
        t0 = time.perf_counter()
        for k in self._skinned:
            obj = self.moving[k][0]
            v = obj.vertices_at(t)
            self.moving[k] = (obj, self._mesh_scene(v, obj.mesh.faces))
            self._corners[k] = box_corners(v)
        self._skin_time = stamp
        self.skin_ms += (time.perf_counter() - t0) * 1e3
        self.skin_builds += 1

    def _static_scene(self, ids: np.ndarray) -> rtcs.EmbreeScene:
        """One Embree scene of the static objects `ids`, geometry k = ids[k]."""
        es = rtcs.EmbreeScene(self._device)
        for i in ids:
            TriangleMesh(es, *self._static_meshes[int(i)])
        return es

    def exclusion_scene(self, own: int):
        """(Embree scene, geomID + 1 -> object id) of the static objects but `own`, built
        on first use; None past the triangle budget (the caller restarts instead)."""
        if own not in self._without:
            ids = self.static_ids[self.static_ids != own]
            size = sum(len(self._static_meshes[int(i)][1]) for i in ids)
            if not len(ids) or self._without_triangles + size > self.exclusion_budget:
                self._without[own] = None
            else:
                self._without_triangles += size
                self._without[own] = (self._static_scene(ids), np.r_[np.uint32(0), ids])
        return self._without[own]

    def _poses(self, t: float, matrices=None) -> "Poses":
        """The moving objects at time t (Poses), all at once in compiled calls (an
        animation's every frame has a new t: per object, np.linalg.inv alone cost ~9 us,
        32 movers 0.3 ms); kept for the last M(t)s (every layer and chunk of a frame asks
        again)."""
        self.pose_skins(t)
        if matrices is None:
            matrices = [obj.matrix(t) for obj, _ in self.moving]
        ms = np.stack(matrices) if len(matrices) else np.zeros((0, 4, 4))
        key = (ms.tobytes(), self._skin_time if self._skinned else None)
        if self._pose_cache is None or self._pose_cache[0] != key:
            lo, hi = kernels.world_boxes(ms, self._corners, 1e-4, 1e-6)
            inv, ok = kernels.affine_inverses(ms)
            if not ok:                  # (a determinant too small or too large for it)
                inv = np.stack([tf.limit_inverse(m) for m in ms]).astype(np.float32)
            # Not renormalised, so t stays in world units; a pure translation keeps them.
            self._pose_cache = (key, Poses(lo, hi, inv, kernels.turns_or_scales(inv)))
        return self._pose_cache[1]

    def static_view(self, view: tuple) -> "StaticHits":
        """The static scene's hits kept for `view` = (key, number of pixels), fresh when the
        key changes (the static geometry never does)."""
        key, size = view
        if self._static_hits is None or self._static_hits.key != key:
            self._static_hits = StaticHits(key, int(size))
        return self._static_hits

    def intersect(self, origins, dirs, t: float, exclude_ids=None, max_restarts: int = 8,
                  tnear=None, tfar=None, view: tuple | None = None, pixels=None,
                  threads: int = 1, image_axes: tuple | None = None, matrices=None) -> Hits:
        """Nearest hit per ray at time t, skipping each ray's excluded object.

        origins, dirs: (n, 3); dirs should be unit length for `distance` to be metres.
        exclude_ids: (n,) object id each ray must pass through (0 or None: none). A moving
        one is simply not traced, nor any other mover of its rigid body (body_of); a static one is passed by restarting the ray just past
        each hit on it, at most `max_restarts` times (then the ray reports what else it found
        nearer, or a miss, and counts as unresolved).
        tnear, tfar: optional (n,) distances along the ray bounding the hits (clipping);
        distances are still reported from `origins`.
        view, pixels: the rays are the primary rays of one view through pixels `pixels`
        ((n,) indices below view[1]), and view[0] names everything they depend on (camera
        pose, size, clipping): a ray's nearest static hit is then the same in every frame
        of that view, so it is traced once and looked up after (not for rays that must pass
        a static object of their own).
        threads: Embree's calls run on up to this many worker threads from PARALLEL_RAYS
        rays: the exclusion scenes' calls (each ray in one of them) side by side, another
        call split into parts.
        image_axes: (forward, up) of the camera whose pixels the rays go through, in image
        row order (as the reveal reads its mask): each moving object's box test then takes
        only the rows its box covers on screen (RowIndex), not every ray.
        matrices: M(t) of each object of self.moving, in order, as SceneObject.matrix(t)
        gives it, where the caller has them already (a frame's G-buffer made them: asking
        each object again costs host time in every frame); None: asked here.
        """
        b = RayBatch.of(origins, dirs, exclude_ids, tnear, tfar)
        if self.moving:
            self._trace_movers(b, t, matrices, image_axes, threads)
        if self._static is None:
            return b.hits()
        static_own = kernels.member(b.excl, self._is_static)
        rows = self._trace_exclusions(b, static_own, threads) if b.excl.any() else None
        if view is not None:
            rows = self._trace_view(b, static_own, view, pixels, rows, threads)
        if rows is None or rows.size:
            self._trace_static(b, rows, max_restarts, threads)
        return b.hits()

    def _trace_movers(self, b: RayBatch, t: float, matrices, image_axes, threads: int):
        """Each moving object's scene, in the object's own space, for the rays that may
        hit its world box at t within [start, best] (best as it stands before any of them:
        one compiled call, not one per object); a ray passes every mover of its own
        object's rigid body. (Nothing of this without moving objects: a camera passing
        static ones would pay it in every frame.)"""
        poses = self._poses(t, matrices)
        bodies = self._body[b.excl]
        if self.cull:
            culled, cuts = self._cull(b, poses, bodies, image_axes)
        body = self._moving_bodies.tolist()
        movers = zip(self.moving, poses.inv, poses.rotate.tolist())
        for k, ((obj, es), inv, rotate) in enumerate(movers):
            rows = (culled[cuts[k]:cuts[k + 1]] if self.cull
                    else np.flatnonzero(bodies != body[k]))
            if not rows.size:
                continue
            lo, ld, tfar = kernels.local_rays(b.o32, b.d32, rows, b.shared, inv, rotate,
                                              b.start, b.best)
            r = _embree_run(es, lo, ld, tfar, threads)
            b.queries += rows.size
            b.merge(rows, r, _NO_IDS, object_id=obj.id)

    def _cull(self, b: RayBatch, poses: Poses, bodies, image_axes) -> tuple:
        """(rows, cuts): the rays of mover k that meet its world box are
        rows[cuts[k]:cuts[k + 1]]; with image_axes and enough movers, each box tests only
        the rows it covers on screen (RowIndex)."""
        n, m = b.n, len(self.moving)
        o_box = b.o[:1].astype(np.float32) if b.from_eye else b.o.astype(np.float32)
        index = (RowIndex.of(b.o[0], b.d, *image_axes)
                 if b.from_eye and image_axes is not None and m >= ROW_INDEX_MOVERS else None)
        spans = (np.tile(np.array([0, n], np.int64), (m, 1)) if index is None
                 else index.spans(poses.lo, poses.hi))
        culled, cuts = kernels.boxes_rows(o_box, b.inv_d, b.from_eye, poses.lo, poses.hi,
                                          b.start, b.best, bodies, self._moving_bodies, spans)
        return culled, cuts.tolist()

    def _trace_exclusions(self, b: RayBatch, static_own, threads: int):
        """The rays whose own object is static, each into the static scene without it where
        one exists (their calls side by side from PARALLEL_RAYS rays); the rays left for
        the static scene (None: all)."""
        # The rays of each own object, in ray order (a counting sort, not a scan each).
        order, starts = kernels.group_rows(b.excl, static_own)
        passed = np.zeros(b.n, dtype=bool)
        groups = []
        for a, e in zip(starts[:-1], starts[1:]):
            sel = order[a:e]
            ex = self.exclusion_scene(int(b.excl[sel[0]]))
            if ex is not None:
                groups.append((sel, ex))
                passed[sel] = True

        def call(sel, es):     # reads best[sel] only: the groups are disjoint
            return lambda: _embree_run(es, *kernels.gather_rays(b.o32, b.d32, b.start, b.best,
                                                                sel))
        sizes = [sel.size for sel, _ in groups]
        results = run_all([call(sel, es) for sel, (es, _) in groups], sizes,
                          threads if sum(sizes) >= PARALLEL_RAYS else 1, "embree")
        for (sel, (_, ex_ids)), r in zip(groups, results):
            b.queries += sel.size
            b.merge(sel, r, ex_ids)
        return np.flatnonzero(~passed) if passed.any() else None

    def _trace_view(self, b: RayBatch, static_own, view: tuple, pixels, rows, threads: int):
        """The view's static hits, looked up (where not yet known, traced, kept and then
        taken), for the rays that pass no static object of their own; the rays left for
        the static scene."""
        hits = self.static_view(view)
        left = np.arange(b.n) if rows is None else rows
        r_new, k_new, rows = kernels.view_lookup(
            left, static_own, np.asarray(pixels, dtype=np.int64).reshape(b.n), hits.known,
            hits.object_id, hits.prim_id, hits.u, hits.v, hits.distance, b.best, b.object_id,
            b.prim_id, b.u, b.v, b.from_view)
        if r_new.size:
            r = _embree_run(self._static,
                            *kernels.gather_rays(b.o32, b.d32, b.start, b.limit, r_new), threads)
            b.queries += r_new.size
            kernels.view_store(r_new, k_new, r["geomID"], r["primID"], r["u"], r["v"],
                               r["tfar"], b.start, self._id_of, hits.known, hits.object_id,
                               hits.prim_id, hits.u, hits.v, hits.distance, b.best,
                               b.object_id, b.prim_id, b.u, b.v, b.from_view)
        return rows

    def _trace_static(self, b: RayBatch, rows, max_restarts: int, threads: int):
        """`rows` (None: all rays) into the shared static scene; a ray that hits its own
        static object restarts just past it, at most max_restarts times."""
        def take(a, rows):
            return a if rows is None else a[rows]
        id_of = self._id_of
        offset, org = b.start.copy(), None
        for depth in range(max_restarts + 1):
            s0 = take(offset, rows)
            if rows is None:
                r = _embree_run(self._static, b.o32, b.d32, b.best - s0, threads)
            elif org is None:           # from the starts: one compiled gather
                r = _embree_run(self._static, *kernels.gather_rays(b.o32, b.d32, b.start,
                                                                   b.best, rows), threads)
            else:                       # restarted past an own static object
                r = _embree_run(self._static, org, b.d32[rows], take(b.best, rows) - s0,
                                threads)
            b.queries += len(s0)
            ids = id_of[r["geomID"] + 1]
            dist = s0 + r["tfar"]
            own = (ids == take(b.excl, rows)) & (ids != 0)
            if own.any():
                r["geomID"][own] = -1
            b.merge(rows, r, id_of, offset)
            if not own.any():
                return
            if depth == max_restarts:
                b.unresolved = int(own.sum())
                return
            rows = np.flatnonzero(own) if rows is None else rows[own]
            dist = dist[own]
            p = b.o[rows] + b.d[rows] * dist[:, None]
            scale = np.maximum(np.maximum(np.abs(p[:, 0]), np.abs(p[:, 1])), np.abs(p[:, 2]))
            offset[rows] = dist + self.restart_eps * (1.0 + scale)
            org = b.o[rows] + b.d[rows] * offset[rows, None]
            b.restarts += rows.size
