"""Guertin 2014 (mode `guertin`): each pass on tiny synthetic buffers against the numpy
statement of the paper's formulas in tests/numpy_guertin.py (itself checked on
hand-computed cases), analytic behaviour, and the tiled gathers of every post-process
mode (McGuire, UE4-style, Guertin) against their full-screen draws, byte for byte.

Arrays are in GL orientation (row 0 at the bottom), as in tests/test_mcguire.py.
"""
from __future__ import annotations

import numpy as np
import pytest

import numpy_guertin as ng
import numpy_mcguire as nm
from numpy_ue4 import ign
from test_mcguire import (assert_still_scene_unchanged, download, images_per_seed,
                          random_velocities, render_basic, two_layer_scene, upload)
from test_mcguire import params as mcguire_params
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.modes.guertin import EARLY_OUT_PX, TAP_NOISE, TILE_STREAM_X, TILE_STREAM_Y, guertin_passes
from viewer.render.modes.mcguire import mcguire_passes
from viewer.render.modes.reference import REGIONS
from viewer.render.modes.ue4 import ue4_passes

SIZE = (32, 16)
STREAMS = (TAP_NOISE, TILE_STREAM_X, TILE_STREAM_Y)


def params(max_radius=None, group="guertin", **kw):
    return mcguire_params(max_radius, group, **kw)


def run(frame, passes=None, output="guertin"):
    for p in passes or guertin_passes():
        p.allocate(frame)
        p.execute(frame)
    return download(frame, output)[..., :3].astype(np.float64)


def reference(frame, color, depth, disp, **kw):
    g = frame.params["guertin"]
    args = dict(samples=g.samples, gamma=g.gamma, kappa=g.kappa, eta=g.eta, phi=g.phi,
                skip_middle=g.skip_middle, tile_jitter=g.tile_jitter, z_scale=g.z_scale,
                seed=frame.seed, streams=STREAMS, early_out=EARLY_OUT_PX)
    return ng.guertin(color, depth, disp, max_radius_px(frame), **{**args, **kw})


# ---- the numpy reference on hand-computed values ---------------------------------------------

def test_reference_by_hand():
    # relative depth compare: nearer is in front; twice as far is wholly behind
    assert ng.front(2.0, 4.0) == 1.0 and ng.front(4.0, 2.0) == 0.0
    assert ng.front(3.0, 2.0) == 0.5 and ng.front(3.0, 2.0, z_scale=2.0) == 0.75
    # the centre direction: perpendicular of wN for a still pixel, its own once fast,
    # a blend in between (|vc| = 1.25 px: half way with gamma = 1.5)
    vn = np.array([[2.0, 0.0]] * 4)
    vc = np.array([[0.0, 0.0], [0.0, -1.0], [3.0, 0.0], [0.75, 1.0]])
    wc = ng.centre_direction(vn, vc, 1.5)
    np.testing.assert_allclose(wc[0], [0, 1], atol=1e-12)
    np.testing.assert_allclose(wc[1], [0, -1], atol=1e-12)     # perpendicular on vC's side
    np.testing.assert_allclose(wc[2], [1, 0], atol=1e-12)
    np.testing.assert_allclose(wc[3], np.array([0.3, 0.9]) / np.hypot(0.3, 0.9), atol=1e-12)
    # diagonal rule: the bottom-left neighbour (o = (-1, -1)) counts only pointing up-right
    for v, taken in (([1.0, 1.0], True), ([-1.0, -1.0], False), ([1.0, -1.0], False)):
        t = np.zeros((3, 3, 2), np.float32)
        t[0, 0] = v
        assert np.array_equal(ng.neighbormax(t)[1, 1], t[0, 0] if taken else [0, 0])
    t = np.zeros((3, 3, 2), np.float32)
    t[1, 0] = [-1.0, 0.0]                     # an axis neighbour counts whatever its direction
    assert np.array_equal(ng.neighbormax(t)[1, 1], [-1, 0])


def test_reference_gather_by_hand():
    # 5x1, v = (2, 0) everywhere, N = 2, no jitter: t = -1/3 (tap 0, even: along wN) and
    # +1/3 (tap 1, odd: along wC; wC = wN = (1, 0)), read at x = 1 and 3 and weighed at
    # the unrounded T = |t| |vN| = 2/3 px (not the 1 px of the pixel read): same depth,
    # cone(2/3, 2) = 2/3 twice and 2 cyl = 2, direction weights 1: a = 10/3. Centre weight
    # N / (kappa |vC|) = 1/40.
    c = (np.arange(15, dtype=float) ** 2).reshape(1, 5, 3)
    v = np.tile(np.float32([2.0, 0.0]), (1, 5, 1))
    kw = dict(k=5, kappa=40.0, eta=0.0, tile_jitter=0.0)
    out, amb = ng.gather(c, np.ones((1, 5)), v, v[:, :1], samples=2, **kw)
    expect = (c[0, 2] / 40 + 10 / 3 * (c[0, 1] + c[0, 3])) / (1 / 40 + 20 / 3)
    np.testing.assert_allclose(out[0, 2], expect, rtol=1e-6)    # (t in float32)
    assert not amb[0, 2]
    # a still pixel X = 2 under vN = (2, 0): wC = (0, 1), the perpendicular; its centre
    # weight is 2 / (40 * 0.5) = 1/10. Tap 0 (along wN) reads x = 1, in front (same
    # depth), moving along wN: cone(2/3, 2) = 2/3; X's terms weigh 0 (wA = 0, and
    # cyl(2/3, 0.5) = 0). Tap 1 (along wC) clamps back onto X (one row) but lies 2/3 px
    # out, past X's 0.5 px spread: a = 0.
    v[0, 2] = 0.0
    out, _ = ng.gather(c, np.ones((1, 5)), v, np.float32([[[2.0, 0.0]]]), samples=2, **kw)
    np.testing.assert_allclose(out[0, 2], (0.1 * c[0, 2] + 2 / 3 * c[0, 1]) / (0.1 + 2 / 3),
                               rtol=1e-6)


def test_middle_tap_and_jitter_by_hand():
    # N = 3, v = (2, 0) everywhere, no jitter: t = -1/2, 0, +1/2. Taps 0 and 2 (along wN)
    # read x = 1 and 3 at T = 1: cone(1, 2) = 1/2 twice + 2 cyl = 3 each. The middle tap
    # (1, along wC) reads X itself at T = 0: a = 4, unless skipped. Centre: 3/80.
    c = (np.arange(15, dtype=float) ** 2).reshape(1, 5, 3)
    v = np.tile(np.float32([2.0, 0.0]), (1, 5, 1))
    kw = dict(k=5, samples=3, kappa=40.0, eta=0.0, tile_jitter=0.0)
    side = 3 * (c[0, 1] + c[0, 3])
    out, _ = ng.gather(c, np.ones((1, 5)), v, v[:, :1], skip_middle=True, **kw)
    np.testing.assert_allclose(out[0, 2], (3 / 80 * c[0, 2] + side) / (3 / 80 + 6), rtol=1e-6)
    out, _ = ng.gather(c, np.ones((1, 5)), v, v[:, :1], skip_middle=False, **kw)
    np.testing.assert_allclose(out[0, 2], ((3 / 80 + 4) * c[0, 2] + side) / (3 / 80 + 10),
                               rtol=1e-6)
    assert ng.taps(3, True) == [(0, True), (2, True)]
    assert ng.taps(4, True) == [(0, True), (1, False), (2, True), (3, False)]   # no middle
    # the jitter: one interleaved-gradient value per pixel, eta * phi / N tap spacings
    ys, xs = np.mgrid[0:4, 0:6]
    j = ng.tap_jitter(xs, ys, 15, 0.95, 27.0, seed=2, noise=3.0)
    want = 0.95 * 27 / 15 * (2 * ign(xs, ys, 3.0, 2).astype(np.float64) - 1)
    np.testing.assert_allclose(j, want, rtol=1e-6, atol=1e-6)
    assert ng.tap_t(0, 15, np.float32(0.0)) == np.float32(-0.875)


def test_lookup_never_reads_a_diagonal_tile():
    """The NeighborMax lookup moves along one axis only, so the tile read is the pixel's
    own or an axis neighbour, whose NeighborMax always holds the pixel's own TileMax:
    |vN| >= |vC| at every pixel, even where the diagonal rule drops a corner tile."""
    k, w, h = 8, 24, 24
    ys, xs = np.mgrid[0:h, 0:w]
    ox, oy = ng.lookup_offset(xs, ys, k, 0.5, seed=1, streams=STREAMS[1:])
    assert not np.any((ox != 0) & (oy != 0))
    assert np.abs(ox).max() > 3.5 and np.abs(oy).max() > 3.5 and np.abs(ox).max() <= 4.0
    tx, ty, _ = ng.lookup_tiles(xs, ys, w, h, k, 0.5, 1, STREAMS[1:])
    moved = np.abs(tx - xs // k) + np.abs(ty - ys // k)
    assert moved.max() == 1 and (moved == 1).mean() > 0.1
    # the bottom-left tile moves down-left, away from its diagonal neighbour (1, 1), whose
    # NeighborMax drops it; the rest is still. Its pixels near that corner, shifted up and
    # right at once, would read vN = 0 and stay sharp.
    v = np.zeros((h, w, 2), np.float32)
    v[:k, :k] = [-3.0, -3.0]
    nmax = ng.neighbormax(nm.tilemax(v, k))
    assert np.array_equal(nmax[1, 1], [0, 0]) and np.array_equal(nmax[1, 0], [-3, -3])
    for seed in range(8):
        tx, ty, _ = ng.lookup_tiles(xs, ys, w, h, k, 0.5, seed, STREAMS[1:])
        vn = nmax[ty, tx]
        assert np.all(np.hypot(vn[..., 0], vn[..., 1]) >= np.hypot(v[..., 0], v[..., 1]))


# ---- the passes against the reference ---------------------------------------------------------

@pytest.mark.parametrize("size,max_radius", [((32, 16), 0.15), ((29, 13), 0.1)])
def test_velocity_tilemax_and_diagonal_neighbormax(synthetic_frame, size, max_radius):
    rng = np.random.default_rng(2)
    w, h = size
    frame = synthetic_frame(size, params(max_radius=max_radius))
    k = max_radius_px(frame)
    disp = random_velocities(rng, h, w, 2.0 * k)
    disp[0, :3] = 0.0
    upload(frame, np.zeros((h, w, 3)), np.ones((h, w)), disp)
    for p in guertin_passes()[:4]:
        p.allocate(frame), p.execute(frame)
    v = download(frame, "guertin_velocity")
    np.testing.assert_allclose(v, nm.clamp_velocity(disp, k), rtol=2e-6, atol=1e-7)
    tiles = download(frame, "guertin_tilemax")
    np.testing.assert_array_equal(tiles, nm.tilemax(v, k))
    nmax = download(frame, "guertin_neighbormax")
    np.testing.assert_array_equal(nmax, ng.neighbormax(tiles))
    assert not np.array_equal(nmax, nm.neighbormax(tiles))     # the rule dropped some


@pytest.mark.parametrize("kw,seed", [
    (dict(eta=0.0, tile_jitter=0.0), 0),
    (dict(), 7),                                          # the paper's defaults
    (dict(samples=9, gamma=0.5, kappa=10.0, tile_jitter=0.5, z_scale=0.3), 3),
    (dict(samples=20, eta=0.5), 1),
    (dict(kappa=40.0, phi=27.0, skip_middle=False), 5),  # the paper's Appendix A
])
def test_gather_matches_reference(synthetic_frame, kw, seed):
    rng = np.random.default_rng(3)
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25, **kw), seed=seed)
    color, depth, disp = two_layer_scene(rng, h, w)
    disp[12:, 24:] = 0.0                      # a still corner: the perpendicular fallback
    upload(frame, color, depth, disp)
    out = run(frame, guertin_passes(tiled=False))
    ref, amb = reference(frame, color, depth, disp)
    assert amb.mean() < 0.2
    np.testing.assert_allclose(out[~amb], ref[~amb], rtol=1e-4, atol=1e-5)


def test_parameters_change_the_image(synthetic_frame):
    rng = np.random.default_rng(4)
    w, h = 64, 32                            # k = 4: tiles with and without the slab
    color, depth, disp = two_layer_scene(rng, h, w)
    base = None
    for kw in ({}, dict(samples=9), dict(gamma=5.0), dict(kappa=200.0), dict(eta=0.2),
               dict(phi=27.0), dict(skip_middle=False), dict(tile_jitter=0.0),
               dict(z_scale=0.05)):
        frame = synthetic_frame((w, h), params(max_radius=0.0625, **kw), seed=2)
        upload(frame, color, depth, disp)
        out = run(frame)
        if base is None:
            base = out
        else:
            assert np.abs(out - base).max() > 1e-3, kw


# ---- analytic behaviour ----------------------------------------------------------------------

BAR, BACK = np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.2, 1.0])


def test_moving_bar_smears_over_static_background(synthetic_frame):
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25, eta=0.0, tile_jitter=0.0))
    color = np.tile(BACK, (h, w, 1))
    depth = np.full((h, w), 10.0)
    disp = np.zeros((h, w, 2))
    color[:, 12:20], depth[:, 12:20], disp[:, 12:20] = BAR, 2.0, [12.0, 0.0]
    upload(frame, color, depth, disp)
    out = run(frame)
    bar = out[8, :, 0]
    assert np.all(bar[9:12] > 0.05) and np.all(bar[20:23] > 0.05)        # outer blur
    np.testing.assert_allclose(out[:, :3], color[:, :3], atol=1e-6)      # out of reach
    assert np.all(out[8, 12:20, 0] > 0.4)                                # still mostly bar


def test_still_detail_beside_motion_stays_sharp(synthetic_frame):
    """Near stripes that do not move, in front of a far plane moving across them: the
    stripes' taps run along the perpendicular and across the motion, none is in front,
    and a neighbour pixel is 1 px away, past a still pixel's 0.5 px spread: the stripes
    keep their exact colour (a tap weighed at its unrounded 0.5 px distance would not)."""
    w, h = SIZE
    frame = synthetic_frame(SIZE, params(max_radius=0.25), seed=4)
    color = np.tile(BACK, (h, w, 1))
    depth = np.full((h, w), 10.0)
    disp = np.tile([0.0, 12.0], (h, w, 1))
    stripes = np.where(np.arange(w) % 2 == 0, 0.9, 0.1)[None, :, None] * np.ones((h, 1, 3))
    color[:, 8:24], depth[:, 8:24], disp[:, 8:24] = stripes[:, 8:24], 2.0, 0.0
    upload(frame, color, depth, disp)
    out = run(frame)
    np.testing.assert_allclose(out[:, 8:24], color[:, 8:24], atol=1e-6)


def test_static_scene_is_unchanged_and_seeds_differ(synthetic_frame):
    assert_still_scene_unchanged(synthetic_frame, params(), run)
    images = images_per_seed(synthetic_frame, params(max_radius=0.25), run, "guertin")
    assert images[0] == images[1] and images[0] != images[2]


# ---- the tiled gathers -----------------------------------------------------------------------

MODES = {"guertin": (guertin_passes, "guertin"), "mcguire": (mcguire_passes, "mcguire"),
         "ue4": (ue4_passes, "ue4")}


@pytest.mark.parametrize("size,tile,reach", [((50, 37), 7, 3), ((64, 32), 16, 5), ((33, 20), 3, 0)])
def test_within_reach_is_the_pixelwise_rule(size, tile, reach):
    """A FINE tile is listed exactly when one of its pixels has a moving lookup tile
    within reach px (the pixel offset on each axis, clamped to the screen)."""
    from viewer.render.passes.gather_tiles import within_reach
    w, h = size
    rng = np.random.default_rng(9)
    moving = rng.uniform(size=(-(-h // tile), -(-w // tile))) < 0.08
    fine = 4
    got = within_reach(moving, tile, size, reach, fine)
    want = np.zeros(got.shape, bool)
    for y in range(h):
        for x in range(w):
            qy = np.clip(np.arange(y - reach, y + reach + 1), 0, h - 1) // tile
            qx = np.clip(np.arange(x - reach, x + reach + 1), 0, w - 1) // tile
            if moving[np.ix_(np.unique(qy), np.unique(qx))].any():
                want[y // fine, x // fine] = True
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("mode", list(MODES))
def test_tiled_gather_is_the_full_screen_one(synthetic_frame, mode):
    """Three frames in one pool (state kept: last frame's tiles), a small object moving
    over a still background, then nothing moving, then the object elsewhere: the tiled
    gather gives the full-screen draw's bytes, and draws only some tiles."""
    rng = np.random.default_rng(8)
    w, h = 96, 48
    make, out = MODES[mode]
    group = {"ue4": dict(group="ue4", tile=8)}.get(mode, {})
    frames = {t: synthetic_frame((w, h), params(max_radius=0.05, **group), seed=3)
              for t in (True, False)}
    color = rng.uniform(0, 1, (h, w, 3))
    for x0, moving in ((10, True), (0, False), (60, True)):
        disp = np.zeros((h, w, 2))
        depth = np.full((h, w), 9.0)
        if moving:
            disp[20:26, x0:x0 + 6] = [7.0, 3.0]
            depth[20:26, x0:x0 + 6] = 2.0
        got = {}
        for tiled, frame in frames.items():
            upload(frame, color, depth, disp)
            run(frame, make(tiled=tiled), out)
            got[tiled] = frame.pool.get(out).read()
        assert got[True] == got[False], (mode, x0)
        tl = next(v for k, v in frames[True].kept.items()
                  if k.startswith("gather_tiles:"))
        assert (0 < tl.count < -(-w // tl.tile) * -(-h // tl.tile)) if moving else tl.count == 0


# ---- the whole mode --------------------------------------------------------------------------

def test_mode_beats_off_on_basic(ctx):
    from viewer.eval.metrics import image_metrics
    from viewer.render.modes.regions import OUTER
    ref, images, names = render_basic(ctx, ("off", "guertin"))
    region = ref.host[REGIONS]
    assert (region == OUTER).sum() > 50
    m = {k: image_metrics(img, ref.image, region) for k, img in images.items()}
    assert m["guertin"]["outer"]["flip"] < m["off"]["outer"]["flip"]
    assert m["guertin"]["all"]["flip"] < m["off"]["all"]["flip"]
    static = region == 0
    assert np.abs(images["guertin"] - images["off"])[static].mean() < 0.003
    for tex in ("guertin_velocity", "guertin_tilemax", "guertin_neighbormax", "guertin"):
        assert tex in names["guertin"]
