"""A glTF mesh whose primitives have different materials keeps each primitive's: the
raster draws each part with its own, and the hybrid's reveal shades a revealed part with
its own (the revealed colour equals the sharp colour of the same surface)."""
import numpy as np
import pytest

from viewer.render.renderer import Renderer
from world.loader import load_scene

from conftest import _context
from gltf_builder import Builder

RED, GREEN = [0.9, 0.1, 0.1, 1.0], [0.1, 0.8, 0.2, 1.0]


def quad(x0, x1):
    p = np.array([[x0, -0.5, 0], [x1, -0.5, 0], [x1, 0.5, 0], [x0, -0.5, 0], [x1, 0.5, 0],
                  [x0, 0.5, 0]], np.float32)
    return p


def two_part_asset(folder):
    b = Builder()
    b.add("materials", {"pbrMetallicRoughness": {"baseColorFactor": RED}})
    b.add("materials", {"pbrMetallicRoughness": {"baseColorFactor": GREEN}})
    normal = b.accessor(np.tile([0.0, 0.0, 1.0], (6, 1)).astype(np.float32))
    prims = [{"attributes": {"POSITION": b.accessor(quad(x0, x1)), "NORMAL": normal},
              "material": m} for m, (x0, x1) in enumerate([(-1.0, 0.0), (0.0, 1.0)])]
    b.add("meshes", {"primitives": prims})
    node = b.add("nodes", {"name": "card", "mesh": 0})
    t = b.accessor(np.array([0.0, 1.0], np.float32), min=[0.0], max=[1.0])
    tr = b.accessor(np.array([[0.0, 0.0, 0.0], [0.4, 0.0, 0.0]], np.float32))
    b.add("animations", {"samplers": [{"input": t, "output": tr}],
                         "channels": [{"sampler": 0, "target": {"node": node,
                                                                "path": "translation"}}]})
    b.doc["scenes"] = [{"nodes": [node]}]
    return b.write(folder, "card.gltf")


SCENE = """
ambient = [0.3, 0.3, 0.3]
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
shutter = 0.1
[render]
width = 96
height = 64
time = 0.5
[[lights]]
direction = [0.0, 0.0, -1.0]
[[objects]]
name = "wall"
mesh = { box = [6.0, 4.0, 0.1] }
position = [0.0, 0.0, -0.6]
[[objects]]
name = "card"
gltf = "card.gltf"
"""
BLOCKER = """
[[objects]]
name = "blocker"
mesh = { box = [0.25, 1.6, 0.1] }
position = [2.7, 0.0, 1.0]
velocity = [-5.0, 0.0, 0.0]
"""


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("parts")
    two_part_asset(folder)
    out = []
    for name, text in (("bare", SCENE), ("blocked", SCENE + BLOCKER)):
        p = folder / f"{name}.toml"
        p.write_text(text)
        out.append(load_scene(p))
    return out


def test_each_part_drawn_with_its_material(scenes):
    bare = scenes[0]
    card = bare.objects[1]
    assert card.parts is not None and len(card.parts) == 2
    r = Renderer(_context(), bare, (96, 64))
    try:
        img = r.render("off", 0.5).image
    finally:
        r.release()
    # The card spans x in [-0.8, 1.2] at t = 0.5: its left half red, its right half green.
    row = img[32]
    lit = 0.3 + 1.0                     # ambient + the head-on light
    red = np.all(np.abs(row - np.array(RED[:3]) * lit) < 0.02, axis=1)
    green = np.all(np.abs(row - np.array(GREEN[:3]) * lit) < 0.02, axis=1)
    assert red.sum() > 10 and green.sum() > 10
    assert np.flatnonzero(red).max() < np.flatnonzero(green).min()


def test_revealed_parts_shaded_with_their_own_material(scenes):
    bare, blocked = scenes
    ctx = _context()
    r = Renderer(ctx, bare, (96, 64))
    try:
        sharp = r.render("off", 0.5).image
    finally:
        r.release()
    r = Renderer(ctx, blocked, (96, 64))
    try:
        r.render("hybrid", 0.5)
        buffers = r.buffers()
    finally:
        r.release()
    back, colour = buffers["hybrid_back"], buffers["hybrid_back_color"]
    revealed = np.round(back[..., 3]) == 1 + blocked.objects[1].id     # the card, revealed
    assert revealed.sum() > 20
    np.testing.assert_allclose(colour[revealed][:, :3], sharp[revealed], atol=1e-4)
    # both parts were revealed
    assert len({tuple(np.round(c, 2)) for c in colour[revealed][:, :3]}) >= 2
