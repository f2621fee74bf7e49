"""Skinned meshes in every mode: a mesh skinned with weight 1 to one animated joint is the
same surface, moving the same way, as the mesh on a node with that animation. Rendered
through the skinned path (posed vertex buffers, posed reveal faces, Embree scenes rebuilt
per time) and the rigid path (model matrices), every mode must give the same image."""
import numpy as np
import pytest

from viewer.render.renderer import Renderer
from world.loader import load_scene

from conftest import _context
from gltf_builder import FLOAT, UBYTE, Builder

TIMES = [0.0, 0.5, 1.0]
TRANSLATIONS = [[-1.2, 0.0, 0.0], [0.0, 0.3, 0.2], [1.2, 0.0, 0.0]]
ROTATIONS = [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.3826834, 0.9238795],
             [0.0, 0.0, 0.7071068, 0.7071068]]        # x y z w: 0, 45, 90 degrees about z


def slab():
    """A 1.6 x 0.5 x 0.3 box of 12 triangles with face normals (flat: corners unshared)."""
    lo, hi = np.array([-0.8, -0.25, -0.15]), np.array([0.8, 0.25, 0.15])
    quads = []
    for axis in range(3):
        for side in (0, 1):
            u, v = [a for a in range(3) if a != axis]
            c = np.zeros((4, 3))
            for k, (a, b) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)]):
                c[k, axis] = (lo, hi)[side][axis]
                c[k, u] = (lo, hi)[a][u]
                c[k, v] = (lo, hi)[b][v]
            quads.append(c if side else c[::-1])
    pos = np.concatenate([q[[0, 1, 2, 0, 2, 3]] for q in quads])
    n = np.cross(pos[1::3] - pos[0::3], pos[2::3] - pos[0::3])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return pos, np.repeat(n, 3, axis=0)


def animation(b: Builder, node: int):
    t = b.accessor(np.array(TIMES, np.float32), min=[TIMES[0]], max=[TIMES[-1]])
    tr = b.accessor(np.array(TRANSLATIONS, np.float32))
    rot = b.accessor(np.array(ROTATIONS, np.float32))
    b.add("animations", {"name": "move", "samplers": [
        {"input": t, "output": tr, "interpolation": "LINEAR"},
        {"input": t, "output": rot, "interpolation": "LINEAR"}], "channels": [
        {"sampler": 0, "target": {"node": node, "path": "translation"}},
        {"sampler": 1, "target": {"node": node, "path": "rotation"}}]})


def asset(folder, skinned: bool):
    b = Builder()
    pos, nrm = slab()
    attrs = {"NORMAL": b.accessor(nrm.astype(np.float32))}
    if skinned:
        attrs["JOINTS_0"] = b.accessor(np.zeros((len(pos), 4)), UBYTE)
        attrs["WEIGHTS_0"] = b.accessor(np.tile([1.0, 0, 0, 0], (len(pos), 1)), FLOAT)
    mesh = b.triangle_mesh(pos.astype(np.float32), **attrs)
    b.add("materials", {"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.2, 1.0]}})
    b.doc["meshes"][mesh]["primitives"][0]["material"] = 0
    if skinned:
        joint = b.add("nodes", {"name": "joint"})
        body = b.add("nodes", {"name": "body", "mesh": mesh, "skin": 0})
        b.add("skins", {"joints": [joint]})
        roots = [joint, body]
    else:
        joint = body = b.add("nodes", {"name": "body", "mesh": mesh})
        roots = [body]
    animation(b, joint)
    b.doc["scenes"] = [{"nodes": roots}]
    return b.write(folder, "skinned.gltf" if skinned else "rigid.gltf")


SCENE = """
background = [0.05, 0.05, 0.06]
ambient = [0.2, 0.2, 0.2]
[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
shutter = 0.12
[render]
width = 96
height = 64
time = 0.45
[[lights]]
direction = [-0.3, -0.5, -1.0]
[[objects]]
name = "wall"
mesh = { box = [8.0, 6.0, 0.1] }
position = [0.0, 0.0, -1.0]
material = { albedo = [0.8, 0.8, 0.8], texture = { kind = "stripes", axis = 0, size = 0.2, albedo2 = [0.2, 0.3, 0.5] } }
[[objects]]
name = "thing"
gltf = "ASSET"
position = [0.0, 0.1, 0.0]
angular_velocity = [0.0, 0.6, 0.0]
[[objects]]
name = "blocker"
mesh = { box = [0.3, 1.2, 0.2] }
position = [2.6, 0.3, 1.2]   # over the slab at the frame time
velocity = [-6.0, 0.0, 0.0]
"""


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    folder = tmp_path_factory.mktemp("skin")
    scenes = []
    for skinned in (False, True):
        name = asset(folder, skinned).name
        p = folder / f"{name}.toml"
        p.write_text(SCENE.replace("ASSET", name))
        scenes.append(load_scene(p))
    return scenes


def test_the_pair_differs_only_in_skinning(pair):
    rigid, skinned = pair
    r, s = rigid.objects[1], skinned.objects[1]
    assert r.skin is None and s.skin is not None and r.moving and s.moving
    for t in (0.2, 0.45, 0.51):
        np.testing.assert_allclose(r.matrix(t) @ np.c_[r.mesh.vertices, np.ones(36)].T,
                                   s.matrix(t) @ np.c_[s.vertices_at(t), np.ones(36)].T,
                                   atol=1e-6)


@pytest.mark.parametrize("mode,params", [
    ("off", {}), ("mcguire", {}), ("ue4", {}), ("guertin", {}), ("hybrid", {}),
    ("hybrid", {"hybrid.segments": 4}), ("reference", {"reference.samples": 16})])
def test_skinned_path_renders_like_rigid_path(pair, mode, params):
    from viewer.render.graph.params import ParamSet
    ctx = _context()
    images = []
    for sc in pair:
        ps = ParamSet()
        for k, v in params.items():
            ps.set(k, v)
        r = Renderer(ctx, sc, (sc.render.width, sc.render.height))
        try:
            images.append(r.render(mode, sc.render.time, ps).image)
        finally:
            r.release()
    rigid, skinned = images
    assert rigid.max() > 0.1
    diff = np.abs(rigid - skinned).max(axis=2)
    # Measured: every mode within 5e-6 of the rigid path (float32 rounding of positions
    # posed in float64 against positions moved by the matrices); a revealed skinned face
    # left in its bind pose puts 3 pixels 0.3 off.
    assert (diff > 1 / 255).sum() == 0, f"{mode}: {(diff > 1 / 255).sum()} pixels differ"
    assert diff.mean() < 1e-5


def test_screen_path_bend_reads_the_posed_vertices(pair):
    from world.camera import Camera
    from world.path_bend import screen_bend
    bends = []
    for sc in pair:
        cam = Camera(sc.camera, 960, 640)      # (px scale with the image: 10x the render)
        bends.append(screen_bend(sc, cam, sc.render.time, sc.camera.shutter))
    rigid, skinned = bends
    assert rigid > 1.0                        # the slab's turn bends its screen paths
    assert skinned == pytest.approx(rigid, rel=1e-6)
