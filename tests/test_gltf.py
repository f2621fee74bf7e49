"""world/gltf/: the glTF 2.0 reader of scene format v1.2 (no GL).

Real sample assets (tests/conformance/gltf/) for hierarchy, the 180-degree flip, the
embedded PNG and the two-joint skin; tiny assets built by hand (tests/gltf_builder.py)
for the sampler rules against hand-computed values, accessor decoding (byteStride, sparse,
normalized integers), GLB, the channel rules, skinning, and every mistake (GltfError with
its one-line message); a hypothesis property test: corrupted GLBs and mutated documents
load or raise GltfError, never anything else.
"""
from __future__ import annotations

import base64
import copy
import io
import json
import math
import os
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

import world.gltf.reader as gl
from world import limits
from conftest import srgb8_to_linear
from gltf_builder import BYTE, FLOAT, SHORT, UBYTE, UINT, USHORT, Builder, make_glb
from world.gltf import GltfError, GltfSampler, load_gltf, sample
from world.gltf_scene import NodeTree
from world.skinning import joint_matrices, skin_vertices

ASSETS = Path(__file__).resolve().parent / "conformance" / "gltf"
BOX_ANIMATED = ASSETS / "BoxAnimated.gltf"
BOX_TEXTURED = ASSETS / "BoxTextured.gltf"
RIGGED = ASSETS / "RiggedSimple.gltf"

TRI = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)


def rot_x(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_z(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def f32(x) -> float:
    return float(np.float32(x))


def one_triangle(b: Builder | None = None, **node) -> Builder:
    b = b or Builder()
    m = b.triangle_mesh(TRI, [0, 1, 2])
    b.add("nodes", {"mesh": m, **node})
    b.doc["scenes"] = [{"nodes": [0]}]
    return b


def write(tmp_path, doc: dict, name="asset.gltf") -> Path:
    p = tmp_path / name
    p.write_text(json.dumps(doc))
    return p


def err(tmp_path, doc: dict, match: str):
    with pytest.raises(GltfError, match=match) as e:
        load_gltf(write(tmp_path, doc))
    assert "\n" not in str(e.value)
    return str(e.value)


# ---------------------------------------------------------------- the sample assets

def test_box_animated_tree_and_ids():
    a = load_gltf(BOX_ANIMATED)
    assert a.roots == [3, 0]
    assert a.depth_first() == [3, 0, 1, 2]
    assert a.mesh_nodes() == [3, 2]
    assert [n.name for n in a.nodes] == ["node0", "node1", "node2", "node3"]
    assert [n.parent for n in a.nodes] == [None, 0, 1, None]
    assert a.nodes[0].children == [1] and a.nodes[2].mesh == 0 and a.nodes[3].mesh == 1
    assert a.ignored == []
    inner, outer = a.meshes[0][0], a.meshes[1][0]
    assert inner.positions.shape == (96, 3) and inner.faces.shape == (62, 3)
    assert outer.positions.shape == (224, 3) and outer.faces.shape == (192, 3)
    assert inner.faces.dtype == np.int64 and inner.positions.dtype == np.float64
    assert inner.uv is None and inner.joints is None and inner.material == 0
    assert np.abs(outer.positions).max() == 0.5
    np.testing.assert_array_equal(a.materials[0].base_color,
                                  np.float32([0.800000011920929, 0.4159420132637024, 0.7952920198440552, 1.0]))
    assert a.materials[1].name == "outer" and a.materials[1].image is None
    assert [an.name for an in a.animations] == ["animation0"]
    assert a.select() == (0,) and a.select("none") == () and a.select(0) == (0,)
    assert a.select("animation0") == (0,)
    assert a.time_range((0,)) == (0.0, f32(3.708329916000366))
    assert a.time_range(()) == (0.0, 0.0)


def test_box_animated_channels_and_flip():
    a = load_gltf(BOX_ANIMATED)
    anims = a.select()
    assert NodeTree(a).animated(anims).tolist() == [True, False, True, False]
    assert NodeTree(a).moving(anims).tolist() == [True, True, True, False]
    assert not NodeTree(a).animated(()).any() and not NodeTree(a).moving(()).any()
    # translation of node 0: keys 0, 1.25, 2.5, 3.7083 -> (0,0,0), (0,2.52,0), (0,2.52,0), 0
    y = f32(2.5199999809265137)
    loc = NodeTree(a).local_matrices(0.625, anims)
    np.testing.assert_allclose(loc[0][:3, 3], [0, 0.5 * y, 0], rtol=0, atol=1e-15)
    # node 2's rotation: (-0,-0,-0,-1) at 1.25 -> (1,0,0,4.49e-11) at 2.5, 180 degrees apart;
    # the float64 dot product is -4.49e-11 < 0, so the second key is negated and the box
    # turns +90 degrees about x at the segment's middle (y goes to +z), not -90.
    r = NodeTree(a).local_matrices(1.875, anims)[2][:3, :3]
    np.testing.assert_allclose(r, rot_x(90), atol=1e-9)
    np.testing.assert_allclose(r @ [0, 1, 0], [0, 0, 1], atol=1e-9)
    # clamped before its first key (1.25): the static-looking first key, identity
    np.testing.assert_allclose(NodeTree(a).local_matrices(0.3, anims)[2], np.eye(4), atol=1e-15)
    # world: node 2 (mesh) = node0 @ node1 @ node2
    w = NodeTree(a).world_matrices(1.875, anims)
    np.testing.assert_allclose(w[2][:3, 3], [0, y, 0], atol=1e-7)
    np.testing.assert_allclose(w[2][:3, :3], rot_x(90), atol=1e-9)
    np.testing.assert_array_equal(w[3], np.eye(4))
    # without animations: the static pose (rotation -1 = identity)
    np.testing.assert_array_equal(NodeTree(a).world_matrices(1.875, ()), np.tile(np.eye(4), (4, 1, 1)))


def test_world_matrices_memoised_and_read_only():
    tree = NodeTree(load_gltf(BOX_ANIMATED))
    w1 = tree.world_matrices(1.0, (0,))
    assert tree.world_matrices(1.0, (0,)) is w1
    assert tree.world_matrices(1.0, ()) is not w1
    with pytest.raises(ValueError):
        w1[0, 0, 0] = 5.0
    for t in np.linspace(0, 3, 20):
        tree.world_matrices(float(t), (0,))
    assert len(tree._cache) <= 8


def test_box_textured_image_uv_and_matrix():
    a = load_gltf(BOX_TEXTURED)
    assert a.mesh_nodes() == [1]
    part = a.meshes[0][0]
    assert part.uv.shape == (24, 2) and part.uv.max() == 6.0 and part.uv.min() == 0.0
    img = a.materials[0].image
    assert img.dtype == np.float32 and img.shape == (211, 211, 3)
    np.testing.assert_array_equal(a.materials[0].base_color, [1, 1, 1, 1])
    # independent decode of the embedded PNG: top row first, sRGB -> linear
    doc = json.loads(BOX_TEXTURED.read_text())
    png = base64.b64decode(doc["images"][0]["uri"].split(",", 1)[1])
    np.testing.assert_array_equal(img, srgb8_to_linear(Image.open(io.BytesIO(png)).convert("RGB")))
    # nodes[0].matrix is stored column-major: columns (1,0,0), (0,0,-1), (0,1,0)
    m = a.nodes[0].matrix
    np.testing.assert_array_equal(m[:3, :3], [[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    np.testing.assert_array_equal(NodeTree(a).world_matrices(0.0, a.select())[1], m)


def test_rigged_simple_skin():
    a = load_gltf(RIGGED)
    assert a.depth_first() == [0, 1, 3, 4, 2]
    assert a.mesh_nodes() == [2]
    assert a.nodes[2].name == "Cylinder" and a.nodes[2].skin == 0
    sk = a.skins[0]
    assert sk.joints == [3, 4] and sk.inverse_bind.shape == (2, 4, 4)
    # column-major storage: the translation of the first inverse bind is its last column
    assert abs(sk.inverse_bind[0][2, 3] - 4.1803) < 1e-4 and sk.inverse_bind[0][3].tolist() == [0, 0, 0, 1]
    ch = a.animations[0].channels
    assert [(c.node, c.path) for c in ch] == [(4, "translation"), (4, "rotation"), (4, "scale")]
    assert all(c.sampler.times.shape == (50,) and c.sampler.interpolation == "LINEAR" for c in ch)
    assert a.time_range((0,)) == (f32(0.04166661947965622), f32(2.083333015441895))
    anims = a.select()
    joints = a.skins[0].joints
    assert NodeTree(a).moving(anims)[joints].any() and not NodeTree(a).moving(())[joints].any()
    part = a.meshes[0][0]
    assert part.joints.shape == (160, 4) and part.joints.dtype == np.int64
    assert part.weights.shape == (160, 4) and part.joints.max() == 1
    # in the static pose the skin is in its bind pose: both joint matrices are (~) the
    # root's Z_UP matrix (the asset's meshes are bound below it)
    w = NodeTree(a).world_matrices(0.0, ())
    jm = joint_matrices(a.skins[0], w)
    np.testing.assert_allclose(jm, np.stack([w[0], w[0]]), atol=1e-5)
    assert abs(jm[0] - np.eye(4)).max() > 0.9
    # animated: J_j = World(joint_j) @ IBM_j, and skinning equals a per-vertex loop
    w = NodeTree(a).world_matrices(1.3, anims)
    jm = joint_matrices(a.skins[0], w)
    np.testing.assert_array_equal(jm[1], w[4] @ sk.inverse_bind[1])
    pos, nrm = skin_vertices(part.positions, part.normals, part.joints, part.weights, jm)
    for v in (0, 2, 77, 159):
        b = sum(part.weights[v, i] * jm[part.joints[v, i]] for i in range(4)) / part.weights[v].sum()
        np.testing.assert_allclose(pos[v], (b @ np.append(part.positions[v], 1.0))[:3], atol=1e-12)
        n = np.linalg.inv(b[:3, :3]).T @ part.normals[v]
        np.testing.assert_allclose(nrm[v], n / np.linalg.norm(n), atol=1e-12)
    # wrap: time_scale 3 with loop lands inside [A0, A1]
    a0, a1 = a.time_range(anims)
    t = a.animation_time(2.0, anims, time_offset=0.5, time_scale=3.0, loop=True)
    assert a0 <= t < a1
    assert t == pytest.approx(a0 + math.fmod((2.0 - 0.5) * 3.0 - a0, a1 - a0), abs=1e-12)


# ---------------------------------------------------------------- sampling

def smp(times, values, interp="LINEAR"):
    return GltfSampler(np.asarray(times, dtype=np.float64), np.asarray(values, dtype=np.float64), interp)


def wxyz(xyzw) -> np.ndarray:
    """glTF's (x, y, z, w) quaternions in the project's (w, x, y, z) order."""
    return np.asarray(xyzw, dtype=np.float64)[..., [3, 0, 1, 2]]


def test_step():
    s = smp([0, 1, 2], [[0, 0, 0], [10, 0, 0], [20, 0, 0]], "STEP")
    for a, x in [(-1, 0), (0, 0), (0.5, 0), (0.999, 0), (1, 10), (1.5, 10), (1.999, 10), (2, 20), (9, 20)]:
        assert sample(s, a, "translation").tolist() == [x, 0, 0], a


def test_linear_translation_and_clamp():
    s = smp([1, 3, 4], [[0, 0, 0], [2, 4, 6], [0, 0, 10]])
    assert sample(s, 2.0, "translation").tolist() == [1, 2, 3]
    assert sample(s, 1.5, "scale").tolist() == [0.5, 1, 1.5]
    assert sample(s, 3.5, "translation").tolist() == [1, 2, 8]
    assert sample(s, -7, "translation").tolist() == [0, 0, 0]      # clamped to k_0
    assert sample(s, 99, "translation").tolist() == [0, 0, 10]     # clamped to k_(n-1)
    assert sample(s, 4, "translation").tolist() == [0, 0, 10]      # last segment at k_(n-1)
    assert sample(smp([5], [[1, 2, 3]]), 0, "translation").tolist() == [1, 2, 3]


def test_cubicspline_hand_computed():
    # keys at 0 and 2 (d = 2): A0, V0, B0 / A1, V1, B1 in x; at u = 0.5 the Hermite basis is
    # h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125:
    # 0.5 * 1 + 2 * 0.125 * 3 + 0.5 * 7 + 2 * (-0.125) * 5 = 3.5
    vals = [[[9, 0, 0], [1, 0, 0], [3, 0, 0]], [[5, 0, 0], [7, 0, 0], [9, 0, 0]]]
    s = smp([0, 2], vals, "CUBICSPLINE")
    assert sample(s, 1.0, "translation").tolist() == [3.5, 0, 0]
    # u = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = -0.046875
    want = 0.84375 * 1 + 2 * 0.140625 * 3 + 0.15625 * 7 + 2 * -0.046875 * 5
    assert sample(s, 0.5, "translation")[0] == pytest.approx(want, abs=1e-15)
    assert sample(s, 0.0, "translation").tolist() == [1, 0, 0]
    assert sample(s, 2.0, "translation").tolist() == [7, 0, 0]
    assert sample(s, 5.0, "translation").tolist() == [7, 0, 0]
    assert sample(smp([1], [vals[0]], "CUBICSPLINE"), 3, "scale").tolist() == [1, 0, 0]
    # rotation: the Hermite value normalised
    q = [[[0, 0, 0, 0], [0, 0, 0, 1], [0, 0, 0, 0]], [[0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 0]]]
    r = sample(smp([0, 1], wxyz(q), "CUBICSPLINE"), 0.5, "rotation")
    np.testing.assert_allclose(r, wxyz([0, 0, math.sqrt(0.5), math.sqrt(0.5)]), atol=1e-15)


def test_linear_rotation_slerp():
    h = math.sqrt(0.5)
    s = smp([0, 1], wxyz([[0, 0, 0, 1], [0, 0, h, h]]))          # 0 -> 90 degrees about z
    q = sample(s, 0.5, "rotation")
    np.testing.assert_allclose(q, wxyz([0, 0, math.sin(math.pi / 8), math.cos(math.pi / 8)]), atol=1e-15)
    q = sample(s, 0.25, "rotation")
    np.testing.assert_allclose(q, wxyz([0, 0, math.sin(math.pi / 16), math.cos(math.pi / 16)]), atol=1e-15)
    # shortest arc: the second key given as its negative gives the same rotation
    s3 = smp([0, 1], wxyz([[0, 0, 0, 1], [0, 0, -h, -h]]))
    np.testing.assert_allclose(sample(s3, 0.5, "rotation"), sample(s, 0.5, "rotation"), atol=1e-15)
    # tiny angle: normalised lerp, no division by ~0
    e = 1e-9
    s4 = smp([0, 1], wxyz([[0, 0, 0, 1], [0, 0, e, 1]] / np.linalg.norm([0, 0, e, 1], axis=-1, keepdims=True)))
    q4 = sample(s4, 0.5, "rotation")
    np.testing.assert_allclose(q4, wxyz(np.array([0, 0, e / 2, 1]) / np.linalg.norm([0, 0, e / 2, 1])),
                               rtol=0, atol=1e-18)


def test_rotation_180_decided_by_dot_sign():
    r = math.sqrt(0.5)
    # identity -> 180 degrees about x: dot = 0 exactly (not < 0): no negation, +90 at u = 0.5
    s = smp([0, 1], wxyz([[0, 0, 0, 1], [1, 0, 0, 0]]))
    np.testing.assert_allclose(sample(s, 0.5, "rotation"), wxyz([r, 0, 0, r]), atol=1e-15)
    # a hair past 180 (w = -1e-12): dot < 0, second key negated, -90 about x
    s = smp([0, 1], wxyz([[0, 0, 0, 1], [1, 0, 0, -1e-12]]))
    np.testing.assert_allclose(sample(s, 0.5, "rotation"), wxyz([-r, 0, 0, r]), atol=1e-12)
    # -0.0 components: dot = -0.0, which is not < 0
    s = smp([0, 1], wxyz([[0, 0, 0, 1], [-1, 0, 0, -0.0]]))
    np.testing.assert_allclose(sample(s, 0.5, "rotation"), wxyz([-r, 0, 0, r]), atol=1e-15)


def test_step_rotation_and_degenerate_time():
    s = smp([0, 1], wxyz([[0, 0, 0, 1], [0, 0, 1, 0]]), "STEP")
    assert sample(s, 0.9, "rotation").tolist() == [1, 0, 0, 0]
    assert sample(s, 1.0, "rotation").tolist() == [0, 0, 0, 1]
    assert sample(s, float("nan"), "rotation").tolist() == [1, 0, 0, 0]


@pytest.mark.parametrize("interp", ["STEP", "LINEAR", "CUBICSPLINE"])
def test_rotation_keys_reordered_and_normalised_as_read(tmp_path, interp):
    """glTF's (x, y, z, w) keys become (w, x, y, z) at load; STEP and LINEAR keys are
    normalised there (a CUBICSPLINE's are tangents and values: left as they are)."""
    h = math.sqrt(0.5)
    keys = [[0, 0, 0, 3], [0, 0, 2 * h, 2 * h]]
    if interp == "CUBICSPLINE":
        keys = [[0, 0, 0, 0], [0, 0, 0, 3], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 2 * h, 2 * h], [0, 0, 0, 0]]
    a = load_gltf(anim_asset([0, 1], keys, path="rotation", interp=interp).write(tmp_path))
    values = a.animations[0].channels[0].sampler.values
    if interp == "CUBICSPLINE":
        np.testing.assert_array_equal(values[:, 1], np.float32([[3, 0, 0, 0], [2 * h, 0, 0, 2 * h]]))
    else:
        np.testing.assert_allclose(values, [[1, 0, 0, 0], [h, 0, 0, h]], rtol=0, atol=1e-15)
    # half way: STEP holds the first key, LINEAR slerps the unit keys (45 degrees about z),
    # CUBICSPLINE normalises (0, 0, h, 1.5 + h), the mean of its values
    want = {"STEP": 0.0, "LINEAR": 45.0, "CUBICSPLINE": math.degrees(2 * math.atan2(h, 1.5 + h))}[interp]
    m = NodeTree(a).local_matrices(0.5, (0,))[0][:3, :3]
    np.testing.assert_allclose(m, rot_z(want), atol=1e-7 if interp == "CUBICSPLINE" else 1e-15)


def test_animation_time_loop_and_scale(tmp_path):
    b = anim_asset([1.0, 3.0], [[0, 0, 0], [2, 0, 0]])
    a = load_gltf(b.write(tmp_path))
    an = a.select()
    assert a.time_range(an) == (1.0, 3.0)
    assert a.animation_time(5.0, an) == 5.0
    assert a.animation_time(5.0, an, loop=True) == 1.0
    assert a.animation_time(4.5, an, loop=True) == 2.5
    assert a.animation_time(0.5, an, loop=True) == 2.5          # before A0 wraps too
    assert a.animation_time(2.0, an, time_offset=1.0, time_scale=3.0) == 3.0
    assert a.animation_time(2.0, an, time_offset=1.0, time_scale=3.0, loop=True) == 1.0
    assert a.animation_time(3.0, an, loop=True) == 1.0
    assert a.animation_time(7.0, (), loop=True) == 7.0          # A1 == A0: no wrap
    # clamp beyond the range without loop: the last key
    np.testing.assert_array_equal(NodeTree(a).local_matrices(10.0, an)[0][:3, 3], [2, 0, 0])
    np.testing.assert_array_equal(NodeTree(a).local_matrices(2.0, an)[0][:3, 3], [1, 0, 0])


def anim_asset(times, values, path="translation", interp="LINEAR", node_extra=None) -> Builder:
    b = one_triangle(**(node_extra or {}))
    ti = b.accessor(np.float32(times))
    vi = b.accessor(np.float32(values))
    b.add("animations", {"samplers": [{"input": ti, "output": vi, "interpolation": interp}],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": path}}]})
    return b


def test_later_channel_wins(tmp_path):
    b = one_triangle()
    t = b.accessor(np.float32([0, 1]))
    v1 = b.accessor(np.float32([[1, 0, 0], [1, 0, 0]]))
    v2 = b.accessor(np.float32([[0, 5, 0], [0, 5, 0]]))
    v3 = b.accessor(np.float32([[0, 0, 7], [0, 0, 7]]))
    s = lambda o: {"input": t, "output": o}
    b.add("animations", {"name": "first", "samplers": [s(v1), s(v2)],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}},
                                      {"sampler": 1, "target": {"node": 0, "path": "translation"}}]})
    b.add("animations", {"name": "second", "samplers": [s(v3)],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]})
    a = load_gltf(b.write(tmp_path))
    assert a.select("first") == (0,) and a.select("second") == (1,) and a.select(1) == (1,)
    np.testing.assert_array_equal(NodeTree(a).local_matrices(0.5, (0,))[0][:3, 3], [0, 5, 0])
    np.testing.assert_array_equal(NodeTree(a).local_matrices(0.5, (0, 1))[0][:3, 3], [0, 0, 7])
    np.testing.assert_array_equal(NodeTree(a).local_matrices(0.5, (1, 0))[0][:3, 3], [0, 0, 7])
    np.testing.assert_array_equal(NodeTree(a).local_matrices(0.5, ())[0][:3, 3], [0, 0, 0])
    with pytest.raises(GltfError, match=r"no animation named 'third'.*'first'.*'second'"):
        a.select("third")
    with pytest.raises(GltfError, match=r"index 2 out of range"):
        a.select(2)
    with pytest.raises(GltfError, match=r"index -1 out of range"):
        a.select(-1)
    with pytest.raises(GltfError):
        a.select(True)


def test_matrix_node_ignores_channels(tmp_path):
    m = np.eye(4)
    m[:3, 3] = [4, 5, 6]
    b = anim_asset([0, 1], [[1, 0, 0], [3, 0, 0]],
                   node_extra={"matrix": m.T.reshape(-1).tolist(), "children": [1]})
    b.add("nodes", {"translation": [0, 0, 1], "scale": [2, 2, 2]})
    a = load_gltf(b.write(tmp_path))
    an = a.select()
    assert not NodeTree(a).animated(an).any() and not NodeTree(a).moving(an).any()
    np.testing.assert_array_equal(NodeTree(a).local_matrices(0.5, an)[0], m)
    w = NodeTree(a).world_matrices(0.5, an)
    np.testing.assert_array_equal(w[1], m @ np.diag([2.0, 2, 2, 1]) + np.array(
        [[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, 0, 0]]))
    np.testing.assert_array_equal(w[1][:3, 3], [4, 5, 7])


def test_trs_order_and_scale_channel(tmp_path):
    h = math.sqrt(0.5)
    b = anim_asset([0, 2], [[1, 1, 1], [3, 1, 1]], path="scale",
                   node_extra={"translation": [1, 2, 3], "rotation": [0, 0, h, h]})
    a = load_gltf(b.write(tmp_path))
    m = NodeTree(a).local_matrices(1.0, a.select())[0]
    want = np.eye(4)
    want[:3, :3] = rot_z(90) @ np.diag([2, 1, 1])
    want[:3, 3] = [1, 2, 3]
    np.testing.assert_allclose(m, want, atol=1e-15)
    assert NodeTree(a).animated(a.select()).tolist() == [True]


def test_step_and_cubic_through_asset(tmp_path):
    b = anim_asset([0, 1, 2], [[0, 0, 0], [1, 0, 0], [2, 0, 0]], interp="STEP")
    a = load_gltf(b.write(tmp_path))
    assert NodeTree(a).local_matrices(1.5, (0,))[0][0, 3] == 1.0
    vals = [[0, 0, 0], [1, 0, 0], [3, 0, 0], [5, 0, 0], [7, 0, 0], [0, 0, 0]]
    b = anim_asset([0, 2], vals, interp="CUBICSPLINE")
    a = load_gltf(b.write(tmp_path, "c.gltf"))
    assert a.animations[0].channels[0].sampler.values.shape == (2, 3, 3)
    assert NodeTree(a).local_matrices(1.0, (0,))[0][0, 3] == 3.5


# ---------------------------------------------------------------- accessors

def test_byte_stride_interleaved(tmp_path):
    b = Builder()
    pos = np.float32([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    nrm = np.float32([[0, 0, 1], [0, 0, -1], [1, 0, 0]])
    inter = np.concatenate([pos, nrm, np.full((3, 2), 99, np.float32)], axis=1)   # stride 32
    v = b.view(inter.tobytes(), stride=32)
    pa = b.add_accessor({"bufferView": v, "componentType": FLOAT, "count": 3, "type": "VEC3"})
    na = b.add_accessor({"bufferView": v, "byteOffset": 12, "componentType": FLOAT, "count": 3, "type": "VEC3"})
    b.add("meshes", {"primitives": [{"attributes": {"POSITION": pa, "NORMAL": na}}]})
    b.add("nodes", {"mesh": 0})
    a = load_gltf(b.write(tmp_path))
    part = a.meshes[0][0]
    np.testing.assert_array_equal(part.positions, pos)
    np.testing.assert_array_equal(part.normals, nrm)
    np.testing.assert_array_equal(part.faces, [[0, 1, 2]])     # no indices: 0..n-1
    assert a.roots == [0]                                        # no scenes: parentless nodes
    # the same accessor one element too long no longer fits its view (96 bytes)
    b.doc["accessors"][na]["count"] = 4
    msg = err(tmp_path, b.gltf_dict(), r"accessors\[1\]: .* = 120 exceeds bufferViews\[0\] \(96 bytes\)")
    assert msg.startswith("accessors[1]")


def test_sparse_accessors(tmp_path):
    b = Builder()
    base = b.accessor(np.float32([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]))
    iv = b.view(np.uint16([1, 3]).tobytes())
    vv = b.view(np.float32([[5, 5, 5], [7, 7, 7]]).tobytes())
    b.doc["accessors"][base]["sparse"] = {"count": 2, "indices": {"bufferView": iv, "componentType": USHORT},
                                          "values": {"bufferView": vv}}
    # sparse without a bufferView: zeros with substitutions (byteOffset on the values)
    iv2 = b.view(np.uint8([2, 0, 0, 0]).tobytes())
    vv2 = b.view(np.float32([[9, 9, 9], [0, 2, 0]]).tobytes())
    z = b.add_accessor({"componentType": FLOAT, "count": 4, "type": "VEC3",
                        "sparse": {"count": 1, "indices": {"bufferView": iv2, "componentType": UBYTE},
                                   "values": {"bufferView": vv2, "byteOffset": 12}}})
    b.add("meshes", {"primitives": [{"attributes": {"POSITION": base, "NORMAL": z},
                                     "indices": b.accessor(np.uint16([0, 1, 2, 2, 1, 3]), USHORT)}]})
    b.add("nodes", {"mesh": 0})
    a = load_gltf(b.write(tmp_path))
    part = a.meshes[0][0]
    np.testing.assert_array_equal(part.positions, [[0, 0, 0], [5, 5, 5], [0, 1, 0], [7, 7, 7]])
    np.testing.assert_array_equal(part.normals, [[0, 0, 0], [0, 0, 0], [0, 2, 0], [0, 0, 0]])
    np.testing.assert_array_equal(part.faces, [[0, 1, 2], [2, 1, 3]])
    # sparse index past the count, and indices not increasing
    d = b.gltf_dict()
    d["accessors"][z]["sparse"]["indices"]["byteOffset"] = 0
    d["bufferViews"][iv2]["byteLength"] = 4
    b2 = copy.deepcopy(d)
    b2["accessors"][base]["sparse"]["indices"]["componentType"] = UBYTE   # reads 1, 0 ...
    err(tmp_path, b2, r"accessors\[0\]\.sparse\.indices: not strictly increasing")
    b3 = copy.deepcopy(d)
    b3["accessors"][base]["sparse"]["count"] = 5
    err(tmp_path, b3, r"accessors\[0\]\.sparse\.count")


def test_normalized_integers(tmp_path):
    b = Builder()
    j = b.accessor(np.uint8([[0, 1, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]]), UBYTE)
    w = b.accessor(np.uint8([[255, 0, 0, 0], [128, 127, 0, 0], [51, 204, 0, 0]]), UBYTE, normalized=True)
    uv = b.accessor(np.uint16([[0, 65535], [32768, 0], [65535, 65535]]), USHORT, normalized=True)
    n = b.accessor(np.int8([[0, 0, 127], [0, -128, 0], [-127, 0, 0]]), BYTE, normalized=True)
    b.triangle_mesh(TRI, None, JOINTS_0=j, WEIGHTS_0=w, TEXCOORD_0=uv, NORMAL=n)
    b.add("nodes", {"mesh": 0})
    part = load_gltf(b.write(tmp_path)).meshes[0][0]
    assert part.weights.dtype == np.float64 and part.joints.dtype == np.int64
    np.testing.assert_array_equal(part.weights[:, :2], [[1, 0], [128 / 255, 127 / 255], [51 / 255, 204 / 255]])
    np.testing.assert_array_equal(part.uv, [[0, 1], [32768 / 65535, 0], [1, 1]])
    np.testing.assert_array_equal(part.normals, [[0, 0, 1], [0, -1, 0], [-1, 0, 0]])
    np.testing.assert_array_equal(part.joints, [[0, 1, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]])
    # USHORT weights and a SHORT-normalized rotation key
    b = Builder()
    w = b.accessor(np.uint16([[65535, 0, 0, 0]] * 3), USHORT, normalized=True)
    j = b.accessor(np.uint16([[0, 0, 0, 0]] * 3), USHORT)
    b.triangle_mesh(TRI, None, JOINTS_0=j, WEIGHTS_0=w)
    b.add("nodes", {"mesh": 0})
    ti = b.accessor(np.float32([0]))
    ri = b.accessor(np.int16([[0, 0, 32767, 0]]), SHORT, normalized=True)
    b.add("animations", {"samplers": [{"input": ti, "output": ri}],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}]})
    a = load_gltf(b.write(tmp_path, "b.gltf"))
    np.testing.assert_array_equal(a.meshes[0][0].weights[:, 0], [1, 1, 1])
    np.testing.assert_allclose(NodeTree(a).local_matrices(0, (0,))[0][:3, :3], rot_z(180), atol=1e-15)


def test_joints_1_and_weights_1(tmp_path):
    b = Builder()
    j0 = b.accessor(np.uint8([[0, 1, 2, 3]] * 3), UBYTE)
    j1 = b.accessor(np.uint8([[4, 5, 6, 7]] * 3), UBYTE)
    w0 = b.accessor(np.float32([[0.1, 0.1, 0.1, 0.1]] * 3))
    w1 = b.accessor(np.float32([[0.1, 0.1, 0.1, 0.3]] * 3))
    b.triangle_mesh(TRI, None, JOINTS_0=j0, JOINTS_1=j1, WEIGHTS_0=w0, WEIGHTS_1=w1)
    b.add("nodes", {"mesh": 0})
    part = load_gltf(b.write(tmp_path)).meshes[0][0]
    assert part.joints.shape == (3, 8) and part.joints[0].tolist() == list(range(8))
    np.testing.assert_array_equal(part.weights[0], np.float32([0.1] * 7 + [0.3]))


def test_glb_round_trip(tmp_path):
    b = two_joint_bar()
    p = tmp_path / "bar.glb"
    p.write_bytes(b.glb())
    g = load_gltf(p)
    t = load_gltf(b.write(tmp_path))
    for x, y in zip(g.meshes[0], t.meshes[0]):
        for f in ("positions", "normals", "faces", "joints", "weights"):
            np.testing.assert_array_equal(getattr(x, f), getattr(y, f))
    np.testing.assert_array_equal(NodeTree(g).world_matrices(0.7, (0,)), NodeTree(t).world_matrices(0.7, (0,)))
    # the GLB magic decides, whatever the suffix; .glb with JSON inside is a GLB error
    q = tmp_path / "bar.bin.gltf"
    q.write_bytes(b.glb())
    assert load_gltf(q).mesh_nodes() == g.mesh_nodes()
    r = tmp_path / "text.glb"
    r.write_text(json.dumps(b.gltf_dict()))
    with pytest.raises(GltfError, match="GLB: bad magic"):
        load_gltf(r)


def test_glb_written_by_pygltflib(tmp_path):
    """An independent GLB writer: pygltflib's, from the BoxTextured sample (buffer and PNG)."""
    import pygltflib
    g = pygltflib.GLTF2().load(str(BOX_TEXTURED))
    g.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
    out = tmp_path / "box.glb"
    g.save_binary(str(out))
    a, ref = load_gltf(out), load_gltf(BOX_TEXTURED)
    np.testing.assert_array_equal(a.meshes[0][0].uv, ref.meshes[0][0].uv)
    np.testing.assert_array_equal(a.meshes[0][0].positions, ref.meshes[0][0].positions)
    np.testing.assert_array_equal(a.materials[0].image, ref.materials[0].image)


def test_external_files(tmp_path):
    b = one_triangle()
    png = io.BytesIO()
    Image.fromarray(np.array([[[255, 0, 0], [0, 0, 0]], [[0, 255, 0], [188, 188, 188]]], np.uint8)).save(png, "PNG")
    sub = tmp_path / "tex dir"
    sub.mkdir()
    (sub / "a b.png").write_bytes(png.getvalue())
    b.add("images", {"uri": "tex%20dir/a%20b.png"})
    b.add("textures", {"source": 0})
    b.add("materials", {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1},
                                                  "baseColorFactor": [0.5, 1, 1, 1]}})
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    p = b.write(tmp_path, "x.gltf", external="my%20data.bin")
    assert (tmp_path / "my data.bin").exists()
    a = load_gltf(p)
    img = a.materials[0].image
    assert img.shape == (2, 2, 3)
    np.testing.assert_array_equal(img[0, 0], [1, 0, 0])                  # top-left first
    np.testing.assert_array_equal(img[1, 0], [0, 1, 0])
    want = np.float32(((188 / 255 + 0.055) / 1.055) ** 2.4)
    assert img[1, 1, 0] == want
    assert a.materials[0].base_color.tolist() == [0.5, 1, 1, 1]
    assert a.meshes[0][0].material == 0
    assert "alpha" not in a.ignored


def test_ignored_features(tmp_path):
    b = one_triangle()
    c = b.accessor(np.float32([[1, 0, 0, 1]] * 3))
    b.doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = c
    b.doc["meshes"][0]["primitives"][0]["targets"] = [{"POSITION": b.accessor(TRI)}]
    b.doc["meshes"][0]["weights"] = [0.5]
    b.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 1, "znear": 0.1}}]
    b.doc["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_unlit", "KHR_materials_ior"]
    b.doc["extensionsRequired"] = ["KHR_materials_unlit"]
    t = b.accessor(np.float32([0, 1]))
    w = b.accessor(np.float32([0, 1]))
    b.add("animations", {"samplers": [{"input": t, "output": w}],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}]})
    a = load_gltf(b.write(tmp_path))
    for what in ("vertex colours", "morph targets (meshes[0])", "cameras", "KHR_lights_punctual",
                 "KHR_materials_* extensions", "weights channels"):
        assert a.ignored.count(what) == 1, (what, a.ignored)
    assert a.animations[0].channels == []
    assert a.time_range((0,)) == (0.0, 1.0)      # the weights sampler's keys still span the range
    assert not NodeTree(a).animated((0,)).any()


# ---------------------------------------------------------------- skinning

def two_joint_bar(weights_scale: float = 1.0) -> Builder:
    """A bar along x with joint 0 at the origin and joint 1 at x = 1 (a child of joint 0),
    whose rotation about z is animated 0 -> 180 degrees over a = 0..2 (90 at a = 1).
    Vertices: (0,0,0) on joint 0, (1,0,0) and (1.5,0,0) half and half, (2,0,0) on joint 1."""
    b = Builder()
    pos = np.float32([[0, 0, 0], [1, 0, 0], [1.5, 0, 0], [2, 0, 0], [2, 0, 0], [1.5, 0, 0]])
    nrm = np.float32([[0, 1, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]])
    joints = b.accessor(np.uint8([[0, 1, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0], [1, 0, 0, 0],
                                  [1, 0, 0, 0], [0, 1, 0, 0]]), UBYTE)
    w = np.float32([[1, 0, 0, 0], [.5, .5, 0, 0], [.5, .5, 0, 0], [1, 0, 0, 0], [1, 0, 0, 0], [.5, .5, 0, 0]])
    weights = b.accessor(w * np.float32(weights_scale))
    mesh = b.triangle_mesh(pos, [0, 1, 2, 3, 4, 5], NORMAL=b.accessor(nrm), JOINTS_0=joints, WEIGHTS_0=weights)
    ibm = np.stack([np.eye(4), np.eye(4)])
    ibm[1][:3, 3] = [-1, 0, 0]
    ibm_acc = b.accessor(ibm.transpose(0, 2, 1).reshape(2, 16).astype(np.float32), FLOAT, "MAT4")
    b.add("nodes", {"name": "root", "children": [1]})
    b.add("nodes", {"name": "elbow", "translation": [1, 0, 0]})
    b.add("nodes", {"name": "bar", "mesh": mesh, "skin": 0, "translation": [100, 0, 0]})
    b.add("skins", {"joints": [0, 1], "inverseBindMatrices": ibm_acc})
    h = math.sqrt(0.5)
    t = b.accessor(np.float32([0, 1, 2]))
    r = b.accessor(np.float32([[0, 0, 0, 1], [0, 0, h, h], [0, 0, 1, 0]]))
    b.add("animations", {"name": "bend", "samplers": [{"input": t, "output": r}],
                         "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}]})
    b.doc["scenes"] = [{"nodes": [0, 2]}]
    b.doc["scene"] = 0
    return b


@pytest.mark.parametrize("weights_scale", [1.0, 2.0, 0.25])
def test_two_joint_bar(tmp_path, weights_scale):
    a = load_gltf(two_joint_bar(weights_scale).write(tmp_path))
    assert a.mesh_nodes() == [2] and a.depth_first() == [0, 1, 2]
    anims = a.select("bend")
    assert NodeTree(a).moving(anims).tolist() == [False, True, False]
    part = a.meshes[0][0]
    jm = joint_matrices(a.skins[0], NodeTree(a).world_matrices(1.0, anims))
    pos, nrm = skin_vertices(part.positions, part.normals, part.joints, part.weights, jm)
    # joint 1 = T(1,0,0) Rz(90) T(-1,0,0): (2,0,0) -> (1,1,0); (1.5,0,0) -> (1,0.5,0), half with (1.5,0,0)
    np.testing.assert_allclose(pos, [[0, 0, 0], [1, 0, 0], [1.25, 0.25, 0], [1, 1, 0], [1, 1, 0],
                                     [1.25, 0.25, 0]], atol=1e-15)
    r = math.sqrt(0.5)
    # B = (I + Rz90) / 2 on the half-and-half vertices: its inverse transpose turns by 45 degrees
    np.testing.assert_allclose(nrm, [[0, 1, 0], [-r, r, 0], [-r, r, 0], [-1, 0, 0], [0, 0, 1], [0, 0, 1]],
                               atol=1e-15)
    # a = 0: bind pose, everything in place (the skinned node's own World is not applied)
    jm0 = joint_matrices(a.skins[0], NodeTree(a).world_matrices(0.0, anims))
    p0, n0 = skin_vertices(part.positions, part.normals, part.joints, part.weights, jm0)
    np.testing.assert_allclose(p0, part.positions, atol=1e-15)
    np.testing.assert_allclose(n0, part.normals, atol=1e-15)


def test_skin_normals_singular_and_mirror():
    p = np.array([[1.0, 2, 3], [1, 1, 1]])
    n = np.array([[0.0, 0, 1], [1, 0, 0]])
    j = np.zeros((2, 4), np.int64)
    w = np.array([[1.0, 0, 0, 0]] * 2)
    flat = np.diag([1.0, 1, 0, 1])[None]                       # squashes z: det 0
    pos, nrm = skin_vertices(p, n, j, w, flat)
    np.testing.assert_array_equal(pos, [[1, 2, 0], [1, 1, 0]])
    assert np.isfinite(nrm).all()
    np.testing.assert_array_equal(nrm, [[0, 0, 1], [0, 0, 0]])  # cofactor: z survives, x -> 0
    mirror = np.diag([-1.0, 2, 1, 1])[None]                    # det < 0: the sign keeps direction
    _, nm = skin_vertices(p, n, j, w, mirror)
    np.testing.assert_allclose(nm, [[0, 0, 1], [-1, 0, 0]], atol=1e-15)
    _, raw = skin_vertices(p, n, j, w, np.diag([2.0, 2, 4, 1])[None], normalize_normals=False)
    np.testing.assert_allclose(raw, [[0, 0, 0.25], [0.5, 0, 0]], atol=1e-15)
    # zero-weight influences ignore their joint index, even out of range
    j2 = np.array([[0, 9, 9, 9]] * 2)
    pos2, _ = skin_vertices(p, n, j2, w, flat)
    np.testing.assert_array_equal(pos2, pos)
    assert skin_vertices(p, None, j, w, flat)[1] is None


def test_skinning_100k_vertices_matches_the_formula_at_a_vertex():
    rng = np.random.default_rng(1)
    n = 100_000
    p, nr = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    j = rng.integers(0, 20, size=(n, 4))
    w = rng.random((n, 4))
    jm = np.tile(np.eye(4), (20, 1, 1)) + rng.normal(scale=0.1, size=(20, 4, 4))
    pos, nrm = skin_vertices(p, nr, j, w, jm)
    v = 12345
    b = sum(w[v, i] * jm[j[v, i]] for i in range(4)) / w[v].sum()
    np.testing.assert_allclose(pos[v], (b @ np.append(p[v], 1))[:3], atol=1e-12)


def test_skin_mistakes_at_load(tmp_path):
    b = two_joint_bar()
    d = b.gltf_dict()
    # weights summing to 0 at vertex 2
    bb = two_joint_bar()
    acc = bb.doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"]
    bb.doc["accessors"][acc]["sparse"] = {
        "count": 1, "indices": {"bufferView": bb.view(np.uint8([2, 0, 0, 0]).tobytes()), "componentType": UBYTE},
        "values": {"bufferView": bb.view(np.float32([0, 0, 0, 0]).tobytes())}}
    err(tmp_path, bb.gltf_dict(), r"nodes\[2\] .*weights of vertex 2 sum to 0\.0")
    # joint index 2 with a non-zero weight, the skin has 2 joints
    bb = two_joint_bar()
    acc = bb.doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"]
    bb.doc["accessors"][acc]["sparse"] = {
        "count": 1, "indices": {"bufferView": bb.view(np.uint8([3, 0, 0, 0]).tobytes()), "componentType": UBYTE},
        "values": {"bufferView": bb.view(np.uint8([2, 0, 0, 0]).tobytes())}}
    err(tmp_path, bb.gltf_dict(), r"vertex 3 uses joint 2, but the skin has 2 joints")
    d2 = copy.deepcopy(d)
    d2["skins"][0]["joints"] = []
    err(tmp_path, d2, r"skins\[0\]\.joints: a skin with no joints")
    d2["skins"][0]["joints"] = [0, 7]
    err(tmp_path, d2, r"skins\[0\]\.joints: 7 is not an index of nodes \(3 entries\)")
    d2 = copy.deepcopy(d)
    del d2["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"]
    err(tmp_path, d2, r"JOINTS_0 and WEIGHTS_0 must come together")
    d2 = copy.deepcopy(d)
    del d2["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"]
    del d2["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"]
    err(tmp_path, d2, r"a skinned primitive needs JOINTS_0 and WEIGHTS_0")
    d2 = copy.deepcopy(d)
    d2["nodes"][2]["skin"] = 1
    err(tmp_path, d2, r"nodes\[2\]\.skin: 1 is not an index of skins \(1 entries\)")
    d2 = copy.deepcopy(d)
    d2["skins"][0]["inverseBindMatrices"] = 0      # the POSITION accessor: VEC3
    err(tmp_path, d2, r"skins\[0\]\.inverseBindMatrices: accessors\[0\] is VEC4, expected MAT4")
    d2 = copy.deepcopy(d)
    del d2["skins"][0]["inverseBindMatrices"]
    a = load_gltf(write(tmp_path, d2))
    np.testing.assert_array_equal(a.skins[0].inverse_bind, np.tile(np.eye(4), (2, 1, 1)))


# ---------------------------------------------------------------- mistakes

def test_file_mistakes(tmp_path, monkeypatch):
    with pytest.raises(GltfError, match="cannot read .*missing.gltf"):
        load_gltf(tmp_path / "missing.gltf")
    with pytest.raises(GltfError, match="is not a regular file"):
        load_gltf(tmp_path)
    with pytest.raises(GltfError, match=r"cannot read .*a\\nb\.gltf") as e:
        load_gltf(tmp_path / "a\nb.gltf")
    assert "\n" not in str(e.value)
    fifo = tmp_path / "fifo.gltf"
    os.mkfifo(fifo)
    with pytest.raises(GltfError, match="is not a regular file"):
        load_gltf(fifo)
    p = one_triangle().write(tmp_path)
    monkeypatch.setattr(limits, "MAX_GLTF_FILE_BYTES", 100)
    with pytest.raises(GltfError, match=r"asset: .* is \d+ bytes, more than the limit of 100"):
        load_gltf(p)


def test_json_and_version_mistakes(tmp_path):
    p = tmp_path / "a.gltf"
    p.write_text('{"asset": {"version": "2.0"},')
    with pytest.raises(GltfError, match="JSON syntax error at line 1"):
        load_gltf(p)
    p.write_text('{"asset": {"version": "2.0"}, "nodes": [{"translation": [NaN, 0, 0]}]}')
    with pytest.raises(GltfError, match="bad JSON"):
        load_gltf(p)
    p.write_bytes(b'{"asset": {"version": "2.0"}, "x": "\xff"}')
    with pytest.raises(GltfError, match="not UTF-8"):
        load_gltf(p)
    p.write_text("[1, 2]")
    with pytest.raises(GltfError, match="top level is not a JSON object"):
        load_gltf(p)
    p.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(GltfError):
        load_gltf(p)
    for v in ("2.1", "2", "1.0", 2.0, None):
        d = one_triangle().gltf_dict()
        d["asset"]["version"] = v
        err(tmp_path, d, r"asset\.version is .*expected exactly \"2\.0\"")
    d = one_triangle().gltf_dict()
    del d["asset"]
    err(tmp_path, d, "missing asset")
    # the minimal asset: only "asset"
    a = load_gltf(write(tmp_path, {"asset": {"version": "2.0"}}))
    assert a.nodes == [] and a.roots == [] and a.mesh_nodes() == []
    assert NodeTree(a).world_matrices(0.0, ()).shape == (0, 4, 4)


def test_glb_mistakes(tmp_path):
    good = one_triangle().glb()
    p = tmp_path / "a.glb"

    def bad(data, match):
        p.write_bytes(data)
        with pytest.raises(GltfError, match=match):
            load_gltf(p)

    p.write_bytes(good)
    assert load_gltf(p).mesh_nodes() == [0]
    bad(good[:2], "GLB: truncated header")
    bad(b"gltF" + good[4:], "GLB: bad magic")
    bad(good[:4] + struct.pack("<I", 1) + good[8:], "GLB: header version 1, expected 2")
    bad(good[:-4], r"GLB: header length \d+ exceeds the file \(\d+ bytes\): truncated")
    cut = good[:-4]
    bad(cut[:8] + struct.pack("<I", len(cut)) + cut[12:], r"GLB: chunk 1: length \d+ .*truncated")
    js_len = struct.unpack_from("<I", good, 12)[0]
    bad(good[:16] + struct.pack("<I", 0x004E4942) + good[20:], "GLB: the first chunk is not JSON")
    only_js = good[:20 + js_len]
    p.write_bytes(only_js[:8] + struct.pack("<I", len(only_js)) + only_js[12:])
    with pytest.raises(GltfError, match=r"buffers\[0\]: no uri \(and no GLB BIN chunk\)"):
        load_gltf(p)
    # BIN chunk shorter than the buffer's byteLength
    doc = one_triangle()._doc_with_buffer(None)
    doc["buffers"][0]["byteLength"] += 8
    bad(make_glb(doc, bytes(one_triangle().bin)), r"buffers\[0\]: \d+ bytes of data, shorter than its byteLength")


@pytest.mark.parametrize("name,msg", [
    ("KHR_draco_mesh_compression", "compressed geometry"),
    ("EXT_meshopt_compression", "compressed geometry"),
    ("EXT_texture_webp", "is not supported"),
])
def test_required_extensions(tmp_path, name, msg):
    d = one_triangle().gltf_dict()
    d["extensionsRequired"] = [name]
    d["extensionsUsed"] = [name]
    err(tmp_path, d, rf"extensionsRequired: {name}.*{msg}")


def test_uri_mistakes(tmp_path):
    sub = tmp_path / "asset"
    sub.mkdir()
    (tmp_path / "outside.bin").write_bytes(b"\0" * 64)
    b = one_triangle()
    d = b.gltf_dict()
    for uri, match in [("nothere.bin", r"buffers\[0\]\.uri: cannot read .*nothere\.bin"),
                       ("../outside.bin", r"buffers\[0\]\.uri: \"\.\./outside\.bin\" leaves the asset's folder"),
                       ("%2E%2E/outside.bin", r"leaves the asset's folder"),
                       (str(tmp_path / "outside.bin"), "not a relative path"),
                       ("file:///etc/passwd", "only relative file paths and data URIs"),
                       ("http://example.com/a.bin", "only relative file paths and data URIs"),
                       ("data:application/octet-stream;base64,@@@", r"bad base64 in data URI"),
                       ("data:application/octet-stream;base64", r"bad data URI \(no comma\)"),
                       (".", r"is not a regular file"),
                       ]:
        d2 = copy.deepcopy(d)
        d2["buffers"][0]["uri"] = uri
        with pytest.raises(GltfError, match=match):
            load_gltf(write(sub, d2))
    os.symlink(tmp_path / "outside.bin", sub / "link.bin")
    d2 = copy.deepcopy(d)
    d2["buffers"][0]["uri"] = "link.bin"
    with pytest.raises(GltfError, match="leaves the asset's folder"):
        load_gltf(write(sub, d2))
    os.mkfifo(sub / "pipe.bin")
    d2["buffers"][0]["uri"] = "pipe.bin"
    with pytest.raises(GltfError, match="not a regular file"):
        load_gltf(write(sub, d2))
    d2 = copy.deepcopy(d)
    d2["buffers"][0]["byteLength"] += 1
    with pytest.raises(GltfError, match=r"buffers\[0\]: \d+ bytes of data, shorter than its byteLength"):
        load_gltf(write(sub, d2))
    d2 = copy.deepcopy(d)
    del d2["buffers"][0]["uri"]
    with pytest.raises(GltfError, match=r"buffers\[0\]: no uri"):
        load_gltf(write(sub, d2))


def mutate(d: dict, path: str, value):
    """Set d[a][b]... for a dotted path ("accessors.0.count"); value None deletes."""
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    o = d
    for k in keys[:-1]:
        o = o[k]
    if value is None:
        del o[keys[-1]]
    else:
        o[keys[-1]] = value


BASE_MISTAKES = [
    # (path, value, message)
    ("bufferViews.0.byteLength", 10_000, r"bufferViews\[0\]: byteOffset \+ byteLength = \d+ exceeds buffers\[0\]"),
    ("bufferViews.0.byteStride", 2, r"bufferViews\[0\]\.byteStride: expected an integer in \[4, 252\]"),
    ("bufferViews.0.byteStride", 6, r"bufferViews\[0\]\.byteStride: 6 is not a multiple of 4"),
    ("bufferViews.0.byteStride", 8, r"accessors\[0\]: bufferViews\[0\]\.byteStride 8 is smaller than the element \(12 bytes\)"),
    ("bufferViews.0.buffer", 3, r"bufferViews\[0\]\.buffer: 3 is not an index of buffers"),
    ("accessors.0.count", 4, r"accessors\[0\]: .* = 48 exceeds bufferViews\[0\] \(36 bytes\)"),
    ("accessors.0.byteOffset", 4, r"accessors\[0\]: .* = 40 exceeds bufferViews\[0\] \(36 bytes\)"),
    ("accessors.0.componentType", 5124, r"accessors\[0\]\.componentType: 5124 is not a glTF component type"),
    ("accessors.0.type", "VEC5", r"accessors\[0\]\.type: \"VEC5\" is not a glTF accessor type"),
    ("accessors.0.type", "VEC2", r"POSITION: accessors\[0\] is VEC2, expected VEC3"),
    ("accessors.1.componentType", FLOAT, r"indices: accessors\[1\] has componentType 5126, not allowed here"),
    ("accessors.0.normalized", "yes", r"accessors\[0\]\.normalized: expected true or false"),
    ("accessors.0.count", 0, r"accessors\[0\]\.count: expected an integer >= 1"),
    ("accessors.0.count", 2**40, r"the scene draws 1099511627776 vertices, more than the limit of 6000000 "
                                 r"\(a mesh counts once for each node drawing it: meshes\[0\]'s 1099511627776 by 1 node\)"),
    ("accessors.0.bufferView", 9, r"accessors\[0\]\.bufferView: 9 is not an index of bufferViews"),
    ("meshes.0.primitives.0.mode", 1, r"meshes\[0\]\.primitives\[0\]: primitives must be triangles \(mode 4\)"),
    ("meshes.0.primitives.0.mode", 5, r"primitives must be triangles \(mode 4\), this one has mode 5"),
    ("meshes.0.primitives.0.attributes.POSITION", 5, r"attributes\.POSITION: 5 is not an index of accessors"),
    ("meshes.0.primitives.0.attributes", {}, r"meshes\[0\]\.primitives\[0\]\.attributes: no POSITION"),
    ("meshes.0.primitives.0.material", 0, r"meshes\[0\]\.primitives\[0\]\.material: 0 is not an index of materials \(0 entries\)"),
    ("meshes.0.primitives", [], r"meshes\[0\]\.primitives: empty"),
    ("nodes.0.mesh", 1, r"nodes\[0\]\.mesh: 1 is not an index of meshes \(1 entries\)"),
    ("nodes.0.children", [0], r"nodes\[0\]\.children: the node is its own child"),
    ("nodes.0.children", [4], r"nodes\[0\]\.children: 4 is not an index of nodes"),
    ("nodes.0.rotation", [0, 0, 0, 0], r"nodes\[0\]\.rotation: a zero quaternion"),
    ("nodes.0.translation", [0, 0], r"nodes\[0\]\.translation: expected 3 finite numbers"),
    ("nodes.0.matrix", [1] * 15, r"nodes\[0\]\.matrix: expected 16 finite numbers"),
    ("nodes.0.scale", [1, True, 1], r"nodes\[0\]\.scale: expected 3 finite numbers"),
    ("scene", 1, r"scene\.scene: 1 is not an index of scenes"),
    ("scenes.0.nodes", [3], r"scenes\[0\]\.nodes: 3 is not an index of nodes"),
    ("scenes.0.nodes", [0, 0], r"scenes\[0\]\.nodes: nodes\[0\] listed twice"),
    ("nodes", {}, r"nodes: expected an array"),
    ("extensionsRequired", "KHR_draco_mesh_compression", r"extensionsRequired: expected an array of strings"),
]


@pytest.mark.parametrize("path,value,match", BASE_MISTAKES)
def test_structure_mistakes(tmp_path, path, value, match):
    d = one_triangle().gltf_dict()
    d["scene"] = 0
    mutate(d, path, value)
    msg = err(tmp_path, d, match)
    assert len(msg) < 300


def test_index_and_value_mistakes(tmp_path):
    b = Builder()
    b.triangle_mesh(TRI, [0, 1, 3])
    b.add("nodes", {"mesh": 0})
    err(tmp_path, b.gltf_dict(), r"meshes\[0\]\.primitives\[0\]\.indices: index 3 out of range of the 3 vertices")
    b = Builder()
    b.triangle_mesh(TRI, [0, 1, 2, 0])
    b.add("nodes", {"mesh": 0})
    err(tmp_path, b.gltf_dict(), r"indices: 4 indices, not a multiple of 3")
    b = Builder()
    b.triangle_mesh(np.float32([[0, 0, 0], [np.nan, 0, 0], [0, 1, 0]]))
    b.add("nodes", {"mesh": 0})
    err(tmp_path, b.gltf_dict(), r"meshes\[0\]\.primitives\[0\]\.attributes\.POSITION: non-finite values")
    b = Builder()
    b.triangle_mesh(np.float32(np.zeros((4, 3))))
    b.add("nodes", {"mesh": 0})
    err(tmp_path, b.gltf_dict(), r"4 vertices without indices, not a multiple of 3")
    b = one_triangle()
    b.doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = b.accessor(np.float32([[0, 0, 1]] * 4))
    err(tmp_path, b.gltf_dict(), r"attributes\.NORMAL: 4 elements, POSITION has 3")


def test_graph_mistakes(tmp_path):
    d = {"asset": {"version": "2.0"}, "nodes": [{"children": [1]}, {"children": [2]}, {"children": [1]}]}
    err(tmp_path, d, r"nodes\[1\] has two parents \(nodes\[0\] and nodes\[2\]\)")
    d = {"asset": {"version": "2.0"}, "nodes": [{"children": [1]}, {"children": [0]}]}
    err(tmp_path, d, r"nodes\[0\]: the node graph has a cycle")
    d = {"asset": {"version": "2.0"}, "nodes": [{"children": [1]}, {}], "scenes": [{"nodes": [1]}]}
    err(tmp_path, d, r"scenes\[0\]\.nodes: nodes\[1\] is not a root \(its parent is nodes\[0\]\)")
    d = {"asset": {"version": "2.0"}, "nodes": [{"name": "a", "children": [2, 1]}, {}, {"children": [3]}, {}],
         "scenes": [{"nodes": [0]}, {"nodes": [1]}]}
    a = load_gltf(write(tmp_path, d))
    assert a.roots == [0] and a.depth_first() == [0, 2, 3, 1]
    assert [n.name for n in a.nodes] == ["a", "node1", "node2", "node3"]
    d["scene"] = 1
    with pytest.raises(GltfError, match=r"scenes\[1\]\.nodes: nodes\[1\] is not a root"):
        load_gltf(write(tmp_path, d))


def test_animation_mistakes(tmp_path):
    def doc(times, values, **extra):
        d = anim_asset(times, values).gltf_dict()
        for k, v in extra.items():
            mutate(d, k, v)
        return d

    good = [[0, 0, 0], [1, 0, 0], [2, 0, 0]]
    err(tmp_path, doc([0, 2, 1], good),
        r"animations\[0\]\.samplers\[0\]\.input: key times not strictly increasing \(key 2: 1\.0 after 2\.0\)")
    err(tmp_path, doc([0, 1, 1], good), r"key times not strictly increasing")
    err(tmp_path, doc([0, np.nan, 1], good), r"animations\[0\]\.samplers\[0\]\.input: non-finite key times")
    err(tmp_path, doc([0, 1, np.inf], good), r"non-finite key times")
    err(tmp_path, doc([0, 1, 2], [[0, 0, 0], [np.inf, 0, 0], [0, 0, 0]]),
        r"animations\[0\]\.samplers\[0\]\.output: non-finite key values")
    err(tmp_path, doc([0, 1, 2], good[:2]),
        r"animations\[0\]\.samplers\[0\]: 3 key times but 2 output values \(expected 3 for LINEAR\)")
    err(tmp_path, doc([0, 1, 2], good, **{"animations.0.samplers.0.interpolation": "CUBICSPLINE"}),
        r"3 key times but 3 output values \(expected 9 for CUBICSPLINE\)")
    err(tmp_path, doc([0, 1, 2], good, **{"animations.0.samplers.0.interpolation": "SMOOTH"}),
        r"interpolation: \"SMOOTH\" is not STEP, LINEAR or CUBICSPLINE")
    err(tmp_path, doc([0, 1, 2], good, **{"animations.0.channels.0.target.node": 1}),
        r"animations\[0\]\.channels\[0\]\.target\.node: 1 is not an index of nodes \(1 entries\)")
    err(tmp_path, doc([0, 1, 2], good, **{"animations.0.channels.0.sampler": 1}),
        r"animations\[0\]\.channels\[0\]\.sampler: 1 is not an index of animations\[0\]\.samplers")
    err(tmp_path, doc([0, 1, 2], good, **{"animations.0.channels.0.target.path": "rotation"}),
        r"samplers\[0\]\.output: accessors\[3\] is VEC3, expected VEC4")
    err(tmp_path, doc([0, 1, 2], good, **{"animations.0.channels.0.target.path": 7}),
        r"target\.path: 7 is not translation, rotation, scale or weights")
    d = anim_asset([0, 1], [[0, 0, 0, 1], [0, 0, 0, 0]], path="rotation").gltf_dict()
    err(tmp_path, d, r"output: a zero rotation quaternion")


def test_image_mistakes(tmp_path, monkeypatch):
    def doc(image: dict):
        b = one_triangle()
        b.add("images", image)
        b.add("textures", {"source": 0})
        b.add("materials", {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
        return b

    err(tmp_path, doc({"uri": "data:image/png;base64," + base64.b64encode(b"not a png").decode()}).gltf_dict(),
        r"images\[0\]: cannot decode the image")
    gif = io.BytesIO()
    Image.new("RGB", (2, 2)).save(gif, "GIF")
    err(tmp_path, doc({"uri": "data:image/gif;base64," + base64.b64encode(gif.getvalue()).decode()}).gltf_dict(),
        r"images\[0\]: cannot decode the image")
    png = io.BytesIO()
    Image.new("RGB", (64, 32), (255, 255, 255)).save(png, "PNG")
    b = doc({"bufferView": 0, "mimeType": "image/png"})
    b.doc["images"][0]["bufferView"] = b.view(png.getvalue())
    a = load_gltf(b.write(tmp_path))
    assert a.materials[0].image.shape == (32, 64, 3) and (a.materials[0].image == 1.0).all()
    monkeypatch.setattr(limits, "MAX_IMAGE_PIXELS", 1000)
    err(tmp_path, b.gltf_dict(), r"images\[0\]: 64x32 pixels, more than the limit of 1000 for one image")
    monkeypatch.undo()
    err(tmp_path, doc({"uri": "missing.png"}).gltf_dict(), r"images\[0\]\.uri: cannot read")
    err(tmp_path, doc({}).gltf_dict(), r"images\[0\]: neither uri nor bufferView")
    # truncated PNG
    err(tmp_path, doc({"uri": "data:image/png;base64," + base64.b64encode(png.getvalue()[:60]).decode()}).gltf_dict(),
        r"images\[0\]: cannot decode")
    # 16-bit grey PNG keeps its precision
    png16 = io.BytesIO()
    Image.fromarray(np.array([[0, 65535], [32768, 1000]], dtype=np.uint16)).save(png16, "PNG")
    a = load_gltf(write(tmp_path, doc({"uri": "data:image/png;base64," + base64.b64encode(png16.getvalue()).decode()}).gltf_dict()))
    img = a.materials[0].image
    assert img[0, 1, 0] == 1.0 and img[0, 0, 2] == 0.0
    assert img[1, 0, 0] == np.float32(((32768 / 65535 + 0.055) / 1.055) ** 2.4)


def test_hostile_sizes_fail_before_allocating(tmp_path):
    # an accessor without bufferView: zeros of `count` elements, bounded
    d = {"asset": {"version": "2.0"},
         "accessors": [{"componentType": FLOAT, "count": 2**31, "type": "VEC3"}],
         "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}
    err(tmp_path, d, r"accessors\[0\]: count 2147483648 makes the asset larger than the limit")
    # many nodes instancing one mesh: the scene's total is bounded
    b = Builder()
    b.triangle_mesh(np.zeros((3 * 2**12, 3), np.float32))
    d = b.gltf_dict()
    d["nodes"] = [{"mesh": 0}] * 5000
    err(tmp_path, d, r"the scene draws 20480000 triangles, more than the limit of 2000000 \(a mesh "
                     r"counts once for each node drawing it: meshes\[0\]'s 4096 by 5000 nodes\)")


# ---------------------------------------------------------------- properties

def _valid_glb() -> bytes:
    b = two_joint_bar()
    png = io.BytesIO()
    Image.new("RGB", (4, 4), (10, 200, 30)).save(png, "PNG")
    b.add("images", {"bufferView": b.view(png.getvalue()), "mimeType": "image/png"})
    b.add("textures", {"source": 0})
    b.add("materials", {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    uv = b.accessor(np.uint16([[0, 0]] * 6), USHORT, normalized=True)
    b.doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = uv
    return b.glb()


VALID_GLB = _valid_glb()
PROPS = dict(max_examples=300, deadline=None, derandomize=True,
             suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _load_direct(path: Path):
    """The reader itself, without load_gltf's last-resort wrapper: any other exception is a bug."""
    try:
        return gl._Reader(path).load()
    except GltfError:
        return None


def test_valid_glb_loads(tmp_path):
    p = tmp_path / "v.glb"
    p.write_bytes(VALID_GLB)
    a = _load_direct(p)
    assert a is not None and a.materials[0].image.shape == (4, 4, 3)


@settings(**PROPS)
@given(st.lists(st.tuples(st.integers(0, len(VALID_GLB) - 1), st.integers(0, 255)), min_size=1, max_size=6),
       st.one_of(st.none(), st.integers(0, len(VALID_GLB))))
def test_corrupted_glb_loads_or_raises_gltf_error(tmp_path_factory, edits, cut):
    data = bytearray(VALID_GLB)
    for pos, val in edits:
        data[pos] = val
    if cut is not None:
        data = data[:cut]
    p = tmp_path_factory.mktemp("glb") / "c.glb"
    p.write_bytes(bytes(data))
    a = _load_direct(p)
    if a is not None:                     # whatever loaded evaluates without raising
        an = a.select()
        w = NodeTree(a).world_matrices(0.5, an)
        for i in a.mesh_nodes():
            nd = a.nodes[i]
            for part in a.meshes[nd.mesh]:
                if nd.skin is not None:
                    skin_vertices(part.positions, part.normals, part.joints, part.weights,
                                  joint_matrices(a.skins[nd.skin], w))


_json_values = st.one_of(st.none(), st.booleans(), st.integers(-3, 40), st.integers(-(2**64), 2**64),
                         st.floats(allow_nan=False), st.text(max_size=6),
                         st.lists(st.integers(-2, 20), max_size=5),
                         st.lists(st.floats(-5, 5), max_size=17), st.dictionaries(st.text(max_size=3), st.integers(), max_size=2))


def _paths(o, prefix=()):
    yield prefix
    if isinstance(o, dict):
        for k, v in o.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(o, list):
        for i, v in enumerate(o):
            yield from _paths(v, prefix + (i,))


BASE_DOC = json.loads(VALID_GLB[20:20 + struct.unpack_from("<I", VALID_GLB, 12)[0]])
BASE_PATHS = [p for p in _paths(BASE_DOC) if p]


@settings(**PROPS)
@given(st.lists(st.tuples(st.integers(0, len(BASE_PATHS) - 1), _json_values, st.booleans()),
                min_size=1, max_size=4))
def test_mutated_document_loads_or_raises_gltf_error(tmp_path_factory, edits):
    doc = copy.deepcopy(BASE_DOC)
    for k, value, delete in edits:
        path = BASE_PATHS[k]
        o = doc
        try:
            for key in path[:-1]:
                o = o[key]
            if delete:
                del o[path[-1]]
            else:
                o[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue
    binary = VALID_GLB[28 + struct.unpack_from("<I", VALID_GLB, 12)[0]:]
    p = tmp_path_factory.mktemp("doc") / "m.glb"
    p.write_bytes(make_glb(doc, binary))
    a = _load_direct(p)
    if a is not None:
        an = a.select()
        NodeTree(a).world_matrices(0.25, an)
        NodeTree(a).moving(an)


def test_quantized_positions_uint_indices_and_long_chain(tmp_path):
    b = Builder()
    pa = b.accessor(np.int16([[0, 0, 0], [300, 0, 0], [0, -300, 0]]), SHORT)
    ia = b.accessor(np.uint32([2, 1, 0]), UINT)
    b.add("meshes", {"primitives": [{"attributes": {"POSITION": pa}, "indices": ia}]})
    b.doc["extensionsUsed"] = b.doc["extensionsRequired"] = ["KHR_mesh_quantization"]
    # a chain of 3000 nodes: the mesh at its end, each link translated by (1, 0, 0)
    n = 3000
    b.doc["nodes"] = [{"children": [i + 1], "translation": [1, 0, 0]} for i in range(n - 1)] + [{"mesh": 0}]
    a = load_gltf(b.write(tmp_path))
    part = a.meshes[0][0]
    assert part.positions.dtype == np.float64 and part.faces.tolist() == [[2, 1, 0]]
    np.testing.assert_array_equal(part.positions, [[0, 0, 0], [300, 0, 0], [0, -300, 0]])
    assert not part.positions.flags.writeable
    assert a.ignored == [] and a.mesh_nodes() == [n - 1] and a.roots == [0]
    assert NodeTree(a).world_matrices(0.0, ())[n - 1][0, 3] == n - 1
    # a long cycle, detached from the root, is found too
    b.doc["nodes"][n - 1]["children"] = [1]
    b.doc["nodes"][0]["children"] = []
    with pytest.raises(GltfError, match=r"nodes\[1\]: the node graph has a cycle"):
        load_gltf(b.write(tmp_path, "c.gltf"))


def test_glb_json_chunk_padding(tmp_path):
    b = one_triangle()
    js = json.dumps(b._doc_with_buffer(None)).encode()
    js += b"\0" * (4 - len(js) % 4)
    binary = bytes(b.bin) + b"\0" * (-len(b.bin) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(binary), 0x004E4942) + binary
    p = tmp_path / "z.glb"
    p.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)
    assert load_gltf(p).mesh_nodes() == [0]


# ---------------------------------------------------------------- against the conformance renders

def _coverage(tris: np.ndarray, eye, look, fov_y: float, w: int, h: int) -> np.ndarray:
    """(h, w) bool: pixel centres inside any of the world-space triangles (m, 3, 3), seen by
    a pinhole camera at `eye` looking at `look` (up +Y), as a ray caster at pixel centres
    sees them (no depth test: coverage of one object)."""
    from world import transforms as tf
    eye = np.asarray(eye, float)
    view = tf.look_at(eye, np.asarray(look, float) - eye, [0.0, 1.0, 0.0])
    proj = tf.perspective(fov_y, w / h, 0.05, 100.0)
    hom = np.concatenate([tris, np.ones(tris.shape[:2] + (1,))], axis=2)
    clip = np.einsum("ij,mkj->mki", proj @ view, hom)
    assert (clip[..., 3] > 0.05).all()
    sx = (clip[..., 0] / clip[..., 3] + 1) * 0.5 * w
    sy = (1 - clip[..., 1] / clip[..., 3]) * 0.5 * h
    mask = np.zeros((h, w), bool)
    for (x0, x1, x2), (y0, y1, y2) in zip(sx, sy):
        lo_x, hi_x = max(int(math.floor(min(x0, x1, x2))), 0), min(int(math.ceil(max(x0, x1, x2))), w)
        lo_y, hi_y = max(int(math.floor(min(y0, y1, y2))), 0), min(int(math.ceil(max(y0, y1, y2))), h)
        if lo_x >= hi_x or lo_y >= hi_y:
            continue
        px, py = np.meshgrid(np.arange(lo_x, hi_x) + 0.5, np.arange(lo_y, hi_y) + 0.5)
        e0 = (x1 - x0) * (py - y0) - (y1 - y0) * (px - x0)
        e1 = (x2 - x1) * (py - y1) - (y2 - y1) * (px - x1)
        e2 = (x0 - x2) * (py - y2) - (y0 - y2) * (px - x2)
        inside = ((e0 >= 0) & (e1 >= 0) & (e2 >= 0)) | ((e0 <= 0) & (e1 <= 0) & (e2 <= 0))
        mask[lo_y:hi_y, lo_x:hi_x] |= inside
    return mask


def _placement(position, rotation_deg, angular_velocity=(0, 0, 0), t=0.0) -> np.ndarray:
    from world import transforms as tf
    m = tf.translate(position)
    m[:3, :3] = tf.axis_angle(np.asarray(angular_velocity, float) * t) @ tf.euler_xyz_degrees(rotation_deg)
    return m


def _tris(part, m: np.ndarray, positions=None) -> np.ndarray:
    p = part.positions if positions is None else positions
    p = p @ m[:3, :3].T + m[:3, 3]
    return p[part.faces]


def _agrees(mask: np.ndarray, ids: np.ndarray, k: int, others: tuple) -> tuple[int, int]:
    """(pixels where mask and `centre_id == k` disagree, outside pixels another object
    `others` covers in front), (pixels of k)."""
    domain = ~np.isin(ids, others)
    return int(((mask != (ids == k)) & domain).sum()), int((ids == k).sum())


def test_conformance_gltf_box_silhouettes():
    """Node hierarchy, the 180-degree flip's direction, column-major matrices: the mesh
    nodes of gltf_box.toml at its frame time cover exactly the pixels that the independent
    renderer's centre_id gives them."""
    ref = np.load(ASSETS / "gltf_box.npz")
    ids, t = ref["centre_id"], 1.6
    cam = dict(eye=[0.3, 2.2, 5.6], look=[0.3, 1.1, 0.0], fov_y=40.0, w=480, h=270)
    anim = load_gltf(BOX_ANIMATED)
    an = anim.select()
    w = NodeTree(anim).world_matrices(anim.animation_time(t, an), an)
    place = _placement([-0.4, 0, 0], [0, 30, 0])
    crate = load_gltf(BOX_TEXTURED)
    cw = NodeTree(crate).world_matrices(0.0, ())
    cplace = _placement([1.3, 0, 0.4], [0, 20, 0], [0, 5, 0], t)
    objects = {2: _tris(anim.meshes[anim.nodes[3].mesh][0], place @ w[3]),
               3: _tris(anim.meshes[anim.nodes[2].mesh][0], place @ w[2]),
               4: _tris(crate.meshes[0][0], cplace @ cw[1])}
    for k, tris in objects.items():
        bad, n = _agrees(_coverage(tris, **cam), ids, k, tuple(j for j in objects if j != k))
        assert n > 4000 and bad <= 2, (k, bad, n)      # 0 when written
    # the other way round through the flip (-50 degrees instead of +50) is visibly wrong
    r = NodeTree(anim).local_matrices(anim.animation_time(t, an), an)[2]
    flipped = rot_x(-2 * 50.4) @ r[:3, :3]
    wrong = w[2].copy()
    wrong[:3, :3] = w[1][:3, :3] @ flipped
    bad, n = _agrees(_coverage(_tris(anim.meshes[0][0], place @ wrong), **cam), ids, 3, (2, 4))
    assert bad > 500, (bad, n)


def test_conformance_gltf_skin_silhouette():
    """Skinning, the looped and scaled animation time, inverse bind matrices: the skinned
    cylinder of gltf_skin.toml at its frame time covers the pixels of its id."""
    ref = np.load(ASSETS / "gltf_skin.npz")
    ids, t = ref["centre_id"], 2.3
    cam = dict(eye=[0.0, 2.0, 14.0], look=[0.0, 0.0, 0.0], fov_y=45.0, w=480, h=270)
    a = load_gltf(RIGGED)
    an = a.select()
    place = _placement([0, 0, 0], [0, 0, 90])

    def mask(at):
        w = NodeTree(a).world_matrices(at, an)
        part = a.meshes[0][0]
        pos, _ = skin_vertices(part.positions, part.normals, part.joints, part.weights, joint_matrices(a.skins[0], w))
        return _coverage(_tris(part, place, pos), **cam)

    at = a.animation_time(t, an, time_scale=3.0, loop=True)
    bad, n = _agrees(mask(at), ids, 2, (3, 4, 5))
    assert n > 6000 and bad <= 2, (bad, n)         # 0 when written
    # unlooped (clamped to the last key) is visibly another pose
    bad, n = _agrees(mask(a.animation_time(t, an, time_scale=3.0)), ids, 2, (3, 4, 5))
    assert bad > 500, (bad, n)


def test_matrix_column_padding(tmp_path):
    """MAT2 of bytes and MAT3 of shorts: each column starts on a 4-byte boundary (glTF
    3.6.2.4); the accessor's components come out column by column."""
    b = Builder()
    m2 = b.view(np.uint8([1, 2, 99, 99, 3, 4, 99, 99, 5, 6, 99, 99, 7, 8, 99, 99]).tobytes())
    b.add_accessor({"bufferView": m2, "componentType": UBYTE, "count": 2, "type": "MAT2"})
    cols = np.int16([[1, 2, 3, 99], [4, 5, 6, 99], [7, 8, 9, 99]])
    m3 = b.view(cols.tobytes())
    b.add_accessor({"bufferView": m3, "componentType": SHORT, "count": 1, "type": "MAT3", "normalized": True})
    r = gl._Reader(write(tmp_path, b.gltf_dict()))
    r.load()
    v2 = r.accessor(0, "test")
    np.testing.assert_array_equal(v2, [[1, 2, 3, 4], [5, 6, 7, 8]])
    v3 = r.accessor(1, "test")
    np.testing.assert_array_equal(v3, [np.arange(1, 10) / 32767.0])


def test_reading_a_file_allocates_its_size_not_the_limit(tmp_path):
    """An external buffer of a few bytes is read into that many (a read sized by the
    256 MiB limit allocated the whole limit first, each file)."""
    import tracemalloc
    p = one_triangle().write(tmp_path, "x.gltf", external="x.bin")
    tracemalloc.start()
    try:
        a = load_gltf(p)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert a.mesh_nodes() == [0] and peak < 8 << 20, peak
