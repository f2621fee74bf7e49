"""The glTF asset of our own making (scenes/make_gltf_assets.py -> scenes/assets/rover.glb)
and the built-in scene that shows it (scenes/rover.toml).

The file is read here with a few lines of struct and json (not the project's reader), so
the checks of its keys stand apart from what the loader makes of them; the loader's scene
is then checked against those keys.
"""
from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from scenes import make_gltf_assets
from world.camera import Camera

GLB = make_gltf_assets.ASSETS / "rover.glb"
WHEELS = ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")
COMPONENTS = {5126: np.float32, 5121: np.uint8, 5123: np.uint16, 5125: np.uint32}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class Glb:
    def __init__(self, data: bytes):
        magic, version, total = struct.unpack_from("<4sII", data, 0)
        assert (magic, version, total) == (b"glTF", 2, len(data))
        n, kind = struct.unpack_from("<I4s", data, 12)
        assert kind == b"JSON" and n % 4 == 0
        self.doc = json.loads(data[20:20 + n])
        m, kind = struct.unpack_from("<I4s", data, 20 + n)
        assert kind == b"BIN\x00" and 28 + n + m == len(data)
        self.bin = data[28 + n:]
        assert self.doc["buffers"] == [{"byteLength": m}]

    def accessor(self, i: int) -> np.ndarray:
        a = self.doc["accessors"][i]
        view = self.doc["bufferViews"][a["bufferView"]]
        w = WIDTH[a["type"]]
        x = np.frombuffer(self.bin, COMPONENTS[a["componentType"]], a["count"] * w,
                          view["byteOffset"] + a.get("byteOffset", 0))
        assert x.nbytes <= view["byteLength"]
        return x.reshape(a["count"], w).astype(np.float64)

    def node(self, name: str) -> int:
        (i,) = [i for i, n in enumerate(self.doc["nodes"]) if n["name"] == name]
        return i

    def parent(self, index: int) -> int:
        (p,) = [i for i, n in enumerate(self.doc["nodes"]) if index in n.get("children", [])]
        return p

    def track(self, animation: str, node: str, path: str):
        """(key times, values) of the channel of `animation` driving node.path."""
        (anim,) = [a for a in self.doc["animations"] if a["name"] == animation]
        (ch,) = [c for c in anim["channels"]
                 if c["target"] == {"node": self.node(node), "path": path}]
        s = anim["samplers"][ch["sampler"]]
        assert s["interpolation"] == "LINEAR"
        return self.accessor(s["input"])[:, 0], self.accessor(s["output"])


def spin(glb: Glb, wheel: str) -> np.ndarray:
    """A wheel's key angles about its axle (local -X), radians, unwrapped."""
    _, q = glb.track("drive", wheel, "rotation")
    return np.unwrap(2.0 * np.arctan2(-q[:, 0], q[:, 3]))


@pytest.fixture(scope="module")
def glb():
    return Glb(GLB.read_bytes())


def test_the_generator_rebuilds_the_committed_file_byte_for_byte(tmp_path):
    make_gltf_assets.main(["--out", str(tmp_path)])
    made = (tmp_path / "rover.glb").read_bytes()
    assert made == GLB.read_bytes()
    assert len(made) < 300_000


def test_structure_names_and_materials(glb):
    d = glb.doc
    assert d["asset"]["version"] == "2.0"
    names = [n["name"] for n in d["nodes"]]
    assert len(set(names)) == len(names)
    roots = d["scenes"][d["scene"]]["nodes"]
    assert [names[i] for i in roots] == ["vehicle", "arm"]
    for w in WHEELS:
        p = glb.parent(glb.node(w))
        assert names[p] == ("vehicle" if w.startswith("wheel_r") else "steer_" + w[-2:])
    assert names[glb.parent(glb.node("arm_tip"))] == "arm_j2"
    assert [a["name"] for a in d["animations"]] == ["drive", "swing"]
    # every primitive is triangles with normals; the body's decal is textured by the PNG
    body = d["meshes"][d["nodes"][glb.node("body")]["mesh"]]
    textured = [p for p in body["primitives"] if "TEXCOORD_0" in p["attributes"]]
    (decal,) = textured
    pbr = d["materials"][decal["material"]]["pbrMetallicRoughness"]
    image = d["images"][d["textures"][pbr["baseColorTexture"]["index"]]["source"]]
    view = d["bufferViews"][image["bufferView"]]
    assert image["mimeType"] == "image/png"
    assert glb.bin[view["byteOffset"]:view["byteOffset"] + 8] == b"\x89PNG\r\n\x1a\n"
    uv = glb.accessor(decal["attributes"]["TEXCOORD_0"])
    assert uv.min() == 0.0 and uv.max() == 1.0
    for mesh in d["meshes"]:
        for p in mesh["primitives"]:
            assert p.get("mode", 4) == 4 and "NORMAL" in p["attributes"]
            n = glb.accessor(p["attributes"]["NORMAL"])
            assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-6)
    # the wheels show their turn: their faces have two colours
    wheel = d["meshes"][d["nodes"][glb.node("wheel_rr")]["mesh"]]
    assert {d["materials"][p["material"]]["name"] for p in wheel["primitives"]} >= {
        "hub_light", "hub_dark"}


def test_png_is_the_decal(glb):
    from io import BytesIO

    from PIL import Image
    d = glb.doc
    view = d["bufferViews"][d["images"][0]["bufferView"]]
    png = glb.bin[view["byteOffset"]:view["byteOffset"] + view["byteLength"]]
    with Image.open(BytesIO(png)) as im:
        np.testing.assert_array_equal(np.asarray(im.convert("RGB")), make_gltf_assets.decal())


def test_rotation_keys_turn_little_between_keys(glb):
    # slerp takes the short way: a turn of 180 degrees or more between keys would go back
    for anim in glb.doc["animations"]:
        for ch in anim["channels"]:
            if ch["target"]["path"] != "rotation":
                continue
            q = glb.accessor(anim["samplers"][ch["sampler"]]["output"])
            assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
            dots = np.abs(np.sum(q[1:] * q[:-1], axis=1))
            turn = 2.0 * np.degrees(np.arccos(np.clip(dots, 0.0, 1.0)))
            assert turn.max() < 30.0, (anim["name"], ch["target"])


def test_wheels_roll_about_their_axles_at_the_distance_travelled(glb):
    t, pos = glb.track("drive", "vehicle", "translation")
    assert t[0] == 0.0 and t[-1] == make_gltf_assets.DURATION
    for w in WHEELS:
        tw, q = glb.track("drive", w, "rotation")
        np.testing.assert_array_equal(tw, t)
        assert np.all(q[:, 1:3] == 0.0)                    # about local X only: the axle
        assert np.all(np.diff(spin(glb, w)) < 0)           # always rolling forward
    # a straight stretch: 3 m/s over a 0.3 m radius is 10 rad/s
    k = np.searchsorted(t, 1.0)
    rate = -np.diff(spin(glb, "wheel_rr")) * make_gltf_assets.KEY_RATE
    assert abs(rate[k] - 10.0) < 0.01
    assert abs(np.linalg.norm(pos[k + 1] - pos[k]) * make_gltf_assets.KEY_RATE - 3.0) < 0.01
    # in the turn the inner (left) wheels roll slower than the outer ones
    k = np.searchsorted(t, 2.9)
    assert -np.diff(spin(glb, "wheel_rl"))[k] < 0.8 * -np.diff(spin(glb, "wheel_rr"))[k]
    # the +Z-facing rover first turns to face +X, along its path (90 degrees about +Y),
    # and the drive turns it 90 degrees further left
    _, q = glb.track("drive", "vehicle", "rotation")
    assert np.allclose(q[0], [0, np.sqrt(0.5), 0, np.sqrt(0.5)])
    assert np.allclose(np.abs(q[-1]), [0, 1, 0, 0], atol=1e-4)


def test_skin_binds_the_tube_to_three_joints(glb):
    d = glb.doc
    arm = d["nodes"][glb.node("arm")]
    skin = d["skins"][arm["skin"]]
    assert [d["nodes"][j]["name"] for j in skin["joints"]] == ["arm_j0", "arm_j1", "arm_j2"]
    ibm = glb.accessor(skin["inverseBindMatrices"]).reshape(-1, 4, 4).transpose(0, 2, 1)
    for p in d["meshes"][arm["mesh"]]["primitives"]:
        w = glb.accessor(p["attributes"]["WEIGHTS_0"])
        j = glb.accessor(p["attributes"]["JOINTS_0"]).astype(int)
        assert np.allclose(w.sum(axis=1), 1.0, atol=1e-6) and j.max() == 2
        pos = glb.accessor(p["attributes"]["POSITION"])
        # at the bind pose every joint matrix J_j = World_bind(j) @ IBM_j is the identity:
        # the joints stand straight up from ARM_BASE, the vehicle at its static pose
        base = make_gltf_assets.to_asset(make_gltf_assets.ARM_BASE)
        for k in range(3):
            world = np.eye(4)
            world[:3, 3] = base + [0.0, k * make_gltf_assets.ARM_LENGTH / 3, 0.0]
            assert np.allclose(world @ ibm[k], np.eye(4), atol=1e-6)
        low = pos[:, 1] < base[1] + 0.2
        assert np.all(w[low, 0] == 1.0)                    # the foot follows arm_j0 only
    _, q = glb.track("swing", "arm_j0", "rotation")
    assert np.ptp(q, axis=0).max() > 0.3                   # it swings


# ---------------------------------------------------------------- through the loader

@pytest.fixture(scope="module")
def scene():
    from world.loader import load_scene
    return load_scene("rover")


def test_rover_scene_ids_names_and_parents(scene):
    names = [o.name for o in scene.objects]
    assert names == ["floor", "wall", "rover/body", "rover/wheel_fl", "rover/wheel_fr",
                     "rover/wheel_rl", "rover/wheel_rr", "rover/arm_tip", "rover/arm",
                     "beacon", "aerial"]
    assert [o.id for o in scene.objects] == list(range(1, 12))
    (inst,) = scene.assets
    assert inst.name == "rover"
    assert [inst.asset.animations[i].name for i in inst.animations] == ["drive", "swing"]
    by = {o.name: o for o in scene.objects}
    assert by["beacon"].parent.name == by["aerial"].parent.name == "rover/body"
    assert not scene.camera.moving
    assert [n for n, o in by.items() if o.moving] == names[2:]
    assert by["rover/arm"].skin is not None and by["rover/arm"].skin.moving
    # the decal is an image texture on the body's sides only
    body = by["rover/body"]
    textures = [m.texture for _, _, m in body.parts if m.texture is not None]
    assert len(textures) == 1 and textures[0].kind == "image"


def test_wheel_matrices_turn_about_the_axle_by_the_keys(scene, glb):
    by = {o.name: o for o in scene.objects}
    (inst,) = scene.assets
    for w in WHEELS:
        obj = by[f"rover/{w}"]
        times, _ = glb.track("drive", w, "rotation")
        angle = spin(glb, w)
        offset = glb.doc["nodes"][glb.node(w)].get("translation", [0.0, 0.0, 0.0])
        parent = glb.parent(glb.node(w))
        for t in (0.5, 1.234, 2.88, 2.9, 2.92, 4.51):
            rel = np.linalg.inv(inst.node_matrix(parent, t)) @ obj.matrix(t)
            a = np.interp(t, times, angle)      # slerp about one axis: the angle is linear
            c, s = np.cos(a), np.sin(a)         # a turn by a about -X
            expect = np.array([[1, 0, 0, offset[0]], [0, c, s, offset[1]],
                               [0, -s, c, offset[2]], [0, 0, 0, 1]])
            np.testing.assert_allclose(rel, expect, atol=1e-5)


def test_blur_lengths_at_the_frame_time(scene):
    by = {o.name: o for o in scene.objects}
    cam = Camera(scene.camera, 1280, 720)
    t0, t1 = scene.exposure(scene.render.time)

    def travel(obj, local):
        p = [(np.c_[local, np.ones(len(local))] @ obj.matrix(t).T)[:, :3] for t in (t0, t1)]
        return np.linalg.norm(cam.project(t1, p[1])[0] - cam.project(t0, p[0])[0], axis=1)

    # a wheel's rim against the hub: the wheel's own turn alone smears it across a spoke
    wheel = by["rover/wheel_rr"]
    rim = np.array([[0.09, 0.2 * np.cos(a), 0.2 * np.sin(a)] for a in np.linspace(0, 6, 12)])
    hub = np.array([[0.09, 0.0, 0.0]])
    assert (travel(wheel, rim) - travel(wheel, hub)).max() > 12.0
    assert travel(wheel, rim).max() > 40.0
    # the arm: skinned; its tip (the lamp) moves a moderate distance relative to the body
    arm = by["rover/arm"]
    v0, v1 = arm.vertices_at(t0), arm.vertices_at(t1)
    assert np.abs(v1 - v0).max() > 0.02
    lamp = by["rover/arm_tip"]
    body = by["rover/body"]
    rel = [np.linalg.inv(body.matrix(t)) @ lamp.matrix(t) for t in (t0, t1)]
    assert 0.01 < np.linalg.norm(rel[1][:3, 3] - rel[0][:3, 3]) < 0.2
    # everything of the rover is in the frame at the frame time
    for o in scene.objects[2:]:
        v = o.vertices_at(scene.render.time)
        p = (np.c_[v, np.ones(len(v))] @ o.matrix(scene.render.time).T)[:, :3]
        xy, _ = cam.project(scene.render.time, p)
        assert xy.min() > 0 and xy[:, 0].max() < 1280 and xy[:, 1].max() < 720, o.name
