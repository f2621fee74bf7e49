"""Inverse motion (hybrid.curve = inverse; viewer/render/modes/hybrid/inverse.py and
glsl/modes/hybrid/hybrid_inverse.frag): the pose table against each node's own matrices,
the motion table's maps against the camera and the objects' matrices, the candidates and
the tiles, and whole frames against the reference: a blade turning about the view axis
blurs along its arc, a body that comes back within the exposure is traced where it
leaves a pixel, straight motion is the linear composite's to the byte."""
import math

import numpy as np
import pytest

from viewer.render.graph.params import ParamSet
from viewer.render.modes.hybrid import inverse
from viewer.render.modes.reference import REGIONS
from viewer.render.renderer import Renderer
from viewer.eval.metrics import image_metrics
from world import transforms as tf
from world.camera import Camera
from world.loader import load_scene
from world.path_bend import object_bends, screen_bend
from world.pose_table import PoseTable

from conftest import scene_from


def curve(kind: str, **more) -> ParamSet:
    p = ParamSet()
    p.set("hybrid.curve", kind)
    for k, v in more.items():
        p.set(k.replace("__", "."), v)
    return p


def test_axis_angles_are_axis_angle_row_by_row():
    w = np.random.default_rng(3).normal(size=(7, 3)) * 2.0
    w[2] = 0.0
    np.testing.assert_allclose(tf.axis_angles(w), np.stack([tf.axis_angle(x) for x in w]),
                               atol=1e-14)


@pytest.mark.parametrize("name", ["fan", "turning_car", "rover", "wheel"])
def test_pose_table_is_every_nodes_matrix(name):
    scene = load_scene(name)
    times = np.linspace(-0.03, 0.03, 7)
    table = PoseTable(times)
    for o in scene.objects:
        np.testing.assert_allclose(table.world(o), np.stack([o.matrix(t) for t in times]),
                                   rtol=0, atol=1e-12, err_msg=o.name)
        if o.skin is None and o.keys is None and o.own_moving:
            np.testing.assert_allclose(o.own_matrices(times),
                                       np.stack([o.own_matrix(t) for t in times]), atol=1e-14)
    # Each node once: its parent's matrices are the very array its children read.
    rotor = next(o for o in load_scene("fan").objects if o.name == "rotor")
    fan = PoseTable(times)
    assert fan.world(rotor) is fan.world(rotor)


def test_object_bends_are_the_frames_bend_per_object():
    scene = load_scene("spinner")
    cam = Camera(scene.camera, 320, 180)
    movers = [o for o in scene.objects if o.moving]
    bends = object_bends(scene, cam, 0.0, scene.camera.shutter, movers)
    assert bends.max() == pytest.approx(screen_bend(scene, cam, 0.0, scene.camera.shutter))
    blades = [b for o, b in zip(movers, bends) if o.name.startswith("blades")]
    assert len(blades) == 3 and min(blades) > 1.0 and np.ptp(blades) < 0.05 * max(blades)


def run_table(ctx, scene, params, size=(320, 180)):
    r = Renderer(ctx, scene, size)
    frame = r.frame(scene.render.time, params)
    scene.pose([scene.render.time])
    p = inverse.MotionTable()
    p.allocate(frame)
    p.execute(frame)
    return r, frame


def table_of(frame) -> np.ndarray:
    tex = frame.pool.get(inverse.MOTION_TABLE)
    return np.frombuffer(tex.read(), np.float32).reshape(tex.size[1], tex.size[0], 4)


def affine(row: np.ndarray, k: int, at: int) -> np.ndarray:
    m = np.eye(4)
    m[:3] = row[k * inverse.COLS + at: k * inverse.COLS + at + 3]
    return m


def test_motion_table_maps_points_between_the_times(ctx):
    """For each mover and table time t_k: L_k takes view space at t_k to the object's own,
    F_k takes a point seen at t_k to where the frame time sees it, B_k is F_k's inverse;
    the screen box at t_k holds the object's projected corners; still rows map by the
    camera alone."""
    scene = load_scene("fan")
    r, frame = run_table(ctx, scene, curve("inverse"))
    try:
        table = table_of(frame)
        k_n = int(frame.params["hybrid"].curve_samples)
        times = inverse.table_times(*frame.exposure, k_n)
        cam, t = frame.camera, frame.time
        movers = [o for o in scene.objects if o.moving]
        assert movers and frame.stats["inverse_tiles"] > 0
        for o in movers:
            row = table[o.id]
            lo, hi = frame.gpu.bounds[o.id]
            corners = np.array([[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                                for z in (lo[2], hi[2])]).T
            for k in (0, k_n // 3, k_n - 1):
                vm_k = cam.view(times[k]) @ o.matrix(times[k])
                vm_t = cam.view(t) @ o.matrix(t)
                np.testing.assert_allclose(affine(row, k, inverse.AT_L) @ vm_k, np.eye(4),
                                           atol=2e-5)
                f = affine(row, k, inverse.AT_F)
                np.testing.assert_allclose(f @ vm_k @ corners, vm_t @ corners, atol=2e-5)
                np.testing.assert_allclose(affine(row, k, inverse.AT_B) @ f, np.eye(4),
                                           atol=2e-5)
                clip = cam.projection() @ vm_k @ corners
                win = (clip[:2] / clip[3] * 0.5 + 0.5) * np.array(frame.size)[:, None]
                x0, y0, x1, y1 = row[k * inverse.COLS + inverse.AT_BOX]
                assert (win[0] >= x0).all() and (win[0] <= x1).all()
                assert (win[1] >= y0).all() and (win[1] <= y1).all()
            tail = (k_n) * inverse.COLS
            assert row[tail + inverse.AT_KIND, 0] == inverse.KIND_RIGID
        still = next(o for o in scene.objects if not o.moving)
        assert table[still.id][k_n * inverse.COLS + inverse.AT_KIND, 0] == inverse.KIND_STILL
        np.testing.assert_allclose(affine(table[still.id], 0, inverse.AT_F), np.eye(4),
                                   atol=1e-6)            # (a still camera: nothing moves)
    finally:
        r.release()


def test_candidates_are_the_movers_that_reach_a_tile_nearest_first(ctx):
    scene = load_scene("fan")
    r, frame = run_table(ctx, scene, curve("inverse"))
    try:
        tex = frame.pool.get(inverse.CANDIDATES)
        cand = np.frombuffer(tex.read(), np.uint32).reshape(tex.size[1], tex.size[0], 4)
        movers = {o.id: o for o in scene.objects if o.moving}
        listed = cand[cand != 0]
        assert set(listed.tolist()) <= set(movers) and len(set(listed.tolist())) == len(movers)
        tiles = frame.host[inverse.INVERSE_TILES]
        assert np.array_equal(tiles, (cand != 0).any(axis=2))
        # nearest first: ordered as the movers' nearest depths over the exposure
        k_n = int(frame.params["hybrid"].curve_samples)
        times = inverse.table_times(*frame.exposure, k_n)
        near = {}
        for i, o in movers.items():
            poses = PoseTable(times).world(o)
            near[i] = inverse.MotionTable._reach(frame, o, times,
                                                 np.stack([frame.camera.view(s) for s in times]),
                                                 poses)[1]
        for ids in cand.reshape(-1, 4):
            ids = [int(i) for i in ids if i]
            assert [near[i] for i in ids] == sorted(near[i] for i in ids)
    finally:
        r.release()


def test_a_camera_whose_motion_bends_maps_every_still_object_and_every_tile(ctx, tmp_path):
    """A camera rolling about its view axis: nothing in the scene moves, yet every still
    point's screen path is an arc. The still rows (and the background's) map by the
    camera alone, F_k = V(t) V(t_k)^-1, and every tile takes the inverse composite."""
    scene = scene_from(tmp_path, """
        [camera]
        position = [0.0, 0.0, 4.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 40.0
        shutter = 0.1
        angular_velocity = [0.0, 0.0, 6.0]
        [[lights]]
        direction = [0.0, 0.0, -1.0]
        [[objects]]
        name = "bar"
        mesh = { box = [2.0, 0.3, 0.1] }""")
    r, frame = run_table(ctx, scene, curve("inverse"))
    try:
        table = table_of(frame)
        k_n = int(frame.params["hybrid"].curve_samples)
        times = inverse.table_times(*frame.exposure, k_n)
        cam, t = frame.camera, frame.time
        tiles = frame.host[inverse.INVERSE_TILES]
        assert tiles.all() and frame.stats["inverse_tiles"] == tiles.size
        for row in (table[0], table[scene.objects[0].id]):
            assert row[k_n * inverse.COLS + inverse.AT_KIND, 0] == inverse.KIND_STILL
            for k in (0, k_n // 2, k_n - 1):
                want = cam.view(t) @ np.linalg.inv(cam.view(times[k]))
                np.testing.assert_allclose(affine(row, k, inverse.AT_F), want, atol=2e-6)
        assert not np.allclose(affine(table[0], 0, inverse.AT_F), np.eye(4), atol=1e-3)
    finally:
        r.release()


def test_a_scene_with_more_rows_than_the_driver_allows_is_a_user_error():
    from types import SimpleNamespace

    from world.errors import UserError
    scene = load_scene("fan")
    frame = SimpleNamespace(params=curve("inverse"), scene=scene,
                            ctx=SimpleNamespace(info={"GL_MAX_TEXTURE_SIZE": 4}))
    with pytest.raises(UserError, match="hybrid.curve = steps"):
        inverse.MotionTable().outputs(frame)
    frame.ctx.info["GL_MAX_TEXTURE_SIZE"] = len(scene.objects) + 1
    assert inverse.MotionTable().outputs(frame)[inverse.MOTION_TABLE].height == len(
        scene.objects) + 1


def test_straight_motion_gives_the_linear_composites_image_to_the_byte(ctx):
    for name in ("living_room", "pan"):
        scene = load_scene(name)
        r = Renderer(ctx, scene, (160, 90))
        try:
            steps = r.render("hybrid", scene.render.time, curve("steps"))
            inv = r.render("hybrid", scene.render.time, curve("inverse"))
            assert inv.stats["inverse_tiles"] == 0
            assert np.array_equal(steps.image, inv.image), name
        finally:
            r.release()


def facing(light: str, backdrop: str, objects: str) -> str:
    """A scene seen down -z from 4 m (fov 40 degrees, shutter 0.1 s), a backdrop 1 m behind
    the origin, one light along the view, then `objects`."""
    return f"""
        [camera]
        position = [0.0, 0.0, 4.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 40.0
        shutter = 0.1
        [[lights]]
        direction = [0.0, 0.0, -1.0]
        color = {light}
        [[objects]]
        name = "backdrop"
        mesh = {{ box = [8.0, 8.0, 0.1] }}
        position = [0.0, 0.0, -1.0]
        material = {backdrop}
        {objects}"""


def test_a_turning_blade_blurs_along_its_arc(ctx, tmp_path):
    """A white blade turning 60 degrees about the view axis within the shutter, lit by
    ambient light alone, over black: at any radius the reference's streak is an arc whose
    brightness is the blade's angular width over the turn. The inverse composite follows
    it (close to the reference everywhere) where the linear composite draws a chord."""
    scene = scene_from(tmp_path, "ambient = [1.0, 1.0, 1.0]\n" + facing(
        "[0.0, 0.0, 0.0]", "{ albedo = [0.0, 0.0, 0.0] }", """
        [[objects]]
        name = "hub"
        mesh = { box = [0.01, 0.01, 0.01] }
        material = { albedo = [0.0, 0.0, 0.0] }
        angular_velocity = [0.0, 0.0, 10.471976]
        [[objects]]
        name = "blade"
        mesh = { box = [1.6, 0.12, 0.02] }
        position = [0.8, 0.0, 0.0]
        parent = "hub"
        material = { albedo = [1.0, 1.0, 1.0] }"""))
    size = (240, 160)
    r = Renderer(ctx, scene, size)
    try:
        p = ParamSet()
        p.set("reference.samples", 128)
        ref = r.render("reference", 0.0, p, record_visibility=True)
        inv = r.render("hybrid", 0.0, curve("inverse", hybrid__time_samples=16))
        lin = r.render("hybrid", 0.0, curve("steps", hybrid__curve_steps=1))
    finally:
        r.release()
    err = {n: float(np.abs(x.image - ref.image).mean()) for n, x in
           (("inverse", inv), ("linear", lin))}
    assert inv.stats["inverse_tiles"] > 0
    assert err["inverse"] < 0.6 * err["linear"], err
    # Along the arc at radius 1.0 (px: F r / 4), sampled over the middle of the turn, the
    # brightness is the blade's width over the arc length it sweeps.
    f = (size[1] / 2) / math.tan(math.radians(20.0))
    rad = f * 1.0 / 4.0
    angles = np.radians(np.linspace(-20.0, 20.0, 9))
    xs = (size[0] / 2 + rad * np.cos(angles)).astype(int)
    ys = (size[1] / 2 - rad * np.sin(angles)).astype(int)
    want = 0.12 / (1.0 * math.radians(60.0))
    got = inv.image[ys, xs, 0]
    assert np.abs(ref.image[ys, xs, 0] - want).max() < 0.06
    assert np.abs(got - want).max() < 0.1 and abs(got.mean() - want) < 0.03, (got, want)


def test_a_body_that_comes_back_is_traced_where_it_leaves_a_pixel(ctx, tmp_path):
    """A box that rises and falls back within the shutter: its chord over the exposure is
    zero, so the displacement test masks nothing; the inverse mask's checks find the
    pixels it leaves mid-exposure and the reveal traces them."""
    scene = scene_from(tmp_path, facing(
        "[1.0, 1.0, 1.0]", '{ albedo = [0.8, 0.8, 0.8], texture = { kind = "checker", '
        'size = 0.3, albedo2 = [0.1, 0.1, 0.1] } }', """
        [[objects]]
        name = "hop"
        mesh = { box = [0.5, 0.5, 0.1] }
        material = { albedo = [0.9, 0.2, 0.1] }
        [[objects.keys]]
        time = -0.05
        position = [0.0, -0.4, 0.0]
        [[objects.keys]]
        time = 0.0
        position = [0.0, 0.0, 0.0]
        [[objects.keys]]
        time = 0.05
        position = [0.0, -0.4, 0.0]"""))
    r = Renderer(ctx, scene, (160, 120))
    try:
        lin = r.render("hybrid", 0.0, curve("steps", hybrid__curve_steps=1))
        inv = r.render("hybrid", 0.0, curve("inverse"))
    finally:
        r.release()
    assert lin.stats["masked_pixels"] == 0
    assert inv.stats["masked_pixels"] > 200 and inv.stats["inverse_tiles"] > 0


def test_the_fan_is_closer_to_the_reference_than_two_sub_frames(ctx):
    scene = load_scene("fan")
    r = Renderer(ctx, scene, (320, 180))
    try:
        p = ParamSet()
        p.set("reference.samples", 32)
        ref = r.render("reference", 0.0, p, record_visibility=True)
        flip = {}
        for kind in ("inverse", "steps"):
            res = r.render("hybrid", 0.0, curve(kind))
            flip[kind] = image_metrics(res.image, ref.image, ref.host[REGIONS])["all"]["flip"]
    finally:
        r.release()
    assert flip["inverse"] < 0.8 * flip["steps"], flip
