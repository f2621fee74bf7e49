"""Time-interleaved sub-frames (docs/algorithms.md 6.1, the second design), measured as a
prototype beside the renderer's designs: K sub-frames, sub-frame s drawn on the image's
columns s, s + K, s + 2K, ... (a W/K x H frame whose projection is shifted onto them) at
the centre of the s-th of K equal parts of the exposure with 1/K of the shutter, each the
linear hybrid; resolved to full resolution by interpolating each sub-frame along its
rows and averaging them where a sub-frame's blur changed a pixel, the full-resolution
sharp frame elsewhere (what nothing moves over keeps its detail). One frame's fragment
work for K times; the price is horizontal detail inside the blur.

    python scripts/interleaved_subframes.py SCENE [--k 2] [--json PATH]

Prints whole-image, static, inner and outer FLIP against the 64-sample reference and the
frame time (median of 9, ctx.finish() and a CPU clock) against McGuire's, 640x360; with
--json writes them for scripts/curve_designs.py.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from viewer.eval.metrics import image_metrics  # noqa: E402
from viewer.glcontext import create_headless  # noqa: E402
from viewer.render.graph.params import ParamSet  # noqa: E402
from viewer.render.modes.reference import REGIONS  # noqa: E402
from viewer.render.renderer import Renderer  # noqa: E402
from world import transforms as tf  # noqa: E402
from world.camera import Camera  # noqa: E402
from world.loader import load_scene  # noqa: E402

W, H = 640, 360


class ColumnCamera(Camera):
    """The camera of a W/K x H frame that draws columns s, s + K, ... of the W x H image:
    the full image's aspect, the projection shifted so that column j's centre is column
    K j + s's. (The reveal's rays go through the same centres: Camera.rays reads the
    aspect, and pixel-centre NDC of a W/K-wide frame plus the shift is the full image's.)"""

    def __init__(self, spec, k: int, s: int):
        super().__init__(spec, W // k, H)
        self.shift = (s + 0.5 - k / 2.0) * 2.0 / W

    @property
    def aspect(self) -> float:
        return W / H

    def projection(self) -> np.ndarray:
        p = tf.perspective(self.spec.fov_y, W / H, self.spec.near, self.spec.far).copy()
        p[0, 2] -= self.shift
        return p


def linear() -> ParamSet:
    p = ParamSet()
    p.set("hybrid.curve", "steps")
    p.set("hybrid.curve_steps", 1)
    return p


def sub_frames(subs, scene, t: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each sub-frame's blurred image and its sharp colour (image rows)."""
    k, shutter, out = len(subs), scene.camera.shutter, []
    for s, r in enumerate(subs):
        ts = t - shutter / 2 + (s + 0.5) * shutter / k
        frame = r.run("hybrid", ts, linear(), s,
                      lambda tk, sh, seed, r=r, ts=ts: r.frame(ts, linear(), seed,
                                                               shutter=shutter / k))
        out.append((frame.read("hybrid")[..., :3].copy(), frame.read("color")[..., :3].copy()))
    return out


def resolve(parts, sharp: np.ndarray) -> np.ndarray:
    k = len(parts)
    xs = np.arange(W)
    total, moved = np.zeros((H, W, 3)), np.zeros((H, W), bool)
    for s, (img, colour) in enumerate(parts):
        pos = (xs - s) / k
        j0 = np.clip(np.floor(pos).astype(int), 0, W // k - 1)
        j1 = np.clip(j0 + 1, 0, W // k - 1)
        w1 = np.clip(pos - np.floor(pos), 0.0, 1.0)[None, :, None]
        total += (1.0 - w1) * img[:, j0] + w1 * img[:, j1]
        changed = np.abs(img - colour).max(axis=-1) > 1e-6
        moved |= changed[:, j0] | changed[:, j1]
    return np.where(moved[..., None], total / k, sharp).astype(np.float32)


def median_ms(ctx, fn, n: int = 9) -> float:
    times = []
    for _ in range(n):
        ctx.finish()
        t0 = time.perf_counter()
        fn()
        ctx.finish()
        times.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(times))


def measure(scene_arg: str, k: int) -> dict:
    scene = load_scene(scene_arg)
    ctx = create_headless()
    full = Renderer(ctx, scene, (W, H))
    subs = [Renderer(ctx, scene, (W // k, H)) for _ in range(k)]
    for s, r in enumerate(subs):
        r.camera = ColumnCamera(scene.camera, k, s)
    try:
        t = scene.render.time
        p = ParamSet()
        p.set("reference.samples", 64)
        ref = full.render("reference", t, p, record_visibility=True)
        image = resolve(sub_frames(subs, scene, t), full.render("off", t).image)
        m = image_metrics(image, ref.image, ref.host[REGIONS])
        flip = {r: m[r]["flip"] for r in ("all", "static", "inner", "outer")}

        def interleaved():
            resolve(sub_frames(subs, scene, t), full.render("off", t).image)
        mc = median_ms(ctx, lambda: full.render("mcguire", t, read_image=False))
        il = median_ms(ctx, interleaved)
        return {"k": k, "flip": flip, "frame_ms": il, "mcguire_ms": mc}
    finally:
        for r in (full, *subs):
            r.release()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--k", type=int, default=2)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    got = measure(a.scene, a.k)
    print(f"{a.scene} interleaved K={a.k}: FLIP " + " ".join(f"{r} {v:.4f}" for r, v in
                                                           got["flip"].items())
          + f"; {got['frame_ms']:.1f} ms, McGuire {got['mcguire_ms']:.1f} ms "
          f"({got['frame_ms'] / got['mcguire_ms']:.2f}x)")
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(got, indent=1))


if __name__ == "__main__":
    main()
