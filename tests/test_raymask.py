"""The hybrid ray mask (viewer/render/modes/hybrid/mask.py): each pass on tiny synthetic buffers
against tests/numpy_hybrid.py, and the numpy statement itself against hand-computed bands.

Arrays here are in GL orientation (row 0 at the bottom, displacement y up) like the numpy
reference; `upload`/`download` flip to and from the frames' image orientation.
"""
from __future__ import annotations

import numpy as np
import pytest

import numpy_hybrid as nh
from world.conventions import BACKGROUND_DEPTH, to_image
from viewer.render.graph.params import ParamSet
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.passes.gbuffer import GBUFFER
from viewer.render.modes.hybrid.config import HybridConfig
from viewer.render.modes.hybrid.mask import raymask_passes

W, H = 40, 6
BAR = (12, 24)                 # columns of the bar, [x0, x1)


def params(**hy):
    """The poster's three steps (hybrid.range_check on) unless told otherwise."""
    p = ParamSet()
    p.set("blur.max_radius", 0.25)          # k = 10 px at W = 40
    p.set("hybrid.range_check", True)
    for key, value in hy.items():
        p.set(f"hybrid.{key}", value)
    return p


def upload(frame, depth, ids, disp, normal):
    """The hybrid G-buffer's targets: hybrid_front (D, depth, id) and (normal, log depth)."""
    front = np.dstack([np.asarray(disp, np.float32), np.asarray(depth, np.float32),
                       np.asarray(ids, np.float32)])
    normal_logz = np.dstack([np.asarray(normal, np.float32)[..., :3],
                             nh.stored_log_depth(depth).astype(np.float32)])
    for name, a in (("hybrid_front", front), ("normal", normal_logz)):
        frame.pool.texture(name, GBUFFER[name])
        frame.write(name, to_image(np.asarray(a, np.float32)))


def run(frame):
    """The mask passes of the frame's configuration, and the masks they made."""
    passes = raymask_passes(HybridConfig.of(frame.params))
    for p in passes:
        p.allocate(frame)
        p.execute(frame)
    made = {n for p in passes for n in p.produces}
    return {n: to_image(frame.read(n))
            for n in ("mask_displacement", "mask_relative", "mask_edge", "ray_mask")
            if n in made}


def bar_scene(bar_disp=(9.2, 0.0), bg_disp=(0.0, 0.0), bar=BAR):
    """A bar (id 2, depth 2) translating over a wall (id 1, depth 10), facing the camera."""
    depth = np.full((H, W), 10.0)
    ids = np.ones((H, W), np.uint32)
    disp = np.tile(np.asarray(bg_disp, float), (H, W, 1))
    normal = np.tile([0.0, 0.0, 1.0, 0.0], (H, W, 1))
    depth[:, bar[0]:bar[1]] = 2.0
    ids[:, bar[0]:bar[1]] = 2
    disp[:, bar[0]:bar[1]] = bar_disp
    return depth, ids, disp, normal


def numpy_mask(frame, depth, ids, disp, normal):
    p = frame.params["hybrid"]
    return nh.ray_mask(depth, ids, disp, normal, min_speed=p.min_speed,
                       threshold=p.depth_threshold, edge_depth=p.edge_depth,
                       edge_normal=p.edge_normal, relative_reach=p.relative_reach,
                       max_reach=max_radius_px(frame))


def columns(mask_row) -> list[int]:
    return [int(x) for x in np.flatnonzero(mask_row)]


# ---- the numpy statement on hand-computed cases -------------------------------------------------

def test_numpy_bar_over_static_wall_masks_half_the_displacement_from_each_edge():
    # Pixel x of the bar is uncovered at some time iff x + 0.5 +- 4.6 leaves [12, 24):
    # x <= 16 (at shutter open, trailing side) or x >= 19 (at close, leading side).
    depth, ids, disp, normal = bar_scene()
    dm, rel, edge, mask = nh.ray_mask(depth, ids, disp, normal, max_reach=10)
    assert columns(dm[0]) == [12, 13, 14, 15, 16, 19, 20, 21, 22, 23]
    assert columns(edge[0]) == [12, 23]                     # the silhouettes only
    assert columns(mask[0]) == columns(dm[0])
    assert set(np.unique(mask)) == {0, 2}                   # the own id where masked
    np.testing.assert_allclose(rel[0, 12], [9.2, 0.0], rtol=1e-6)


def test_numpy_background_moving_the_other_way_widens_the_band_to_the_relative_reach():
    # Relative displacement 9.2 - (-4.6) = 13.8: the band is 6.9 px deep on each side.
    # A 16-px bar [12, 28): within 6.9 steps of column 12 or 27 -> x <= 18 or x >= 21.
    depth, ids, disp, normal = bar_scene(bg_disp=(-4.6, 0.0), bar=(12, 28))
    dm, rel, edge, mask = nh.ray_mask(depth, ids, disp, normal, max_reach=10)
    assert columns(dm[0]) == [12, 13, 14, 15, 16, 23, 24, 25, 26, 27]
    np.testing.assert_allclose(rel[0, 12], [13.8, 0.0], rtol=1e-6)
    assert columns(mask[0]) == list(range(12, 19)) + list(range(21, 28))
    # Searching only ceil(4.6) = 5 steps (relative_reach 1) misses 18 and 21.
    _, _, _, narrow = nh.ray_mask(depth, ids, disp, normal, max_reach=10, relative_reach=1.0)
    assert columns(narrow[0]) == list(range(12, 18)) + list(range(22, 28))


def test_numpy_sobel_of_a_unit_step_reads_one():
    a = np.zeros((5, 6))
    a[:, 3:] = 1.0
    gx, gy = nh.sobel(a)
    # Both sides of the step see (1 + 2 + 1) * 1 / 4; one pixel away, nothing.
    assert gx[2, 2] == 1.0 and gx[2, 3] == 1.0 and gx[2, 1] == 0.0 and gx[2, 4] == 0.0
    assert np.all(gy == 0.0)
    gx_t, gy_t = nh.sobel(a.T)
    assert np.all(gx_t == 0.0) and gy_t[2, 2] == 1.0


# ---- GPU passes against numpy -------------------------------------------------------------------

def test_bar_over_static_wall(synthetic_frame):
    frame = synthetic_frame((W, H), params())
    bufs = bar_scene()
    upload(frame, *bufs)
    got = run(frame)
    dm, rel, edge, mask = numpy_mask(frame, *bufs)
    np.testing.assert_array_equal(got["mask_displacement"], dm)
    np.testing.assert_array_equal(got["mask_edge"], edge)
    np.testing.assert_array_equal(got["ray_mask"], mask)
    np.testing.assert_allclose(got["mask_relative"], rel, rtol=1e-6, atol=1e-6)
    assert columns(got["ray_mask"][3]) == [12, 13, 14, 15, 16, 19, 20, 21, 22, 23]


@pytest.mark.parametrize("bg", [0.0, 6.0, -4.6])
def test_default_mask_is_where_the_hidden_surface_shows(synthetic_frame, bg):
    # The default mask (no range check): bar pixel x is masked iff the wall behind it at
    # the frame time shows at some time, i.e. x + 0.5 +- (9.2 - bg) / 2 leaves the bar
    # [12, 24). A still wall: the poster's band, 4.6 px from each edge. The wall moving
    # 6 px the same way (a pan's parallax): 1.6 px, where the poster's test marks 4.6.
    # Moving the other way (-4.6): 6.9 px wide, but only pixels whose own probes (4.6 px)
    # see the wall are tested: 4.6 px again (the range check finds the rest).
    frame = synthetic_frame((W, H), params())
    frame.params.set("hybrid.range_check", False)
    bufs = bar_scene(bg_disp=(bg, 0.0))
    upload(frame, *bufs)
    got = run(frame)["ray_mask"]
    want = {0.0: [12, 13, 14, 15, 16, 19, 20, 21, 22, 23], 6.0: [12, 13, 22, 23],
            -4.6: [12, 13, 14, 15, 16, 19, 20, 21, 22, 23]}[bg]
    assert all(columns(row) == want for row in got)
    relative, _ = nh.displacement_test(*bufs[:3], 1.0, 0.01, relative_only=True)
    np.testing.assert_array_equal(got, np.where(relative != 0, bufs[1], 0))
    poster, _ = nh.displacement_test(*bufs[:3], 1.0, 0.01)
    assert (poster >= relative).all()
    assert columns(poster[0]) == [12, 13, 14, 15, 16, 19, 20, 21, 22, 23]


def test_camera_motion_uses_the_relative_displacement(synthetic_frame):
    frame = synthetic_frame((W, H), params())
    bufs = bar_scene(bg_disp=(-4.6, 0.0))
    upload(frame, *bufs)
    got = run(frame)
    np.testing.assert_array_equal(got["ray_mask"], numpy_mask(frame, *bufs)[3])
    assert columns(got["ray_mask"][2]) == list(range(12, 24))


def test_vertical_motion_and_image_borders(synthetic_frame):
    # A square moving down (GL y) at the bottom edge: probes past the border read the
    # border row (off-screen content is not "behind"), so only the top band is masked.
    w, h = 12, 16
    frame = synthetic_frame((w, h), params())
    depth = np.full((h, w), 6.0)
    ids = np.ones((h, w), np.uint32)
    disp = np.zeros((h, w, 2))
    normal = np.tile([0.0, 0.0, 1.0, 0.0], (h, w, 1))
    depth[0:7, 3:9], ids[0:7, 3:9], disp[0:7, 3:9] = 1.5, 3, (0.0, -5.2)
    upload(frame, depth, ids, disp, normal)
    got = run(frame)
    ref = numpy_mask(frame, depth, ids, disp, normal)
    for name, want in zip(("mask_displacement", "mask_relative", "mask_edge", "ray_mask"), ref):
        if name == "mask_relative":
            np.testing.assert_allclose(got[name], want, atol=1e-6)
        else:
            np.testing.assert_array_equal(got[name], want, err_msg=name)
    # Rows y with y + 0.5 + 2.6 >= 7 (uncovered at shutter open): y >= 4; column 5 is
    # interior, so its only uncovering is vertical.
    assert [int(y) for y in np.flatnonzero(got["ray_mask"][:, 5])] == [4, 5, 6]


def random_layers(rng, w, h):
    """Three layers with distinct ids, depths and motions; sloped and creased normals."""
    depth = 9.0 + rng.uniform(0, 0.5, (h, w))
    ids = np.ones((h, w), np.uint32)
    disp = np.tile([1.7, -0.6], (h, w, 1)) + rng.uniform(-0.2, 0.2, (h, w, 2))
    normal = np.tile([0.0, 0.0, 1.0, 0.0], (h, w, 1))
    depth[3:13, 4:18] = 3.0 + 0.02 * rng.uniform(size=(10, 14))
    ids[3:13, 4:18] = 2
    disp[3:13, 4:18] = [7.3, 2.9]
    normal[3:13, 11:18] = [0.6, 0.0, 0.8, 0.0]              # a crease inside object 2
    depth[6:10, 20:26] = 2.0
    ids[6:10, 20:26] = 3
    disp[6:10, 20:26] = [-3.1, 5.7]
    depth[0, 0:4] = BACKGROUND_DEPTH                        # sky, with a camera motion
    ids[0, 0:4] = 0
    disp[0, 0:4] = [6.0, 0.0]
    return depth, ids, disp, normal


@pytest.mark.parametrize("seed", [1, 2])
def test_random_layers_match_numpy(synthetic_frame, seed):
    rng = np.random.default_rng(seed)
    w, h = 30, 16
    frame = synthetic_frame((w, h), params(edge_depth=0.04, edge_normal=0.25))
    bufs = random_layers(rng, w, h)
    upload(frame, *bufs)
    got = run(frame)
    dm, rel, edge, mask = numpy_mask(frame, *bufs)
    np.testing.assert_array_equal(got["mask_displacement"], dm)
    np.testing.assert_array_equal(got["mask_edge"], edge)
    np.testing.assert_array_equal(got["ray_mask"], mask)
    np.testing.assert_allclose(got["mask_relative"], rel, atol=1e-5)
    assert np.count_nonzero(mask == 2) > 10 and np.count_nonzero(mask == 3) > 5
    k = max_radius_px(frame)
    # The reveal's tile summary, from the masked pixels it reads back (image rows).
    from viewer.render.modes.hybrid.composite import mask_tiles
    jj, ii = np.nonzero(got["ray_mask"])
    np.testing.assert_array_equal(mask_tiles(np.c_[ii, jj], (w, h), k),
                                  to_image(nh.tile_summary(mask, k)))
    assert not np.any(mask[bufs[1] == 0])                   # the sky is never traced


@pytest.mark.parametrize("seed", [1, 2])
def test_without_the_range_check_the_mask_is_the_displacement_tests_survivors(
        synthetic_frame, seed):
    """hybrid.range_check off (the default): ray_mask holds the displacement test's
    survivors (as their object ids) and nothing else; no edge test, no range check, and
    none of their targets in the configuration's pipeline."""
    rng = np.random.default_rng(seed)
    w, h = 30, 16
    frame = synthetic_frame((w, h), params(edge_depth=0.04, edge_normal=0.25))
    bufs = random_layers(rng, w, h)
    upload(frame, *bufs)
    three = run(frame)                                      # the poster's steps first
    frame.params.set("hybrid.range_check", False)
    got = run(frame)
    dm, _, _, with_range = numpy_mask(frame, *bufs)
    p = frame.params["hybrid"]
    relative, _ = nh.displacement_test(bufs[0], bufs[1], bufs[2], p.min_speed,
                                       p.depth_threshold, relative_only=True)
    want = np.where(relative != 0, bufs[1], 0).astype(np.uint32)
    np.testing.assert_array_equal(got["ray_mask"], want)
    np.testing.assert_array_equal(three["ray_mask"], with_range)
    assert np.count_nonzero(want) > 10 and np.count_nonzero(with_range != want) > 5
    assert set(got) == {"ray_mask"} and three["mask_edge"].any()
    # The configuration's pipeline makes none of the range check's targets (what an
    # earlier configuration left in the pool is neither read nor listed).
    from viewer.render.modes.hybrid.config import HybridConfig
    from viewer.render.modes.hybrid.pipeline import hybrid_pipeline
    made = set(hybrid_pipeline(HybridConfig(range_check=False)).textures())
    for name in ("mask_displacement", "mask_relative", "mask_edge", "mask_edge_probe",
                 "mask_edge_ids", "mask_edge_near"):
        assert name not in made, name
        assert name in hybrid_pipeline(HybridConfig(range_check=True)).textures(), name


def test_masked_pixels_read_in_image_order_from_gl_rows():
    # The reveal's read-back: the nonzero pixels of a GL-orientation window in image order
    # (top row first) with the window's top-left image pixel added, and their values.
    # Widths below, at and past its runs of 8 pixels; dense, banded and empty windows.
    from viewer.render.modes.hybrid.reveal_kernels import nonzero_pixels
    rng = np.random.default_rng(5)
    for h, w, density in ((7, 9, 0.5), (5, 8, 0.9), (12, 31, 0.05), (40, 64, 0.01),
                          (3, 7, 1.0), (6, 17, 0.0), (1, 1, 1.0)):
        gl_rows = np.where(rng.random((h, w)) < density,
                           rng.integers(1, 2 ** 32, (h, w), dtype=np.uint64), 0).astype(np.uint32)
        gl_rows[h // 2, w // 3:] = 7 if density else 0          # a band across a row
        ij, values = nonzero_pixels(gl_rows, 20, 30)
        image = gl_rows[::-1]
        jj, ii = np.nonzero(image)
        np.testing.assert_array_equal(ij, np.c_[ii + 20, jj + 30])
        np.testing.assert_array_equal(values, image[jj, ii])
        assert values.dtype == np.uint32 and len(values) == np.count_nonzero(gl_rows)


def test_static_frame_masks_nothing(synthetic_frame):
    frame = synthetic_frame((W, H), params())
    depth, ids, _, normal = bar_scene()
    upload(frame, depth, ids, np.zeros((H, W, 2)), normal)
    got = run(frame)
    assert not got["mask_displacement"].any() and not got["ray_mask"].any()


def test_slow_pixels_below_min_speed_are_not_masked(synthetic_frame):
    frame = synthetic_frame((W, H), params(min_speed=10.0))
    upload(frame, *bar_scene())                             # |D| = 9.2 < 10
    assert not run(frame)["ray_mask"].any()


@pytest.mark.parametrize("seed", [3, 4])
def test_sparse_edges_on_a_wide_frame_match_numpy(synthetic_frame, seed):
    # A wide frame where the background moves too (every pixel searches) and the edges
    # are few and far apart: the range check's coarse look along each search (16-px
    # tiles with an edge nearby) must skip exactly the searches that find nothing.
    rng = np.random.default_rng(seed)
    w, h = 176, 48
    frame = synthetic_frame((w, h), params())             # k = 44 px
    depth = 9.0 + rng.uniform(0, 0.3, (h, w))
    ids = np.ones((h, w), np.uint32)
    disp = np.tile([-6.0, 1.5], (h, w, 1))
    normal = np.tile([0.0, 0.0, 1.0, 0.0], (h, w, 1))
    for oid, (x0, y0) in enumerate(rng.integers([0, 0], [w - 30, h - 14], (3, 2)), start=2):
        sl = np.s_[y0:y0 + 14, x0:x0 + 30]
        depth[sl], ids[sl] = 2.0 + oid, oid
        disp[sl] = rng.uniform(-30, 30, 2)
    upload(frame, depth, ids, disp, normal)
    got = run(frame)
    dm, rel, edge, mask = numpy_mask(frame, depth, ids, disp, normal)
    np.testing.assert_array_equal(got["mask_edge"], edge)
    np.testing.assert_array_equal(got["ray_mask"], mask)
    # Masked pixels that only the range check finds (not displacement survivors) exist.
    assert np.count_nonzero((mask > 0) & (dm == 0)) >= 10


def wide_bar_masks(synthetic_frame, bg_disp):
    """A bar (columns 40-199 of 240 x 48, id 2, depth 2) moving 60 px over a wall (id 1,
    depth 10) moving bg_disp: (stats with tile lists, masks with tile lists, masks of the
    full-screen passes), masks in image orientation."""
    from viewer.render.modes.hybrid.tile_select import selection_passes
    w, h, bar = 240, 48, (40, 200)
    depth = np.full((h, w), 10.0)
    ids = np.ones((h, w), np.uint32)
    disp = np.tile(np.asarray(bg_disp, float), (h, w, 1))
    depth[:, bar[0]:bar[1]], ids[:, bar[0]:bar[1]], disp[:, bar[0]:bar[1]] = 2.0, 2, (60.0, 0.0)
    normal = np.tile([0.0, 0.0, 1.0, 0.0], (h, w, 1))
    got = []
    for tiled in (True, False):
        frame = synthetic_frame((w, h), params())
        upload(frame, depth, ids, disp, normal)
        mask = raymask_passes(HybridConfig.of(frame.params))
        for p in (selection_passes() if tiled else []) + mask:
            p.allocate(frame)
            p.execute(frame)
        got.append({n: to_image(frame.read(n)) for n in ("mask_displacement", "ray_mask")})
        if tiled:
            stats = dict(frame.stats)
    return stats, got[0], got[1]


def test_tile_lists_keep_far_uncoverings(synthetic_frame):
    # A wide bar moving 60 px over a still wall: its pixels up to 30 px inside its edges
    # are uncovered, two tiles from the tiles holding the outline. With tile lists (the
    # displacement test only within |D|/2 + 2 px of an id boundary) the masks equal the
    # full-screen passes'.
    stats, tiled, full = wide_bar_masks(synthetic_frame, (0.0, 0.0))
    assert stats["surface_tiles"] < stats["moving_tiles"]
    for n in ("mask_displacement", "ray_mask"):
        np.testing.assert_array_equal(tiled[n], full[n], err_msg=n)
    # Uncovered 30 px in from the leading and trailing edges, by the displacement test.
    assert columns(full["mask_displacement"][20]) == list(range(40, 70)) + list(range(170, 200))


def test_tile_lists_keep_the_range_checks_far_reach(synthetic_frame):
    # Everything moves (a camera-like frame: the range check draws only the tiles with an
    # edge within their search's reach): the bar moving 60 px over a wall moving -60 px.
    # Bar pixels whose own probes (30 px) stay on the bar are masked by the range check
    # where the silhouette, whose relative motion reaches 60 px, lies within their search
    # (min(k, |D|) = 60 px): up to four tiles from the edge tiles. With tile lists the
    # mask equals the full-screen passes'.
    stats, tiled, full = wide_bar_masks(synthetic_frame, (-60.0, 0.0))
    assert 0 < stats["range_tiles"] < stats["moving_tiles"]
    np.testing.assert_array_equal(tiled["ray_mask"], full["ray_mask"])
    masked = columns(full["ray_mask"][20])
    assert 95 in masked and 120 not in masked


def test_hybrid_gbuffer_stores_log_depth_for_the_edge_test(ctx):
    # The edge test (the range check's mask) reads log depth from the normal target's w
    # (what upload() writes).
    from conftest import CONFORMANCE
    from viewer.render.renderer import Renderer
    from world.loader import load_scene
    r = Renderer(ctx, load_scene(str(CONFORMANCE / "basic.toml")), (96, 54))
    p = ParamSet()
    p.set("hybrid.range_check", True)
    try:
        r.render("hybrid", 0.0, p, read_image=False)
        bufs = r.buffers()
    finally:
        r.release()
    depth, logz = bufs["hybrid_front"][..., 2], bufs["normal"][..., 3]
    assert np.ptp(logz) > 1.0
    # log on the GPU may differ from numpy's by an ulp before the rounding to half.
    np.testing.assert_allclose(logz, nh.stored_log_depth(depth).astype(np.float32),
                               rtol=2e-3, atol=2e-3)
    surface = bufs["hybrid_front"][..., 3] != 0                   # (the sky has no normal)
    np.testing.assert_allclose(np.linalg.norm(bufs["normal"][surface][:, :3], axis=-1), 1.0,
                               atol=2e-3)
