"""Worker threads kept for the process, one pool per purpose and size (starting threads
every frame costs ~1 ms). Purposes get separate pools so that work run on one pool never
waits for a task of the same pool (no nesting deadlock)."""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

_POOLS: dict[tuple[str, int], ThreadPoolExecutor] = {}


def worker_pool(purpose: str, threads: int) -> ThreadPoolExecutor:
    pool = _POOLS.get((purpose, threads))
    if pool is None:
        pool = _POOLS[(purpose, threads)] = ThreadPoolExecutor(
            max_workers=threads, thread_name_prefix=purpose)
    return pool


def run_all(jobs: list, sizes: list[int], threads: int, purpose: str) -> list:
    """[job() for job in jobs] on `threads` threads when threads > 1: the calling thread
    and threads - 1 of the `purpose` pool, the largest jobs first (sizes: each job's share
    of the work) so that the threads end about together; results in the jobs' order."""
    if threads <= 1 or len(jobs) < 2:
        return [job() for job in jobs]
    order = sorted(range(len(jobs)), key=lambda k: -sizes[k])
    results: list = [None] * len(jobs)
    pending = list(order)

    def worker():
        while pending:
            try:
                k = pending.pop(0)
            except IndexError:
                return
            results[k] = jobs[k]()
    helpers = [worker_pool(purpose, threads - 1).submit(worker) for _ in range(threads - 1)]
    try:
        worker()
    finally:
        pending.clear()                 # after an error here, no helper starts another job
        for h in helpers:
            h.exception()               # (waits for it)
    for h in helpers:
        h.result()                      # a helper's error, raised here
    return results
