"""A scene file's `gltf` entry (scene format v1.2) -> its AssetInstance and one SceneObject
per mesh node, with every mistake a SceneError naming the scene file, the entry and what
is wrong (the asset's own mistakes as world.gltf words them).

Ids: the asset's mesh nodes in depth-first order take consecutive ids from `first_id`,
named `entry/<node name>`. A rigid mesh node hangs from its AssetNode (M(t) = P(t) @
World(node, t)); a skinned one from the entry's root (M(t) = P(t)) and deforms its mesh.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from world import limits
from world.gltf import GltfError, GltfPart, load_gltf
from world.gltf_scene import AssetInstance, AssetNode
from world.images import ImageError
from world.skinning import Skin
from world.scene import Material, Mesh, Placement, SceneObject

ENTRY_KEYS = ("name", "gltf", "animation", "time_offset", "time_scale", "loop", "position",
              "rotation", "scale", "velocity", "angular_velocity", "interpolation", "keys",
              "material", "parent")


def load_entry(loader, t: dict, number: int, first_id: int):
    """(AssetInstance with .nodes, [SceneObject]) of objects entry `number` (a table with
    `gltf`); `loader` is world.loader's _Loader (its checks and fail())."""
    k = loader.entry_key(t, number)
    if "mesh" in t:
        loader.fail(f"{k}.mesh", "not allowed together with gltf (the asset brings its meshes)")
    loader.table(t, k, ENTRY_KEYS)
    name = loader.name(t.get("name", f"object{number}"), f"{k}.name")
    if "parent" in t:
        loader.fail(f"{k}.parent", "not allowed on a gltf entry: place the asset with its own "
                    "position, rotation, scale, velocities or keys")
    rel = loader.string(t["gltf"], f"{k}.gltf")
    path = loader.file(rel, f"{k}.gltf", "glTF")
    errors = _AssetErrors(loader, f"{k}.gltf", path)
    try:
        asset = load_gltf(path, loader.images)
    except GltfError as e:
        errors.fail(str(e))
    animation = t.get("animation", "all")
    if isinstance(animation, bool) or not isinstance(animation, (str, int)):
        loader.fail(f"{k}.animation", "expected an animation's name or index, \"all\" or "
                    f"\"none\", got {type(animation).__name__}")
    try:
        anims = asset.select(animation)
    except GltfError as e:
        loader.fail(f"{k}.animation", f"{path}: {e}")
    time_offset = loader.number(t.get("time_offset", 0.0), f"{k}.time_offset")
    time_scale = loader.positive(t.get("time_scale", 1.0), f"{k}.time_scale")
    loop = t.get("loop", False)
    if not isinstance(loop, bool):
        loader.fail(f"{k}.loop", f"expected true or false, got {loop!r}")
    mt = loader.table(t.get("material", {}), f"{k}.material", ("specular", "shininess"))
    specular = loader.non_negative(mt.get("specular", 0.0), f"{k}.material.specular")
    shininess = loader.non_negative(mt.get("shininess", 32.0), f"{k}.material.shininess")
    root = Placement(**loader.placement(t, k))
    instance = AssetInstance(name, asset, anims, time_offset, time_scale, loop, root)
    instance.nodes = [AssetNode(instance, i, f"{name}/{asset.nodes[i].name}")
                      for i in asset.depth_first()]
    if asset.ignored:
        print(f"{loader.path}: {k}.gltf: ignored (scene format v1.2 draws none of these): "
              + ", ".join(asset.ignored), file=sys.stderr)
    _count(loader, errors, asset, first_id)
    materials = _Materials(loader, errors, asset, specular, shininess)
    return instance, _objects(instance, materials, first_id)


class _AssetErrors:
    """Mistakes of the asset itself, named by its file and the glTF item (`nodes[3].scale`),
    after the entry's key where a scene file names the asset; a bare asset is its own
    scene file, and its entry no key the user wrote."""

    def __init__(self, loader, key: str, path: Path):
        self.loader, self.key, self.path = loader, key, path
        self.bare = Path(os.path.realpath(loader.path)) == path

    def fail(self, what: str):
        if self.bare:
            self.loader.fail("", what)
        self.loader.fail(self.key, f"{self.path}: {what}")


def _count(loader, errors: _AssetErrors, asset, first_id: int) -> None:
    """The entry's objects and the triangles they draw (a mesh drawn by several nodes
    counts once for each) against the scene's limits, with the scene's earlier objects,
    before a mesh is built."""
    drawn = asset.mesh_nodes()
    if first_id - 1 + len(drawn) > limits.MAX_OBJECTS:
        errors.fail(f"its {len(drawn)} mesh nodes would bring the scene's objects to "
                    f"{first_id - 1 + len(drawn)}, more than the limit of {limits.MAX_OBJECTS}")
    triangles = sum(len(p.faces) for i in drawn for p in asset.meshes[asset.nodes[i].mesh])
    loader.budget(triangles, errors.key)
    loader.triangles += triangles


def _objects(instance: AssetInstance, materials: "_Materials", first_id: int) -> list[SceneObject]:
    """One SceneObject per mesh node: a rigid node hanging from its AssetNode (a mesh drawn
    by several rigid nodes built once), a skinned one from the entry's root."""
    asset, name = instance.asset, instance.name
    by_index = {n.index: n for n in instance.nodes}
    objects = []
    shared: dict[int, dict] = {}
    for i in asset.mesh_nodes():
        node = asset.nodes[i]
        if node.skin is None and node.mesh in shared:
            arrays = shared[node.mesh]
        else:
            arrays = _mesh(asset.meshes[node.mesh], node.skin is not None)
            if node.skin is None:
                shared[node.mesh] = arrays
        mesh, ranges = arrays["mesh"], arrays["ranges"]
        parts = arrays.setdefault("parts", [
            (first, count, materials.get(m, mesh.uv is not None and has_uv))
            for first, count, m, has_uv in ranges])
        skin = None
        if node.skin is not None:
            skin = Skin(instance, node.skin, mesh.vertices, mesh.vertex_normals,
                        arrays["joints"], arrays["weights"])
            if not skin.moving:        # a still skin: its pose once, drawn as a rigid mesh
                mesh = _posed(mesh, *skin.deformed(0.0))
                skin = None
        objects.append(SceneObject(name=f"{name}/{node.name}", id=first_id + len(objects),
                                   mesh=mesh, material=parts[0][2], shading="smooth",
                                   parent=instance.root if node.skin is not None else by_index[i],
                                   skin=skin, parts=_parts(parts)))
    return objects


class _Materials:
    """Scene materials of the asset's materials: albedo baseColorFactor.rgb, times the
    baseColorTexture where the mesh has TEXCOORD_0 (the factor premultiplied into the
    image: bilinear filtering is linear, so the product is the same; the scene's images
    make each image and factor pair once), specular and shininess from the entry. Each
    made once."""

    def __init__(self, loader, errors: _AssetErrors, asset, specular: float, shininess: float):
        self.loader, self.errors, self.asset = loader, errors, asset
        self.specular, self.shininess = specular, shininess
        self.made: dict = {}

    def get(self, index: int | None, textured: bool) -> Material:
        key = (index, textured)
        if key not in self.made:
            if index is None:
                base, image = np.ones(4), None
            else:
                m = self.asset.materials[index]
                base, image = np.asarray(m.base_color, np.float64), m.image
            albedo = np.clip(base[:3], 0.0, None)
            texture = None
            if textured and image is not None:
                try:
                    texture = self.loader.images.texture(self.loader.images.tinted(image, albedo))
                except ImageError as e:
                    self.errors.fail(f"materials[{index}]: {e}")
            self.made[key] = Material(albedo=albedo, specular=self.specular,
                                      shininess=self.shininess, texture=texture)
        return self.made[key]


def _parts(parts):
    """None where every part has one material (the common case), else the parts."""
    first = parts[0][2]
    return None if all(m is first for _, _, m in parts) else parts


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit normals of the faces by their winding ((v1 - v0) x (v2 - v0)); 0 where a face
    has no area."""
    v = vertices[faces]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _unit(n: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _mesh(parts: list[GltfPart], skinned: bool) -> dict:
    """One Mesh of a glTF mesh's primitives, in order. A primitive with NORMAL is smooth
    (its normals interpolated); one without is flat: its corners unshared, each with its
    face's normal. UVs turned to this project's convention (origin bottom-left: v -> 1 -
    v); zeros for a primitive without TEXCOORD_0 where another has them. Returns the mesh,
    the face ranges with their material and whether they have UVs, and for a `skinned`
    node's mesh its joints and weights (the reader checked that every primitive has them)."""
    pos, nrm, uvs, faces, joints, weights, ranges = [], [], [], [], [], [], []
    any_uv = any(p.uv is not None for p in parts)
    nv = nf = 0
    for p in parts:
        f = np.asarray(p.faces, np.int64)
        v = np.asarray(p.positions, np.float64)
        cols = {"uv": p.uv, "joints": p.joints, "weights": p.weights}
        if p.normals is None:                   # flat: unshare the corners
            n = np.repeat(face_normals(v, f), 3, axis=0)
            corners = f.reshape(-1)
            v = v[corners]
            cols = {c: (a[corners] if a is not None else None) for c, a in cols.items()}
            f = np.arange(len(corners), dtype=np.int64).reshape(-1, 3)
        else:
            n = _unit(np.asarray(p.normals, np.float64))
        pos.append(v)
        nrm.append(n)
        if any_uv:
            uv = cols["uv"]
            uvs.append(np.zeros((len(v), 2)) if uv is None
                       else np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1))
        if skinned:
            joints.append(cols["joints"])
            weights.append(cols["weights"])
        faces.append(f + nv)
        ranges.append((nf, len(f), p.material, p.uv is not None))
        nv += len(v)
        nf += len(f)
    vertices = np.concatenate(pos)
    allf = np.concatenate(faces)
    mesh = Mesh(vertices=vertices, faces=allf, vertex_normals=np.concatenate(nrm),
                face_normals=face_normals(vertices, allf),
                uv=np.concatenate(uvs) if any_uv else None)
    width = max((j.shape[1] for j in joints), default=0)

    def padded(a, fill):           # JOINTS_1 on some primitives only: pad the others
        return np.concatenate([np.pad(x, ((0, 0), (0, width - x.shape[1])),
                                      constant_values=fill) for x in a])
    return {"mesh": mesh, "ranges": ranges,
            "joints": padded(joints, 0) if joints else None,
            "weights": padded(weights, 0.0) if weights else None}


def _posed(mesh: Mesh, vertices: np.ndarray, normals: np.ndarray) -> Mesh:
    """The mesh in one skinned pose (vertices, normals), its face normals remade."""
    v = np.array(vertices)
    return Mesh(vertices=v, faces=mesh.faces, vertex_normals=np.array(normals),
                face_normals=face_normals(v, mesh.faces), uv=mesh.uv)
