"""glTF entries in the scene tree (scene format v1.2): shared meshes built once, the
entry's timing keys, animation selection, and what the format leaves out said on stderr."""
import shutil

import numpy as np
import pytest

from raytrace import RayScene
from viewer.render.graph.gpu_scene import GpuScene
from world.loader import load_scene

from conftest import CONFORMANCE, _context
from gltf_builder import Builder

BOX = CONFORMANCE / "gltf" / "BoxAnimated.gltf"


def entry_file(tmp_path, gltf: str, name: str, entry: str = "", file: str | None = None):
    """A scene file holding one `gltf` entry named `name` (with the `entry` lines)."""
    p = tmp_path / f"{file or name}.toml"
    p.write_text(f"""
[camera]
position = [0.0, 1.0, 6.0]
look_at = [0.0, 0.5, 0.0]
fov_y = 45.0
shutter = 0.05
[[objects]]
name = "{name}"
gltf = "{gltf}"
{entry}
""")
    return p


def scene_with(tmp_path, entry: str, name="s"):
    shutil.copy(BOX, tmp_path / BOX.name)     # (a scene names files in its own folder)
    return load_scene(entry_file(tmp_path, BOX.name, "a", entry, name))


def test_mesh_used_by_several_nodes_is_built_and_uploaded_once():
    sc = load_scene("rover")
    wheels = [o for o in sc.objects if "/wheel_" in o.name]
    assert len(wheels) == 4 and all(o.mesh is wheels[0].mesh for o in wheels)
    gpu = GpuScene(_context(), sc)
    try:
        assert len({id(gpu.buffers[o.id - 1]) for o in wheels}) == 1
    finally:
        gpu.release()
    rs = RayScene(sc)
    scenes = {id(es) for o, es in rs.moving if o in wheels}
    assert len(scenes) == 1
    assert len({int(rs.surfaces.face_offset[o.id]) for o in wheels}) == 1


def test_timing_keys_drive_the_animation_time(tmp_path):
    plain = scene_with(tmp_path, "", "plain")
    timed = scene_with(tmp_path, "time_offset = 0.5\ntime_scale = 2.0", "timed")
    inner_plain, inner_timed = plain.objects[1], timed.objects[1]
    assert inner_plain.moving and inner_timed.moving
    for t in (0.6, 0.9, 1.3):
        np.testing.assert_allclose(inner_timed.matrix(t), inner_plain.matrix((t - 0.5) * 2.0),
                                   atol=1e-12)


def test_loop_wraps_into_the_key_range(tmp_path):
    looped = scene_with(tmp_path, "loop = true", "looped")
    inner = looped.objects[1]
    a0, a1 = looped.assets[0].asset.time_range(looped.assets[0].animations)
    assert a1 > a0
    np.testing.assert_allclose(inner.matrix(a0 + 0.3 + 2 * (a1 - a0)), inner.matrix(a0 + 0.3),
                               atol=1e-9)
    clamped = scene_with(tmp_path, "", "clamped").objects[1]
    np.testing.assert_allclose(clamped.matrix(a1 + 5.0), clamped.matrix(a1), atol=1e-12)


def test_animation_none_keeps_the_asset_still(tmp_path):
    still = scene_with(tmp_path, 'animation = "none"', "still")
    assert not any(o.moving for o in still.objects)
    np.testing.assert_allclose(still.objects[1].matrix(0.0), still.objects[1].matrix(1.7))


def test_features_left_out_are_named_once_on_stderr(tmp_path, capsys):
    b = Builder()
    b.triangle_mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32))
    b.add("nodes", {"mesh": 0})
    b.add("cameras", {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}})
    b.doc["scenes"] = [{"nodes": [0]}]
    b.write(tmp_path, "cam.gltf")
    sc = load_scene(entry_file(tmp_path, "cam.gltf", "tri"))
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "camera" in err and "objects[1] (tri)" in err
    assert sc.objects[0].name == "tri/node0"


@pytest.mark.parametrize("entry, words", [
    ('animation = "Walk"', "no animation named 'Walk'"),
    ("animation = 3", "index 3 out of range"),
    ("time_scale = 0.0", "time_scale: expected a number > 0"),
    ('loop = "yes"', "loop: expected true or false"),
    ('mesh = { box = [1.0, 1.0, 1.0] }', "mesh: not allowed together with gltf"),
    ('parent = "x"', "parent: not allowed on a gltf entry"),
    ("material = { albedo = [1.0, 0.0, 0.0] }", "material.albedo: unknown key"),
])
def test_entry_mistakes_one_line(tmp_path, entry, words):
    from world.errors import SceneError
    with pytest.raises(SceneError) as e:
        scene_with(tmp_path, entry)
    assert words in str(e.value) and "objects[1] (a)" in str(e.value)
    assert "\n" not in str(e.value)


def test_bench_speeds_retime_the_animation_about_the_frame_time(tmp_path):
    sc = scene_with(tmp_path, "")
    inner, instance = sc.objects[1], sc.assets[0]
    t0 = 0.6
    before = [inner.matrix(t) for t in (0.5, 0.7)]
    instance.retime = (t0, 0.0)          # held at the pose of t0
    np.testing.assert_allclose(inner.matrix(0.5), inner.matrix(0.7), atol=1e-12)
    instance.retime = (t0, 2.0)          # twice as fast about t0
    np.testing.assert_allclose(inner.matrix(0.65), _plain(instance, inner, 0.7), atol=1e-12)
    instance.retime = None
    np.testing.assert_allclose(inner.matrix(0.5), before[0], atol=1e-12)


def _plain(instance, obj, t):
    saved, instance.retime = instance.retime, None
    try:
        return obj.matrix(t)
    finally:
        instance.retime = saved


def test_a_rigid_node_draws_a_mesh_whose_primitives_differ_in_joints(tmp_path):
    """JOINTS_0/WEIGHTS_0 on one primitive only: a rigid node's mesh needs no joints (the
    entry once asked every primitive for them), a skinned node's must have them all (the
    reader says which primitive lacks them)."""
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    b = Builder()
    j = b.accessor(np.zeros((3, 4), np.uint8), 5121)
    w = b.accessor(np.float32([[1, 0, 0, 0]] * 3))
    first = {"attributes": {"POSITION": b.accessor(tri), "JOINTS_0": j, "WEIGHTS_0": w}}
    second = {"attributes": {"POSITION": b.accessor(tri + np.float32([2, 0, 0]))}}
    b.add("meshes", {"primitives": [first, second]})
    b.add("nodes", {"mesh": 0})
    b.doc["scenes"] = [{"nodes": [0]}]
    b.write(tmp_path, "mixed.gltf")
    p = entry_file(tmp_path, "mixed.gltf", "m")
    (o,) = load_scene(p).objects
    assert o.skin is None and len(o.mesh.faces) == 2
    np.testing.assert_array_equal(o.mesh.vertices[3:, 0], [2, 3, 2])
    b.add("nodes", {"name": "joint"})
    b.doc["nodes"][0]["skin"] = 0
    b.add("skins", {"joints": [1]})
    b.doc["scenes"] = [{"nodes": [0, 1]}]
    b.write(tmp_path, "mixed.gltf")
    from world.errors import SceneError
    with pytest.raises(SceneError, match=r"nodes\[0\] \(skins\[0\], meshes\[0\]\.primitives\[1\]\): "
                                         r"a skinned primitive needs JOINTS_0 and WEIGHTS_0"):
        load_scene(p)


def moving_triangle(tmp_path):
    """A triangle keyed over 0..2 s: translation x 0 -> 2 and a turn about +Z 0 -> 90 deg,
    LINEAR, in one animation named "move"."""
    b = Builder()
    m = b.triangle_mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), [0, 1, 2])
    b.add("nodes", {"mesh": m, "name": "tri"})
    b.doc["scenes"] = [{"nodes": [0]}]
    times = b.accessor(np.float32([0.0, 2.0]))
    s = np.sqrt(0.5)
    b.add("animations", {"name": "move", "samplers": [
        {"input": times, "output": b.accessor(np.float32([[0, 0, 0], [2, 0, 0]]))},
        {"input": times, "output": b.accessor(np.float32([[0, 0, 0, 1], [0, 0, s, s]]))}],
        "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}},
                     {"sampler": 1, "target": {"node": 0, "path": "rotation"}}]})
    b.write(tmp_path, "tri.gltf")


def pose(x: float, degrees: float) -> np.ndarray:
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[0, 3] = x
    return m


@pytest.mark.parametrize("timing,loop,expected", [
    # a = (t - time_offset) * time_scale; x = a, 45 deg a second, within [0, 2] s
    ("time_offset = 0.4\ntime_scale = 2.5", False,
     {0.6: (0.5, 22.5), 0.8: (1.0, 45.0), 1.0: (1.5, 67.5), 1.5: (2.0, 90.0), 0.2: (0.0, 0.0)}),
    # looped: a wraps into [0, 2]
    ("time_offset = 0.4\ntime_scale = 2.5", True,
     {1.5: (0.75, 33.75), 0.2: (1.5, 67.5), 1.0: (1.5, 67.5)}),
    ("time_scale = 0.5", False, {2.4: (1.2, 54.0), 3.0: (1.5, 67.5), 5.0: (2.0, 90.0)}),
])
def test_time_scale_and_offset_against_hand_computed_poses(tmp_path, timing, loop, expected):
    from viewer.ui.panel import animation_lines
    from world.asset_scene import animation_range
    moving_triangle(tmp_path)
    p = tmp_path / "s.toml"
    p.write_text(f"""
[camera]
position = [0.0, 0.0, 6.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
[[objects]]
name = "a"
gltf = "tri.gltf"
loop = {str(loop).lower()}
{timing}
""")
    sc = load_scene(p)
    (tri,) = sc.objects
    for t, (x, degrees) in expected.items():
        np.testing.assert_allclose(tri.matrix(t), pose(x, degrees), atol=1e-6, err_msg=str(t))
    # the animation's range in scene time: time_offset + [0, 2] / time_scale
    inst = sc.assets[0]
    offset = 0.4 if "offset" in timing else 0.0
    scale = 2.5 if "2.5" in timing else 0.5
    assert animation_range(inst) == pytest.approx((offset, offset + 2.0 / scale), abs=1e-12)
    assert animation_lines(sc) == [f"a: move {offset:.2f}-{offset + 2.0 / scale:.2f} s"
                                   + (" (looped)" if loop else "")]
