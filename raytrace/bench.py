"""The ceiling for the reveal's throughput: bare Embree `run` calls on exactly the rays the
reveal traced, into the scenes it traced them in, with nothing else timed (no box tests,
restarts, view look-ups, attribute fetches or Python bookkeeping). The rays are carried
into each moving object's space and grouped before the clock starts."""
from __future__ import annotations

import time

import numpy as np

from .embree_scene import RayScene, _embree_run, transform_points, transform_vectors


def ceiling_jobs(batch: dict, front: bool = False) -> list[tuple]:
    """The Embree calls of the ceiling, [(Embree scene, origins, directions, rows)], rows
    the batch's rays each call takes. `batch`: {"rayscene": RayScene, "camera": Camera,
    "pixels": (n, 2) image (i, j), "own": (n,) own object ids, "t": float}, as the hybrid
    mode records it (host resource reveal_batch): the primary ray through each pixel
    centre, into the static objects but its own (RayScene.exclusion_scene: the scene the
    reveal answers it from; the whole static scene where the own object moves or has no
    exclusion scene) and into every moving object's scene but those of its own's rigid body.
    front: the static part into the whole static scene for every ray, where a ray of a
    static own object stops at that object (a cheaper query than the reveal's, which must
    pass it)."""
    rs: RayScene = batch["rayscene"]
    t = float(batch["t"])
    px = np.asarray(batch["pixels"])
    own = np.asarray(batch.get("own", np.zeros(len(px))), dtype=np.uint32).reshape(len(px))
    origins, dirs = batch["camera"].rays(t, px[:, 0], px[:, 1])
    o = np.ascontiguousarray(origins, dtype=np.float32)
    d = np.ascontiguousarray(dirs, dtype=np.float32)
    jobs = []
    if rs._static is not None:
        rest = np.ones(len(o), dtype=bool)
        if not front:
            for key in np.unique(own[np.isin(own, rs.static_ids)]).tolist():
                ex = rs.exclusion_scene(int(key))
                if ex is not None:
                    rows = np.flatnonzero(own == key)
                    jobs.append((ex[0], o[rows], d[rows], rows))
                    rest[rows] = False
        rows = np.flatnonzero(rest)
        if rows.size:
            jobs.append((rs._static, o[rows], d[rows], rows))
    poses = rs._poses(t)                     # M(t)^-1 as the reveal takes them
    bodies = rs._body[own] if rs.moving else own
    for (obj, es), inv, body in zip(rs.moving, poses.inv, rs._moving_bodies):
        rows = np.flatnonzero(bodies != body)       # not the own object's rigid body
        if rows.size:
            jobs.append((es, transform_points(inv, o[rows]), transform_vectors(inv, d[rows]),
                         rows))
    return jobs


def bare_embree_rays_per_s(batch: dict | None, repeats: int = 5, front: bool = False) -> float:
    """Rays per second of the ceiling_jobs(batch, front) calls: n / (time of all the run
    calls), median over `repeats`; 0 for an empty batch."""
    if not batch or len(batch["pixels"]) == 0:
        return 0.0
    jobs = [(es, oo, dd, np.full(len(rows), np.inf, dtype=np.float32))
            for es, oo, dd, rows in ceiling_jobs(batch, front)]
    n = len(batch["pixels"])
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for es, oo, dd, far in jobs:
            _embree_run(es, oo, dd, far)
        runs.append(time.perf_counter() - t0)
    return n / float(np.median(runs))
