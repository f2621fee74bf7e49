"""One cell of a sweep, as a worker runs it: (scene, time, shutter, size, samples, seed)
with every variant. The reference is rendered once and shared; the numbers come from
viewer.eval.comparison.compare_frame, the function `hmblur compare` runs.

A cell never raises for its own failure (a scene that does not load, a render that fails):
it returns its error, which becomes one row of the table. Each worker keeps one headless
EGL context in the thread that runs its cells (made by the sweep's worker plugin when the
worker joins, or on the first cell) and a few Renderers by scene, until close_gl().
"""
from __future__ import annotations

import hashlib
import json
import os
import resource
import socket
import statistics
import threading
import time
import traceback
from collections import OrderedDict
from dataclasses import dataclass, field

from world.errors import UserError
from viewer.eval.comparison import check_capacity, compare_frame
from viewer.io.imageio import json_safe, linear_to_srgb8, png_bytes
from viewer.render.graph.params import ParamSet
from ..render.modes import MODE_GROUPS
from viewer.eval.strip import REGION_ORDER, choose_inset, make_strip, region_picture
from .bundle import Bundle, materialise, unplace

TIMING_FRAMES = 5          # warm frames per variant whose median is frame_ms (--timing)
RENDERERS_KEPT = 3         # per worker: scenes whose GPU scene and ray tracer stay built
FORMAT = 1                 # of a cell's result file; part of its key


@dataclass
class CellTask:
    """What a worker needs besides the scene's bundle (which travels once per worker)."""
    scene: str                     # the table's label
    digest: str                    # the scene bundle's (Bundle.digest)
    time: float | None             # None: the scene's own
    shutter: float | None
    size: tuple | None
    samples: int
    seed: int
    common: dict
    variants: list                 # [SweepVariant]
    version: str
    images: bool = False
    timing: bool = False
    run: str = ""                  # the sweep's token: its copies folder on each machine
    key: str = field(default="", init=False)

    def __post_init__(self):
        self.key = cell_key(self)


def base_params(task: CellTask) -> ParamSet:
    p = ParamSet()
    for k, v in task.common.items():
        p.set(k, v, label="set")
    p.set("reference.samples", task.samples, label="samples")
    return p


def cell_key(task: CellTask) -> str:
    """sha256 of all a cell's numbers depend on: the scene's files, the cell's values, every
    variant's resolved parameters (defaults included) and a user pass's file (its
    digest: the method's bytes travel with the task), the project's version; and the
    scene's label, which its file holds (two scenes of the same bytes are two cells)."""
    base = base_params(task)
    doc = {"format": FORMAT, "version": task.version, "scene": task.digest,
           "label": task.scene,
           "time": task.time, "shutter": task.shutter,
           "size": list(task.size) if task.size else None, "seed": task.seed,
           "reference": base.to_dict(MODE_GROUPS["reference"]),
           "variants": [[v.name, v.mode, v.params(base, v.name).to_dict(v.groups)]
                        + ([v.method.digest] if v.method is not None else [])
                        for v in task.variants]}
    text = json.dumps(json_safe(doc), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


class _WorkerState(threading.local):
    """Per worker thread (a GL context is current in one thread): the context and the
    Renderers of the scenes seen last."""
    ctx = None
    renderers: OrderedDict


_state = _WorkerState()


def open_gl():
    """This thread's GL context, made once (the worker plugin calls this in the thread
    that runs the worker's cells)."""
    from ..glcontext import create_headless
    if _state.ctx is None:
        _state.ctx = create_headless()
        _state.renderers = OrderedDict()
    _state.ctx.__enter__()        # current again (a caller may have made another one current)
    return _state.ctx


def close_gl():
    """Release this thread's Renderers and GL context (made again if a cell comes)."""
    if _state.ctx is None:
        return
    _state.ctx.__enter__()
    try:
        for _, r, _ in _state.renderers.values():
            r.release()
    finally:
        _state.renderers = OrderedDict()
        ctx, _state.ctx = _state.ctx, None
        ctx.release()


def gl_is_open() -> bool:
    return _state.ctx is not None


def _renderer(bundle: Bundle, size, run: str):
    """(scene, Renderer) for the bundle, made or reused; the least recent one released
    when more than RENDERERS_KEPT are kept."""
    from world.loader import load_scene
    from ..render.renderer import Renderer
    open_gl()
    kept = _state.renderers
    if bundle.digest not in kept:
        scene = load_scene(materialise(bundle, run))
        kept[bundle.digest] = (scene, Renderer(_state.ctx, scene, size or scene_size(scene)),
                               scene.camera.shutter)
        while len(kept) > RENDERERS_KEPT:
            kept.popitem(last=False)[1][1].release()
    kept.move_to_end(bundle.digest)
    return kept[bundle.digest]


def _forget(bundle: Bundle):
    kept = getattr(_state, "renderers", None) or {}
    if bundle.digest in kept:
        kept.pop(bundle.digest)[1].release()


def scene_size(scene) -> tuple[int, int]:
    return scene.render.width, scene.render.height


def blank_result(task: CellTask, worker: str | None) -> dict:
    """A cell's result with no rows yet: its values as the task gives them, no error."""
    return {"key": task.key, "scene": task.scene, "time": task.time, "shutter": task.shutter,
            "size": list(task.size) if task.size else None, "samples": task.samples,
            "seed": task.seed, "rows": [], "images": {}, "error": None,
            "timing": task.timing, "worker": worker}


def run_cell(task: CellTask, bundle: Bundle) -> dict:
    """The cell's result: its resolved values, one row per variant and region, the images
    (PNG bytes) when asked, or its error; and the worker's peak memory. `bundle`: the
    scene's (its digest is the task's)."""
    t_start = time.perf_counter()
    out = blank_result(task, f"{socket.gethostname()}:{os.getpid()}")
    try:
        if bundle.digest != task.digest:
            raise RuntimeError("the scene bundle given is not the task's")
        if bundle.error is not None:
            raise UserError(bundle.error)
        _check_version(task)
        _run(task, bundle, out)
    except UserError as exc:
        out["error"] = unplace(str(exc), bundle, task.run)
    except Exception as exc:      # a failed render is this cell's error; the sweep goes on
        _forget(bundle)           # (its renderer may be half-way through a frame)
        out["error"] = (f"{type(exc).__name__}: {unplace(str(exc), bundle, task.run)} "
                        f"({traceback.extract_tb(exc.__traceback__)[-1].name})")
    if out["error"] is not None:
        out["rows"], out["images"] = [], {}
    out["cell_s"] = time.perf_counter() - t_start
    out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return out


def _check_version(task: CellTask):
    """A worker of another version would file its numbers under this version's key."""
    from viewer.io.sidecar import version
    if version() != task.version:
        raise UserError(f"this worker runs hmblur {version()}, the sweep was started with "
                        f"{task.version}: install the same version on every worker")


def _run(task: CellTask, bundle: Bundle, out: dict):
    from ..glcontext import device_name
    scene, r, shutter0 = _renderer(bundle, task.size, task.run)
    out["device"] = device_name(_state.ctx)
    size = tuple(task.size) if task.size else scene_size(scene)
    if task.size is None:         # (a size the sweep gives is checked with the sweep file)
        check_capacity(len(task.variants), size, f"{task.scene}: [render] size")
    if r.size != size:
        r.resize(size)
    # the scene's own shutter unless the sweep replaces it (the kept scene is shared by
    # cells that differ in shutter, so it is set every time)
    scene.camera.shutter = shutter0 if task.shutter is None else task.shutter
    t = scene.render.time if task.time is None else task.time
    out.update(time=t, shutter=scene.camera.shutter, size=list(size))
    base = base_params(task)
    c = compare_frame(r, t, base, task.variants, task.seed)
    frame_ms = _frame_ms(r, t, task, c.params) if task.timing else {}
    for v in task.variants:
        table = c.table[v.name]
        for region in REGION_ORDER:
            if region in table:
                m = table[region]
                out["rows"].append({"variant": v.name, "mode": v.mode, "region": region,
                                    "pixels": m["pixels"], "flip": m["flip"],
                                    "psnr": m["psnr"], "ssim": m["ssim"],
                                    "frame_ms": frame_ms.get(v.name)})
    if task.images:
        out["images"] = _images(task, c)


def _frame_ms(r, t, task: CellTask, params: dict) -> dict:
    """Median wall ms of TIMING_FRAMES warm frames per variant, the GL work finished
    (compare_frame's own render of each was its first: compiles and builds included)."""
    ms = {}
    for v in task.variants:
        samples = []
        for _ in range(TIMING_FRAMES):
            t0 = time.perf_counter()
            r.render(v.mode, t, params[v.name], seed=task.seed, read_image=False)
            r.ctx.finish()
            samples.append((time.perf_counter() - t0) * 1e3)
        ms[v.name] = statistics.median(samples)
    return ms


def _images(task: CellTask, c) -> dict:
    """PNG bytes: each variant, the reference, the region map and a labelled strip."""
    imgs = {v.name: c.results[v.name].image for v in task.variants}
    h = c.region.shape[0]
    box = choose_inset(c.region, (max(8, h // 4),) * 2)
    strip = make_strip([(n, im) for n, im in imgs.items()] + [("reference", c.reference.image)],
                       inset_box=box,
                       metrics=[[f"FLIP {c.table[n]['all']['flip']:.3f} all"] for n in imgs]
                       + [[f"{task.samples} sub-frames"]])
    out = {f"{n}.png": png_bytes(linear_to_srgb8(im)) for n, im in imgs.items()}
    out["reference.png"] = png_bytes(linear_to_srgb8(c.reference.image))
    out["regions.png"] = png_bytes(region_picture(c.region))
    out["strip.png"] = png_bytes(strip)
    return out


__all__ = ["CellTask", "run_cell", "cell_key"]
