"""The built-in scenes: they load by name and each shows the motion it exists for.

Blur lengths are measured as the screen displacement over the exposure with
world.camera.Camera.project at the shutter open and close times, at 1280x720.
"""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from world.camera import Camera
from world.errors import SceneError
from world.loader import builtin_scene_names, builtin_scene_path, load_scene

NAMES = ["fan", "living_room", "pan", "rover", "spinner", "thin", "turning_car", "wheel"]


def world(obj, t, local_points):
    p = np.c_[np.asarray(local_points, dtype=np.float64), np.ones(len(local_points))]
    return (p @ obj.matrix(t).T)[:, :3]


def screen(scene, obj, t, local_points):
    cam = Camera(scene.camera, 1280, 720)
    return cam.project(t, world(obj, t, local_points))


def by_name(scene, name):
    (obj,) = [o for o in scene.objects if o.name == name]
    return obj


def displacement(scene, obj, local_points, t=None):
    t = scene.render.time if t is None else t
    t0, t1 = scene.exposure(t)
    a, _ = screen(scene, obj, t0, local_points)
    b, _ = screen(scene, obj, t1, local_points)
    return np.linalg.norm(b - a, axis=1)


def centre(obj):
    v = obj.mesh.vertices
    return (0.5 * (v.min(0) + v.max(0)))[None, :]


@pytest.fixture(scope="module")
def scenes():
    return {n: load_scene(n) for n in NAMES}


def test_names_and_paths():
    assert builtin_scene_names() == NAMES
    for n in NAMES:
        p = builtin_scene_path(n)
        assert p.is_file() and p.name == f"{n}.toml" and p.parent.name == "scenes"


def test_unknown_name_lists_the_available_scenes():
    with pytest.raises(SceneError) as info:
        load_scene("kitchen")
    msg = str(info.value)
    assert "kitchen" in msg
    for n in NAMES:
        assert n in msg


def test_every_scene_is_modest_and_has_detailed_backgrounds(scenes):
    for name, s in scenes.items():
        assert s.name == name
        assert (s.render.width, s.render.height) == (1280, 720)
        assert s.camera.shutter > 0
        assert sum(len(o.mesh.faces) for o in s.objects) < 4000, name
        textured = [o for o in s.objects if o.material.texture is not None]
        assert len(textured) >= 2, name
        assert any(o.moving for o in s.objects) or s.camera.moving


def test_no_textured_face_lies_on_a_cell_boundary(scenes):
    # A face whose constant coordinate is a multiple of the cell size would pick a colour
    # by rounding noise, differently in a rasteriser and a ray tracer.
    for name, s in scenes.items():
        for o in s.objects:
            tx = o.material.texture
            if tx is None or tx.kind == "image":
                continue
            tri = o.mesh.vertices[o.mesh.faces]
            for a in ([0, 1, 2] if tx.kind == "checker" else [tx.axis]):
                flat = np.ptp(tri[:, :, a], axis=1) < 1e-12
                q = tri[flat][:, 0, a] / tx.size
                assert np.all(np.abs(q - np.round(q)) > 1e-3), (name, o.name, a)


def test_living_room_vase_blur_and_what_it_covers(scenes):
    s = scenes["living_room"]
    vase = by_name(s, "vase")
    moving = [o.name for o in s.objects if o.moving]
    assert moving == ["vase"] and not s.camera.moving
    d = displacement(s, vase, centre(vase))[0]
    assert 60 <= d <= 150, d

    # The vase's path on screen crosses the gap between two seat cushions, in front of them.
    t0, t1 = s.exposure(s.render.time)
    (a, za), (b, zb) = screen(s, vase, t0, centre(vase)), screen(s, vase, t1, centre(vase))
    left = by_name(s, "seat cushion left")
    half_l = left.mesh.vertices.max(0)
    top_front_right_of_left = [[half_l[0], half_l[1], half_l[2]]]
    gap, zgap = screen(s, left, 0.0, top_front_right_of_left)
    lo, hi = sorted([a[0, 0], b[0, 0]])
    assert lo < gap[0, 0] < hi
    vz = vase.mesh.vertices[:, 2]                          # revolve axis: local z
    ends = np.c_[np.zeros((2, 2)), [vz.min(), vz.max()]]
    ys, _ = screen(s, vase, 0.0, ends)
    assert ys[:, 1].min() < gap[0, 1] < ys[:, 1].max()
    assert max(za[0], zb[0]) < zgap[0] - 1.0               # at least a metre in front


def test_living_room_picture_is_an_image_on_a_uv_quad(scenes):
    pic = by_name(scenes["living_room"], "picture")
    tx = pic.material.texture
    assert tx.kind == "image" and tx.image.shape[2] == 3 and tx.image.dtype == np.float32
    assert pic.mesh.uv is not None and pic.mesh.uv.shape == (len(pic.mesh.vertices), 2)
    assert tx.path.parent.name == "assets"


def test_assets_match_their_generator():
    from scenes import make_assets
    png = np.asarray(Image.open(make_assets.ASSETS / "painting.png").convert("RGB"))
    np.testing.assert_array_equal(png, make_assets.painting())
    assert (make_assets.ASSETS / "quad_uv.obj").read_text() == make_assets.QUAD_OBJ


def test_thin_rod_moves_much_farther_than_its_width(scenes):
    s = scenes["thin"]
    rod = by_name(s, "rod")
    cam = Camera(s.camera, 1280, 720)
    _, fwd, up = s.camera.pose(0.0)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    c = world(rod, 0.0, centre(rod))[0]
    r = rod.mesh.vertices[:, 0].max()                      # cylinder radius (axis: local z)
    edges, _ = cam.project(0.0, np.array([c - r * right, c + r * right]))
    width = abs(edges[1, 0] - edges[0, 0])
    d = displacement(s, rod, centre(rod))[0]
    assert width > 3.0                                     # a few pixels, not sub-pixel
    assert d > 4 * width, (d, width)


def test_pan_moves_the_camera_and_nothing_else(scenes):
    s = scenes["pan"]
    assert s.camera.moving
    assert not any(o.moving for o in s.objects)
    cam = Camera(s.camera, 1280, 720)
    t0, t1 = s.exposure(0.0)
    wall = by_name(s, "back wall")
    p = world(wall, 0.0, [[0.0, 0.0, 0.05], [1.0, 0.5, 0.05]])
    d = np.linalg.norm(cam.project(t1, p)[0] - cam.project(t0, p)[0], axis=1)
    assert np.all(d > 20), d


def test_spinner_blade_tips_move_fast_on_arcs(scenes):
    s = scenes["spinner"]
    blades = [o for o in s.objects if o.name.startswith("blades")]
    assert len(blades) == 3
    for b in blades:
        tip = [[b.mesh.vertices[:, 0].max(), 0.0, 0.0]]
        assert displacement(s, b, tip)[0] > 40
        # curved: the mid-exposure position is off the chord between open and close
        t0, t1 = s.exposure(0.0)
        a, m, c = (screen(s, b, t, tip)[0][0] for t in (t0, 0.0, t1))
        chord = c - a
        off = abs(chord[0] * (m - a)[1] - chord[1] * (m - a)[0]) / np.linalg.norm(chord)
        assert off > 2.0, off


def test_wheel_rolls_faster_and_the_ball_turns_back_inside_the_exposure(scenes):
    s = scenes["wheel"]
    tyre, rim, ball = (by_name(s, n) for n in ("tyre", "rim", "ball"))
    assert not s.camera.moving and [o.name for o in s.objects if o.moving] == [
        "tyre", "rim", "ball"]
    assert np.array_equal(tyre.keys.token, rim.keys.token)       # one wheel
    turns = np.abs(np.diff(tyre.keys.rotations[:, 2]))
    assert turns.max() < 180.0 and turns.max() > 90.0             # slerp goes the right way
    t0, t1 = s.exposure(0.0)
    r = tyre.mesh.vertices[:, 0].max()
    # rolling: at the frame time, the wheel's top moves twice as fast as the hub and its
    # contact point is still (velocities by central differences)
    rot = tyre.matrix(0.0)[:3, :3]
    top, hub, ground = ([rot.T @ [0.0, y, 0.0]] for y in (r, 0.0, -r))
    speed = {n: np.linalg.norm(world(tyre, 1e-5, p) - world(tyre, -1e-5, p)) / 2e-5
             for n, p in (("top", top), ("hub", hub), ("ground", ground))}
    assert abs(speed["hub"] - 3.0) < 0.01
    assert abs(speed["top"] / speed["hub"] - 2.0) < 0.02 and speed["ground"] < 0.02 * speed["hub"]
    assert displacement(s, tyre, top)[0] > 60                    # px at 1280x720
    assert displacement(s, tyre, hub, t=0.5)[0] > 1.4 * displacement(s, tyre, hub)[0]
    # the ball: down to the floor and back up within the shutter, its chord short
    c = centre(ball)
    path = np.array([screen(s, ball, t, c)[0][0] for t in np.linspace(t0, t1, 33)])
    length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
    assert length > 30 and np.linalg.norm(path[-1] - path[0]) < 0.6 * length


def test_bench_scenes_hold_many_visible_movers():
    """scenes/bench (scripts/bench_all.sh, not built-ins): 32 movers, each blurred on
    screen; crowd_pan's camera moves, crowd's does not, and the movers are the same."""
    from pathlib import Path
    bench = Path(builtin_scene_path("pan")).parent / "bench"
    crowd, crowd_pan = (load_scene(str(bench / f"{n}.toml")) for n in ("crowd", "crowd_pan"))
    assert "bench" not in builtin_scene_names()
    assert not crowd.camera.moving and crowd_pan.camera.moving
    for scene in (crowd, crowd_pan):
        movers = [o for o in scene.objects if o.moving]
        assert len(movers) == 32
    still = [o for o in crowd.objects if o.moving]
    blur = np.array([displacement(crowd, o, centre(o))[0] for o in still])
    assert (blur > 2.0).all(), blur          # px at 1280x720: every mover blurs
    cam = Camera(crowd.camera, 1280, 720)
    xy, _ = cam.project(0.0, np.array([o.matrix(0.0)[:3, 3] for o in still]))
    on_screen = ((xy >= 0) & (xy < [1280, 720])).all(axis=1)
    assert on_screen.sum() >= 24, on_screen.sum()
    assert [o.name for o in crowd.objects] == [o.name for o in crowd_pan.objects]


def test_turning_car_turns_29_degrees_within_the_shutter_over_a_textured_road(scenes):
    s = scenes["turning_car"]
    chassis = by_name(s, "chassis")
    t0, t1 = s.exposure(s.render.time)
    r0, r1 = (chassis.matrix(t)[:3, :3] for t in (t0, t1))
    turn = np.degrees(np.arccos(np.clip((np.trace(r0.T @ r1) - 1.0) / 2.0, -1.0, 1.0)))
    assert turn == pytest.approx(29.0, abs=0.5)
    # Its parts ride on it, and it moves far over the textured ground seen from above.
    parts = [o for o in s.objects if o.parent is chassis]
    assert len(parts) == 5 and all(o.moving and not o.own_moving for o in parts)
    assert by_name(s, "ground").material.texture is not None
    assert displacement(s, chassis, centre(chassis)).max() > 200     # px at 1280x720


def test_fan_blades_turn_60_degrees_within_the_shutter_along_curved_screen_paths(scenes):
    s = scenes["fan"]
    rotor = by_name(s, "rotor")
    t0, t1 = s.exposure(s.render.time)
    r0, r1 = (rotor.matrix(t)[:3, :3] for t in (t0, t1))
    turn = np.degrees(np.arccos(np.clip((np.trace(r0.T @ r1) - 1.0) / 2.0, -1.0, 1.0)))
    assert turn == pytest.approx(60.0, abs=0.5)
    blades = [o for o in s.objects if o.parent is rotor]
    assert len(blades) == 4 and all(o.moving and not o.own_moving for o in blades)
    # The axle is tilted from the view: a blade tip's screen path is an arc whose middle
    # lies far off its chord (the sagitta), not a straight streak.
    tip = np.array([[0.17, 0.0, 0.0]])
    times = np.linspace(t0, t1, 9)
    path = np.array([screen(s, by_name(s, "blade red"), t, tip)[0][0] for t in times])
    chord = path[0] + np.linspace(0, 1, 9)[:, None] * (path[-1] - path[0])
    assert np.linalg.norm(path - chord, axis=1).max() > 20.0       # px at 1280x720
    assert np.linalg.norm(path[-1] - path[0]) > 100.0
