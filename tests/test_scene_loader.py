"""world.loader against the scene format (docs/scene-format.md): values, defaults,
motion, and errors.

Invalid inputs are small TOML documents written to tmp_path; each must raise SceneError
whose message names the file and the dotted key.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh
from PIL import Image

from world.errors import SceneError, UserError
from world.scene import Scene
from world.images import linear_rgb, srgb_to_linear
from world.loader import load_scene

CONFORMANCE = Path(__file__).resolve().parent / "conformance"


# ---------------------------------------------------------------- helpers

def toml_value(v) -> str:
    """A tiny TOML writer (inline tables only) so tests can state documents as dicts."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + "".join(c if c not in '"\\' and 0x20 <= ord(c) != 0x7F
                             else f"\\u{ord(c):04x}" for c in v) + '"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_value(str(k))} = {toml_value(x)}"
                               for k, x in v.items()) + "}"
    raise TypeError(type(v))


def toml_doc(d: dict) -> str:
    return "".join(f"{toml_value(str(k))} = {toml_value(v)}\n" for k, v in d.items())


def base_doc() -> dict:
    """A valid scene using every feature that needs no external file."""
    return {
        "name": "t",
        "background": [0.1, 0.2, 0.3],
        "ambient": [0.1, 0.1, 0.1],
        "camera": {"position": [0.0, 1.0, 4.0], "look_at": [0.0, 1.0, 0.0], "fov_y": 45.0,
                   "up": [0.0, 1.0, 0.0], "near": 0.1, "far": 50.0, "shutter": 0.04,
                   "velocity": [0.0, 0.0, 0.0], "angular_velocity": [0.0, 0.0, 0.0]},
        "render": {"width": 64, "height": 32, "time": 0.0},
        "lights": [{"direction": [0.0, -1.0, 0.0], "color": [1.0, 1.0, 1.0]}],
        "objects": [
            {"name": "floor", "mesh": {"box": [4.1, 0.1, 4.1]},
             "material": {"albedo": [0.8, 0.8, 0.8],
                          "texture": {"kind": "checker", "size": 0.3,
                                      "albedo2": [0.1, 0.1, 0.1]}}},
            {"name": "vase", "mesh": {"revolve": [[0.0, 0.0], [0.2, 0.0], [0.1, 0.5],
                                                  [0.0, 0.5]], "sections": 8},
             "position": [0.0, 0.5, 0.0], "rotation": [-90.0, 0.0, 0.0], "scale": 1.0,
             "shading": "smooth",
             "material": {"albedo": [0.8, 0.3, 0.2], "specular": 0.2, "shininess": 16.0,
                          "texture": {"kind": "stripes", "axis": 2, "size": 0.1,
                                      "albedo2": [0.9, 0.9, 0.9]}},
             "velocity": [1.0, 0.0, 0.0], "angular_velocity": [0.0, 2.0, 0.0]},
            {"name": "ball", "mesh": {"sphere": {"radius": 0.3, "subdivisions": 1}}},
            {"name": "can", "mesh": {"cylinder": {"radius": 0.1, "height": 0.4,
                                                  "sections": 6}}},
        ],
    }


def write(tmp_path: Path, doc, name: str = "scene.toml") -> Path:
    p = tmp_path / name
    p.write_text(doc if isinstance(doc, str) else toml_doc(doc), encoding="utf-8")
    return p


def expect_error(path: Path, key: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_scene(path)
    msg = str(info.value)
    assert str(path) in msg, msg
    assert key in msg, f"{key!r} not in {msg!r}"
    assert info.value.key.startswith(key) or key in info.value.key, (key, info.value.key)
    return info.value


def rx(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry_rad(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rodrigues(axis, angle):
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def affine(r3, t):
    m = np.eye(4)
    m[:3, :3] = r3
    m[:3, 3] = t
    return m


# ---------------------------------------------------------------- valid files

def test_conformance_basic_values_and_defaults():
    s = load_scene(CONFORMANCE / "basic.toml")
    assert isinstance(s, Scene) and s.name == "basic"
    assert s.path == CONFORMANCE / "basic.toml"
    np.testing.assert_array_equal(s.background, [0.05, 0.06, 0.08])
    np.testing.assert_array_equal(s.ambient, [0.15, 0.15, 0.17])
    c = s.camera
    np.testing.assert_array_equal(c.position, [0.0, 1.0, 4.0])
    np.testing.assert_array_equal(c.look_at, [0.0, 0.7, 0.0])
    assert c.fov_y == 40.0 and c.shutter == 0.05
    # defaults
    np.testing.assert_array_equal(c.up, [0, 1, 0])
    assert (c.near, c.far) == (0.05, 100.0)
    np.testing.assert_array_equal(c.velocity, 0)
    np.testing.assert_array_equal(c.angular_velocity, 0)
    assert (s.render.width, s.render.height, s.render.time) == (320, 180, 0.0)
    assert len(s.lights) == 1
    d = np.array([-0.5, -1.0, -0.4])
    np.testing.assert_allclose(s.lights[0].direction, d / np.sqrt(0.25 + 1 + 0.16), rtol=1e-15)
    np.testing.assert_array_equal(s.lights[0].color, [0.9, 0.88, 0.82])

    names = [o.name for o in s.objects]
    assert names == ["floor", "wall", "sphere", "box"]
    assert [o.id for o in s.objects] == [1, 2, 3, 4]
    floor, wall, sphere, box = s.objects
    assert [o.shading for o in s.objects] == ["flat", "flat", "smooth", "flat"]
    tx = floor.material.texture
    assert tx.kind == "checker" and tx.size == 0.35
    np.testing.assert_array_equal(tx.albedo2, [0.15, 0.15, 0.18])
    tx = wall.material.texture
    assert (tx.kind, tx.axis, tx.size) == ("stripes", 0, 0.2)
    np.testing.assert_array_equal(sphere.velocity, [12.0, 0.0, 0.0])
    assert sphere.material.specular == 0.4 and sphere.material.shininess == 40.0
    assert sphere.material.texture is None
    assert box.material.specular == 0.0 and box.material.shininess == 32.0
    np.testing.assert_array_equal(box.rotation, [0.0, 30.0, 0.0])
    np.testing.assert_array_equal(box.angular_velocity, [0.0, 15.0, 0.0])
    np.testing.assert_array_equal(box.scale, [1.0, 1.0, 1.0])
    np.testing.assert_array_equal(floor.position, [0.0, -0.05, 0.0])
    assert sphere.moving and box.moving and not floor.moving

    ref = trimesh.creation.icosphere(subdivisions=3, radius=0.35)
    m = sphere.mesh
    np.testing.assert_array_equal(m.vertices, ref.vertices)
    np.testing.assert_array_equal(m.faces, ref.faces)
    np.testing.assert_array_equal(m.vertex_normals, ref.vertex_normals)
    np.testing.assert_array_equal(m.face_normals, ref.face_normals)
    assert m.uv is None
    for arr in (m.vertices, m.vertex_normals, m.face_normals):
        assert arr.dtype == np.float64
    assert m.faces.dtype == np.int64
    np.testing.assert_array_equal(floor.mesh.vertices,
                                  trimesh.creation.box(extents=[6.1, 0.1, 6.1]).vertices)


def test_conformance_vase_pan_values():
    s = load_scene(CONFORMANCE / "vase_pan.toml")
    c = s.camera
    np.testing.assert_array_equal(c.up, [0, 1, 0])
    assert (c.fov_y, c.near, c.far, c.shutter) == (45.0, 0.1, 30.0, 0.04)
    np.testing.assert_array_equal(c.velocity, [1.5, 0, 0])
    np.testing.assert_array_equal(c.angular_velocity, [0, 0.6, 0])
    assert s.render.time == 0.1 and len(s.lights) == 2
    np.testing.assert_allclose(s.lights[1].direction, [-1 / math.sqrt(1.04), -0.2 / math.sqrt(1.04), 0])
    vase = s.objects[2]
    assert (vase.name, vase.id, vase.shading) == ("vase", 3, "smooth")
    ref = trimesh.creation.revolve(
        linestring=[[0.0, 0.0], [0.18, 0.0], [0.25, 0.25], [0.12, 0.55], [0.16, 0.7], [0.0, 0.7]],
        sections=40)
    np.testing.assert_array_equal(vase.mesh.vertices, ref.vertices)
    np.testing.assert_array_equal(vase.mesh.faces, ref.faces)
    assert vase.material.texture.axis == 2 and vase.material.texture.size == 0.07


def test_camera_pose_against_hand_computed_values():
    s = load_scene(CONFORMANCE / "vase_pan.toml")
    t = 0.1
    eye, fwd, up = s.camera.pose(t)
    np.testing.assert_allclose(eye, [0.2 + 1.5 * t, 1.2, 3.5], rtol=0, atol=1e-15)
    f0 = np.array([-0.2, -0.4, -3.5]) / np.linalg.norm([-0.2, -0.4, -3.5])
    np.testing.assert_allclose(fwd, ry_rad(0.6 * t) @ f0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(up, [0, 1, 0], atol=1e-15)
    # turning right-handed about +Y moves a forward vector with negative z towards -x
    assert fwd[0] < f0[0]


def test_object_matrix_against_hand_computed_values(tmp_path):
    d = base_doc()
    d["objects"] = [{"mesh": {"box": [1.0, 1.0, 1.0]}, "position": [1.0, 2.0, 3.0],
                     "rotation": [30.0, 45.0, 60.0], "scale": [1.0, 2.0, 3.0],
                     "velocity": [0.5, -1.0, 2.0], "angular_velocity": [1.0, 2.0, 2.0]}]
    s = load_scene(write(tmp_path, d))
    o = s.objects[0]
    t = 0.25
    r0 = rz(60) @ ry_rad(math.radians(45)) @ rx(30)
    rot = rodrigues([1, 2, 2], 3.0 * t)            # |w| = 3
    expected = affine(rot @ r0 @ np.diag([1.0, 2.0, 3.0]),
                      np.array([1.0, 2.0, 3.0]) + t * np.array([0.5, -1.0, 2.0]))
    np.testing.assert_allclose(o.matrix(t), expected, rtol=0, atol=1e-13)
    # the basic scene's box: spinning about Y at 15 rad/s from a 30 degree start
    box = load_scene(CONFORMANCE / "basic.toml").objects[3]
    expected = affine(ry_rad(15 * 0.02 + math.radians(30)), [0.9, 0.45, 0.2])
    np.testing.assert_allclose(box.matrix(0.02), expected, rtol=0, atol=1e-14)


def test_defaults_of_a_minimal_file(tmp_path):
    p = write(tmp_path, """
[camera]
position = [0, 1, 5]
look_at = [0, 1, 0]
fov_y = 50

[[lights]]
direction = [0, 0, -2]

[[objects]]
mesh = { box = [1, 2, 3] }

[[objects]]
mesh = { sphere = {} }
scale = 2
""", "minimal_scene.toml")
    s = load_scene(p)
    assert s.name == "minimal_scene"
    np.testing.assert_array_equal(s.background, 0)
    np.testing.assert_array_equal(s.ambient, 0)
    assert (s.render.width, s.render.height, s.render.time) == (1280, 720, 0.0)
    c = s.camera
    assert (c.near, c.far, c.shutter, c.fov_y) == (0.05, 100.0, 0.0, 50.0)
    assert c.position.dtype == np.float64
    np.testing.assert_array_equal(c.up, [0, 1, 0])
    np.testing.assert_array_equal(s.lights[0].direction, [0, 0, -1])
    np.testing.assert_array_equal(s.lights[0].color, [1, 1, 1])
    box, ball = s.objects
    assert (box.name, box.id, ball.id) == ("object1", 1, 2)
    assert box.shading == "flat" and ball.shading == "smooth"
    np.testing.assert_array_equal(box.position, 0)
    np.testing.assert_array_equal(box.rotation, 0)
    np.testing.assert_array_equal(box.scale, [1, 1, 1])
    np.testing.assert_array_equal(ball.scale, [2, 2, 2])
    np.testing.assert_array_equal(box.material.albedo, [0.8, 0.8, 0.8])
    assert (box.material.specular, box.material.shininess, box.material.texture) == (0, 32, None)
    assert not box.moving
    # an omitted primitive parameter is omitted from the trimesh call: trimesh's default
    np.testing.assert_array_equal(ball.mesh.vertices, trimesh.creation.icosphere().vertices)


def test_base_document_loads_with_all_primitives(tmp_path):
    s = load_scene(write(tmp_path, base_doc()))
    assert [o.name for o in s.objects] == ["floor", "vase", "ball", "can"]
    can = s.objects[3].mesh
    ref = trimesh.creation.cylinder(radius=0.1, height=0.4, sections=6)
    np.testing.assert_array_equal(can.vertices, ref.vertices)
    np.testing.assert_array_equal(can.faces, ref.faces)


def test_object_names_may_repeat(tmp_path):
    d = base_doc()
    for o in d["objects"]:
        o["name"] = "same"
    s = load_scene(write(tmp_path, d))
    assert [o.id for o in s.objects] == [1, 2, 3, 4]


def test_path_argument_forms(tmp_path):
    p = write(tmp_path, base_doc())
    assert load_scene(str(p)).name == "t"
    assert load_scene(p).name == "t"
    with pytest.raises(SceneError, match="file not found"):
        load_scene(tmp_path / "nope.toml")
    assert issubclass(SceneError, UserError)


# ---------------------------------------------------------------- mesh and image files

QUAD_OBJ = """v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 1/1 2/2 3/3
f 1/1 3/3 4/4
"""


def scene_with_mesh(mesh, texture=None) -> dict:
    d = base_doc()
    obj = {"name": "thing", "mesh": mesh}
    if texture is not None:
        obj["material"] = {"texture": texture}
    d["objects"] = [d["objects"][0], obj]
    return d


def test_obj_mesh_file_with_uvs_and_image_texture(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "quad.obj").write_text(QUAD_OBJ)
    # 2 rows x 3 columns of known sRGB bytes; the top row is written first
    srgb = np.array([[[0, 10, 128], [255, 0, 0], [1, 2, 3]],
                     [[200, 100, 50], [0, 255, 0], [9, 99, 199]]], dtype=np.uint8)
    Image.fromarray(srgb).save(tmp_path / "sub" / "tex.png")
    p = write(tmp_path, scene_with_mesh("sub/quad.obj", {"kind": "image", "path": "sub/tex.png"}))
    o = load_scene(p).objects[1]
    ref = trimesh.load(str(tmp_path / "sub" / "quad.obj"), force="mesh")
    np.testing.assert_array_equal(o.mesh.vertices, ref.vertices)
    np.testing.assert_array_equal(o.mesh.faces, ref.faces)
    np.testing.assert_array_equal(o.mesh.uv, ref.visual.uv)
    assert o.mesh.uv.shape == (4, 2) and o.mesh.uv.dtype == np.float64
    assert o.shading == "smooth"                    # only box defaults to flat
    tx = o.material.texture
    assert tx.kind == "image" and tx.path == tmp_path / "sub" / "tex.png"
    img = tx.image
    assert img.dtype == np.float32 and img.shape == (2, 3, 3)
    assert img[0, 1, 0] == 1.0 and img[0, 1, 1] == 0.0          # top row first
    assert img[1, 1, 1] == 1.0 and img[1, 1, 0] == 0.0
    np.testing.assert_allclose(img[0, 0], [0.0, 10 / 255 / 12.92,
                                           ((128 / 255 + 0.055) / 1.055) ** 2.4], rtol=1e-6)
    np.testing.assert_allclose(img[0, 0, 2], 0.2158605, rtol=1e-6)


@pytest.mark.parametrize("mode", ["I;16", "L", "LA", "P", "RGBA"])
def test_image_texture_modes_decode_at_their_precision(tmp_path, mode):
    """Grey and palette images become grey RGB; 16-bit grey keeps its 16 bits (Pillow's
    RGB conversion clipped every 16-bit value to 255: a white texture); alpha is dropped."""
    (tmp_path / "quad.obj").write_text(QUAD_OBJ)
    if mode == "I;16":
        raw = np.array([[0, 1000, 30000], [65535, 40000, 7]], np.uint16)
        im = Image.fromarray(raw)
        srgb = raw / 65535.0
        # (older Pillows open a 16-bit grey PNG as 32-bit "I", same values)
        np.testing.assert_array_equal(linear_rgb(Image.fromarray(raw.astype(np.int32)))[..., 0],
                                      srgb_to_linear(srgb).astype(np.float32))
    else:
        raw = np.array([[0, 10, 128], [255, 200, 7]], np.uint8)
        im = Image.fromarray(raw).convert(mode)
        srgb = raw / 255.0
    im.save(tmp_path / "tex.png")
    with Image.open(tmp_path / "tex.png") as back:
        assert back.mode.startswith("I;16") == (mode == "I;16")
    p = write(tmp_path, scene_with_mesh("quad.obj", {"kind": "image", "path": "tex.png"}))
    img = load_scene(p).objects[1].material.texture.image
    np.testing.assert_allclose(img, np.repeat(srgb_to_linear(srgb)[..., None], 3, -1),
                               rtol=1e-6, atol=1e-9)


def test_srgb_decoding_is_the_standard_curve():
    c = np.array([0.0, 0.04045, 0.04046, 0.5, 1.0])
    expected = [0.0, 0.04045 / 12.92, ((0.04046 + 0.055) / 1.055) ** 2.4, 0.21404114, 1.0]
    np.testing.assert_allclose(srgb_to_linear(c), expected, rtol=1e-7)


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_mesh_file_with_non_finite_vertices(tmp_path, bad):
    (tmp_path / "bad.obj").write_text(f"v 0 0 0\nv 1 0 0\nv {bad} 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n")
    e = expect_error(write(tmp_path, scene_with_mesh("bad.obj")), "objects[2] (thing).mesh")
    assert "NaN or inf" in str(e)


def test_mesh_file_errors(tmp_path):
    e = expect_error(write(tmp_path, scene_with_mesh("missing.obj")), "objects[2] (thing).mesh")
    assert "not found" in str(e) and "missing.obj" in str(e)
    (tmp_path / "empty.obj").write_text("")
    e = expect_error(write(tmp_path, scene_with_mesh("empty.obj")), "objects[2] (thing).mesh")
    assert "triangles" in str(e)
    (tmp_path / "junk.xyz").write_text("not a mesh\n")
    e = expect_error(write(tmp_path, scene_with_mesh("junk.xyz")), "objects[2] (thing).mesh")
    assert "readable mesh" in str(e)
    (tmp_path / "adir").mkdir()
    expect_error(write(tmp_path, scene_with_mesh("adir")), "objects[2] (thing).mesh")


def test_image_texture_errors(tmp_path):
    (tmp_path / "quad.obj").write_text(QUAD_OBJ)
    p = write(tmp_path, scene_with_mesh("quad.obj", {"kind": "image", "path": "none.png"}))
    e = expect_error(p, "objects[2] (thing).material.texture.path")
    assert "not found" in str(e)
    (tmp_path / "broken.png").write_text("this is not a png")
    p = write(tmp_path, scene_with_mesh("quad.obj", {"kind": "image", "path": "broken.png"}))
    expect_error(p, "objects[2] (thing).material.texture.path")
    Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "ok.png")
    p = write(tmp_path, scene_with_mesh({"box": [1, 1, 1]}, {"kind": "image", "path": "ok.png"}))
    e = expect_error(p, "objects[2] (thing).material.texture")
    assert "UV" in str(e)
    # an OBJ without texture coordinates has no UVs either
    (tmp_path / "nouv.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    p = write(tmp_path, scene_with_mesh("nouv.obj", {"kind": "image", "path": "ok.png"}))
    assert "UV" in str(expect_error(p, "objects[2] (thing).material.texture"))


# ---------------------------------------------------------------- invalid documents

def _set(d: dict, path: str, value):
    """Set d[a][b]... along a dotted path; list indices are numbers; DELETE removes."""
    parts = path.split(".")
    for part in parts[:-1]:
        d = d[int(part)] if isinstance(d, list) else d[part]
    last = parts[-1]
    if value is DELETE:
        del d[last]
    elif isinstance(d, list):
        d[int(last)] = value
    else:
        d[last] = value


DELETE = object()

# (path in base_doc, new value, key the message must name)
INVALID = [
    # unknown keys at every level
    ("colour", [1, 1, 1], "colour"),
    ("camera.fov", 45.0, "camera.fov"),
    ("render.fps", 30, "render.fps"),
    ("lights.0.intensity", 2.0, "lights[1].intensity"),
    ("objects.1.colour", [1, 0, 0], "objects[2] (vase).colour"),
    ("objects.1.material.roughness", 0.5, "objects[2] (vase).material.roughness"),
    ("objects.1.material.texture.axis2", 1, "objects[2] (vase).material.texture.axis2"),
    ("objects.0.material.texture.axis", 1, "objects[1] (floor).material.texture.axis"),
    ("objects.2.mesh.sphere.segments", 8, "objects[3] (ball).mesh.sphere.segments"),
    ("objects.2.mesh.sections", 8, "objects[3] (ball).mesh.sections"),
    ("objects.2.mesh.cube", [1.0, 1.0, 1.0], "objects[3] (ball).mesh.cube"),
    # wrong types; a boolean is not a number
    ("name", 3, "name"),
    ("background", "black", "background"),
    ("camera.fov_y", True, "camera.fov_y"),
    ("camera.fov_y", "45", "camera.fov_y"),
    ("camera.position", [0, True, 4], "camera.position[1]"),
    ("camera", [1, 2], "camera"),
    ("render.width", 64.0, "render.width"),
    ("render.height", True, "render.height"),
    ("render.time", "now", "render.time"),
    ("lights", {"direction": [0, -1, 0]}, "lights"),
    ("lights", [1, 2], "lights"),
    ("objects", {"mesh": {"box": [1, 1, 1]}}, "objects"),
    ("objects.1.name", 7, "objects[2].name"),
    ("objects.1.scale", "big", "objects[2] (vase).scale"),
    ("objects.1.scale", False, "objects[2] (vase).scale"),
    ("objects.1.material", "red", "objects[2] (vase).material"),
    ("objects.1.material.texture", "wood", "objects[2] (vase).material.texture"),
    ("objects.1.material.texture.axis", 1.0, "objects[2] (vase).material.texture.axis"),
    ("objects.1.mesh", 5, "objects[2] (vase).mesh"),
    ("objects.1.shading", 1, "objects[2] (vase).shading"),
    ("objects.2.mesh.sphere.subdivisions", 2.5, "objects[3] (ball).mesh.sphere.subdivisions"),
    # wrong vector lengths
    ("ambient", [0.1, 0.1], "ambient"),
    ("camera.look_at", [0, 1, 0, 1], "camera.look_at"),
    ("camera.up", [], "camera.up"),
    ("lights.0.color", [1, 1], "lights[1].color"),
    ("objects.1.velocity", [1, 0], "objects[2] (vase).velocity"),
    ("objects.1.scale", [1, 1], "objects[2] (vase).scale"),
    ("objects.0.mesh.box", [1, 1], "objects[1] (floor).mesh.box"),
    ("objects.1.mesh.revolve", [[0.0, 0.0]], "objects[2] (vase).mesh.revolve"),
    ("objects.1.mesh.revolve", [[0.0, 0.0], [0.1, 0.2, 0.3]], "objects[2] (vase).mesh.revolve[1]"),
    # NaN and infinity
    ("camera.position", [0.0, math.nan, 4.0], "camera.position[1]"),
    ("camera.shutter", math.inf, "camera.shutter"),
    ("render.time", math.nan, "render.time"),
    ("lights.0.direction", [0.0, -math.inf, 0.0], "lights[1].direction[1]"),
    ("objects.1.angular_velocity", [0.0, math.nan, 0.0], "objects[2] (vase).angular_velocity[1]"),
    ("objects.1.material.specular", math.nan, "objects[2] (vase).material.specular"),
    ("objects.1.rotation", [-math.inf, 0.0, 0.0], "objects[2] (vase).rotation[0]"),
    ("objects.1.mesh.revolve", [[0.0, 0.0], [math.nan, 0.5]], "objects[2] (vase).mesh.revolve[1][0]"),
    ("camera.far", 10 ** 400, "camera.far"),
    # missing required keys
    ("camera", DELETE, "camera"),
    ("camera.position", DELETE, "camera.position"),
    ("camera.look_at", DELETE, "camera.look_at"),
    ("camera.fov_y", DELETE, "camera.fov_y"),
    ("lights.0.direction", DELETE, "lights[1].direction"),
    ("objects.1.mesh", DELETE, "objects[2] (vase).mesh"),
    ("objects.0.material.texture.size", DELETE, "objects[1] (floor).material.texture.size"),
    ("objects.0.material.texture.albedo2", DELETE, "objects[1] (floor).material.texture.albedo2"),
    ("objects.1.material.texture.axis", DELETE, "objects[2] (vase).material.texture.axis"),
    ("objects.1.material.texture.kind", DELETE, "objects[2] (vase).material.texture.kind"),
    ("objects.3.mesh.cylinder.height", DELETE, "objects[4] (can).mesh.cylinder.height"),
    # invalid values
    ("camera.fov_y", 0.0, "camera.fov_y"),
    ("camera.fov_y", 180, "camera.fov_y"),
    ("camera.fov_y", -30.0, "camera.fov_y"),
    ("camera.near", 0.0, "camera.near"),
    ("camera.near", -1.0, "camera.near"),
    ("camera.far", 0.1, "camera.far"),
    ("camera.far", 0.05, "camera.far"),
    ("camera.shutter", -0.01, "camera.shutter"),
    ("camera.look_at", [0.0, 1.0, 4.0], "camera.look_at"),
    ("camera.up", [0.0, 0.0, -1.0], "camera.up"),
    ("camera.up", [0.0, 0.0, 0.0], "camera.up"),
    ("render.width", 0, "render.width"),
    ("render.height", -720, "render.height"),
    ("render.width", 10 ** 6, "render.width"),
    ("objects.1.mesh.sections", 2, "objects[2] (vase).mesh.sections"),
    ("objects.3.mesh.cylinder.sections", 2, "objects[4] (can).mesh.cylinder.sections"),
    ("objects.2.mesh.sphere.radius", 0.0, "objects[3] (ball).mesh.sphere.radius"),
    ("objects.3.mesh.cylinder.radius", -0.1, "objects[4] (can).mesh.cylinder.radius"),
    ("objects.3.mesh.cylinder.height", 0, "objects[4] (can).mesh.cylinder.height"),
    ("objects.2.mesh.sphere.subdivisions", -1, "objects[3] (ball).mesh.sphere.subdivisions"),
    ("objects.2.mesh.sphere.subdivisions", 12, "objects[3] (ball).mesh.sphere.subdivisions"),
    ("objects.0.mesh.box", [1.0, 0.0, 1.0], "objects[1] (floor).mesh.box"),
    ("objects.0.mesh.box", [1.0, 1.0, -2.0], "objects[1] (floor).mesh.box"),
    ("objects.0.mesh", {}, "objects[1] (floor).mesh"),
    ("objects.0.mesh", {"box": [1, 1, 1], "sphere": {}}, "objects[1] (floor).mesh"),
    ("objects.0.mesh", {"cone": [1, 1]}, "objects[1] (floor).mesh.cone"),
    ("objects.1.mesh.revolve", [[0.0, 0.0], [0.0, 1.0]], "objects[2] (vase).mesh.revolve"),
    ("objects.1.mesh.revolve", [[0.0, 0.0], [-0.2, 1.0]], "objects[2] (vase).mesh.revolve[1][0]"),
    ("objects.1.material.texture.axis", 3, "objects[2] (vase).material.texture.axis"),
    ("objects.1.material.texture.axis", -1, "objects[2] (vase).material.texture.axis"),
    ("objects.1.material.texture.size", 0.0, "objects[2] (vase).material.texture.size"),
    ("objects.0.material.texture.size", -0.3, "objects[1] (floor).material.texture.size"),
    ("objects.1.material.texture.kind", "marble", "objects[2] (vase).material.texture.kind"),
    ("objects.1.material.shininess", -1.0, "objects[2] (vase).material.shininess"),
    ("objects.1.material.specular", -0.5, "objects[2] (vase).material.specular"),
    ("objects.1.material.albedo", [0.5, -0.1, 0.5], "objects[2] (vase).material.albedo"),
    ("objects.1.material.texture.albedo2", [-1.0, 0.0, 0.0], "objects[2] (vase).material.texture.albedo2"),
    ("background", [-0.1, 0.0, 0.0], "background"),
    ("ambient", [0.0, 0.0, -1e-9], "ambient"),
    ("lights.0.color", [1.0, -1.0, 1.0], "lights[1].color"),
    ("lights.0.direction", [0.0, 0.0, 0.0], "lights[1].direction"),
    ("objects.1.shading", "phong", "objects[2] (vase).shading"),
    ("objects.1.scale", 0.0, "objects[2] (vase).scale"),
    ("objects.1.scale", [1.0, 0.0, 1.0], "objects[2] (vase).scale"),
]


@pytest.mark.parametrize("path,value,key", INVALID, ids=[f"{p}={'DEL' if v is DELETE else v}"
                                                          for p, v, _ in INVALID])
def test_invalid_document_names_file_and_key(tmp_path, path, value, key):
    d = base_doc()
    _set(d, path, value)
    e = expect_error(write(tmp_path, d), key)
    assert e.key == key
    if "[" in key:
        assert "count from 1" in str(e)


def test_error_messages_say_what_was_expected(tmp_path):
    d = base_doc()
    d["camera"]["fov_y"] = True
    assert "number" in str(expect_error(write(tmp_path, d), "camera.fov_y"))
    d = base_doc()
    d["camera"]["zoom"] = 2
    e = expect_error(write(tmp_path, d), "camera.zoom")
    assert "unknown key" in str(e) and "fov_y" in str(e)
    d = base_doc()
    d["objects"][1]["material"]["texture"]["kind"] = "wood"
    e = expect_error(write(tmp_path, d), "objects[2] (vase).material.texture.kind")
    assert "checker" in str(e) and "wood" in str(e)


def test_toml_syntax_error_has_line_info(tmp_path):
    p = write(tmp_path, 'name = "x"\n[camera]\nposition = [0, 1,\nfov_y = 3\n')
    e = expect_error(p, "")
    assert "line" in str(e) and "TOML" in str(e)
    p = write(tmp_path, "[camera]\n[camera]\n")
    assert "line 2" in str(expect_error(p, ""))


def test_non_utf8_and_unreadable_files(tmp_path):
    p = tmp_path / "latin1.toml"
    p.write_bytes(b'name = "caf\xe9"\n')
    assert "UTF-8" in str(expect_error(p, ""))
    with pytest.raises(SceneError) as info:
        load_scene(tmp_path)          # a directory
    assert str(tmp_path) in str(info.value)


def test_deeply_nested_toml_is_a_scene_error(tmp_path):
    p = write(tmp_path, "a = " + "[" * 5000 + "]" * 5000 + "\n")
    expect_error(p, "")
