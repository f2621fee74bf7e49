"""Ray reveal (docs/algorithms.md 4): the surface hidden behind each masked pixel's own object.

One primary ray per pixel through its centre, from the camera at time t (Camera.rays): the
first hit on an object other than the pixel's own (object identity, not luminance). Hits
are clipped to the camera's [near, far] view depth, as the rasteriser clips, so the reveal
sees what a raster pass without the own object would.

Large batches are split into chunks over a thread pool: Embree's `run` releases the GIL
and every ray is independent, so the result does not depend on the split. Within a single
chunk, its Embree calls share the threads from embree_scene.PARALLEL_RAYS rays.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, fields

import numpy as np

from world.camera import Camera
from world.conventions import BACKGROUND_DEPTH

from . import kernels
from .attributes import SurfaceTable
from .embree_scene import RayScene
from .workers import worker_pool

CPUS = os.cpu_count() or 1    # read once: os.cpu_count() costs ~60 us a call here
# Threads pay only for large batches (on 2 cores, and the reveal's own Python between
# Embree calls holds the GIL): tens of thousands of rays run faster on one thread, a
# hundred thousand and more in chunks on several. Chunks of at most this many rays, and
# threads from two chunks.
MIN_CHUNK = 65536    # below this, a thread costs more than it saves
MAX_CHUNK = 65536    # above this, the per-ray temporaries fall out of the caches


@dataclass
class RevealLayer:
    """The revealed surface of n pixels; misses read as object 0."""
    object_id: np.ndarray       # (n,) uint32, 0 = nothing revealed
    prim_id: np.ndarray         # (n,) int32, face index in the object's Mesh.faces; -1 = miss
    barycentrics: np.ndarray    # (n, 2) float32, Embree (u, v): weights of face vertices 1, 2
    distance: np.ndarray        # (n,) float64, from the eye along the unit ray; inf = miss
    depth: np.ndarray           # (n,) float64, view depth at t; BACKGROUND_DEPTH = miss
    world_position: np.ndarray  # (n, 3) float64, eye + distance * dir; zeros on a miss
    static_view: np.ndarray     # (n,) bool: the hit is the first static surface along the
                                # pixel's primary ray (RayScene.intersect's from_view)
    table: SurfaceTable | None = field(default=None, repr=False, compare=False)


@dataclass
class RevealResult:
    layer: RevealLayer
    rays: int = 0          # rays cast: one per pixel, plus every restart
    queries: int = 0       # Embree queries (one ray into one Embree scene)
    restarts: int = 0      # restarts past a static own object
    unresolved: int = 0    # rays that ran out of restarts
    pixels_hit: int = 0    # pixels whose ray found a surface


# Views up to this many pixels keep their static hits (~25 bytes a pixel: 105 MB here).
MAX_VIEW_PIXELS = 1 << 22


def primary_view(camera: Camera, t: float) -> tuple | None:
    """(key, pixel count) naming what a primary ray's static hit depends on: the camera's
    pose at t, its lens and clipping, the image size (RayScene.intersect's `view`); None
    for images too large to keep them, and for a moving camera: its pose changes every
    frame of an animation, so what it kept would never be looked up again (only a frame
    rendered twice, as `hmblur bench` does, would find it, and time what an animation
    never sees)."""
    if camera.width * camera.height > MAX_VIEW_PIXELS or camera.spec.moving:
        return None
    eye, fwd, up = camera.spec.pose(t)
    s = camera.spec
    key = (np.concatenate([eye, fwd, up]).tobytes(), s.fov_y, s.near, s.far,
           camera.width, camera.height)
    return key, camera.width * camera.height


def _reveal_chunk(rs: RayScene, camera: Camera, t: float, pixels_ij: np.ndarray,
                  own_ids: np.ndarray, max_depth: int, view: tuple | None,
                  call_threads: int = 1, matrices=None) -> RevealResult:
    """view: primary_view(camera, t), asked once by reveal() for every chunk."""
    n = len(pixels_ij)
    origin, direction = camera.rays(t, pixels_ij[:, 0], pixels_ij[:, 1])
    _, fwd, up = camera.spec.pose(t)
    # Clip by view depth like the rasteriser: depth = distance * cos(ray, forward).
    cos, near, far = kernels.view_clip(direction, np.asarray(fwd, np.float64),
                                       float(camera.spec.near), float(camera.spec.far))
    # The rays are the view's primary rays: their static hits are kept.
    primary = {} if view is None else {
        "view": view, "pixels": pixels_ij[:, 1] * camera.width + pixels_ij[:, 0]}
    hits = rs.intersect(origin, direction, t, np.asarray(own_ids, dtype=np.uint32).reshape(n),
                        max_restarts=max_depth, tnear=near, tfar=far, threads=call_threads,
                        image_axes=(fwd, up), matrices=matrices, **primary)
    # The rays are unit length from the eye: view depth = distance * cos(ray, forward).
    depth, world, bary = kernels.layer_columns(hits.object_id, hits.distance, hits.u, hits.v,
                                               origin, direction, cos, BACKGROUND_DEPTH)
    layer = RevealLayer(object_id=hits.object_id, prim_id=hits.prim_id, barycentrics=bary,
                        distance=hits.distance, depth=depth, world_position=world,
                        static_view=hits.from_view, table=rs.surfaces)
    return RevealResult(layer, rays=len(hits.object_id) + hits.restarts, queries=hits.queries,
                        restarts=hits.restarts, unresolved=hits.unresolved,
                        pixels_hit=int(np.count_nonzero(hits.object_id)))


def _concatenate(parts: list[RevealResult]) -> RevealResult:
    if len(parts) == 1:
        return parts[0]
    cols = {f.name: np.concatenate([getattr(p.layer, f.name) for p in parts])
            for f in fields(RevealLayer) if f.name != "table"}
    out = RevealResult(RevealLayer(**cols, table=parts[0].layer.table))
    for name in ("rays", "queries", "restarts", "unresolved", "pixels_hit"):
        setattr(out, name, sum(getattr(p, name) for p in parts))
    return out


def reveal(rs: RayScene, camera: Camera, t: float, pixels_ij, own_ids, max_depth: int = 8,
           threads: int | None = None, min_chunk: int = MIN_CHUNK, max_chunk: int = MAX_CHUNK,
           matrices=None) -> RevealResult:
    """Reveal what lies behind each pixel's own object.

    pixels_ij: (n, 2) int image coordinates (column i from the left, row j from the top).
    own_ids: (n,) the object id of each pixel (0 for none: plain primary rays).
    max_depth: restarts allowed to pass a static own object.
    threads: worker threads for large batches (default: the CPU count; 1 = no pool).
    min_chunk, max_chunk: the fewest pixels worth a thread's chunk, the most in one chunk.
    matrices: M(t) of each of rs.moving's objects, as SceneObject.matrix(t) gives it, where
    the caller has them already (RayScene.intersect's).
    """
    pixels_ij = np.asarray(pixels_ij, dtype=np.int64).reshape(-1, 2)
    own_ids = np.asarray(own_ids, dtype=np.uint32).reshape(-1)
    if len(own_ids) != len(pixels_ij):
        raise ValueError(f"{len(pixels_ij)} pixels but {len(own_ids)} own ids")
    n = len(pixels_ij)
    view = primary_view(camera, t)
    if view is not None:
        rs.static_view(view)         # made here, not by racing threads
    threads = CPUS if threads is None else max(1, int(threads))
    n_chunks = max(-(-n // max(1, max_chunk)),
                   min(threads * 4, n // max(1, min_chunk)) if threads > 1 else 1)
    if n_chunks <= 1:     # one chunk: its independent Embree calls may share the threads
        return _reveal_chunk(rs, camera, t, pixels_ij, own_ids, max_depth, view, threads,
                             matrices)
    bounds = np.linspace(0, n, n_chunks + 1).astype(np.int64)

    def run(k):
        a, b = bounds[k], bounds[k + 1]
        return _reveal_chunk(rs, camera, t, pixels_ij[a:b], own_ids[a:b], max_depth, view,
                             matrices=matrices)

    if threads == 1:
        return _concatenate([run(k) for k in range(n_chunks)])
    return _concatenate(list(worker_pool("reveal", threads).map(run, range(n_chunks))))
