"""UE4-style motion blur (viewer/render/modes/ue4.py): each pass on tiny synthetic buffers against
the numpy reference in tests/numpy_ue4.py (itself checked on hand-computed cases first), the
behaviour docs/algorithms.md 3.2, 3.4 promises (linear ramps, mirrored inner background, fast path,
static scenes unchanged) and the whole mode against the reference on a conformance scene.

Synthetic arrays are built in GL orientation (row 0 at the bottom, velocity y up) and
flipped once on upload and read-back.
"""
from __future__ import annotations

import numpy as np
import pytest

import numpy_ue4 as nu
from conftest import CONFORMANCE
from world.conventions import to_image
from viewer.render.graph.params import ParamSet
from viewer.render.passes.gbuffer import GBUFFER
from viewer.render.graph.pool import TexSpec
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.modes.ue4 import Dilate, Flatten, Gather, TileMinMax, dilation_reach, tile_spec
from viewer.render.modes.reference import REGIONS


def make_params(**ue4) -> ParamSet:
    ps = ParamSet()
    max_radius = ue4.pop("max_radius", None)
    if max_radius is not None:
        ps.set("blur.max_radius", max_radius)
    for k, v in ue4.items():
        ps.set(f"ue4.{k}", v)
    return ps


def upload(frame, name, spec, gl_array):
    frame.pool.texture(name, spec)
    frame.write(name, to_image(np.asarray(gl_array)))


def read_gl(frame, name):
    return to_image(frame.read(name))


def run(frame, *passes):
    for p in passes:
        p.allocate(frame)
        p.execute(frame)


def run_gather(frame, color, flat, dilated):
    """The gather alone on these inputs (its tile list reads the tile min/max too)."""
    upload(frame, "color", GBUFFER["color"], np.dstack([color, np.ones(color.shape[:2])]))
    upload(frame, "ue4_flat", TexSpec(4, "f4"), flat)
    upload(frame, "ue4_tiles", tile_spec(frame), nu.tile_minmax(flat, frame.params["ue4"].tile))
    upload(frame, "ue4_dilated", tile_spec(frame), dilated)
    run(frame, Gather())
    return read_gl(frame, "ue4")[..., :3]


def gather_kwargs(params: ParamSet, seed: int = 0) -> dict:
    p = params["ue4"]
    return dict(tile=p.tile, taps=p.taps, depth_scale=p.depth_scale,
                tile_jitter=p.tile_jitter, tap_jitter=p.tap_jitter, fast_path=p.fast_path,
                fast_ratio=p.fast_ratio, mirror=p.mirror, bilinear_taps=p.bilinear, seed=seed)


def bar_scene(w, h, lo, hi, bar_v, bg_v, bar_depth=2.0, bg_depth=10.0):
    """GL-orientation buffers of a bar [lo, hi) (red) over a background whose green channel
    is x / w; `bar_v`, `bg_v` are the FULL displacements D (px) along x."""
    x = np.arange(w)
    in_bar = np.broadcast_to((x >= lo) & (x < hi), (h, w))
    color = np.zeros((h, w, 3), np.float32)
    color[..., 1] = np.where(in_bar, 0.0, x / w)
    color[..., 0] = in_bar
    velocity = np.zeros((h, w, 2), np.float32)
    velocity[..., 0] = np.where(in_bar, bar_v, bg_v)
    depth = np.where(in_bar, bar_depth, bg_depth).astype(np.float32)
    return color, velocity, depth


def render_ue4(frame, color, velocity, depth):
    """Upload a G-buffer (GL orientation) and run flatten -> tiles -> dilate -> gather."""
    upload(frame, "color", GBUFFER["color"], np.dstack([color, np.ones(color.shape[:2])]))
    upload(frame, "velocity", GBUFFER["velocity"], velocity)
    upload(frame, "depth", GBUFFER["depth"], depth)
    run(frame, Flatten(), TileMinMax(), Dilate(), Gather())
    return read_gl(frame, "ue4")[..., :3]


def numpy_ue4(frame, color, velocity, depth, seed=0):
    p = frame.params["ue4"]
    max_px = max_radius_px(frame)
    flat = nu.flatten(velocity, depth, max_px)
    tiles = nu.tile_minmax(flat, p.tile)
    dil = nu.dilate(tiles, p.tile, dilation_reach(max_px, p.tile), p.fast_path_guard,
                    p.tile_jitter)
    return nu.gather(color, flat, dil, **gather_kwargs(frame.params, seed))


# ---------------------------------------------------------------- numpy reference, by hand

def test_numpy_box_coverage_hand_values():
    # interval [10, 20) moving by 8 px in all (radius 4)
    got = nu.box_coverage([5.0, 6.0, 8.0, 10.0, 14.0, 15.0, 20.0, 24.0, 25.0], 10, 20, 4)
    assert np.allclose(got, [0.0, 0.0, 0.25, 0.5, 1.0, 1.0, 0.5, 0.0, 0.0])


def test_numpy_flatten_and_tiles_hand_values():
    vel = np.array([[[6.0, 8.0], [30.0, -40.0]]], np.float32)      # |v| = 5 and 25
    flat = nu.flatten(vel, np.array([[1.0, 2.0]]), max_px=10)
    assert np.allclose(flat[0, 0], [3, 4, 1, 5]) and np.allclose(flat[0, 1], [6, -8, 2, 10])
    f = np.zeros((3, 3, 4), np.float32)
    f[..., 3] = [[2, 1, 3], [1, 5, 0], [5, 0.5, 4]]
    f[..., 0] = np.arange(9).reshape(3, 3)                            # tags each pixel
    t = nu.tile_minmax(f, 2)
    assert t.shape == (2, 2, 4)
    assert t[0, 0, 0] == 1 and t[0, 0, 2] == 4        # min 1: the first in scan order wins
    assert t[0, 1, 0] == 5 and t[0, 1, 2] == 2        # column 2 alone: min 0, max 3
    assert t[1, 0, 0] == 7 and t[1, 0, 2] == 6        # row 2 alone: min 0.5, max 5


def test_numpy_quad_cover_hand_values():
    # 8 px to the right with 4 px tiles: 2 tiles along, e = 0.99 across
    cover = {(ox, oy) for ox in range(-5, 6) for oy in range(-5, 6)
             if nu.covers(np.array([8.0, 0.0]), (ox, oy), 4)}
    assert cover == {(ox, 0) for ox in range(-2, 3)}
    # diagonal (6, 6) px: |v_t| = 2.12 tiles, e = 1.40
    diag = {(ox, oy) for ox in range(-5, 6) for oy in range(-5, 6)
            if nu.covers(np.array([6.0, 6.0]), (ox, oy), 4)}
    assert (2, 2) in diag and (2, 1) in diag and (1, 0) in diag and (-2, -1) in diag
    assert (3, 3) not in diag and (2, 0) not in diag and (3, 2) not in diag
    # slower than half a pixel: only itself
    assert nu.covers(np.array([0.3, 0.3]), (0, 0), 4)
    assert not nu.covers(np.array([0.3, 0.3]), (1, 0), 4)


def test_numpy_gather_bar_ramps_by_hand():
    # K = 2 taps per side, R = 4 px, jitter off: taps at 1 and 3 px from the centre
    color, vel, depth = bar_scene(24, 1, 8, 16, bar_v=8.0, bg_v=0.0)
    flat = nu.flatten(vel, depth, 8)
    dil = nu.dilate(nu.tile_minmax(flat, 8), 8, 2)
    out = nu.gather(color, flat, dil, tile=8, taps=2, tile_jitter=0.0, tap_jitter=0.0)
    red = out[0, :, 0]
    # outer blur right of the bar: taps at 1 and 3 px toward the bar, weight 1 each in F
    assert np.allclose(red[16:21], [0.5, 0.25, 0.25, 0.0, 0.0])
    # inner blur just inside: 2 of the 4 taps reach the background at 16.5 and 17.5+...
    assert np.allclose(red[12:16], [1.0, 0.75, 0.75, 0.5])
    assert np.allclose(red[4:8], [0.0, 0.25, 0.25, 0.5])


# ---------------------------------------------------------------- single passes on the GPU

def test_flatten_halves_and_clamps(synthetic_frame):
    rng = np.random.default_rng(1)
    frame = synthetic_frame((32, 16), make_params(max_radius=0.25))     # 8 px
    vel = rng.uniform(-30, 30, (16, 32, 2)).astype(np.float32)
    vel[0, 0] = 0.0
    depth = rng.uniform(0.5, 20, (16, 32)).astype(np.float32)
    depth[0, 1] = 1e9
    upload(frame, "velocity", GBUFFER["velocity"], vel)
    upload(frame, "depth", GBUFFER["depth"], depth)
    run(frame, Flatten())
    got = read_gl(frame, "ue4_flat")
    want = nu.flatten(vel, depth, 8)
    assert np.allclose(got, want, rtol=1e-6, atol=1e-6)
    clamped = np.linalg.norm(vel, axis=-1) > 16
    assert clamped.any() and (~clamped).any()
    assert np.all(got[clamped, 3] == 8.0)
    assert np.array_equal(got[0, 0], [0, 0, depth[0, 0], 0])
    assert got[0, 1, 2] == np.float32(1e9)


def test_tile_min_max_partial_border_tiles(synthetic_frame):
    rng = np.random.default_rng(2)
    frame = synthetic_frame((37, 19), make_params(tile=8))          # 5 x 3 tiles, partial
    flat = np.zeros((19, 37, 4), np.float32)
    flat[..., :2] = rng.normal(0, 5, (19, 37, 2))
    flat[..., 2] = 5.0
    flat[..., 3] = np.linalg.norm(flat[..., :2], axis=-1)
    # tile (0, 0): one length, 64 directions: the first pixel in scan order wins both
    angle = np.arange(64).reshape(8, 8)
    flat[:8, :8, 0], flat[:8, :8, 1], flat[:8, :8, 3] = np.cos(angle), np.sin(angle), 1.0
    upload(frame, "ue4_flat", TexSpec(4, "f4"), flat)
    run(frame, TileMinMax())
    got = read_gl(frame, "ue4_tiles")
    assert got.shape == (3, 5, 4)
    assert np.array_equal(got[0, 0], [1, 0, 1, 0])
    assert np.array_equal(got, nu.tile_minmax(flat, 8))
    # the corner tile holds 5 x 3 pixels; nothing outside the screen takes part
    corner = flat[16:, 32:].reshape(-1, 4)
    assert np.array_equal(got[2, 4, :2], corner[np.argmin(corner[:, 3]), :2])
    assert np.array_equal(got[2, 4, 2:], corner[np.argmax(corner[:, 3]), :2])


def test_dilation_quad_cover_on_tile_grid(synthetic_frame):
    # 64 x 32 px, 4 px tiles -> 16 x 8 tiles; limit 16 px = 4 tiles, so reach = 5 tiles
    frame = synthetic_frame((64, 32), make_params(tile=4, max_radius=0.25))
    tiles = np.zeros((8, 16, 4), np.float32)
    tiles[3, 7] = [1.0, 0.0, 16.0, 0.0]       # 4 tiles to the right: beyond a +-3 window
    tiles[6, 2] = [0.0, 0.5, 6.0, 6.0]        # diagonal
    tiles[0, 12] = [0.0, 0.0, 0.3, 0.3]       # under half a pixel: covers itself only
    tiles[3, 9] = [3.0, 0.0, 5.0, 0.0]        # its min is larger than the static tiles'
    upload(frame, "ue4_tiles", tile_spec(frame), tiles)
    run(frame, Dilate())
    got = read_gl(frame, "ue4_dilated")
    assert dilation_reach(16, 4) == 5
    assert np.array_equal(got, nu.dilate(tiles, 4, 5))
    # the fast tile's max reaches +-4 tiles along its row, not beyond, not across
    assert all(np.array_equal(got[3, x, 2:], [16, 0]) for x in range(3, 12))
    assert not got[3, 2, 2:].any() and not got[3, 12, 2:].any() and not got[2, 7, 2:].any()
    # min-of-mins: static tiles keep their zero min; the covered tile (3, 9) merges with
    # the fast tile's min (1, 0) and its own (3, 0)
    assert np.array_equal(got[3, 9], [1, 0, 16, 0]) and np.array_equal(got[3, 5], [0, 0, 16, 0])
    # diagonal sweep: (2, 2) and (2, 1) tiles away are covered, (2, 0) is not
    assert np.array_equal(got[7, 4, 2:], [6, 6]) and np.array_equal(got[7, 3, 2:], [6, 6])
    assert np.array_equal(got[5, 1, 2:], [6, 6])
    assert not got[6, 4, 2:].any()
    assert np.array_equal(got[0, 12], np.float32([0, 0, 0.3, 0.3])) and not got[0, 13, 2:].any()


def test_gather_matches_numpy_with_noise(synthetic_frame):
    """Every pixel of a two-layer scene with mixed motion, IGN and tile jitter on."""
    rng = np.random.default_rng(3)
    params = make_params(tile=8, max_radius=0.25, taps=6)
    frame = synthetic_frame((32, 16), params, seed=5)
    h, w = 16, 32
    color = rng.uniform(0, 1, (h, w, 3)).astype(np.float32)
    yy, xx = np.mgrid[0:h, 0:w]
    disc = (xx - 14) ** 2 + (yy - 8) ** 2 < 30
    vel = np.zeros((h, w, 2), np.float32)
    vel[disc] = [11.0, 5.0]
    vel[~disc] = [-3.0, 0.0]
    vel[:, 26:] = 0.0                                   # a static strip
    depth = np.where(disc, 2.0, 6.0 + 0.01 * xx).astype(np.float32)
    flat = nu.flatten(vel, depth, max_radius_px(frame))
    dil = nu.dilate(nu.tile_minmax(flat, 8), 8, dilation_reach(max_radius_px(frame), 8))
    got = run_gather(frame, color, flat, dil)
    want = nu.gather(color, flat, dil, **gather_kwargs(params, seed=5))
    assert np.abs(got - want).max() < 2e-5
    assert np.abs(got - color).max() > 0.1             # it did blur something


@pytest.mark.parametrize("taps", [4, 8])
def test_moving_bar_linear_ramps_both_sides_of_each_edge(synthetic_frame, taps):
    """A bar of width 32 moving 32 px (R = 16) over a static background. Jitter off, the
    taps sit at whole-pixel offsets (i + 1/2) R/K, so they read pixel centres and every
    weight is 0 or 1: UE4-style gives staircases within a quarter of a 1/(2K) step of the
    analytic box-shutter coverage, i.e. linear ramps of slope 1/(2R)."""
    w, h, R = 128, 4, 16
    params = make_params(tile=16, max_radius=0.125, taps=taps, tile_jitter=0.0, tap_jitter=0.0)
    frame = synthetic_frame((w, h), params)
    color, vel, depth = bar_scene(w, h, 48, 80, bar_v=2 * R, bg_v=0.0)
    got = render_ue4(frame, color, vel, depth)
    assert np.abs(got - numpy_ue4(frame, color, vel, depth)).max() < 1e-6
    red = got[..., 0]
    assert np.all(red == red[:1])                      # rows agree
    x = np.arange(w) + 0.5
    analytic = nu.box_coverage(x, 48, 80, R)
    assert np.abs(red[0] - analytic).max() <= 1 / (4 * taps) + 1e-6
    for lo, sign in ((32, 1), (48, 1), (64, -1), (80, -1)):   # outer, inner, inner, outer
        seg = slice(lo, lo + R)
        slope = np.polyfit(x[seg], red[0, seg], 1)[0]
        assert abs(slope - sign / (2 * R)) < 0.05 / (2 * R)
    # the bar smears over the background; beyond R the background is exactly untouched
    assert np.array_equal(got[:, :32], color[:, :32]) and np.array_equal(got[:, 96:], color[:, 96:])


def test_moving_bar_with_default_jitter_averages_to_the_ramp(synthetic_frame):
    """With the default jitter the staircase turns into noise about the analytic ramp: the
    mean over rows (different noise per row) follows the box-shutter coverage."""
    w, h, R = 128, 48, 16
    frame = synthetic_frame((w, h), make_params(max_radius=0.125), seed=1)
    color, vel, depth = bar_scene(w, h, 48, 80, bar_v=2 * R, bg_v=0.0)
    got = render_ue4(frame, color, vel, depth)
    assert np.abs(got - numpy_ue4(frame, color, vel, depth, seed=1)).max() < 2e-5
    analytic = nu.box_coverage(np.arange(w) + 0.5, 48, 80, R)
    mean_red = got[..., 0].mean(axis=0)
    # away from where the +-1/4-tile lookup jitter reaches a static tile (x < 36, x > 91)
    assert np.abs(mean_red - analytic)[36:92].max() < 0.03
    assert np.abs(got[..., 0] - analytic).max() > 0.03            # single rows are noisy


def test_inner_blur_background_is_mirrored_from_outside(synthetic_frame):
    """Inside the bar near an edge, the background share comes from taps beyond the
    silhouette (green = x / w there), never from the hidden background behind the pixel."""
    w, h, R, K = 128, 2, 16, 8
    frame = synthetic_frame((w, h), make_params(tile=16, max_radius=0.125, taps=K,
                                                tile_jitter=0.0, tap_jitter=0.0))
    color, vel, depth = bar_scene(w, h, 48, 80, bar_v=2 * R, bg_v=0.0)
    got = render_ue4(frame, color, vel, depth)[0]
    offsets = (np.arange(K) + 0.5) * R / K
    for x in range(66, 80):                 # inside, within R of the right edge (80)
        X = x + 0.5
        beyond = X + offsets[X + offsets >= 80]
        bg_share = 1.0 - got[x, 0]
        assert bg_share == pytest.approx(len(beyond) / (2 * K), abs=1e-6)
        assert got[x, 1] == pytest.approx(np.sum((beyond - 0.5) / w) / (2 * K), abs=1e-6)
        # the mean background colour used lies outside, not at the pixel itself
        assert got[x, 1] / bg_share > 80 / w > X / w
    for x in range(48, 62):                 # and mirrored the other way at the left edge
        X = x + 0.5
        beyond = X - offsets[X - offsets < 48]
        assert got[x, 1] == pytest.approx(np.sum((beyond - 0.5) / w) / (2 * K), abs=1e-6)


def test_mirror_rule_in_outer_blur(synthetic_frame):
    """Outside the bar, the mirror gives the background weight to the background taps on
    the far side instead of the centre fill; the bar's coverage is the same either way."""
    w, h, R, K = 128, 2, 16, 8
    common = dict(tile=16, max_radius=0.125, taps=K, tile_jitter=0.0, tap_jitter=0.0)
    color, vel, depth = bar_scene(w, h, 48, 80, bar_v=2 * R, bg_v=0.0)
    on = render_ue4(synthetic_frame((w, h), make_params(**common)), color, vel, depth)[0]
    off = render_ue4(synthetic_frame((w, h), make_params(mirror=False, **common)),
                     color, vel, depth)[0]
    assert np.array_equal(on[:, 0], off[:, 0])
    offsets = (np.arange(K) + 0.5) * R / K
    for x in range(80, 96):
        X = x + 0.5
        n_bar = np.count_nonzero(X - offsets < 80)
        assert on[x, 0] == pytest.approx(n_bar / (2 * K), abs=1e-6)
        mirrored = X + offsets[X - offsets < 80]           # the bar taps' partners
        fill = 1.0 - n_bar / (2 * K)
        # on: bar and partner taps both weigh 1, the centre fills 1 - 2 n_bar / 2K
        assert on[x, 1] == pytest.approx(np.sum((mirrored - 0.5) / w) / (2 * K)
                                         + (1.0 - n_bar / K) * x / w, abs=1e-6)
        # off: the partners weigh 0 (static background), the centre fills the rest
        assert off[x, 1] == pytest.approx(fill * x / w, abs=1e-6)


@pytest.mark.parametrize("config", [dict(fast_path=False, tile_jitter=0.0),
                                    dict(fast_path_guard=True)])
@pytest.mark.parametrize("bilinear", [False, True])
def test_static_foreground_is_never_smeared_by_moving_background(synthetic_frame, config,
                                                                 bilinear):
    """The reverse of the moving bar: a static bar in front of a background moving 24 px.
    The weights keep the bar sharp and keep it from bleeding out (the plain UE fast path
    does not: see the next test), except that bilinear taps in the background within half a
    pixel of the bar mix in some of its colour."""
    w, h = 128, 16
    frame = synthetic_frame((w, h), make_params(tile=16, max_radius=0.125, bilinear=bilinear,
                                                **config))
    color, vel, depth = bar_scene(w, h, 48, 80, bar_v=0.0, bg_v=24.0)
    got = render_ue4(frame, color, vel, depth)
    assert np.abs(got - numpy_ue4(frame, color, vel, depth)).max() < 2e-5
    assert np.array_equal(got[:, 48:80], color[:, 48:80])     # the bar stays sharp
    outside = got[..., 0][:, np.r_[0:48, 80:w]]
    if bilinear:         # at most half of each of the 2K taps' weights, for a few taps
        assert 0 < outside.max() < 0.25
    else:
        assert np.all(outside == 0.0)                         # never bleeds out
    assert np.abs(got[:, :40, 1] - color[:, :40, 1]).max() > 0  # the background blurs


def test_ue_fast_path_smears_moving_background_over_static_neighbour(synthetic_frame):
    """UE's dilation lets a tile slower than half a pixel cover only itself, so the
    background tiles beside the static bar keep min = max and take the fast path: their
    plain average pulls the bar out over the background, and bar pixels whose jittered
    lookup (up to a quarter tile) lands there smear too. Deeper in, the bar stays sharp.
    This is the behaviour `fast_path_guard` removes."""
    w, h = 128, 16
    frame = synthetic_frame((w, h), make_params(tile=16, max_radius=0.125))
    color, vel, depth = bar_scene(w, h, 48, 80, bar_v=0.0, bg_v=24.0)
    got = render_ue4(frame, color, vel, depth)
    assert np.abs(got - numpy_ue4(frame, color, vel, depth)).max() < 2e-5
    assert np.array_equal(got[:, 52:76], color[:, 52:76])
    assert np.abs(got[:, 48:52] - color[:, 48:52]).max() > 0.1
    assert got[:, 40:44, 0].min() > 0.1      # red over the background, beyond the jitter

@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("tap_jitter", [0.0, 1.0])
def test_uniform_translation_is_a_box_blur_of_length_D(synthetic_frame, axis, tap_jitter):
    """Everything moves by D = 12 px along x (or y, up): the fast path averages 2K taps
    spread over [-D/2, D/2], a box blur of length |D| of the (bilinear) image."""
    n, D, K = 64, 12.0, 8
    size = (n, 8) if axis == 0 else (24, n)                 # the limit: 6 px either way
    params = make_params(tile=8, max_radius=0.125 if axis == 0 else 0.25, taps=K,
                         tap_jitter=tap_jitter)
    frame = synthetic_frame(size, params, seed=2)
    s = np.arange(n) + 0.5                                  # pixel centres along the motion
    step = (s >= 32).astype(np.float32)                     # 0 below 32 px, 1 above
    color = np.zeros((size[1], size[0], 3), np.float32)
    color[..., 2] = 0.25
    if axis == 0:
        color[..., 0] = step[None, :]
    else:
        color[..., 0] = step[:, None]
    vel = np.zeros((size[1], size[0], 2), np.float32)
    vel[..., axis] = D
    depth = np.full(color.shape[:2], 5.0, np.float32)
    got = render_ue4(frame, color, vel, depth)
    assert np.abs(got - numpy_ue4(frame, color, vel, depth, seed=2)).max() < 1e-5
    tiles = read_gl(frame, "ue4_dilated")
    assert np.all(tiles[..., axis] == D / 2) and np.all(tiles[..., 2 + axis] == D / 2)
    # against the box filter of the bilinear reconstruction, integrated finely
    fine = np.linspace(-D / 2, D / 2, 4801)
    box = np.array([np.clip(x + fine - 31.5, 0, 1).mean() for x in s])
    red = got[..., 0] if axis == 0 else got[..., 0].T
    tol = (1.0 if tap_jitter else 0.5) / (2 * K)           # a jittered shift of <= half a step
    assert np.abs(red - box[None, :]).max() <= tol
    assert np.all(red[:, :24] == 0) and np.all(red[:, 39:] == 1)    # ramp of length |D|
    assert np.all(got[..., 2] == np.float32(0.25))
    # the full path gives the same average here (every weight is 1)
    slow = synthetic_frame(size, make_params(tile=8, max_radius=params["blur"].max_radius,
                                             taps=K, tap_jitter=tap_jitter, fast_path=False),
                           seed=2)
    assert np.abs(render_ue4(slow, color, vel, depth) - got).max() < 1e-6


def test_fast_path_threshold(synthetic_frame):
    """Half the pixels move 16 px, half 12.8 px (|vmin|^2 = 0.64 |vmax|^2): above the
    default 0.4 the plain average is taken, which ignores the slower pixels' shorter
    spread; the full path (fast path off, or a 0.7 threshold) does not."""
    rng = np.random.default_rng(4)
    w, h = 64, 16
    color = rng.uniform(0, 1, (h, w, 3)).astype(np.float32)
    vel = np.zeros((h, w, 2), np.float32)
    vel[..., 0] = np.where((np.arange(w) // 3) % 2 == 0, 16.0, 12.8)[None, :]
    depth = np.full((h, w), 3.0, np.float32)
    out = {}
    configs = {"fast": {}, "off": dict(fast_path=False), "0.7": dict(fast_ratio=0.7)}
    for name, cfg in configs.items():
        frame = synthetic_frame((w, h), make_params(tile=8, max_radius=0.125, **cfg), seed=4)
        out[name] = render_ue4(frame, color, vel, depth)
        assert np.abs(out[name] - numpy_ue4(frame, color, vel, depth, seed=4)).max() < 2e-5
    assert np.array_equal(out["off"], out["0.7"])
    assert np.abs(out["fast"] - out["off"]).max() > 0.01


def test_static_and_sub_half_pixel_scenes_are_unchanged_exactly(synthetic_frame):
    rng = np.random.default_rng(5)
    color = rng.uniform(0, 3, (16, 32, 3)).astype(np.float32)
    depth = rng.uniform(1, 9, (16, 32)).astype(np.float32)
    for speed in (0.0, 0.9):                       # |v| = |D| / 2 < 0.5 px: skip path
        vel = np.zeros((16, 32, 2), np.float32)
        vel[..., 0] = speed * np.cos(np.arange(32))[None, :]
        vel[..., 1] = speed * np.sin(np.arange(32))[None, :]
        got = render_ue4(synthetic_frame((32, 16), make_params(tile=4)), color, vel, depth)
        assert np.array_equal(got, color)


def test_deterministic_per_seed(synthetic_frame):
    color, vel, depth = bar_scene(64, 16, 20, 40, bar_v=20.0, bg_v=-4.0)
    runs = [render_ue4(synthetic_frame((64, 16), make_params(max_radius=0.25), seed=s),
                       color, vel, depth) for s in (9, 9, 10)]
    assert runs[0].tobytes() == runs[1].tobytes()
    assert runs[0].tobytes() != runs[2].tobytes()


def test_dilation_guard_matches_numpy(synthetic_frame):
    frame = synthetic_frame((64, 32), make_params(tile=4, max_radius=0.25, fast_path_guard=True))
    tiles = np.zeros((8, 16, 4), np.float32)
    tiles[..., 0] = tiles[..., 2] = 6.0             # everything moves 6 px ...
    tiles[4, 8] = 0.0                               # ... but one screen-static tile
    upload(frame, "ue4_tiles", tile_spec(frame), tiles)
    run(frame, Dilate())
    got = read_gl(frame, "ue4_dilated")
    assert np.array_equal(got, nu.dilate(tiles, 4, 5, guard=True, tile_jitter=0.25))
    # r = ceil(6/4 + 1/4) = 2 tiles: the static tile's zero min reaches a 5 x 5 square
    zero_min = ~got[..., :2].any(axis=-1)
    assert np.array_equal(np.argwhere(zero_min).min(0), [2, 6])
    assert np.array_equal(np.argwhere(zero_min).max(0), [6, 10])
    # without the guard only the static tile itself has a zero min
    frame2 = synthetic_frame((64, 32), make_params(tile=4, max_radius=0.25))
    upload(frame2, "ue4_tiles", tile_spec(frame2), tiles)
    run(frame2, Dilate())
    assert np.count_nonzero(~read_gl(frame2, "ue4_dilated")[..., :2].any(axis=-1)) == 1


def test_mode_beats_off_against_reference_on_basic(ctx):
    """The whole mode through the Renderer: closer to the reference than the sharp frame,
    over the whole image and in the outer-blur region."""
    from viewer.eval.metrics import image_metrics
    from viewer.render.renderer import Renderer
    from world.loader import load_scene
    scene = load_scene(CONFORMANCE / "basic.toml")
    r = Renderer(ctx, scene, (160, 90))
    try:
        t = scene.render.time
        ref = r.render("reference", t, record_visibility=True)
        region = ref.host[REGIONS]
        off = r.render("off", t).image
        ue4 = r.render("ue4", t).image
        assert set(("ue4_flat", "ue4_tiles", "ue4_dilated", "ue4")) <= set(r.pool.names())
    finally:
        r.release()
    m_off, m_ue4 = image_metrics(off, ref.image, region), image_metrics(ue4, ref.image, region)
    assert m_ue4["outer"]["pixels"] > 50
    for reg in ("all", "outer"):
        assert m_ue4[reg]["flip"] < m_off[reg]["flip"]
        assert m_ue4[reg]["psnr"] > m_off[reg]["psnr"]
