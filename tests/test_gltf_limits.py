"""What a glTF asset may hold (world/limits.py, docs/scene-format.md "Limits"), checked as
it is read: the objects, triangles and vertices its scene draws (a mesh drawn by several
nodes counts once for each) before any mesh is read; names; every number at the glTF
boundary finite and in range, named by its glTF path; how far the node tree carries a
vertex; and a bare asset's framing, whose mistakes name the asset, not keys of the scene
document made around it."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from gltf_builder import FLOAT, Builder
from world import limits
from world.errors import SceneError
from world.gltf import GltfError, load_gltf
from world.loader import load_scene

TRI = np.float32([[0, 0, 0], [1, 0, 0], [0, 1, 0]])
SCENE = """[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
[[objects]]
name = "before"
mesh = {{ box = [1.0, 1.0, 1.0] }}
[[objects]]
name = "g"
gltf = "{gltf}"
"""


def instanced(meshes: list[int], uses: list[int]) -> Builder:
    """Meshes of meshes[m] triangles (a fan), node k drawing mesh uses[k]."""
    b = Builder()
    for t in meshes:
        pos = np.float32([[0, 0, 0]] + [[math.cos(a), math.sin(a), 0] for a in np.linspace(0, 1, t + 1)])
        fan = np.array([[0, i + 1, i + 2] for i in range(t)]).reshape(-1)
        b.triangle_mesh(pos, fan)
    for k, m in enumerate(uses):
        b.add("nodes", {"mesh": m, "translation": [k, 0, 0]})
    b.doc["scenes"] = [{"nodes": list(range(len(uses)))}]
    return b


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.lists(st.integers(1, 4), min_size=1, max_size=3).flatmap(
           lambda meshes: st.tuples(st.just(meshes),
                                    st.lists(st.integers(0, len(meshes) - 1), min_size=1, max_size=6))),
       st.integers(1, 20), st.integers(1, 6))
def test_drawn_triangles_and_objects_count_every_node(tmp_path_factory, case, most, objects):
    meshes, uses = case
    path = instanced(meshes, uses).write(tmp_path_factory.mktemp("drawn"))
    drawn = sum(meshes[m] for m in uses)
    saved = limits.MAX_TRIANGLES, limits.MAX_OBJECTS
    limits.MAX_TRIANGLES, limits.MAX_OBJECTS = most, objects
    try:
        if len(uses) > objects:
            with pytest.raises(GltfError, match=rf"^the scene has {len(uses)} mesh nodes, more "
                                                rf"than the limit of {objects} objects$"):
                load_gltf(path)
        elif drawn > most:
            top = max(set(uses), key=lambda m: meshes[m] * uses.count(m))
            with pytest.raises(GltfError, match=rf"^the scene draws {drawn} triangles, more than "
                                                rf"the limit of {most} \(a mesh counts once for "
                                                rf"each node drawing it: meshes\[{top}\]'s "):
                load_gltf(path)
        else:
            a = load_gltf(path)
            assert sum(len(a.meshes[a.nodes[i].mesh][0].faces) for i in a.mesh_nodes()) == drawn
    finally:
        limits.MAX_TRIANGLES, limits.MAX_OBJECTS = saved


def test_drawn_triangles_are_counted_before_a_buffer_is_read(tmp_path):
    b = instanced([4], [0, 0, 0])
    d = b.gltf_dict()
    d["buffers"][0]["uri"] = "missing.bin"          # never read: the count comes first
    (tmp_path / "a.gltf").write_text(json.dumps(d))
    saved = limits.MAX_TRIANGLES
    limits.MAX_TRIANGLES = 11
    try:
        with pytest.raises(GltfError, match=r"^the scene draws 12 triangles"):
            load_gltf(tmp_path / "a.gltf")
    finally:
        limits.MAX_TRIANGLES = saved


def test_a_scene_counts_a_shared_mesh_for_each_node_and_its_earlier_objects(tmp_path, monkeypatch):
    instanced([4], [0, 0, 0]).write(tmp_path, "g.gltf")
    (tmp_path / "s.toml").write_text(SCENE.format(gltf="g.gltf"))
    monkeypatch.setattr(limits, "MAX_TRIANGLES", 24)     # the box's 12 and 3 x 4
    sc = load_scene(tmp_path / "s.toml")
    assert len(sc.objects) == 4 and all(o.mesh is sc.objects[1].mesh for o in sc.objects[1:])
    monkeypatch.setattr(limits, "MAX_TRIANGLES", 23)
    with pytest.raises(SceneError, match=r"objects\[2\] \(g\)\.gltf: 12 triangles here would make "
                                         r"the scene's 24, more than the 23 it may hold"):
        load_scene(tmp_path / "s.toml")
    monkeypatch.setattr(limits, "MAX_OBJECTS", 3)
    monkeypatch.setattr(limits, "MAX_TRIANGLES", 24)
    with pytest.raises(SceneError, match=r"objects\[2\] \(g\)\.gltf: .*g\.gltf: its 3 mesh nodes would "
                                         r"bring the scene's objects to 4, more than the limit of 3"):
        load_scene(tmp_path / "s.toml")


def test_names_are_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "MAX_NAME_CHARS", 8)
    b = instanced([1], [0])
    b.doc["nodes"][0]["name"] = "n" * 9
    with pytest.raises(GltfError, match=r"^nodes\[0\]\.name: 9 characters, more than the limit of 8$"):
        load_gltf(b.write(tmp_path))
    b.doc["nodes"][0]["name"] = "n" * 8
    t = b.accessor(np.float32([0, 1]))
    v = b.accessor(np.float32([[0, 0, 0], [1, 0, 0]]))
    b.add("animations", {"name": "a" * 12, "samplers": [{"input": t, "output": v}],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]})
    with pytest.raises(GltfError, match=r"^animations\[0\]\.name: 12 characters"):
        load_gltf(b.write(tmp_path))
    (tmp_path / "s.toml").write_text(SCENE.replace('"before"', '"' + "b" * 9 + '"').format(gltf="x"))
    with pytest.raises(SceneError, match=r"s\.toml: objects\[1\]\.name: expected a name of at most 8 "
                                         r"characters, got 9"):
        load_scene(tmp_path / "s.toml")


# Where a number enters from the asset, and the bound it keeps there.
PLACES = {
    "nodes[1].translation": limits.MAX_SCENE_NUMBER,
    "nodes[1].scale": limits.MAX_SCENE_NUMBER,
    "nodes[1].rotation": limits.MAX_SCENE_NUMBER,
    "nodes[1].matrix": limits.MAX_SCENE_NUMBER,
    "materials[0].pbrMetallicRoughness.baseColorFactor": limits.MAX_SCENE_NUMBER,
    "meshes[0].primitives[0].attributes.POSITION": limits.MAX_SCENE_NUMBER,
    "meshes[0].primitives[0].attributes.TEXCOORD_0": limits.MAX_SCENE_NUMBER,
    "skins[0].inverseBindMatrices": limits.MAX_SCENE_NUMBER,
    "animations[0].samplers[0].input": limits.MAX_TIME,
    "animations[0].samplers[0].output": limits.MAX_SCENE_NUMBER,
}
LITERAL = ("nodes", "materials")        # JSON numbers (past float64: 1e400, read as inf)


def asset_with(place: str, x: float) -> tuple[dict, float]:
    """A skinned triangle, its joint nodes[1] animated, with `x` at `place`; and the value
    as the file holds it (float32 in a buffer, a key time made to follow 0)."""
    b = Builder()
    pos, uv = TRI.copy(), np.float32([[0, 0], [1, 0], [0, 1]])
    ibm = np.eye(4, dtype=np.float32)
    times, moves = np.float32([0, 1]), np.float32([[0, 0, 0], [1, 0, 0]])
    held = {"POSITION": pos[1], "TEXCOORD_0": uv[1], "inverseBindMatrices": ibm[0, 3:],
            "input": times[1:], "output": moves[1]}
    for suffix, row in held.items():
        if place.endswith(suffix):
            row[0] = abs(x) + 1e-3 if suffix == "input" and x <= 0 else x
            stored = float(row[0])
    b.triangle_mesh(pos, None, TEXCOORD_0=b.accessor(uv),
                    JOINTS_0=b.accessor(np.uint8([[0, 0, 0, 0]] * 3), 5121),
                    WEIGHTS_0=b.accessor(np.float32([[1, 0, 0, 0]] * 3)))
    b.add("materials", {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]}})
    b.doc["meshes"][0]["primitives"][0]["material"] = 0
    b.add("nodes", {"mesh": 0, "skin": 0})
    b.add("nodes", {"name": "joint"})
    b.add("skins", {"joints": [1], "inverseBindMatrices": b.accessor(ibm.T.reshape(1, 16), FLOAT, "MAT4")})
    b.add("animations", {"samplers": [{"input": b.accessor(times), "output": b.accessor(moves)}],
                         "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}]})
    d = b.gltf_dict()
    if place.startswith(LITERAL):
        stored = x if math.isfinite(x) else math.copysign(math.inf, x)
        literal = x if math.isfinite(x) else "-1e400" if x < 0 else "1e400"   # (written bare)
        first = {"translation": [literal, 0, 0], "scale": [literal, 1, 1],
                 "rotation": [literal, 0, 0, 1], "baseColorFactor": [literal, 1, 1, 1],
                 "matrix": [literal] + [0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}
        key = place.rsplit(".", 1)[1]
        owner = d["nodes"][1] if place.startswith("nodes") else d["materials"][0]["pbrMetallicRoughness"]
        owner[key] = first[key]
    return d, stored


@settings(derandomize=True, max_examples=150, deadline=None)
@given(st.sampled_from(sorted(PLACES)),
       st.one_of(st.floats(-1e6, 1e6), st.sampled_from([1e38, -3e38, 2e7, -1.5e7, 1e6 + 1, 0.0,
                                                        math.inf, -math.inf, math.nan])))
def test_numbers_at_the_boundary_are_finite_and_in_range(tmp_path_factory, place, x):
    """The value loads where it is finite and within its bound (a scale of 0 too), else a
    one-line GltfError begins with the glTF path where it stands."""
    assume(not (place.startswith(LITERAL) and math.isnan(x)))     # JSON has no NaN
    d, stored = asset_with(place, x)
    path = tmp_path_factory.mktemp("num") / "a.gltf"
    path.write_text(json.dumps(d).replace('"1e400"', "1e400").replace('"-1e400"', "-1e400"))
    if math.isfinite(stored) and abs(stored) <= PLACES[place]:
        a = load_gltf(path)
        assert [n.name for n in a.nodes] == ["node0", "joint"]
        return
    with pytest.raises(GltfError) as e:
        load_gltf(path)
    assert str(e.value).startswith(place + ": ") and "\n" not in str(e.value), str(e.value)


def test_a_node_tree_carrying_a_vertex_too_far_is_refused(tmp_path):
    b = instanced([1], [])
    b.doc["nodes"] = [{"children": [1], "scale": [1e4] * 3}, {"children": [2], "scale": [1e4] * 3},
                      {"mesh": 0, "translation": [0.5, 0, 0]}]
    b.doc["scenes"] = [{"nodes": [0]}]
    with pytest.raises(GltfError, match=r"^nodes\[2\]: its mesh can reach 1\.5e\+08 from the asset's "
                                        r"origin"):
        load_gltf(b.write(tmp_path))
    b.doc["nodes"][1]["scale"] = [1e2] * 3               # 1e6 x (0.5 + 1): within
    a = load_gltf(b.write(tmp_path))
    assert a.mesh_nodes() == [2]
    # an animated scale counts with its largest key (500: 1e4 x 500 x 1.5 within), a
    # cubic one with its tangents too, weighted by at most 8/27 of the segment's length:
    # 1e4 x 600 (1 + 8/27 x 2) x 1.5 = 1.43e7
    t = b.accessor(np.float32([0, 2]))
    linear = b.accessor(np.float32([[1, 1, 1], [500, 500, 500]]))
    cubic = b.accessor(np.float32([[0, 0, 0], [1, 1, 1], [600, 0, 0], [0, 0, 0], [500, 500, 500], [0, 0, 0]]))
    for output, interpolation in ((linear, "LINEAR"), (cubic, "CUBICSPLINE")):
        b.doc["animations"] = [{"samplers": [{"input": t, "output": output, "interpolation": interpolation}],
                                "channels": [{"sampler": 0, "target": {"node": 1, "path": "scale"}}]}]
        if interpolation == "LINEAR":
            assert load_gltf(b.write(tmp_path)).animations[0].channels[0].node == 1
        else:
            with pytest.raises(GltfError, match=r"^nodes\[2\]: its mesh can reach 1\.43e\+07"):
                load_gltf(b.write(tmp_path))


def test_a_bare_asset_says_its_own_mistakes(tmp_path):
    """Mistakes of a .gltf given as the scene name the file and the glTF path; framing
    that would pass the scene's numbers says so, not `camera.far`."""
    b = instanced([1], [0])
    b.doc["nodes"][0]["scale"] = [1e38, 1, 1]
    with pytest.raises(SceneError) as e:
        load_scene(b.write(tmp_path, "big.gltf"))
    assert str(e.value) == (f"{tmp_path / 'big.gltf'}: nodes[0].scale: expected 3 finite numbers "
                            "within +-1e+07, got [1e+38, 1, 1]")
    b = Builder()
    b.triangle_mesh(np.float32([[0, 0, 0], [9e6, 0, 0], [0, 1, 0]]))
    b.add("nodes", {"mesh": 0})
    with pytest.raises(SceneError, match=r"far\.gltf: the asset spans \[0\.0, 0\.0, 0\.0\] to "
                                         r"\[9000000\.0, 1\.0, 0\.0\] over its animation: a camera "
                                         r"framing it would stand 1\.21e\+07 from its centre") as e:
        load_scene(b.write(tmp_path, "far.gltf"))
    assert "camera" not in str(e.value).split(": ", 1)[1].split(" ")[0]
