"""Running a sweep: the cells not yet in DIR/cells go to Dask (a LocalCluster of
single-threaded worker processes, or the scheduler at --scheduler), each finished cell is
written whole as it arrives, and the table is assembled from the cell files.

Nothing lost, nothing repeated: a cell file (DIR/cells/KEY.json, its images first) appears
by rename, whole or not at all, and KEY hashes everything its numbers depend on, so a rerun
skips finished cells; a cell file that does not read back as a whole cell is run again. A
worker that dies mid-cell: the scheduler gives its cell to another worker (Dask's
allowed-failures); a cell that failed is written with its error and tried again on the
next run. A signal stops the sweep between files; the workers' copies of the scenes go
with it.

On Dask: the SweepWorker plugin gives every worker its GL context once (and releases it,
and the copies, at the end); each scene's bundle is scattered to the workers once, not
pickled into every cell; timed cells (--timing) ask for the resource `timer`, which one
worker per machine declares, so that no other cell of the sweep shares its cores.
"""
from __future__ import annotations

import json
import logging
import secrets
import signal
import sys
import threading
import time
from pathlib import Path

from world import limits
from world.errors import UserError
from viewer.io import progress
from viewer.io.ending import held
from viewer.io.imageio import OutputSet, json_safe
from viewer.io.outdir import OutputFolder
from .bundle import Budget, remove_copies, scene_bundle
from .cells import CellTask, blank_result, close_gl, run_cell
from .spec import Sweep
from .table import plot_names, write_outputs


WAIT_FOR_WORKERS_S = 30
LOST_SCENE_TRIES = 3         # a cell whose scene was lost with its workers: run again
TIMER = "timer"              # the Dask resource a timed cell asks for (one per machine)


def tasks_of(spec: Sweep, version: str, images: bool, timing: bool,
             run: str) -> tuple[list[CellTask], dict]:
    """The cells, and the scene bundles by digest (every file through the asset rule,
    the sweep's bytes within limits.MAX_SWEEP_BYTES, before any cell runs)."""
    budget = Budget(f"{spec.path}: scenes")
    by_path = {s.path: scene_bundle(s.path, budget) for s in spec.scenes}
    tasks = [CellTask(scene.label, by_path[scene.path].digest, t, shutter, size, samples, seed,
                      spec.common, spec.variants, version, images, timing, run)
             for scene, t, shutter, size, samples, seed in spec.cells()]
    return tasks, {b.digest: b for b in by_path.values()}


def cell_path(out: Path, key: str) -> Path:
    return out / "cells" / f"{key}.json"


# What a cell file holds, each field with the types it may have (a file lacking one, or
# with another type, is not a whole cell: it is run again).
_CELL_FIELDS = {"key": (str,), "scene": (str,), "time": (int, float), "shutter": (int, float),
                "size": (list,), "samples": (int,), "seed": (int,), "rows": (list,),
                "error": (str, type(None)), "timing": (bool,)}
_NUMBER = (int, float, str, type(None))         # (a JSON file's PSNR "inf"; None: no pixels)
_ROW_FIELDS = {"variant": (str,), "mode": (str,), "region": (str,), "pixels": (int,),
               "flip": _NUMBER, "psnr": _NUMBER, "ssim": _NUMBER,
               "frame_ms": (int, float, type(None))}


def _whole(c, task: CellTask) -> bool:
    """`c` (a cell file's JSON) is a finished cell of `task`: every field, of its type,
    one row per variant and region it names, for this task's variants."""
    if not isinstance(c, dict) or c.get("key") != task.key:
        return False
    for k, kinds in _CELL_FIELDS.items():
        if k not in c or not isinstance(c[k], kinds) or isinstance(c[k], bool) and bool not in kinds:
            return False
    if not (len(c["size"]) == 2 and all(isinstance(x, int) and not isinstance(x, bool)
                                        for x in c["size"])):
        return False
    names = {v.name for v in task.variants}
    for r in c["rows"]:
        if not isinstance(r, dict):
            return False
        for k, kinds in _ROW_FIELDS.items():
            if k not in r or not isinstance(r[k], kinds) or isinstance(r[k], bool):
                return False
        if r["variant"] not in names:
            return False
        if task.timing and r["frame_ms"] is None:
            return False
    return {r["variant"] for r in c["rows"]} == names


def finished(out: Path, task: CellTask) -> dict | None:
    """The cell's file if it holds a whole success that gives what this run asks for
    (timing, images); else None (to be run: missing, damaged, failed, or lacking them)."""
    path = cell_path(out, task.key)
    try:
        if path.is_symlink() or path.stat().st_size > limits.MAX_CELL_FILE_BYTES:
            return None
        c = json.loads(path.read_bytes().decode("utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    if not _whole(c, task) or c["error"] is not None:
        return None
    files = c.get("image_files")
    if task.images and not (isinstance(files, list) and files
                            and all(isinstance(p, str) and _inside(out, p) and
                                    (out / p).is_file() for p in files)):
        return None
    return c


def _inside(out: Path, rel: str) -> bool:
    """`rel` names a file under DIR/images (a cell file cannot point elsewhere)."""
    parts = Path(rel).parts
    return len(parts) >= 2 and parts[0] == "images" and ".." not in parts \
        and not Path(rel).is_absolute()


def _image_dir(c: dict) -> str:
    w, h = c["size"]
    scene = c["scene"].replace("/", "_").removesuffix(".toml")
    return f"images/{scene}-t{c['time']:g}-s{c['shutter']:g}-{w}x{h}-n{c['samples']}-seed{c['seed']}"


def output_folder(out: Path, spec: Sweep, images: bool, timing: bool) -> OutputFolder:
    """DIR under the rule of viewer/io/outdir.py, checked before any work: the table, summary and
    plots replace only hmblur's own, cells/ and images/ are folders hmblur made."""
    folder = OutputFolder(out, "--out", whole=("cells", "images"))
    folder.check(["table.csv", "table.parquet", "summary.md"]
                 + [f"plots/{n}" for n in plot_names(spec, timing)],
                 ["cells"] + (["images"] if images else []))
    return folder


def write_cell(folder: OutputFolder, result: dict) -> dict:
    """The cell's images, then its JSON: renamed in that order, so a cell file never names
    an image that is not there."""
    out = folder.path
    files = OutputSet(folder)
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


def run_in_process(tasks, bundles, on_result):
    """Every cell in this process, one after another (--workers 0)."""
    for task in tasks:
        on_result(task, run_cell(task, bundles[task.digest]))
    return {"engine": "in process (no Dask)"}


class DaskEngine:
    """A Dask cluster for one sweep: started (a LocalCluster) or joined (--scheduler),
    checked and given the sweep's worker plugin by start(), before anything is shown;
    called like a runner; close() frees the workers' contexts and copies (the plugin's
    teardown) and the cluster."""

    def __init__(self, workers: int, scheduler: str | None, run: str, timing: bool):
        self.workers, self.scheduler, self.run, self.timing = workers, scheduler, run, timing
        self.cluster = self.client = self.plugin = None
        self.name = ""

    def start(self):
        from dask.distributed import Client, LocalCluster
        from .plugin import SweepWorker
        if self.scheduler:
            self.client = _connect(self.scheduler)
        else:
            self.cluster = LocalCluster(
                n_workers=0, threads_per_worker=1, processes=True,
                # Dask's own log lines off: what befalls a cell (a worker lost, a scene
                # scattered again) is its row's or the sweep's to say
                dashboard_address=None, silence_logs=logging.CRITICAL,
                # no dashboard; the scheduler's own HTTP server on a free port (its
                # default 8787 may be another cluster's: a warning on stderr)
                scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},
                resources={TIMER: 1} if self.workers == 1 else None)
            self.client = Client(self.cluster)
            _spawn_ignoring_sigint(self.cluster, self.workers)
            self.client.wait_for_workers(self.workers)
        info = self.client.scheduler_info()["workers"]
        if self.timing and not any(TIMER in w.get("resources", {}) for w in info.values()):
            raise UserError(f"--timing: no worker of {self.scheduler} declares the resource "
                            f"{TIMER} (start one worker per machine with `dask worker "
                            f"{self.scheduler} --nthreads 1 --resources {TIMER}=1`: timed "
                            "cells run there, one at a time on their machine)")
        plugin = SweepWorker(self.run, quiet_interrupt=self.cluster is not None)
        try:
            self.client.register_plugin(plugin)
        except UserError as exc:               # (no EGL on a worker: create_headless)
            raise UserError(f"a Dask worker: {exc}") from None
        self.plugin = plugin
        self.name = (f"dask scheduler {self.scheduler}" if self.scheduler
                     else "dask LocalCluster") + _workers(len(info))

    def __call__(self, tasks, bundles, on_result) -> dict:
        from dask.distributed import as_completed
        client = self.client

        def scatter(digest):
            # Each scene once to every worker; the cells name it by its future.
            return client.scatter(bundles[digest], broadcast=True, hash=False)
        scattered = {d: scatter(d) for d in dict.fromkeys(t.digest for t in tasks)}
        by_key, tries = {}, {}

        def submit(task):
            # a key per cell, run and try (a task lost with its worker is run again by the
            # scheduler under the same key)
            tries[task.key] = tries.get(task.key, 0) + 1
            scene = scattered[task.digest]
            fut = client.submit(run_cell, task, scene,
                                key=f"cell-{task.key}-{self.run}-{tries[task.key]}",
                                pure=False, resources={TIMER: 1} if task.timing else None)
            by_key[fut.key] = (task, scene)
            return fut
        pending = as_completed([submit(t) for t in tasks])
        for fut in pending:
            task, scene = by_key.pop(fut.key)
            try:
                result = fut.result()
            except Exception as exc:       # KilledWorker: the cell took workers down
                if scene.status != "finished" and tries[task.key] < LOST_SCENE_TRIES:
                    # Scattered data dies with the last worker holding it (Dask cannot
                    # make it again): scatter the scene anew (once), run the cell again.
                    if scattered[task.digest] is scene:
                        client.wait_for_workers(1, timeout=WAIT_FOR_WORKERS_S)
                        scattered[task.digest] = scatter(task.digest)
                    pending.add(submit(task))
                    fut.release()
                    continue
                result = _failed(task, f"{type(exc).__name__}: {exc}")
            on_result(task, result)
            fut.release()
        return {"engine": self.name}

    def close(self):
        with held():                       # (a signal now: once they are closed)
            if self.plugin is not None:
                try:
                    self.client.unregister_worker_plugin(self.plugin.name)
                except Exception:          # (workers gone: nothing of theirs to free)
                    pass
            if self.client is not None:
                self.client.close()
            if self.cluster is not None:
                self.cluster.close()


def _spawn_ignoring_sigint(cluster, n: int):
    """Start the local cluster's n worker processes with SIGINT ignored. Ctrl-C at a
    terminal reaches the whole process group, and ending the sweep is this process's
    work (it closes the cluster), not the workers'. An ignored signal is inherited
    through exec, so it is ignored here only until their processes exist (a Ctrl-C in
    those milliseconds is lost); a worker started later (a nanny's restart) is quieted by
    the plugin."""
    import multiprocessing
    if threading.current_thread() is not threading.main_thread():
        cluster.scale(n)
        return
    before = set(multiprocessing.active_children())
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        cluster.scale(n)
        t_end = time.monotonic() + WAIT_FOR_WORKERS_S
        while (len(set(multiprocessing.active_children()) - before) < n
               and time.monotonic() < t_end):
            time.sleep(0.002)
    finally:
        signal.signal(signal.SIGINT, old)


def _connect(scheduler: str):
    from dask.distributed import Client
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
    return client


def _failed(task: CellTask, error: str) -> dict:
    return {**blank_result(task, None), "error": error}


def run_sweep(spec: Sweep, out: Path, version: str, workers: int, scheduler: str | None,
              images: bool, timing: bool, stream=None, runner=None) -> dict:
    """Run what is not finished, then write the table; returns facts for the report
    (counts, wall time, the engine, peak memory per worker). `runner`: for tests, a
    function (tasks, bundles, on_result) -> facts in place of Dask."""
    stream = stream or sys.stderr
    t0 = time.perf_counter()
    folder = output_folder(out, spec, images, timing)
    run = secrets.token_hex(8)
    tasks, bundles = tasks_of(spec, version, images, timing, run)
    keys = [t.key for t in tasks]
    if len(set(keys)) != len(keys):     # (cannot happen for distinct cells: a bug guard)
        raise RuntimeError("two cells of the sweep have the same key")
    results = {t.key: c for t in tasks if (c := finished(out, t)) is not None}
    todo = [t for t in tasks if t.key not in results]
    ran = []

    def on_result(task, result):
        results[task.key] = write_cell(folder, result)
        ran.append(results[task.key])
        bar.update(result["error"] is not None)

    engine = {"engine": "nothing to run"}
    # A scene whose files break the asset rule is its cells' error, here: no worker
    # receives it.
    refused = [t for t in todo if bundles[t.digest].error is not None]
    todo = [t for t in todo if bundles[t.digest].error is None]
    dask = None
    try:
        try:
            if todo and runner is None and workers != 0:
                dask = DaskEngine(workers, scheduler, run, timing)
                dask.start()             # (its mistakes before the first line is shown)
            bar = Bar(len(tasks), len(results), stream)
            bar.show()
            for task in refused:
                on_result(task, run_cell(task, bundles[task.digest]))
            if todo:
                if runner is not None:
                    engine = runner(todo, bundles, on_result)
                elif dask is None:
                    engine = run_in_process(todo, bundles, on_result)
                else:
                    engine = dask(todo, bundles, on_result)
        finally:
            with held():                 # (a signal now: once all of it is done)
                if dask is not None:
                    dask.close()
                close_gl()               # (this process's, when cells ran here)
                remove_copies(run)       # (this machine's, whoever made them)
        facts = _facts(tasks, ran, [results[k] for k in keys], engine, t0)
        write_outputs(folder, spec, [results[k] for k in keys], facts, timing)
    except KeyboardInterrupt as exc:     # (a signal: Terminated is one too)
        from viewer.io.progress import end_line
        end_line()
        exc.add_note(f"all {len(tasks)} cells kept in {out / 'cells'}; run the same command "
                     "again to write the table from them" if len(results) == len(tasks) else
                     f"{len(results)} of {len(tasks)} cells kept in {out / 'cells'}; run the "
                     "same command again to continue")
        raise
    cells = [results[k] for k in keys]
    facts["failed"] = sum(c["error"] is not None for c in cells)
    facts["total"] = len(cells)
    facts["ran"] = ran
    return facts


def _facts(tasks, ran, cells, engine: dict, t0: float) -> dict:
    """What summary.md says of the run: counts, the engine, wall time, devices, memory."""
    peak = {}
    for c in ran:
        if c.get("worker"):
            peak[c["worker"]] = max(peak.get(c["worker"], 0.0), c.get("peak_rss_mb", 0.0))
    facts = {"cells run now": len(ran), "cells from earlier runs": len(tasks) - len(ran),
             **engine, "wall time": f"{time.perf_counter() - t0:.1f} s (this run)"}
    devices = sorted({c["device"] for c in cells if c.get("device")})
    if devices:
        facts["devices"] = "; ".join(devices)
    if peak:
        facts["peak memory per worker (RSS)"] = ", ".join(
            f"{w} {mb:.0f} MB" for w, mb in sorted(peak.items()))
    return facts


def _workers(n: int) -> str:
    return f", {n} worker" + ("" if n == 1 else "s")
