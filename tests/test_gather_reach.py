"""The FINE tiles of the McGuire and UE4-style gathers (viewer/render/passes/gather_reach.py): the
kernels against their pixel-by-pixel definitions, the self-tap test against the taps the
gather takes, and the tiled draw against the full-screen one, byte for byte, on synthetic
frames (small movers fast and slow, at the screen's edge, nothing moving, a pan) and on
real scenes.

Arrays are in GL orientation (row 0 at the bottom), as in tests/test_mcguire.py.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import numpy_mcguire as nm
from test_mcguire import download, params, upload
from viewer.render.graph.params import ParamSet
from viewer.render.passes import tile_kernels
from viewer.render.passes.gather_reach import self_tap_tiles
from viewer.render.modes.mcguire import JITTER_STREAM, mcguire_passes
from viewer.render.modes.ue4 import ue4_passes
from world.conventions import to_image

F32 = np.float32


def fine_of(pixels: np.ndarray, fine: int) -> np.ndarray:
    """Per fine x fine tile, whether any of its pixels is set."""
    h, w = pixels.shape
    out = np.zeros((-(-h // fine), -(-w // fine)), bool)
    ys, xs = np.nonzero(pixels)
    out[ys // fine, xs // fine] = True
    return out


@pytest.mark.parametrize("size,box,fine", [((37, 29), (5, 1), 4), ((40, 24), (4, 4), 16),
                                           ((33, 20), (7, 3), 5)])
def test_reach_boxes_is_the_pixelwise_rule(size, box, fine):
    """A tile is set exactly when one of its pixels lies closer than the box's reach to
    one of the box's pixels."""
    w, h = size
    bw, bh = box
    rng = np.random.default_rng(4)
    reach = np.where(rng.uniform(size=(-(-h // bh), -(-w // bw))) < 0.1,
                     rng.uniform(0.0, 9.0, (-(-h // bh), -(-w // bw))), -1.0)
    reach[0, 0] = 3.0                                   # an integer reach: strictly less
    got = tile_kernels.reach_boxes(reach, bw, bh, w, h, fine)
    yy, xx = np.mgrid[0:h, 0:w]
    near = np.zeros((h, w), bool)
    for j, i in zip(*np.nonzero(reach >= 0)):
        inside = (yy // bh == j) & (xx // bw == i)
        by, bx = yy[inside], xx[inside]
        d2 = (yy[..., None] - by) ** 2 + (xx[..., None] - bx) ** 2
        near |= (d2 < reach[j, i] ** 2).any(-1)
    np.testing.assert_array_equal(got, fine_of(near, fine))


@pytest.mark.parametrize("size,k", [((50, 37), 7), ((33, 20), 3), ((16, 1), 4), ((1, 9), 2)])
def test_self_taps_is_the_pixelwise_rule(size, k):
    """A tile is set when a pixel of it has a running k-tile and no axis that moves its
    taps off it: an axis counts where the tile says so and the pixel is off that axis'
    first and last index."""
    w, h = size
    rng = np.random.default_rng(5)
    shape = (-(-h // k), -(-w // k))
    off_x, off_y, run = (rng.uniform(size=shape) < 0.5 for _ in range(3))
    got = tile_kernels.self_taps(off_x, off_y, run, k, w, h, 4)
    yy, xx = np.mgrid[0:h, 0:w]
    ty, tx = yy // k, xx // k
    safe = (~run[ty, tx] | (off_x[ty, tx] & (xx > 0) & (xx < w - 1))
            | (off_y[ty, tx] & (yy > 0) & (yy < h - 1)))
    np.testing.assert_array_equal(got, fine_of(~safe, 4))


@pytest.mark.parametrize("samples,jitter", [(15, 1.0), (7, 0.0), (3, 0.5)])
def test_self_tap_tiles_hold_every_pixel_a_tap_lands_on(samples, jitter):
    """The gather's own taps (numpy_mcguire's tap rule and hash port, float32): wherever a
    tap other than the middle one lands on its own pixel, the tile is listed."""
    w, h, k, fine = 96, 64, 13, 16
    rng = np.random.default_rng(6)
    shape = (-(-h // k), -(-w // k))
    vn = rng.uniform(-12.0, 12.0, shape + (2,)).astype(F32)
    vn[1, 2] = (0.0, 7.9)                               # one axis alone near the threshold
    run = np.hypot(vn[..., 0], vn[..., 1]) > 0.501
    got = self_tap_tiles(vn, run, k, (w, h), samples, jitter)
    yy, xx = np.mgrid[0:h, 0:w]
    v = vn[yy // k, xx // k]
    j = F32(jitter) * (nm.hash01(xx, yy, 0, JITTER_STREAM).astype(F32) - F32(0.5))
    fx, fy = xx.astype(F32) + F32(0.5), yy.astype(F32) + F32(0.5)
    lands = np.zeros((h, w), bool)
    for i in range(samples):
        if i == (samples - 1) // 2:
            continue
        t = F32(-1.0) + F32(2.0) * (F32(i) + j + F32(1.0)) / F32(samples + 1)
        ty = np.clip(np.floor(fy + t * v[..., 1]), 0, h - 1)
        tx = np.clip(np.floor(fx + t * v[..., 0]), 0, w - 1)
        lands |= (tx == xx) & (ty == yy)
    lands &= run[yy // k, xx // k]
    assert lands.any()
    assert not (fine_of(lands, fine) & ~got).any()


# ---- the tiled draw against the full-screen one ------------------------------------------------

W, H = 160, 96


def frames_of(rng):
    """(name, depth, displacement) of a sequence: a small fast mover, a slow one, one in
    the left edge, nothing moving, a pan, a fast and a slow mover side by side."""
    def scene(*movers, pan=None):
        depth = rng.uniform(8.0, 9.0, (H, W))
        disp = np.zeros((H, W, 2))
        if pan is not None:
            disp[:] = pan + rng.uniform(-1.0, 1.0, (H, W, 2))
        for (y0, x0, hh, ww), d in movers:
            disp[y0:y0 + hh, x0:x0 + ww] = d
            depth[y0:y0 + hh, x0:x0 + ww] = 2.0
        return depth, disp
    return [("fast", *scene(((40, 70, 6, 8), (30.0, 10.0)))),
            ("slow", *scene(((40, 70, 6, 8), (5.0, -2.0)))),
            ("edge", *scene(((40, 0, 6, 5), (30.0, 0.0)))),
            ("still", *scene()),
            ("pan", *scene(pan=(12.0, 3.0))),
            ("pair", *scene(((40, 40, 6, 8), (40.0, 0.0)), ((40, 52, 4, 4), (1.5, 0.0))))]


def assert_tiled_is_full(synthetic_frame, passes, out, p, stat):
    """Every frame of frames_of, one pool per way (state kept across the frames): the same
    bytes; returns the stat `stat` per frame."""
    rng = np.random.default_rng(8)
    frames = {t: synthetic_frame((W, H), p, seed=3) for t in (True, False)}
    seen = {}
    for name, depth, disp in frames_of(rng):
        color = rng.uniform(0.0, 1.0, (H, W, 3))
        got = {}
        for tiled, frame in frames.items():
            upload(frame, color, depth, disp)
            for q in passes(tiled=tiled):
                q.allocate(frame)
                q.execute(frame)
            got[tiled] = download(frame, out)
        assert got[True].tobytes() == got[False].tobytes(), name
        seen[name] = frames[True].stats[stat]
    return seen


@pytest.mark.parametrize("kw", [{}, dict(jitter=0.0, samples=7), dict(centre_kappa=40.0),
                                dict(samples=31)])
def test_tiled_mcguire_is_the_full_screen_one(synthetic_frame, kw):
    seen = assert_tiled_is_full(synthetic_frame, mcguire_passes, "mcguire",
                                params(0.08, **kw), "mcguire_gather_centre_tiles")
    assert seen["edge"] > 0 and seen["still"] == 0  # a tap clamped back onto column 0
    if not kw:                  # |vN| / 16 < 0.5 px: taps of the slow mover's land on X
        assert seen["slow"] > 0 and seen["fast"] == 0


def test_tiled_mcguire_draws_only_near_motion(synthetic_frame):
    """A small fast mover: its blur reaches under half the FINE tiles of the k x k tiles
    whose NeighborMax lookup runs."""
    from viewer.render.passes.gather_tiles import within_reach
    size, k = (320, 192), 32
    frame = synthetic_frame(size, params(k / 320))
    disp = np.zeros((192, 320, 2))
    disp[90:96, 150:158] = (30.0, 10.0)
    upload(frame, np.random.default_rng(8).uniform(0.0, 1.0, (192, 320, 3)),
           np.full((192, 320), 9.0), disp)
    for q in mcguire_passes():
        q.allocate(frame)
        q.execute(frame)
    lookups = to_image(frame.read("mcguire_neighbormax"))[..., :2]
    run = within_reach(np.hypot(lookups[..., 0], lookups[..., 1]) > 0.501, k, size, 0)
    assert 0 < frame.stats["mcguire_gather_tiles"] < run.sum() / 2
    assert frame.stats["mcguire_gather_centre_tiles"] == 0


def test_tiled_mcguire_reaches_as_far_as_the_blur(synthetic_frame):
    """A mover whose blur (|v| = 5.25 px) ends a quarter pixel past a FINE tile's edge:
    a still pixel 5 px away, in a tile only that reach lists, is blurred, and the tiled
    draw has it."""
    p = params(0.08)                                   # k = 13: strips of 13 px
    rng = np.random.default_rng(2)
    color = rng.uniform(0.0, 1.0, (H, W, 3))
    depth = np.full((H, W), 9.0)
    disp = np.zeros((H, W, 2))
    disp[36:41, 39:52] = (0.0, 10.5)                   # rows 36-40: row 31 is 5 px off
    depth[36:41, 39:52] = 2.0
    got = {}
    for tiled in (True, False):
        frame = synthetic_frame((W, H), p, seed=1)
        upload(frame, color, depth, disp)
        for q in mcguire_passes(tiled=tiled):
            q.allocate(frame)
            q.execute(frame)
        got[tiled] = download(frame, "mcguire")[..., :3]
    assert got[True].tobytes() == got[False].tobytes()
    assert (np.abs(got[False][31, 39:52] - color[31, 39:52]) > 1e-3).any()
    # a pixel farther off keeps its colour up to rounding (taps landing on itself)
    np.testing.assert_allclose(got[False][30], color[30], rtol=1e-6)


@pytest.mark.parametrize("kw", [dict(tile=16), dict(tile=8, taps=2), dict(fast_path=False),
                                dict(fast_ratio=0.0, tile_jitter=0.0)])
def test_tiled_ue4_is_the_full_screen_one(synthetic_frame, kw):
    seen = assert_tiled_is_full(synthetic_frame, ue4_passes, "ue4", params(0.08, "ue4", **kw),
                                "ue4_gather_tiles")
    assert seen["still"] == 0 and 0 < seen["fast"] < seen["pan"]


@pytest.mark.parametrize("scene,sets", [("living_room", {}), ("wheel", {}),
                                        ("pan", {}), ("living_room", {"motion.steps": 2})])
def test_tiled_gathers_are_the_full_screen_ones_on_scenes(ctx, scene, sets):
    """Three frame times of a scene, each tiled and full screen in one renderer."""
    from viewer.render.renderer import Renderer
    from world.loader import load_scene
    sc = load_scene(scene)
    r = Renderer(ctx, sc, (320, 180))
    p = ParamSet()
    for key, value in sets.items():
        p.set(key, value)
    try:
        for mode in ("mcguire", "ue4"):
            gather = r.pipeline(mode).passes[-1]
            for k in range(3):
                got = {}
                for tiled in (True, False):
                    gather.tiled = tiled
                    got[tiled] = r.render(mode, sc.render.time + k / 30.0, p, seed=k).image
                assert got[True].tobytes() == got[False].tobytes(), (mode, k)
    finally:
        r.release()
