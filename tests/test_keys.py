"""Keyframed motion (scene format v1.1): object and camera keys evaluated by the scene model
against numpy computations written here from the format's formulas (Euler matrices,
quaternions from matrices, slerp, Catmull-Rom), and every mistake in keys as a one-line
error naming the file and the key, exit status 2."""
from __future__ import annotations

import math

import numpy as np
import pytest

from world import transforms as tf
from world.camera import Camera
from viewer.commands.main import main
from world.loader import check_camera, load_scene, merge_camera

CAMERA = """[camera]
position = [0.0, 1.0, 5.0]
look_at = [0.0, 1.0, 0.0]
fov_y = 45.0
shutter = 0.04
"""


def scene_file(tmp_path, objects: str, camera: str = CAMERA, name="k.toml"):
    p = tmp_path / name
    p.write_text('name = "k"\n[render]\nwidth = 32\nheight = 18\n' + camera + objects)
    return p


def object_with_keys(keys, interpolation=None, extra=""):
    text = '[[objects]]\nname = "thing"\nmesh = { box = [0.2, 0.3, 0.4] }\n' + extra
    if interpolation:
        text += f'interpolation = "{interpolation}"\n'
    for k in keys:
        text += "[[objects.keys]]\n" + "".join(f"{a} = {v!r}\n".replace("'", '"')
                                                 for a, v in k.items())
    return text


# ---------------------------------------------------------------- the formulas, in numpy

def euler(deg):
    """R0 = Rz @ Ry @ Rx from degrees, written out."""
    x, y, z = np.radians(deg)
    rx = np.array([[1, 0, 0], [0, math.cos(x), -math.sin(x)], [0, math.sin(x), math.cos(x)]])
    ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
    rz = np.array([[math.cos(z), -math.sin(z), 0], [math.sin(z), math.cos(z), 0], [0, 0, 1]])
    return rz @ ry @ rx


def quat_of(r):
    """(w, x, y, z) of a rotation matrix (the largest of the four squared terms first)."""
    tr = np.trace(r)
    cands = [1 + tr, 1 + r[0, 0] - r[1, 1] - r[2, 2], 1 - r[0, 0] + r[1, 1] - r[2, 2],
             1 - r[0, 0] - r[1, 1] + r[2, 2]]
    k = int(np.argmax(cands))
    s = 2.0 * math.sqrt(cands[k])
    if k == 0:
        q = [s / 4, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif k == 1:
        q = [(r[2, 1] - r[1, 2]) / s, s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif k == 2:
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s]
    else:
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4]
    return np.array(q)


def matrix_of(q):
    """The rotation q v q* of a unit quaternion, from the product v' = v + 2w(u x v) +
    2 u x (u x v), applied to the basis vectors."""
    w, u = q[0], q[1:]
    cols = [e + 2 * w * np.cross(u, e) + 2 * np.cross(u, np.cross(u, e)) for e in np.eye(3)]
    return np.stack(cols, axis=1)


def slerp(q0, q1, u):
    if q0 @ q1 < 0:
        q1 = -q1
    th = math.acos(min(1.0, q0 @ q1))
    if th < 1e-6:
        q = q0 + u * (q1 - q0)
        return q / np.linalg.norm(q)
    return (math.sin((1 - u) * th) * q0 + math.sin(u * th) * q1) / math.sin(th)


def segment(times, t):
    t = min(max(t, times[0]), times[-1])
    for i in range(len(times) - 1):
        if times[i] <= t <= times[i + 1]:
            return i, (t - times[i]) / (times[i + 1] - times[i])


def catmull_rom(p, i, u):
    n = len(p)
    a, b, c, d = (np.asarray(p[min(max(j, 0), n - 1)], float) for j in (i - 1, i, i + 1, i + 2))
    return 0.5 * (2 * b + (c - a) * u + (2 * a - 5 * b + 4 * c - d) * u ** 2
                  + (3 * b - a - 3 * c + d) * u ** 3)


def expected_matrix(keys, t, smooth=False):
    times = [k["time"] for k in keys]
    pos = [np.asarray(k.get("position", [0, 0, 0]), float) for k in keys]
    rot = [k.get("rotation", [0, 0, 0]) for k in keys]
    sc = [np.broadcast_to(np.asarray(k.get("scale", 1.0), float), 3) for k in keys]
    if len(keys) == 1:
        p, r, s = pos[0], euler(rot[0]), sc[0]
    else:
        i, u = segment(times, t)
        if smooth:
            p, s = catmull_rom(pos, i, u), catmull_rom(sc, i, u)
        else:
            p, s = pos[i] + u * (pos[i + 1] - pos[i]), sc[i] + u * (sc[i + 1] - sc[i])
        r = matrix_of(slerp(quat_of(euler(rot[i])), quat_of(euler(rot[i + 1])), u))
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(s)
    m[:3, 3] = p
    return m


ARC = [{"time": -0.1, "position": [-1.0, 1.0, 0.0], "rotation": [-60.0, 0.0, 40.0]},
       {"time": -0.02, "position": [-0.3, 0.6, 0.2], "rotation": [-90.0, 10.0, 10.0],
        "scale": [1.0, 2.0, 1.0]},
       {"time": 0.05, "position": [0.4, 0.7, 0.1], "rotation": [-110.0, 20.0, -25.0]},
       {"time": 0.1, "position": [0.9, 1.3, -0.2], "rotation": [-130.0, 30.0, -60.0],
        "scale": 0.5}]
TIMES = [-0.3, -0.1, -0.07, -0.02, 0.0, 0.013, 0.05, 0.08, 0.1, 0.4]


@pytest.mark.parametrize("interpolation", ["linear", "smooth"])
def test_object_keys_against_the_formulas(tmp_path, interpolation):
    sc = load_scene(scene_file(tmp_path, object_with_keys(ARC, interpolation)))
    obj = sc.objects[0]
    assert obj.moving
    for t in TIMES:
        want = expected_matrix(ARC, t, interpolation == "smooth")
        np.testing.assert_allclose(obj.matrix(t), want, rtol=0, atol=1e-12, err_msg=f"t={t}")
    # clamped: before the first key and after the last, the end poses
    np.testing.assert_array_equal(obj.matrix(-5.0), obj.matrix(-0.1))
    np.testing.assert_array_equal(obj.matrix(7.0), obj.matrix(0.1))


def test_smooth_differs_from_linear_between_keys_and_agrees_at_them(tmp_path):
    lin, smo = (load_scene(scene_file(tmp_path, object_with_keys(ARC, i), name=f"{i}.toml"))
                .objects[0] for i in ("linear", "smooth"))
    for k in ARC:
        np.testing.assert_allclose(lin.matrix(k["time"]), smo.matrix(k["time"]), atol=1e-12)
    assert np.abs(lin.matrix(0.013)[:3, 3] - smo.matrix(0.013)[:3, 3]).max() > 1e-3


def test_slerp_takes_the_short_way_when_the_dot_product_is_negative(tmp_path):
    # 170 and -170 degrees about z: their quaternions' dot product is cos(170 deg) < 0;
    # the short way passes 180 degrees (the long way would pass 0).
    keys = [{"time": 0.0, "rotation": [0.0, 0.0, 170.0]},
            {"time": 1.0, "position": [1.0, 0.0, 0.0], "rotation": [0.0, 0.0, -170.0]}]
    obj = load_scene(scene_file(tmp_path, object_with_keys(keys))).objects[0]
    np.testing.assert_allclose(obj.matrix(0.5)[:3, :3], euler([0, 0, 180.0]), atol=1e-12)
    for t in (0.1, 0.25, 0.9):
        np.testing.assert_allclose(obj.matrix(t), expected_matrix(keys, t), atol=1e-12)
    # The quaternions of the two keys by half angles, (cos(a/2), sin(a/2) z): dot < 0, so
    # the second is negated; and with the sign flipped (dot > 0) the same rotations.
    h = math.radians(85.0)
    q0, q1 = np.array([math.cos(h), 0, 0, math.sin(h)]), np.array([math.cos(h), 0, 0, -math.sin(h)])
    assert q0 @ q1 < 0
    for u in (0.0, 0.3, 0.5, 1.0):
        a = math.radians(170.0 + 20.0 * u) / 2          # the short way: 170 -> 190 degrees
        want = np.array([math.cos(a), 0, 0, math.sin(a)])
        np.testing.assert_allclose(tf.slerp(q0, q1, u), want, atol=1e-15)
        np.testing.assert_allclose(tf.slerp(q0, -q1, u), want, atol=1e-15)


@pytest.mark.parametrize("degrees", [0.0, 2e-5])
def test_slerp_of_a_tiny_angle_is_the_normalised_lerp(tmp_path, degrees):
    # theta (half the turn) below 1e-6: the normalised q0 + u (q1 - q0); at theta = 0 the
    # slerp formula would divide 0 by 0.
    keys = [{"time": 0.0, "rotation": [10.0, 20.0, 30.0]},
            {"time": 1.0, "position": [0.5, 0.0, 0.0], "rotation": [10.0, 20.0, 30.0 + degrees]}]
    obj = load_scene(scene_file(tmp_path, object_with_keys(keys))).objects[0]
    q0, q1 = quat_of(euler(keys[0]["rotation"])), quat_of(euler(keys[1]["rotation"]))
    assert math.acos(min(1.0, q0 @ q1)) < 1e-6
    for u in (0.25, 0.5, 0.8):
        q = q0 + u * (q1 - q0)
        np.testing.assert_allclose(tf.slerp(q0, q1, u), q / np.linalg.norm(q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(obj.matrix(u), expected_matrix(keys, u), atol=1e-12)


def test_one_key_is_a_still_pose_and_equal_keys_do_not_move(tmp_path):
    one = [{"time": 0.3, "position": [1.0, 2.0, 3.0], "rotation": [0.0, 45.0, 0.0],
            "scale": [1.0, 2.0, 3.0]}]
    obj = load_scene(scene_file(tmp_path, object_with_keys(one, "smooth"))).objects[0]
    assert not obj.moving
    for t in (-1.0, 0.3, 2.0):
        np.testing.assert_allclose(obj.matrix(t), expected_matrix(one, t), atol=1e-12)
    same = [dict(one[0]), dict(one[0], time=0.5)]
    obj = load_scene(scene_file(tmp_path, object_with_keys(same), name="s.toml")).objects[0]
    assert not obj.moving


def test_key_defaults(tmp_path):
    keys = [{"time": 0.0}, {"time": 1.0, "position": [2.0, 0.0, 0.0], "scale": 3.0}]
    obj = load_scene(scene_file(tmp_path, object_with_keys(keys))).objects[0]
    np.testing.assert_allclose(obj.matrix(0.0), np.eye(4), atol=0)
    np.testing.assert_allclose(obj.matrix(0.5), np.diag([2.0, 2.0, 2.0, 1.0])
                               + np.pad([[1.0], [0.0], [0.0]], ((0, 1), (3, 0))), atol=1e-15)


def test_replaced_keys_are_not_served_from_the_memo(tmp_path):
    obj = load_scene(scene_file(tmp_path, object_with_keys(ARC))).objects[0]
    before = obj.matrix(0.0)
    fast = obj.keys.retimed(0.0, 2.0)
    obj.keys = fast
    for t in (-0.04, 0.0, 0.01, 0.03):
        np.testing.assert_allclose(obj.matrix(t), expected_matrix(ARC, 2.0 * t), atol=1e-12)
    np.testing.assert_allclose(obj.matrix(0.0), before, atol=1e-12)
    obj.keys = obj.keys.retimed(0.01, 0.0)        # held at the pose of 0.01 (old 0.02)
    assert not obj.moving
    np.testing.assert_allclose(obj.matrix(-3.0), expected_matrix(ARC, 0.02), atol=1e-9)


CAM_KEYS = [{"time": -0.2, "position": [-0.3, 1.1, 3.6], "look_at": [-0.2, 0.7, 0.0]},
            {"time": 0.0, "position": [0.0, 1.1, 3.6], "look_at": [0.0, 0.7, 0.0],
             "up": [0.1, 1.0, 0.0]},
            {"time": 0.2, "position": [0.35, 1.15, 3.55], "look_at": [0.25, 0.72, 0.0]},
            {"time": 0.3, "position": [0.5, 1.4, 3.0], "look_at": [0.5, 0.7, 0.1]}]


def camera_text(keys, interpolation, up="[0.0, 1.0, 0.2]"):
    text = f'[camera]\nfov_y = 40.0\nup = {up}\ninterpolation = "{interpolation}"\n'
    for k in keys:
        text += "[[camera.keys]]\n" + "".join(f"{a} = {v!r}\n" for a, v in k.items())
    return text


@pytest.mark.parametrize("interpolation", ["linear", "smooth"])
def test_camera_keys_against_the_formulas(tmp_path, interpolation):
    sc = load_scene(scene_file(tmp_path, "", camera_text(CAM_KEYS, interpolation)))
    cam = Camera(sc.camera, 32, 18)
    assert sc.camera.moving
    times = [k["time"] for k in CAM_KEYS]
    P = [np.array(k["position"]) for k in CAM_KEYS]
    L = [np.array(k["look_at"]) for k in CAM_KEYS]
    U = [np.array(k.get("up", [0.0, 1.0, 0.2])) for k in CAM_KEYS]   # the [camera] up
    for t in (-1.0, -0.2, -0.13, 0.0, 0.07, 0.2, 0.26, 0.3, 1.0):
        i, u = segment(times, t)
        f = ((lambda v: catmull_rom(v, i, u)) if interpolation == "smooth"
             else (lambda v: v[i] + u * (v[i + 1] - v[i])))
        eye, look, up = f(P), f(L), f(U)
        fwd = (look - eye) / np.linalg.norm(look - eye)
        right = np.cross(fwd, up)
        right /= np.linalg.norm(right)
        true_up = np.cross(right, fwd)
        view = np.eye(4)
        view[:3, :3] = np.stack([right, true_up, -fwd])
        view[:3, 3] = -view[:3, :3] @ eye
        np.testing.assert_allclose(cam.view(t), view, atol=1e-12, err_msg=f"t={t}")
        np.testing.assert_allclose(cam.eye(t), eye, atol=1e-14)


def test_camera_one_key_and_the_sidecar_round_trip(tmp_path):
    sc = load_scene(scene_file(tmp_path, "", camera_text(CAM_KEYS[1:2], "smooth")))
    assert not sc.camera.moving
    again = check_camera(sc.camera.to_dict(), "side.json")
    for t in (-1.0, 0.0, 1.0):
        assert all(np.array_equal(a, b) for a, b in zip(again.pose(t), sc.camera.pose(0.0)))
    keyed = load_scene(scene_file(tmp_path, "", camera_text(CAM_KEYS, "smooth"), "c.toml")).camera
    back = check_camera(keyed.to_dict(), "side.json")
    assert all(np.array_equal(a, b) for a, b in zip(back.pose(0.11), keyed.pose(0.11)))
    # a sidecar's still camera (the viewer moved it) over a keyed scene camera, and back
    still = merge_camera(keyed, {"position": [0.0, 2.0, 5.0], "look_at": [0.0, 0.0, 0.0]}, "s")
    assert still.keys is None and not still.moving and still.fov_y == 40.0
    again = merge_camera(still, keyed.to_dict(), "s")
    assert all(np.array_equal(a, b) for a, b in zip(again.pose(0.11), keyed.pose(0.11)))


def test_detached_camera_keeps_the_pose_it_showed(tmp_path):
    spec = load_scene(scene_file(tmp_path, "", camera_text(CAM_KEYS, "smooth"))).camera
    shown = [np.array(a) for a in spec.pose(0.07)]
    view = Camera(spec, 32, 18).view(0.07).copy()
    spec.detach(0.07)
    assert spec.keys is None and not spec.moving
    np.testing.assert_allclose(spec.pose(0.07)[0], shown[0], atol=1e-15)
    np.testing.assert_allclose(spec.pose(5.0)[1], shown[1], atol=1e-12)
    np.testing.assert_allclose(Camera(spec, 32, 18).view(1.0), view, atol=1e-12)


# ---------------------------------------------------------------- errors

K2 = [{"time": 0.0}, {"time": 0.1, "position": [1.0, 0.0, 0.0]}]
OBJ = "objects[1] (thing)"
ERRORS = {
    **{f"object keys with {f}": (object_with_keys(K2, extra=f"{f} = {v}\n"), CAMERA, f"{OBJ}.{f}")
       for f, v in (("position", "[0.0, 0.0, 0.0]"), ("rotation", "[0.0, 0.0, 0.0]"),
                    ("scale", "2.0"), ("velocity", "[1.0, 0.0, 0.0]"),
                    ("angular_velocity", "[0.0, 1.0, 0.0]"))},
    **{f"camera keys with {f}": ("", camera_text(CAM_KEYS[:2], "linear") .replace(
        "[[camera.keys]]", f"{f} = [0.0, 0.5, 0.0]\n[[camera.keys]]", 1), f"camera.{f}")
       for f in ("position", "look_at", "velocity", "angular_velocity")},
    "object interpolation without keys": (
        '[[objects]]\nmesh = { box = [1.0, 1.0, 1.0] }\ninterpolation = "smooth"\n', CAMERA,
        "objects[1] (object1).interpolation"),
    "camera interpolation without keys": ("", CAMERA + 'interpolation = "linear"\n',
                                          "camera.interpolation"),
    "unknown interpolation": (object_with_keys(K2, "cubic"), CAMERA, f"{OBJ}.interpolation"),
    "interpolation not a string": (object_with_keys(K2, extra="interpolation = 1\n"), CAMERA,
                                   f"{OBJ}.interpolation"),
    "no object keys": ('[[objects]]\nname = "thing"\nmesh = { box = [1.0, 1.0, 1.0] }\nkeys = []\n',
                       CAMERA, f"{OBJ}.keys"),
    "no camera keys": ("", '[camera]\nfov_y = 40.0\nkeys = []\n', "camera.keys"),
    "keys not tables": ('[[objects]]\nname = "thing"\nmesh = { box = [1.0, 1.0, 1.0] }\nkeys = 3\n',
                        CAMERA, f"{OBJ}.keys"),
    "object key without time": (object_with_keys([{"time": 0.0}, {"position": [1.0, 0.0, 0.0]}]),
                                CAMERA, f"{OBJ}.keys[2].time"),
    "camera key without time": ("", camera_text([CAM_KEYS[0], {"position": [0.0, 1.0, 3.0],
                                                               "look_at": [0.0, 0.0, 0.0]}],
                                                "linear"), "camera.keys[2].time"),
    "equal times": (object_with_keys([{"time": 0.0}, {"time": 0.1}, {"time": 0.1}]), CAMERA,
                    f"{OBJ}.keys[3].time"),
    "decreasing times": ("", camera_text([CAM_KEYS[1], CAM_KEYS[0]], "smooth"),
                         "camera.keys[2].time"),
    "unknown object key field": (object_with_keys([{"time": 0.0, "velocity": [1.0, 0.0, 0.0]}]),
                                 CAMERA, f"{OBJ}.keys[1].velocity"),
    "unknown camera key field": ("", camera_text([dict(CAM_KEYS[0], fov_y=30.0)], "linear"),
                                 "camera.keys[1].fov_y"),
    "camera key without position": ("", camera_text([{"time": 0.0, "look_at": [0.0, 0.0, 0.0]}],
                                                    "linear"), "camera.keys[1].position"),
    "camera key without look_at": ("", camera_text([{"time": 0.0, "position": [0.0, 0.0, 3.0]}],
                                                   "linear"), "camera.keys[1].look_at"),
    "time not a number": (object_with_keys([{"time": "soon"}]), CAMERA, f"{OBJ}.keys[1].time"),
    "position of 2": (object_with_keys([{"time": 0.0, "position": [1.0, 2.0]}]), CAMERA,
                      f"{OBJ}.keys[1].position"),
    "rotation not numbers": (object_with_keys([{"time": 0.0, "rotation": [1.0, "x", 0.0]}]),
                             CAMERA, f"{OBJ}.keys[1].rotation[1]"),
    "scale zero": (object_with_keys([{"time": 0.0, "scale": [1.0, 0.0, 1.0]}]), CAMERA,
                   f"{OBJ}.keys[1].scale"),
    "scale a string": (object_with_keys([{"time": 0.0, "scale": "big"}]), CAMERA,
                       f"{OBJ}.keys[1].scale"),
    "camera key up zero": ("", camera_text([dict(CAM_KEYS[0], up=[0.0, 0.0, 0.0])], "linear"),
                           "camera.keys[1].up"),
    "camera key up along the view": ("", camera_text([{"time": 0.0, "position": [0.0, 3.0, 0.0],
                                                       "look_at": [0.0, 0.0, 0.0]}], "linear",
                                                     up="[0.0, 1.0, 0.0]"), "camera.keys[1].up"),
    "camera key looking at its eye": ("", camera_text([{"time": 0.0, "position": [0.0, 1.0, 0.0],
                                                        "look_at": [0.0, 1.0, 0.0]}], "linear"),
                                      "camera.keys[1].look_at"),
}


@pytest.mark.parametrize("case", sorted(ERRORS))
def test_every_key_mistake_is_one_line_naming_file_and_key_exit_2(tmp_path, capsys, case):
    objects, camera, key = ERRORS[case]
    path = scene_file(tmp_path, objects, camera)
    out = tmp_path / "o.png"
    assert main(["shot", str(path), "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    assert str(path) in lines[0] and f"{key}:" in lines[0], (key, lines[0])
    assert not out.exists()


def test_viewer_moves_leave_a_keyed_camera_at_the_shown_pose_and_reset_restores_it(tmp_path):
    from viewer.ui.camera_control import CameraControl
    spec = load_scene(scene_file(tmp_path, "", camera_text(CAM_KEYS, "smooth"))).camera
    eye = np.array(spec.pose(0.13)[0])
    control = CameraControl(spec, lambda: 0.13)
    control.zoom(0)                                   # a move of nothing: only the detach
    assert spec.keys is None
    np.testing.assert_allclose(spec.position, eye, atol=1e-15)
    control.pan(10, 0, 100)
    assert not np.allclose(spec.position, eye)
    control.reset()
    assert spec.keys is not None and spec.moving
    np.testing.assert_allclose(spec.pose(0.13)[0], eye, atol=1e-15)
