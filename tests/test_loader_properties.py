"""Property: for any TOML document, load_scene returns a valid Scene or raises SceneError
whose message names the file; never any other exception.

Three sources of documents: random nested tables and arrays, random mutations of a valid
scene (drop, add or replace keys at any depth), and random edits of a valid file's text.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from test_scene_loader import QUAD_OBJ, base_doc, toml_doc
from world.errors import SceneError
from world.scene import Scene
from world.loader import load_scene

# derandomize: the same examples on every run and machine (a failure reproduces as it is).
SETTINGS = dict(max_examples=200, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])

KEYS = ["name", "background", "ambient", "camera", "render", "lights", "objects", "position",
        "look_at", "up", "fov_y", "near", "far", "shutter", "velocity", "angular_velocity",
        "width", "height", "time", "direction", "color", "mesh", "rotation", "scale", "shading",
        "material", "albedo", "specular", "shininess", "texture", "kind", "size", "albedo2",
        "axis", "path", "box", "sphere", "cylinder", "revolve", "sections", "radius",
        "subdivisions"]
WORDS = ["smooth", "flat", "checker", "stripes", "image", "quad.obj", "tex.png", "", "box",
         "missing.obj", "scene.toml", "."]

text = st.text(st.characters(blacklist_categories=("Cs",)), max_size=8)
scalars = st.one_of(
    st.booleans(),
    st.integers(-3, 50),
    st.integers(-(2 ** 70), 2 ** 70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-10, 10),
    st.sampled_from(WORDS),
    text,
)
keys = st.one_of(st.sampled_from(KEYS), text)
values = st.recursive(
    scalars,
    lambda children: st.one_of(
        st.lists(children, max_size=4),
        st.lists(st.floats(-5, 5) | st.integers(-2, 5), min_size=2, max_size=4),
        st.lists(st.floats(-5, 5), min_size=3, max_size=3),
        st.dictionaries(keys, children, max_size=5)),
    max_leaves=25)
documents = st.dictionaries(keys, values, max_size=7)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    d = tmp_path_factory.mktemp("props")
    (d / "quad.obj").write_text(QUAD_OBJ)
    Image.fromarray(np.arange(12, dtype=np.uint8).reshape(2, 2, 3) * 20).save(d / "tex.png")
    return d


def valid_doc() -> dict:
    d = base_doc()
    d["objects"].append({"name": "picture", "mesh": "quad.obj", "scale": [1.0, 0.5, 1.0],
                         "material": {"texture": {"kind": "image", "path": "tex.png"}}})
    return d


def check(path):
    """The property itself, plus the invariants a loaded Scene must satisfy."""
    try:
        s = load_scene(path)
    except SceneError as e:
        assert str(path) in str(e)
        return None
    assert isinstance(s, Scene)
    assert [o.id for o in s.objects] == list(range(1, len(s.objects) + 1))
    for light in s.lights:
        assert abs(np.linalg.norm(light.direction) - 1) < 1e-12
    for o in s.objects:
        for a in (o.position, o.rotation, o.scale, o.velocity, o.angular_velocity,
                  o.mesh.vertices, o.mesh.vertex_normals, o.mesh.face_normals):
            assert a.dtype == np.float64 and np.all(np.isfinite(a))
        assert len(o.mesh.faces) > 0 and o.shading in ("smooth", "flat")
    c = s.camera
    assert 0 < c.fov_y < 180 and 0 < c.near < c.far and c.shutter >= 0
    return s


def test_the_valid_document_loads(workdir):
    p = workdir / "scene.toml"
    p.write_text(toml_doc(valid_doc()))
    s = check(p)
    assert s.objects[-1].material.texture.image.shape == (2, 2, 3)


@settings(**SETTINGS)
@given(doc=documents)
def test_random_documents(workdir, doc):
    p = workdir / "scene.toml"
    p.write_text(toml_doc(doc), encoding="utf-8")
    check(p)


def _paths(node, prefix=()):
    yield prefix
    items = node.items() if isinstance(node, dict) else enumerate(node) \
        if isinstance(node, list) else ()
    for k, child in items:
        yield from _paths(child, prefix + (k,))


def plausible(old):
    """A value of the same shape as `old`: edits that often still load."""
    if isinstance(old, (int, float)) and not isinstance(old, bool):
        return st.floats(-10, 10) | st.integers(-2, 60) | st.sampled_from(
            [0, 0.0, 180.0, float("nan"), float("inf"), -0.0])
    if isinstance(old, list) and old and all(isinstance(x, (int, float)) for x in old):
        return st.lists(st.floats(-5, 5) | st.integers(-1, 3), min_size=len(old),
                        max_size=len(old))
    if isinstance(old, str):
        return st.sampled_from(WORDS)
    return values


def _mutate(draw, doc: dict) -> None:
    """One random edit at a node drawn uniformly from the whole tree (so mostly deep in
    objects and materials): drop it, replace it, or add a key or an element inside it."""
    path = draw(st.sampled_from(list(_paths(doc))))
    node = doc
    for k in path:
        node = node[k]
    op = draw(st.sampled_from(["drop", "replace", "similar", "add"])) if path else "add"
    if op == "add" and isinstance(node, dict):
        node[draw(keys)] = draw(values)
    elif op == "add" and isinstance(node, list):
        node.append(draw(values))
    else:
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        if op == "drop":
            del parent[path[-1]]
        elif op == "similar":
            parent[path[-1]] = draw(plausible(node))
        else:
            parent[path[-1]] = draw(values)


@settings(**SETTINGS)
@given(data=st.data())
def test_mutations_of_a_valid_scene(workdir, data):
    doc = copy.deepcopy(valid_doc())
    for _ in range(data.draw(st.integers(1, 3))):
        _mutate(data.draw, doc)
    p = workdir / "scene.toml"
    p.write_text(toml_doc(doc), encoding="utf-8")
    check(p)


@settings(**{**SETTINGS, "max_examples": 100})
@given(data=st.data())
def test_text_edits_of_a_valid_file(workdir, data):
    src = toml_doc(valid_doc())
    for _ in range(data.draw(st.integers(1, 3))):
        i = data.draw(st.integers(0, len(src)))
        j = data.draw(st.integers(i, min(len(src), i + 6)))
        src = src[:i] + data.draw(st.sampled_from(["", "[", "]", "=", "\"", ",", "\n", "{",
                                                   "0", "-", "nan", "x", "#"])) + src[j:]
    p = workdir / "scene.toml"
    p.write_text(src, encoding="utf-8")
    check(p)
