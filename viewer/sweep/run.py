"""Running a sweep: the cells not yet in DIR/cells go to Dask (a LocalCluster of one
single-threaded worker process per core, or the scheduler at --scheduler), each finished
cell is written whole as it arrives, and the table is assembled from the cell files.

Nothing lost, nothing repeated: a cell file (DIR/cells/KEY.json, its images first) appears
by rename, whole or not at all, and KEY hashes everything its numbers depend on, so a rerun
skips finished cells. A worker that dies mid-cell: the scheduler gives its cell to another
worker (Dask's allowed-failures); a cell that failed is written with its error and tried
again on the next run. SIGINT and SIGTERM stop the sweep between files.
"""
from __future__ import annotations

import json
import logging
import os
import signal
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from world.errors import UserError
from viewer.io import progress
from viewer.io.imageio import OutputSet, json_safe
from .bundle import scene_bundle
from .cells import CellTask, run_cell
from .spec import Sweep
from .table import write_outputs


WAIT_FOR_WORKERS_S = 30


def tasks_of(spec: Sweep, version: str, images: bool, timing: bool) -> list[CellTask]:
    bundles = {s.path: scene_bundle(s.path) for s in spec.scenes}
    return [CellTask(scene.label, bundles[scene.path], t, shutter, size, samples, seed,
                     spec.common, spec.variants, version, images, timing)
            for scene, t, shutter, size, samples, seed in spec.cells()]


def cell_path(out: Path, key: str) -> Path:
    return out / "cells" / f"{key}.json"


def finished(out: Path, task: CellTask) -> dict | None:
    """The cell's file if it holds a success that gives what this run asks for (timing,
    images); else None (to be run)."""
    try:
        c = json.loads(cell_path(out, task.key).read_text())
    except (OSError, ValueError):
        return None
    if c.get("error") is not None or (task.timing and not c.get("timing")):
        return None
    if task.images and not (c.get("image_files")
                            and all((out / p).is_file() for p in c["image_files"])):
        return None
    return c


def _image_dir(c: dict) -> str:
    w, h = c["size"]
    scene = c["scene"].replace("/", "_").removesuffix(".toml")
    return f"images/{scene}-t{c['time']:g}-s{c['shutter']:g}-{w}x{h}-n{c['samples']}-seed{c['seed']}"


def write_cell(out: Path, result: dict) -> dict:
    """The cell's images, then its JSON: renamed in that order, so a cell file never names
    an image that is not there."""
    files = OutputSet()
    images = result.pop("images", {}) or {}
    if images:
        folder = _image_dir(result)
        result["image_files"] = [f"{folder}/{n}" for n in sorted(images)]
        for name in sorted(images):
            files.add(out / folder / name, lambda f, d=images[name]: f.write(d))
    files.json(cell_path(out, result["key"]), result)
    files.commit()
    return json.loads(json.dumps(json_safe(result)))      # as a rerun would read it


class Bar:
    """One line on stderr: cells done, failed and left, elapsed and the estimated time
    left (from the cells this run has finished)."""

    def __init__(self, total: int, skipped: int, stream=None):
        self.stream = stream or sys.stderr
        self.tty = progress.is_terminal(self.stream)
        self.total, self.skipped, self.done, self.failed = total, skipped, 0, 0
        self.t0 = time.perf_counter()

    def update(self, failed: bool):
        self.done += 1
        self.failed += failed
        self.show()

    def show(self):
        finished = self.skipped + self.done
        left = self.total - finished
        el = time.perf_counter() - self.t0
        eta = f", ETA {_clock(el / self.done * left)}" if self.done and left else ""
        line = (f"sweep: {finished}/{self.total} cells done ({self.skipped} from earlier runs), "
                f"{self.failed} failed, {left} left, {_clock(el)} elapsed{eta}")
        if self.tty:
            progress.redraw(self.stream, line + "\x1b[K", not left)
        else:
            self.stream.write(line + "\n")
            self.stream.flush()


def _clock(s: float) -> str:
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


@contextmanager
def _sigterm_as_interrupt():
    """SIGTERM ends the sweep as Ctrl-C does: a KeyboardInterrupt, files cleaned up."""
    def handler(signum, frame):
        raise KeyboardInterrupt
    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:                    # not the main thread: leave signals alone
        old = None
    try:
        yield
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)


def run_in_process(tasks, on_result):
    """Every cell in this process, one after another (--workers 0)."""
    for task in tasks:
        on_result(task, run_cell(task))
    return {"engine": "in process (no Dask)"}


def run_on_dask(tasks, on_result, workers: int, scheduler: str | None):
    from dask.distributed import Client, LocalCluster, as_completed
    cluster = None
    try:
        if scheduler:
            try:
                client = Client(scheduler, timeout="20s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise UserError(f"--scheduler {scheduler}: cannot connect "
                                f"({type(exc).__name__}: {' '.join(str(exc).split())})") from None
            try:                         # tasks would wait for ever on a cluster of none
                client.wait_for_workers(1, timeout=WAIT_FOR_WORKERS_S)
            except TimeoutError:
                client.close()
                raise UserError(f"--scheduler {scheduler}: no worker joined within "
                                f"{WAIT_FOR_WORKERS_S} s (start `dask worker {scheduler} "
                                "--nthreads 1` on the machines that render)") from None
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster)
        engine = (f"dask scheduler {scheduler}" if scheduler else "dask LocalCluster") + \
            _workers(len(client.scheduler_info()["workers"]))
        try:
            by_key, futures = {}, []
            for task in tasks:
                # a key per cell and run (a task lost with its worker is run again by the
                # scheduler under the same key)
                fut = client.submit(run_cell, task, key=f"cell-{task.key}-{os.getpid()}",
                                    pure=False)
                by_key[fut.key] = task
                futures.append(fut)
            for fut in as_completed(futures):
                task = by_key[fut.key]
                try:
                    result = fut.result()
                except Exception as exc:       # KilledWorker: the cell took workers down
                    result = _failed(task, f"{type(exc).__name__}: {exc}")
                on_result(task, result)
                fut.release()
        finally:
            client.close()
    finally:
        if cluster is not None:
            cluster.close()
    return {"engine": engine}


def _failed(task: CellTask, error: str) -> dict:
    return {"key": task.key, "scene": task.scene, "time": task.time, "shutter": task.shutter,
            "size": list(task.size) if task.size else None, "samples": task.samples,
            "seed": task.seed, "rows": [], "images": {}, "error": error,
            "timing": task.timing, "worker": None}


def run_sweep(spec: Sweep, out: Path, version: str, workers: int, scheduler: str | None,
              images: bool, timing: bool, stream=None, runner=None) -> dict:
    """Run what is not finished, then write the table; returns facts for the report
    (counts, wall time, the engine, peak memory per worker). `runner`: for tests, a
    function (tasks, on_result) -> facts in place of Dask."""
    stream = stream or sys.stderr
    t0 = time.perf_counter()
    tasks = tasks_of(spec, version, images, timing)
    keys = [t.key for t in tasks]
    if len(set(keys)) != len(keys):     # (cannot happen for distinct cells: a bug guard)
        raise RuntimeError("two cells of the sweep have the same key")
    results = {t.key: c for t in tasks if (c := finished(out, t)) is not None}
    todo = [t for t in tasks if t.key not in results]
    bar = Bar(len(tasks), len(results), stream)
    bar.show()
    ran = []

    def on_result(task, result):
        results[task.key] = write_cell(out, result)
        ran.append(results[task.key])
        bar.update(result["error"] is not None)

    engine = {"engine": "nothing to run"}
    with _sigterm_as_interrupt():
        try:
            if todo:
                if runner is not None:
                    engine = runner(todo, on_result)
                elif workers == 0:
                    engine = run_in_process(todo, on_result)
                else:
                    engine = run_on_dask(todo, on_result, workers, scheduler)
        except KeyboardInterrupt:
            from viewer.io.progress import end_line
            end_line()
            print(f"sweep: interrupted; {len(results)} of {len(tasks)} cells kept in "
                  f"{out / 'cells'}; run the same command again to continue", file=stream)
            raise
    cells = [results[k] for k in keys]
    peak = {}
    for c in ran:
        if c.get("worker"):
            peak[c["worker"]] = max(peak.get(c["worker"], 0.0), c.get("peak_rss_mb", 0.0))
    facts = {"cells run now": len(ran), "cells from earlier runs": len(tasks) - len(todo),
             **engine, "wall time": f"{time.perf_counter() - t0:.1f} s (this run)"}
    devices = sorted({c["device"] for c in cells if c.get("device")})
    if devices:
        facts["devices"] = "; ".join(devices)
    if peak:
        facts["peak memory per worker (RSS)"] = ", ".join(
            f"{w} {mb:.0f} MB" for w, mb in sorted(peak.items()))
    write_outputs(out, spec, cells, facts, timing)
    facts["failed"] = sum(c["error"] is not None for c in cells)
    facts["total"] = len(cells)
    facts["ran"] = ran
    return facts


def _workers(n: int) -> str:
    return f", {n} worker" + ("" if n == 1 else "s")
