"""The ceiling for the reveal's throughput: bare Embree `run` calls on exactly the rays the
reveal traced, into the same scenes, with nothing else timed (no exclusion, restarts,
attribute fetches or Python bookkeeping). The rays are transformed into each moving
object's space before the clock starts."""
from __future__ import annotations

import time

import numpy as np

from .embree_scene import RayScene, _embree_run, transform_points, transform_vectors


def bare_embree_rays_per_s(batch: dict | None, repeats: int = 5) -> float:
    """`batch`: {"rayscene": RayScene, "camera": Camera, "pixels": (n, 2) image (i, j),
    "t": float} as the hybrid mode records it (frame.host["reveal_batch"]): the primary
    rays through those pixel centres, each into the static scene and every moving one.
    Median over `repeats` of n / (time of all the run calls)."""
    if not batch or len(batch["pixels"]) == 0:
        return 0.0
    rs: RayScene = batch["rayscene"]
    t = float(batch["t"])
    px = np.asarray(batch["pixels"])
    origins, dirs = batch["camera"].rays(t, px[:, 0], px[:, 1])
    o = np.ascontiguousarray(origins, dtype=np.float32)
    d = np.ascontiguousarray(dirs, dtype=np.float32)
    jobs = []
    if rs._static is not None:
        jobs.append((rs._static, o, d))
    for obj, es in rs.moving:
        inv = np.linalg.inv(obj.matrix(t)).astype(np.float32)
        jobs.append((es, transform_points(inv, o), transform_vectors(inv, d)))
    far = np.full(len(o), np.inf, dtype=np.float32)
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for es, oo, dd in jobs:
            _embree_run(es, oo, dd, far)
        runs.append(time.perf_counter() - t0)
    return len(o) / float(np.median(runs))
