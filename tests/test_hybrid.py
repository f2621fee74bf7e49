"""The hybrid mode (viewer/render/modes/hybrid/pipeline.py): the ray reveal against a raster oracle (the
scene rendered without the pixel's own object), same-coloured objects,
transforms at t != 0, the composite against tests/numpy_hybrid.py and the analytic box
shutter, determinism, an empty mask, and the whole mode against the reference.
"""
from __future__ import annotations

import dataclasses
import textwrap

import numpy as np
import pytest

import numpy_hybrid as nh
import numpy_mcguire as nm
from conftest import CONFORMANCE
from world.conventions import to_image
from viewer.eval.metrics import image_metrics
from viewer.render.graph.params import ParamSet
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.passes.gbuffer import GBUFFER
from viewer.render.modes.hybrid.composite import composite_kind, mask_tiles
from viewer.render.modes.hybrid.config import HybridConfig
from viewer.render.modes.hybrid.pipeline import hybrid_pipeline
from viewer.render.modes import MODES
from viewer.render.graph.pool import TexSpec
from viewer.render.renderer import Renderer
from viewer.render.modes.reference import REGIONS
from viewer.render.modes.hybrid.reveal import BACK, PACKED, REVEAL_BATCH, shade_draws
from viewer.render.modes.hybrid.tile_select import KEPT_LISTS
from world.loader import load_scene

SMALL = (160, 90)


def params(**hy) -> ParamSet:
    p = ParamSet()
    for key, value in hy.items():
        p.set(f"hybrid.{key}", value)
    return p


def render(ctx, scene, mode, t, p=None, size=SMALL, seed=0, timing=False):
    """(RenderResult, every pool buffer) of one frame on a fresh renderer."""
    r = Renderer(ctx, scene, size)
    try:
        res = r.render(mode, t, p or ParamSet(), seed=seed, timing=timing)
        return res, r.buffers()
    finally:
        r.release()


def without(scene, ids):
    """The scene with objects `ids` parked far behind the camera, still: a raster render
    of it shows what lies behind them (object ids of the others unchanged)."""
    cam = scene.camera
    parked = cam.position - 1000.0 * (cam.look_at - cam.position)
    objects = [dataclasses.replace(o, position=parked, velocity=np.zeros(3),
                                   angular_velocity=np.zeros(3)) if o.id in ids else o
               for o in scene.objects]
    return dataclasses.replace(scene, objects=objects)


def revealed(bufs):
    """The revealed layer's (id, depth, D, colour with alpha) unpacked from hybrid_back*:
    packed (D, depth, 1 + id) and (colour, 1), 0 where nothing was revealed (id -1)."""
    motion, colour = (bufs[n] for n in BACK)
    return motion[..., 3] - 1.0, motion[..., 2], motion[..., :2], colour


def assert_layer_matches(bufs, oracle, sel):
    """The revealed layer at the selected pixels is the oracle's G-buffer there."""
    assert sel.any()
    ids, depth, disp, colour = revealed(bufs)
    np.testing.assert_array_equal(ids[sel], oracle["id"][sel])
    np.testing.assert_allclose(depth[sel], oracle["depth"][sel], rtol=2e-6)
    np.testing.assert_allclose(colour[sel][:, :3], oracle["color"][sel][:, :3], atol=1e-5)
    np.testing.assert_allclose(disp[sel], oracle["velocity"][sel], atol=1e-3)
    assert np.all(colour[sel][:, 3] == 1.0)


# ---- the reveal against the raster oracle -------------------------------------------------------

@pytest.mark.parametrize("name, t", [("basic", 0.0), ("basic", 0.013), ("vase_pan", 0.1)])
def test_reveal_equals_raster_without_the_own_object(ctx, name, t):
    """At t != 0 the rotating box and the moving camera check that the ray tracer and the
    rasteriser place moving objects identically (depth and displacement agree too)."""
    scene = load_scene(CONFORMANCE / f"{name}.toml")
    res, bufs = render(ctx, scene, "hybrid", t)
    mask = bufs["ray_mask"]
    owners = [int(k) for k in np.unique(mask[mask > 0])]
    assert len(owners) >= 2
    for oid in owners:
        _, oracle = render(ctx, without(scene, {oid}), "off", t)
        assert_layer_matches(bufs, oracle, mask == oid)
    # The tile-bounded read found exactly the masked pixels (one revealed point each).
    assert res.stats["masked_pixels"] == np.count_nonzero(bufs["hybrid_back_color"][..., 3])
    # Unmasked pixels reveal nothing (every packed channel 0).
    assert not bufs["hybrid_back_color"][mask == 0].any()
    assert not bufs["hybrid_back"][mask == 0].any()
    assert res.stats["masked_pixels"] == np.count_nonzero(mask)
    assert res.stats["rays"] >= res.stats["masked_pixels"]
    # Under a still camera, the revealed static surfaces came from the static layer.
    if scene.camera.moving:
        assert res.stats["static_layer_hits"] == 0
    else:
        assert 0 < res.stats["static_layer_hits"] <= res.stats["masked_pixels"]


def test_the_reveal_passes_the_own_objects_rigid_body(ctx):
    """turning_car: the cabin and the wheels ride on the keyed chassis. What the car's
    motion reveals behind any of its pixels is the road, never another part of the car
    (the wheels hidden under the body, the chassis under the cabin: they move with it):
    the raster of the scene without the car."""
    scene = load_scene("turning_car")
    res, bufs = render(ctx, scene, "hybrid", 0.0)
    car = [o.id for o in scene.objects if o.moving]
    assert len(car) == 6
    cam = scene.camera
    parked = cam.position - 1000.0 * (cam.look_at - cam.position)
    gone = dataclasses.replace(scene, objects=[
        dataclasses.replace(o, keys=None, parent=None, position=parked) if o.id in car else o
        for o in scene.objects])
    _, oracle = render(ctx, gone, "off", 0.0)
    mask = bufs["ray_mask"]
    for part in car[:2]:              # the chassis and the cabin
        assert np.count_nonzero(mask == part) > 50
    assert_layer_matches(bufs, oracle, np.isin(mask, car))


# A camera 5 m before a wall, one light: the stage of the scenes below (named by their
# files), which add the camera's motion and the objects.
STAGE = """
    background = [0.02, 0.02, 0.03]
    ambient = [0.2, 0.2, 0.2]
    [[lights]]
    direction = [-0.3, -0.4, -1.0]
    [camera]
    position = [0.0, 0.0, 5.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 40.0
    shutter = 0.04
"""

IMAGE_WALL = STAGE + """    velocity = [0.5, 0.0, 0.0]
    [[objects]]
    name = "painted wall"
    mesh = "{assets}/quad_uv.obj"
    position = [0.0, 0.0, -1.0]
    scale = [6.0, 4.0, 1.0]
    shading = "flat"
    material = {{ albedo = [1.0, 1.0, 1.0], texture = {{ kind = "image", path = "{assets}/painting.png" }} }}
    [[objects]]
    name = "box"
    mesh = {{ box = [0.8, 0.8, 0.3] }}
    position = [-0.2, 0.1, 1.0]
    material = {{ albedo = [0.7, 0.2, 0.1] }}
    velocity = [12.0, 3.0, 0.0]
    [[objects]]
    name = "striped box"
    mesh = {{ box = [0.6, 0.6, 0.3] }}
    position = [0.9, -0.6, 0.5]
    material = {{ albedo = [0.2, 0.6, 0.3], texture = {{ kind = "stripes", axis = 0, size = 0.1, albedo2 = [0.9, 0.9, 0.8] }} }}
    velocity = [-10.0, 0.0, 0.0]
"""


def test_reveal_shades_image_textured_surfaces_like_the_raster(ctx, tmp_path):
    """A moving camera: every revealed surface is shaded (no static layer), here an
    image-textured wall behind two movers; the image and the faces' table are bound to
    texture units of their own, whichever object's draw comes first."""
    from world.loader import builtin_dir
    path = tmp_path / "image_wall.toml"
    path.write_text(textwrap.dedent(IMAGE_WALL.format(assets=builtin_dir() / "assets")))
    scene = load_scene(path)
    res, bufs = render(ctx, scene, "hybrid", 0.0)
    mask = bufs["ray_mask"]
    owners = [int(k) for k in np.unique(mask[mask > 0])]
    assert owners == [2, 3]
    ids, *_ = revealed(bufs)
    assert (ids[mask > 0] == 1).sum() > 50          # the wall is what most rays reveal
    for oid in owners:
        _, oracle = render(ctx, without(scene, {oid}), "off", 0.0)
        assert_layer_matches(bufs, oracle, mask == oid)


def test_shade_draws_join_runs_of_table_keys():
    """Keys with a table row side by side share a draw; an image-textured object's and
    the static layer's key (no row) are drawn alone and cut the runs."""
    image, static = 5, 9
    keys = [(1, 0, 3), (2, 3, 1), (4, 4, 2), (image, 6, 4), (6, 10, 1), (7, 11, 5),
            (static, 16, 7)]
    draws = shade_draws(keys, lambda k: k not in (image, static))
    assert draws == [([1, 2, 4], 0, 6), ([image], 6, 4), ([6, 7], 10, 6), ([static], 16, 7)]
    assert shade_draws([(image, 0, 2), (image + 1, 2, 3)], lambda k: k != image) == [
        ([image], 0, 2), ([image + 1], 2, 3)]
    assert shade_draws([], lambda k: True) == []


@pytest.mark.parametrize("per_row", [256, 4])
def test_many_revealed_objects_are_shaded_by_few_draws_like_the_raster(ctx, monkeypatch,
                                                                        per_row):
    """crowd_pan (32 movers, moving camera): every revealed object in one draw of the
    object table, each the raster without the pixel's own object; with 4 objects to a
    row of the table too (its records over 9 rows, as past 256 objects)."""
    from viewer.render.modes.hybrid.reveal import ObjectTable
    from world.loader import builtin_dir
    monkeypatch.setattr(ObjectTable, "OBJECTS_PER_ROW", per_row)
    scene = load_scene(builtin_dir() / "bench" / "crowd_pan.toml")
    res, bufs = render(ctx, scene, "hybrid", 0.0, size=(320, 180))
    mask = bufs["ray_mask"]
    ids, *_ = revealed(bufs)
    shown = np.unique(ids[mask > 0])
    assert len(shown) >= 8, shown                   # objects revealed (with the sky, 0)
    assert res.stats["shade_draws"] == 1
    for oid in np.unique(mask[mask > 0]):
        _, oracle = render(ctx, without(scene, {int(oid)}), "off", 0.0, size=(320, 180))
        assert_layer_matches(bufs, oracle, mask == oid)


def test_the_reveal_takes_the_movers_matrices_from_the_frame(ctx, monkeypatch):
    """The G-buffer made every object's M(t): the reveal's poses take them from the frame
    (asking each object again costs host time in every frame), equal to SceneObject.matrix(t);
    its hits are those of asking each object."""
    from raytrace import reveal
    from viewer.render.modes.hybrid.reveal import frame_models, reveal_state
    from world.scene import SceneObject
    from world.loader import builtin_dir
    scene = load_scene(builtin_dir() / "bench" / "crowd_pan.toml")
    r = Renderer(ctx, scene, (160, 90))
    try:
        t = 0.01
        frame = r.frame(t, ParamSet())
        r.pipeline("hybrid").run(frame)
        batch = frame.host[REVEAL_BATCH]
        rs = reveal_state(frame).rays
        models = frame_models(frame, rs.moving)
        assert models is not None and len(models) == len(rs.moving) == 32
        for (obj, _), m in zip(rs.moving, models):
            np.testing.assert_array_equal(m, obj.matrix(t))
        asked = []
        real = SceneObject.matrix
        monkeypatch.setattr(SceneObject, "matrix", lambda o, tt: asked.append(o.id) or real(o, tt))
        given = reveal(rs, batch["camera"], t, batch["pixels"], batch["own"], matrices=models)
        assert not asked
        own = reveal(rs, batch["camera"], t, batch["pixels"], batch["own"])
        assert len(asked) == 32
        assert len(batch["pixels"]) > 100
        for name in ("object_id", "prim_id", "barycentrics", "distance"):
            np.testing.assert_array_equal(getattr(given.layer, name),
                                          getattr(own.layer, name), name)
    finally:
        r.release()


SAME_COLOUR = STAGE + """    [[objects]]
    name = "wall"
    mesh = {{ box = [8.0, 6.0, 0.1] }}
    position = [0.0, 0.0, -2.0]
    material = {{ albedo = [0.8, 0.8, 0.8], texture = {{ kind = "checker", size = 0.3, albedo2 = [0.2, 0.3, 0.5] }} }}
    [[objects]]
    name = "front"
    mesh = {{ box = [0.9, 0.9, 0.2] }}
    position = [0.0, 0.0, 1.0]
    material = {{ albedo = [0.7, 0.2, 0.1] }}
    velocity = [{front_speed}, 0.0, 0.0]
    [[objects]]
    name = "middle"
    mesh = {{ box = [0.9, 0.9, 0.2] }}
    position = [0.35, 0.15, 0.0]
    rotation = [0.0, 0.0, 15.0]
    material = {{ albedo = [0.7, 0.2, 0.1] }}
    velocity = [-15.0, 0.0, 0.0]
"""


def same_colour_scene(tmp_path, front_speed=20.0):
    path = tmp_path / "same_colour.toml"
    path.write_text(textwrap.dedent(SAME_COLOUR.format(front_speed=front_speed)))
    return load_scene(path)


def test_two_overlapping_objects_of_the_same_colour_reveal_the_right_one(ctx, tmp_path):
    scene = same_colour_scene(tmp_path)
    res, bufs = render(ctx, scene, "hybrid", 0.0)
    front = bufs["ray_mask"] == 2
    _, oracle = render(ctx, without(scene, {2}), "off", 0.0)
    assert_layer_matches(bufs, oracle, front)
    # Behind the front box lie both the middle box (same colour) and the wall.
    ids = revealed(bufs)[0][front]
    assert np.count_nonzero(ids == 3) > 50 and np.count_nonzero(ids == 1) > 50


def test_trace_off_leaves_the_revealed_layer_empty(ctx):
    scene = load_scene(CONFORMANCE / "basic.toml")
    res, bufs = render(ctx, scene, "hybrid", 0.0, params(trace=False))
    assert res.stats["masked_pixels"] == np.count_nonzero(bufs["ray_mask"]) > 0
    assert res.stats["rays"] == 0 and not bufs["hybrid_back_color"].any()


# ---- the composite on synthetic buffers ---------------------------------------------------------

W, H = 40, 4


def upload(frame, name, a):
    spec = GBUFFER.get(name) or PACKED
    frame.pool.texture(name, spec)
    frame.write(name, to_image(np.asarray(a, np.uint32 if spec.dtype == "u4" else np.float32)))


def bar_layers(rng, bar=(12, 24), d=(9.3, 0.0), reveal_cols=range(12, 24)):
    """GL-orientation buffers: a textured bar translating over a static textured wall, and
    the wall revealed behind the bar at `reveal_cols` (the exact hidden background)."""
    wall = rng.uniform(0, 1, (H, W, 3))
    bar_c = rng.uniform(0, 1, (H, W, 3))
    colour = wall.copy()
    colour[:, bar[0]:bar[1]] = bar_c[:, bar[0]:bar[1]]
    depth = np.full((H, W), 10.0)
    depth[:, bar[0]:bar[1]] = 2.0
    disp = np.zeros((H, W, 2))
    disp[:, bar[0]:bar[1]] = d
    rev_c = np.zeros((H, W, 4))
    rev_d = np.full((H, W), 1e9)
    cols = list(reveal_cols)
    rev_c[:, cols, :3] = wall[:, cols]
    rev_c[:, cols, 3] = 1.0
    rev_d[:, cols] = 10.0
    ids = np.ones((H, W), np.uint32)
    ids[:, bar[0]:bar[1]] = 2
    rev_ids = np.zeros((H, W), np.uint32)
    rev_ids[:, cols] = 1
    return dict(colour=colour, depth=depth, disp=disp, ids=ids, rev_c=rev_c, rev_d=rev_d,
                rev_ids=rev_ids, rev_v=np.zeros((H, W, 2)), wall=wall, bar=bar_c)


def composite_stage(config: HybridConfig = HybridConfig()) -> list:
    """The hybrid pipeline's composite and its displacement tiles (the passes named
    hybrid_*), run here on a frame whose G-buffer and revealed layer a test uploaded."""
    return [p for p in hybrid_pipeline(config).passes if p.name.startswith("hybrid_")]


def run_composite(frame, b):
    """The composite on the layers as the G-buffer and reveal_shade store them."""
    ones = np.ones((H, W, 1))
    upload(frame, "color", np.concatenate([b["colour"], ones], -1))
    front, _, back, back_color = nh.pack_layers(
        b["colour"], b["depth"], b["disp"], b["rev_c"], b["rev_d"], b["rev_v"],
        2.0 * max_radius_px(frame), b["ids"], b["rev_ids"])
    upload(frame, "hybrid_front", front)
    stored = nh.stored_back(back, back_color)
    for name, a in zip(BACK, stored):
        upload(frame, name, a)
    # The mask the revealed pixels came from, summarised per tile for the composite.
    k = max_radius_px(frame)
    jj, ii = np.nonzero(to_image(b["rev_c"][..., 3] > 0))
    frame.pool.texture("ray_mask_tiles", TexSpec(2, "f4", tile=k))
    frame.write("ray_mask_tiles", mask_tiles(np.c_[ii, jj], (W, H), k))
    for p in composite_stage():
        p.allocate(frame)
        p.execute(frame)
    return to_image(frame.read("hybrid"))[..., :3].astype(np.float64)


def numpy_composite(frame, b):
    p = frame.params["hybrid"]
    k = max_radius_px(frame)
    front, fc, back, bc = nh.pack_layers(b["colour"], b["depth"], b["disp"], b["rev_c"],
                                         b["rev_d"], b["rev_v"], 2.0 * k, b["ids"], b["rev_ids"])
    tiles = nm.tilemax(b["disp"].astype(np.float32), k)
    if composite_kind(frame) == "bucket":
        return nh.bucket_composite(front, fc, back, bc, nm.neighbormax(tiles), k, 2.0 * k,
                                   p.samples_min, p.samples_max, p.sample_spacing)
    return nh.time_composite(front, fc, back, bc, tiles, nm.neighbormax(tiles), k, 2.0 * k,
                             p.samples_min, p.samples_max, p.sample_spacing, p.tolerance,
                             p.iterations, p.seeds)


def composite_params(**kw):
    p = params(**{"composite": "time", "jitter": 0.0, "samples_min": 8, "samples_max": 8, **kw})
    p.set("blur.max_radius", 0.25)          # k = 10 px
    return p


def test_numpy_composite_with_an_exact_background_is_the_box_shutter():
    rng = np.random.default_rng(3)
    b = bar_layers(rng)
    front, fc, back, bc = nh.pack_layers(b["colour"], b["depth"], b["disp"], b["rev_c"],
                                         b["rev_d"], b["rev_v"], 20.0)
    tiles = nm.tilemax(b["disp"].astype(np.float32), 10)
    # With the landing tolerance at half a pixel, coverage follows the pixel-centre rule.
    got = nh.time_composite(front, fc, back, bc, tiles, nm.neighbormax(tiles), 10, 20.0, 8, 8,
                            tolerance=0.5)
    for y in range(H):
        want = nh.box_shutter_bar(b["bar"][y], b["wall"][y], 12, 24, 9.3, 8)
        np.testing.assert_allclose(got[y], want, atol=1e-12)


def test_numpy_box_shutter_hand_values():
    fg, bg = np.ones((8, 3)), np.zeros((8, 3))
    # Bar [3, 5) moving 4 px, 4 samples at 4u = -1.5, -0.5, 0.5, 1.5: pixel x's centre
    # maps back into pixel x + 2, x + 1, x, x - 1; covered when that is 3 or 4. A 2-px box
    # spread over 4 px: a trapezoid with a plateau of 2/4, summing to the bar's width.
    got = nh.box_shutter_bar(fg, bg, 3, 5, 4.0, 4)[:, 0]
    np.testing.assert_allclose(got, [0, 0.25, 0.5, 0.5, 0.5, 0.25, 0, 0])


def test_composite_matches_numpy_and_the_box_shutter(synthetic_frame):
    rng = np.random.default_rng(4)
    frame = synthetic_frame((W, H), composite_params(tolerance=0.5))
    b = bar_layers(rng)
    got = run_composite(frame, b)
    np.testing.assert_allclose(got, numpy_composite(frame, b), atol=2e-6)
    for y in range(H):
        np.testing.assert_allclose(got[y], nh.box_shutter_bar(b["bar"][y], b["wall"][y], 12, 24,
                                                               9.3, 8), atol=2e-6)


def test_default_tolerance_widens_translating_silhouettes_by_at_most_its_excess(synthetic_frame):
    # A landing tolerance above half a pixel (for curved motion) lets a silhouette pixel
    # cover a time sample whose source lies up to 0.15 px outside it: on a translating
    # bar only the two silhouette columns change, by at most one sample in eight.
    rng = np.random.default_rng(8)
    frame = synthetic_frame((W, H), composite_params())
    b = bar_layers(rng)
    got = run_composite(frame, b)
    np.testing.assert_allclose(got, numpy_composite(frame, b), atol=2e-6)
    exact = np.stack([nh.box_shutter_bar(b["bar"][y], b["wall"][y], 12, 24, 9.3, 8)
                      for y in range(H)])
    diff = np.abs(got - exact).max(axis=(0, 2))
    assert set(np.flatnonzero(diff > 1e-6)) <= {12, 23}
    assert diff.max() <= 1.0 / 8 + 1e-6


def test_composite_without_a_revealed_background_stands_in_from_outside(synthetic_frame):
    # No ray cast: where the bar uncovers the pixel, the closest miss behind it stands in.
    rng = np.random.default_rng(5)
    frame = synthetic_frame((W, H), composite_params())
    b = bar_layers(rng, reveal_cols=())
    got = run_composite(frame, b)
    np.testing.assert_allclose(got, numpy_composite(frame, b), atol=2e-6)
    exact = np.stack([nh.box_shutter_bar(b["bar"][y], b["wall"][y], 12, 24, 9.3, 8)
                      for y in range(H)])
    assert np.abs(got - exact).max() > 0.05             # the hidden wall is missing


def test_composite_with_a_moving_revealed_layer_matches_numpy(synthetic_frame):
    rng = np.random.default_rng(6)
    frame = synthetic_frame((W, H), composite_params(samples_max=16, samples_min=3))
    b = bar_layers(rng, d=(-7.7, 1.3))
    b["disp"][:, :12] = b["disp"][:, 24:] = (2.3, 0.4)            # the wall moves too
    b["rev_v"][:, 12:24] = (2.3, 0.4)
    got = run_composite(frame, b)
    np.testing.assert_allclose(got, numpy_composite(frame, b), atol=2e-6)


def test_numpy_bucket_composite_with_an_exact_background_is_the_box_shutter():
    # Displacement 9 and 9 taps: one-pixel pieces centred on the pixels within 4 px, each
    # worth 1/9 of the exposure, as are the 9 stratified times of the box shutter.
    rng = np.random.default_rng(9)
    b = bar_layers(rng, d=(9.0, 0.0))
    front, fc, back, bc = nh.pack_layers(b["colour"], b["depth"], b["disp"], b["rev_c"],
                                         b["rev_d"], b["rev_v"], 20.0, b["ids"], b["rev_ids"])
    tiles = nm.tilemax(b["disp"].astype(np.float32), 10)
    got = nh.bucket_composite(front, fc, back, bc, nm.neighbormax(tiles), 10, 20.0, 9, 9, 1.0)
    for y in range(H):
        want = nh.box_shutter_bar(b["bar"][y], b["wall"][y], 12, 24, 9.0, 9)
        np.testing.assert_allclose(got[y], want, atol=1e-12)


@pytest.mark.parametrize("case", ["exact", "no_reveal", "moving_wall", "parallel_wall",
                                  "many_taps", "merged_ends"])
def test_bucket_composite_matches_numpy(synthetic_frame, case):
    rng = np.random.default_rng(10)
    # many_taps: lines of 40 taps, past the 32 own-presence bits (a separate presence walk)
    taps = {"many_taps": dict(samples_min=40, samples_max=40, sample_spacing=0.5)}
    p = composite_params(composite="bucket", **taps.get(case, dict(samples_min=3,
                                                                     samples_max=12)))
    frame = synthetic_frame((W, H), p)
    d = {"exact": (9.0, 0.0), "parallel_wall": (-15.4, 2.6)}.get(case, (-7.7, 1.3))
    b = bar_layers(rng, d=d, reveal_cols=() if case == "no_reveal" else range(12, 24))
    if case in ("moving_wall", "many_taps"):
        b["disp"][:, :12] = b["disp"][:, 24:] = (2.3, 0.4)
        b["rev_v"][:, 12:24] = (2.3, 0.4)
    if case == "parallel_wall":
        # The wall moves along the bar's line, 0.77 as far (a camera pan's parallax): the
        # wall pixels' own line is merged with the neighbourhood's.
        b["disp"][:, :12] = b["disp"][:, 24:] = (-11.85, 2.0)
        b["rev_v"][:, 12:24] = (-11.85, 2.0)
    if case == "merged_ends":
        # The bar's displacement grows along it (a slanted surface under a pan) and turns
        # by up to 4 degrees, the wall's is 0.6 of the slowest: every line merged, and its
        # ends hold bar fragments fast enough to reach pixels whose own line does not.
        bar_d = np.linspace(5.0, 11.0, 12)[:, None] * np.c_[np.cos(np.linspace(0.0, 0.07, 12)),
                                                             np.sin(np.linspace(0.0, 0.07, 12))]
        b["disp"][:, 12:24] = -bar_d
        b["disp"][:, :12] = b["disp"][:, 24:] = (-3.0, 0.0)
        b["rev_v"][:, 12:24] = (-3.0, 0.0)
    got = run_composite(frame, b)
    want = numpy_composite(frame, b)
    np.testing.assert_allclose(got, want, atol=2e-6)
    if case == "merged_ends":
        # (the merged lines' ends count: not merging reads otherwise)
        k = max_radius_px(frame)
        front, fc, back, bc = nh.pack_layers(b["colour"], b["depth"], b["disp"], b["rev_c"],
                                             b["rev_d"], b["rev_v"], 2.0 * k, b["ids"],
                                             b["rev_ids"])
        tiles = nm.tilemax(b["disp"].astype(np.float32), k)
        hp = frame.params["hybrid"]
        apart = nh.bucket_composite(front, fc, back, bc, nm.neighbormax(tiles), k, 2.0 * k,
                                    hp.samples_min, hp.samples_max, hp.sample_spacing,
                                    merge_cos=2.0)
        assert np.abs(apart - want).max() > 0.01
    if case == "exact":
        p.set("hybrid.sample_spacing", 1.0)
        p.set("hybrid.samples_min", 9)
        p.set("hybrid.samples_max", 9)
        got = run_composite(synthetic_frame((W, H), p), b)
        for y in range(H):
            np.testing.assert_allclose(
                got[y], nh.box_shutter_bar(b["bar"][y], b["wall"][y], 12, 24, 9.0, 9), atol=2e-6)


def test_jitter_is_deterministic_and_seeded(synthetic_frame):
    rng = np.random.default_rng(7)
    b = bar_layers(rng)
    p = composite_params()
    p.set("hybrid.jitter", 1.0)
    a1 = run_composite(synthetic_frame((W, H), p, seed=1), b)
    a2 = run_composite(synthetic_frame((W, H), p, seed=1), b)
    a3 = run_composite(synthetic_frame((W, H), p, seed=2), b)
    assert a1.tobytes() == a2.tobytes()
    assert np.abs(a1 - a3).max() > 1e-3


# ---- the whole mode -----------------------------------------------------------------------------

def test_deterministic(ctx):
    scene = load_scene(CONFORMANCE / "basic.toml")
    a, ba = render(ctx, scene, "hybrid", 0.0, seed=5)
    b, bb = render(ctx, scene, "hybrid", 0.0, seed=5)
    assert a.image.tobytes() == b.image.tobytes()
    for name in ("ray_mask", "hybrid_back", "hybrid_back_color", "hybrid"):
        assert ba[name].tobytes() == bb[name].tobytes()
    assert a.stats["rays"] == b.stats["rays"] > 0


def test_stored_layers_are_the_packed_g_buffer_and_revealed_layer(ctx):
    # The hybrid G-buffer's hybrid_front is the full G-buffer's (D, depth, id), D not
    # clamped (the composite clamps on read); reveal_shade's hybrid_back likewise holds
    # (D, depth, 1 + id) and (colour, 1) where revealed, 0 elsewhere (its values against
    # the raster oracle: test_reveal_equals_raster_without_the_own_object).
    scene = load_scene(CONFORMANCE / "basic.toml")
    p = ParamSet()
    p.set("blur.max_radius", 0.05)            # k = 8 px: some displacements exceed 2k
    res, bufs = render(ctx, scene, "hybrid", 0.0, p)
    _, full = render(ctx, scene, "off", 0.0, p)          # the full G-buffer layout
    assert not {"depth", "id", "velocity"} & set(bufs)   # the hybrid layout packs them
    assert "normal" not in bufs                          # read by the range check only
    p.set("hybrid.range_check", True)
    _, with_edges = render(ctx, scene, "hybrid", 0.0, p)
    np.testing.assert_array_equal(with_edges["normal"][..., :3], full["normal"][..., :3])
    np.testing.assert_array_equal(with_edges["hybrid_front"], bufs["hybrid_front"])
    k = 8
    np.testing.assert_array_equal(
        bufs["hybrid_front"], np.dstack([full["velocity"], full["depth"], full["id"]]))
    np.testing.assert_array_equal(bufs["color"], full["color"])
    assert np.linalg.norm(full["velocity"], axis=-1).max() > 2.0 * k
    motion, colour = bufs["hybrid_back"], bufs["hybrid_back_color"]
    hit = colour[..., 3] == 1.0
    assert res.stats["revealed_pixels"] == np.count_nonzero(hit) > 0
    assert np.all(motion[hit, 3] >= 1.0) and np.all(motion[hit, 2] > 0.0)
    assert not motion[~hit].any() and not colour[~hit].any()


def test_static_scene_traces_nothing_and_equals_off(ctx):
    scene = load_scene(CONFORMANCE / "basic.toml")
    still = dataclasses.replace(scene, objects=[
        dataclasses.replace(o, velocity=np.zeros(3), angular_velocity=np.zeros(3))
        for o in scene.objects])
    res, bufs = render(ctx, still, "hybrid", 0.0, timing=True)
    off, _ = render(ctx, still, "off", 0.0)
    assert res.stats["masked_pixels"] == 0 and res.stats["rays"] == 0
    assert not bufs["ray_mask"].any() and not bufs["hybrid_back_color"].any()
    assert res.image.tobytes() == off.image.tobytes()
    assert {"reveal", "reveal_shade", "hybrid_composite"} <= set(res.pass_ms)
    assert res.stats["revealed_pixels"] == 0 and "reveal_ms" in res.stats


def test_inner_blur_beats_the_post_process_modes_on_basic(ctx):
    scene = load_scene(CONFORMANCE / "basic.toml")
    p = ParamSet()
    p.set("reference.samples", 32)
    r = Renderer(ctx, scene, SMALL)
    try:
        ref = r.render("reference", 0.0, p, record_visibility=True)
        region = ref.host[REGIONS]
        flip = {m: image_metrics(r.render(m, 0.0, p).image, ref.image, region)
                for m in ("hybrid", "mcguire", "ue4") if m in MODES}
    finally:
        r.release()
    assert flip["hybrid"]["inner"]["pixels"] > 200
    for other in set(flip) - {"hybrid"}:
        assert flip["hybrid"]["inner"]["flip"] < 0.6 * flip[other]["inner"]["flip"], other
        assert flip["hybrid"]["all"]["flip"] <= flip[other]["all"]["flip"], other


def test_split_composite_is_time_near_the_mask_and_bucket_elsewhere(ctx):
    # A moving camera: each active tile holds exactly what the time-sampled or the bucketed
    # composite gives there; the time tiles are those within reach of a masked pixel.
    from viewer.render.passes.tile_runs import FINE
    scene = load_scene(CONFORMANCE / "vase_pan.toml")
    size = (160, 90)
    r = Renderer(ctx, scene, size)
    try:
        split = r.render("hybrid", 0.0, params(composite="split"))
        lists = r.kept.get(KEPT_LISTS)
        time_tiles = lists.extra("time100").tiles.copy()
        bucket_tiles = np.concatenate([lists.extra(n).tiles
                                       for n in ("bucket000", "bucket001", "bucket010")])
        mask = r.pool.get("ray_mask").read()
        t = r.render("hybrid", 0.0, params(composite="time"))
        b = r.render("hybrid", 0.0, params(composite="bucket"))
    finally:
        r.release()
    assert len(time_tiles) and len(bucket_tiles) and split.stats["time_tiles"] == len(time_tiles)
    assert np.frombuffer(mask, np.uint32).any()
    gl = [to_image(x.image) for x in (split, t, b)]     # GL rows, as the tiles count
    for tiles, want in ((time_tiles, gl[1]), (bucket_tiles, gl[2])):
        for tx, ty in tiles:
            sl = np.s_[ty * FINE:(ty + 1) * FINE, tx * FINE:(tx + 1) * FINE]
            assert gl[0][sl].tobytes() == want[sl].tobytes(), (tx, ty)


def test_mask_tiles_are_made_only_where_the_time_composite_reads_them(ctx):
    # ray_mask_tiles, the time composite's summary of the ray mask, holds the k-tiles of
    # the pixels masked this frame, and is not among the bucketed composite's buffers.
    scene = load_scene(CONFORMANCE / "basic.toml")
    r = Renderer(ctx, scene, SMALL)
    try:
        r.render("hybrid", 0.013, params(composite="time"))
        mask = r.buffers()["ray_mask"] != 0            # image rows, as buffers() reads
        k = max_radius_px(r.frame(0.0, ParamSet()))
        tiles = r.buffers()["ray_mask_tiles"][..., 1]
        r.render("hybrid", 0.013, params(composite="bucket"))
        assert "ray_mask_tiles" not in r.buffers() and "ray_mask" in r.buffers()
    finally:
        r.release()
    jj, ii = np.nonzero(mask)
    want = mask_tiles(np.c_[ii, jj], SMALL, k)[..., 1]
    assert mask.sum() > 50 and want.sum() > 1 and not want.all()
    np.testing.assert_array_equal(tiles, want)


def test_split_tiles_hand_values():
    from viewer.render.modes.hybrid.composite import split_tiles
    from viewer.render.passes.tile_runs import FINE
    active = np.ones((3, 6), bool)
    active[0, 5] = False
    # One masked pixel in image row 0 of a 48-row screen: GL row 47, tile row 2; column 20
    # is tile column 1. Reach 1: tile columns 0-2, tile rows 1-2 are near it.
    time, bucket = split_tiles(active, np.array([[20, 0]]), 3 * FINE, 1)
    want = np.zeros((3, 6), bool)
    want[1:3, 0:3] = True
    np.testing.assert_array_equal(time, want)
    np.testing.assert_array_equal(bucket, active & ~want)
    # No mask: every active tile is the bucket's.
    time, bucket = split_tiles(active, np.zeros((0, 2), int), 3 * FINE, 1)
    assert not time.any() and (bucket == active).all()


def test_numpy_bucket_inner_blur_over_a_moving_background_follows_the_time_average():
    # A bar (16 px, D = -9) over a textured wall that moves too (D = -5, a camera pan),
    # with the exact wall revealed behind the bar: where the bar uncovers the pixel, the
    # wall seen is the part that passes the pixel while the bar is away, not the wall's
    # blur both ways. Within 0.03 of n = 64 time samples of the scene on the inner-blur
    # columns (before pairing background taps with their times: up to 0.097).
    h, w = 2, 48
    rng = np.random.default_rng(3)
    wall, bar = rng.uniform(0, 1, (h, w, 3)), rng.uniform(0, 1, (h, w, 3))
    x0, x1, d_bar, d_wall = 16, 32, -9.0, -5.0
    colour = wall.copy()
    colour[:, x0:x1] = bar[:, x0:x1]
    depth = np.full((h, w), 10.0)
    depth[:, x0:x1] = 2.0
    disp = np.zeros((h, w, 2))
    disp[..., 0] = d_wall
    disp[:, x0:x1, 0] = d_bar
    ids = np.ones((h, w))
    ids[:, x0:x1] = 2
    rev_c = np.zeros((h, w, 4))
    rev_c[:, x0:x1, :3], rev_c[:, x0:x1, 3] = wall[:, x0:x1], 1.0
    rev_d = np.full((h, w), 1e9)
    rev_d[:, x0:x1] = 10.0
    rev_v = np.zeros((h, w, 2))
    rev_v[:, x0:x1, 0] = d_wall
    rev_ids = np.zeros((h, w))
    rev_ids[:, x0:x1] = 1
    front, fc, back, bc = nh.pack_layers(colour, depth, disp, rev_c, rev_d, rev_v, 40.0,
                                         ids, rev_ids)
    tiles = nm.tilemax(disp.astype(np.float32), 20)
    got = nh.bucket_composite(front, fc, back, bc, nm.neighbormax(tiles), 20, 40.0, 32, 32, 0.5)
    def seen(u, x):
        pb = x + 0.5 - u * d_bar
        if x0 <= pb < x1:
            return bar[:, int(np.floor(pb))]
        return wall[:, int(np.clip(np.floor(x + 0.5 - u * d_wall), 0, w - 1))]
    want = nh.time_average(w, 64, seen)
    inner = list(range(x0, x0 + 4)) + list(range(x1 - 4, x1))
    assert np.abs(got[:, inner] - want[:, inner]).max() <= 0.03


def test_numpy_bucket_surfaces_sliding_together_blur_like_the_translated_image():
    # A camera pan seen as two surfaces side by side, the nearer one on the left, both
    # moving 10 px: the exact result is the image blurred along the motion. The nearer
    # surface covers the wall's pixels beside it only while the wall is away from them,
    # so it is not laid "over" the wall: within 0.03 of 64 time samples at the boundary
    # (laid over: up to 0.11).
    h, w = 2, 48
    rng = np.random.default_rng(5)
    tex = rng.uniform(0, 1, (h, w, 3))
    d = -10.0
    depth = np.full((h, w), 6.0)
    depth[:, :24] = 5.0
    ids = np.ones((h, w))
    ids[:, :24] = 2
    disp = np.zeros((h, w, 2))
    disp[..., 0] = d
    none = (np.zeros((h, w, 4)), np.full((h, w), 1e9), np.zeros((h, w, 2)))
    front, fc, back, bc = nh.pack_layers(tex, depth, disp, *none, 40.0, ids, np.zeros((h, w)))
    tiles = nm.tilemax(disp.astype(np.float32), 20)
    got = nh.bucket_composite(front, fc, back, bc, nm.neighbormax(tiles), 20, 40.0, 20, 20, 1.0)
    want = nh.time_average(w, 64, lambda u, x: tex[:, int(np.clip(np.floor(x + 0.5 - u * d),
                                                                  0, w - 1))])
    assert np.abs(got[:, 14:34] - want[:, 14:34]).max() <= 0.03
