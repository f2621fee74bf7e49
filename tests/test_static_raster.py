"""The G-buffer's kept static raster (viewer/render/passes/static_raster.py): under a still camera
a renderer that copies the statics in and draws only the movers makes every target the
full draw makes, bit for bit, ties included; a moved camera, a moving one or a new size
never finds a stale raster."""
import numpy as np
import pytest

from conftest import scene_from
from viewer.render.graph.params import ParamSet
from viewer.render.passes import static_raster
from viewer.render.passes.gbuffer import GBUFFER, LAYOUTS, GBufferPass
from viewer.render.renderer import Renderer

SIZE = (96, 64)
TIMES = [0.0, 0.02, 0.04, 0.06, 0.1]

# Equal boxes whose front faces lie in one plane facing the camera (z = 0.1, view depth
# 4.9 exactly): every overlap is a depth tie, which the full draw gives to the object drawn
# first (front to back by box centre: s1, m1, s2, m2, s3). Statics come both before and
# after each mover, so the kept raster needs both of its tie rules.
TIES = """
    background = [0.1, 0.1, 0.1]
    ambient = [0.3, 0.3, 0.3]
    [camera]
    position = [0.0, 0.0, 5.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 45.0
    shutter = 0.05
    [[lights]]
    direction = [0.0, 0.0, -1.0]
    [[objects]]
    name = "s1"
    mesh = { box = [1.2, 1.2, 0.2] }
    position = [0.1, 0.0, 0.0]
    material = { albedo = [0.9, 0.2, 0.2], texture = { kind = "checker", size = 0.2, albedo2 = [0.1, 0.1, 0.1] } }
    [[objects]]
    name = "m1"
    mesh = { box = [1.2, 1.2, 0.2] }
    position = [0.3, 0.1, 0.0]
    velocity = [0.0, 0.1, 0.0]
    material = { albedo = [0.2, 0.9, 0.2] }
    [[objects]]
    name = "s2"
    mesh = { box = [1.2, 1.2, 0.2] }
    position = [-0.4, 0.0, 0.0]
    material = { albedo = [0.2, 0.2, 0.9] }
    [[objects]]
    name = "m2"
    mesh = { box = [1.2, 1.2, 0.2] }
    position = [-0.2, -0.5, 0.0]
    velocity = [0.1, 0.0, 0.0]
    material = { albedo = [0.9, 0.9, 0.2] }
    [[objects]]
    name = "s3"
    mesh = { box = [1.2, 1.2, 0.2] }
    position = [0.6, 0.3, 0.0]
    material = { albedo = [0.5, 0.5, 0.5], specular = 0.4, shininess = 12.0 }
"""


def params(**sets) -> ParamSet:
    p = ParamSet()
    for k, v in sets.items():
        p.set(k.replace("__", "."), v)
    return p


def fresh(ctx, scene, mode, t, p, size=SIZE):
    """The frame at t from a renderer of its own: its one G-buffer is the full draw."""
    r = Renderer(ctx, scene, size)
    try:
        r.render(mode, t, p)
        return r.buffers()
    finally:
        r.release()


def assert_same(got: dict, want: dict):
    """Every texture of `want` in `got`, the same bytes."""
    assert want.keys() <= got.keys()
    for name in want:
        assert got[name].dtype == want[name].dtype, name
        assert np.array_equal(got[name].view(np.uint8), want[name].view(np.uint8)), name


@pytest.fixture
def spy(monkeypatch):
    """Counts of the kept raster's use: frames composed over it, depth restores."""
    calls = {"compose": 0, "restore": 0}
    compose, restore = GBufferPass._compose, static_raster.StaticRaster.restore_depth

    def counted_compose(*a):
        calls["compose"] += 1
        return compose(*a)

    def counted_restore(self, *a):
        calls["restore"] += 1
        return restore(self, *a)
    monkeypatch.setattr(GBufferPass, "_compose", staticmethod(counted_compose))
    monkeypatch.setattr(static_raster.StaticRaster, "restore_depth", counted_restore)
    return calls


@pytest.mark.parametrize("mode, sets", [
    ("off", {}),
    ("mcguire", {"mcguire__segments": 4}),
    ("hybrid", {"hybrid__segments": 2}),
    ("hybrid", {"hybrid__range_check": True, "motion__steps": 2}),
    ("reference", {"reference__samples": 4}),
])
def test_kept_raster_gives_every_target_of_the_full_draw(ctx, tmp_path, spy, mode, sets):
    scene = scene_from(tmp_path, TIES)
    p = params(**sets)
    r = Renderer(ctx, scene, SIZE)
    try:
        for t in TIMES:
            r.render(mode, t, p)
            assert_same(r.buffers(), fresh(ctx, scene, mode, t, p))
    finally:
        r.release()
    # (the first frame draws everything and the second keeps the raster; then each frame
    # is composed over it, restoring s1's depth before m1 and s2's before m2)
    assert spy["compose"] >= len(TIMES) - 2 and spy["restore"] >= 2 * spy["compose"]


def test_a_tie_goes_to_the_object_drawn_first(ctx, tmp_path, spy):
    scene = scene_from(tmp_path, TIES)
    ids = {o.name: o.id for o in scene.objects}
    r = Renderer(ctx, scene, SIZE)
    try:
        for t in TIMES:
            r.render("off", t)
        got = r.buffers()["id"]
        order = [o.name for o in r.gpu.front_to_back(r.camera.eye(TIMES[-1]), TIMES[-1])]
        # m1 over s3 (a mover before a static), s2 over m2 (a static before a mover)
        win, depth = r.camera.project(TIMES[-1], np.array([[0.8, 0.2, 0.1], [-0.65, -0.2, 0.1]]))
    finally:
        r.release()
    assert order == ["s1", "m1", "s2", "m2", "s3"] and spy["compose"] > 0
    assert np.allclose(depth, 4.9)
    rows = SIZE[1] - 1 - np.floor(win[:, 1]).astype(int)
    cols = np.floor(win[:, 0]).astype(int)
    assert list(got[rows, cols]) == [ids["m1"], ids["s2"]]
    assert set(np.unique(got)) == {0, *ids.values()}


def test_a_moved_camera_a_moving_camera_or_a_new_size_finds_no_stale_raster(ctx, tmp_path, spy):
    scene = scene_from(tmp_path, TIES)
    cam = scene.camera
    r = Renderer(ctx, scene, SIZE)
    try:
        for t in TIMES[:3]:
            r.render("off", t)
        assert spy["compose"] == 2
        # The viewer moves the camera: the next frame draws everything, then one keeps
        # the new view's raster.
        cam.position = cam.position + [0.3, 0.2, 0.0]
        cam.look_at = cam.look_at + [0.1, 0.0, 0.0]
        for t in TIMES:
            r.render("off", t)
            assert_same(r.buffers(), fresh(ctx, scene, "off", t, ParamSet()))
        assert spy["compose"] == 2 + len(TIMES) - 1
        # A moving camera: nothing is kept for it.
        cam.velocity = np.array([0.5, 0.0, 0.0])
        for t in TIMES[:3]:
            r.render("off", t)
            assert_same(r.buffers(), fresh(ctx, scene, "off", t, ParamSet()))
        assert spy["compose"] == 2 + len(TIMES) - 1
        cam.velocity = np.zeros(3)
        # A new size.
        r.resize((80, 48))
        for t in TIMES:
            r.render("off", t)
            assert_same(r.buffers(), fresh(ctx, scene, "off", t, ParamSet(), (80, 48)))
        kept = r.kept.get(static_raster.KEPT_STATIC)
        assert [x.size for x in kept.rasters.values()] == [(80, 48)]
    finally:
        r.release()
    assert r.kept.names() == []          # released with the renderer


def test_a_raster_past_the_budget_is_not_kept(ctx, tmp_path, monkeypatch, spy):
    scene = scene_from(tmp_path, TIES)
    full = [GBUFFER[n] for n in LAYOUTS["full"][1]]
    monkeypatch.setattr(static_raster, "BUDGET_BYTES", static_raster.nbytes(SIZE, full) - 1)
    r = Renderer(ctx, scene, SIZE)
    try:
        for t in TIMES:
            r.render("off", t)        # full layout: 5 targets, over the budget
            r.render("mcguire", t)    # motion layout: 3 targets, within
            assert_same(r.buffers(), fresh(ctx, scene, "mcguire", t, ParamSet()))
        kept = r.kept.get(static_raster.KEPT_STATIC)
        assert len(kept.rasters) == 1 and spy["compose"] == len(TIMES) - 1
    finally:
        r.release()


def test_draw_plan_runs_of_statics_between_movers():
    class O:
        def __init__(self, moving):
            self.moving = moving
    s, m1, m2, m3 = O(False), O(True), O(True), O(True)
    assert static_raster.draw_plan([s, s, m1, s, m2, m3, s]) == [[1, 3], m1, [3, 4], m2, m3,
                                                                  [4, 5]]
    assert static_raster.draw_plan([m1, s]) == [m1, [1, 2]]
