"""What a glTF asset may hold (world/limits.py), checked once as it is read: the objects,
triangles and vertices its scene draws, counted from the accessors' counts before any
mesh is read (a mesh drawn by several nodes counts once for each); how far its node tree
can carry a vertex from the asset's origin over every animation; and that each skinned
primitive can be skinned.
"""
from __future__ import annotations

import math

import numpy as np

from world import limits
from world.gltf.document import GltfError, array, fail, integer, obj, ref
from world.gltf.model import GltfAsset, GltfNode, GltfPart, walk

_BIG = 1e300                    # bounds are capped here: past every limit, never inf or NaN
_HERMITE = 8.0 / 27.0           # |h10| + |h11| at most: a cubic segment's tangents' weight


def check_drawn(doc: dict, accessors: list[dict], nodes: list[GltfNode], roots: list[int]) -> None:
    """The scene's mesh nodes against limits.MAX_OBJECTS, their meshes' triangles against
    limits.MAX_TRIANGLES and vertices against limits.MAX_GLTF_VERTICES."""
    drawn = [i for i in walk(nodes, roots) if nodes[i].mesh is not None]
    if len(drawn) > limits.MAX_OBJECTS:
        fail(f"the scene has {len(drawn)} mesh nodes, more than the limit of "
             f"{limits.MAX_OBJECTS} objects")
    meshes = doc.get("meshes", [])
    counts: dict[int, tuple[int, int]] = {}
    uses: dict[int, int] = {}
    for i in drawn:
        m = nodes[i].mesh
        if m not in counts:
            counts[m] = _mesh_counts(meshes[m], f"meshes[{m}]", accessors)
        uses[m] = uses.get(m, 0) + 1
    for k, (what, most) in enumerate((("triangles", limits.MAX_TRIANGLES),
                                      ("vertices", limits.MAX_GLTF_VERTICES))):
        total = sum(counts[m][k] * uses[m] for m in counts)
        if total > most:
            m = max(counts, key=lambda m: counts[m][k] * uses[m])
            fail(f"the scene draws {total} {what}, more than the limit of {most} (a mesh counts "
                 f"once for each node drawing it: meshes[{m}]'s {counts[m][k]} by {uses[m]} "
                 f"node{'s' if uses[m] > 1 else ''})")


def _mesh_counts(mesh, where: str, accessors: list[dict]) -> tuple[int, int]:
    """(triangles, vertices) of a mesh, from its accessors' counts."""
    triangles = vertices = 0
    for k, p in enumerate(array(obj(mesh, where), "primitives", where, required=True)):
        pw = f"{where}.primitives[{k}]"
        p = obj(p, pw)
        attrs = obj(p.get("attributes"), f"{pw}.attributes") if "attributes" in p else fail(f"{pw}: missing attributes")
        pos = ref(attrs, "POSITION", f"{pw}.attributes", accessors, "accessors")
        if pos is None:
            fail(f"{pw}.attributes: no POSITION")
        n = integer(obj(accessors[pos], f"accessors[{pos}]"), "count", f"accessors[{pos}]", lo=1)
        if "indices" in p:
            ii = ref(p, "indices", pw, accessors, "accessors")
            n_indices = integer(obj(accessors[ii], f"accessors[{ii}]"), "count", f"accessors[{ii}]", lo=1)
            triangles += n_indices // 3
        else:
            triangles += n // 3
        vertices += n
    return triangles, vertices


def check_reach(asset: GltfAsset) -> None:
    """Every mesh node's vertices within +-limits.MAX_SCENE_NUMBER of the asset's origin at
    every animation time: bounded through the node tree, World = World(parent) @ Local with
    |Local's 3x3| <= its largest scale factor (or a matrix's Frobenius norm) and its
    translation's length, each the largest over the node's values and keys (a cubic
    segment's tangents added with their largest weight)."""
    lin, off = _world_bounds(asset)
    most = limits.MAX_SCENE_NUMBER
    for i in asset.mesh_nodes():
        nd = asset.nodes[i]
        radius = max(float(np.sqrt(np.einsum("ij,ij->i", p.positions, p.positions)).max())
                     for p in asset.meshes[nd.mesh])
        if nd.skin is None:
            reach = _mul(lin[i], radius) + off[i]
        else:
            sk = asset.skins[nd.skin]
            reach = max(_mul(lin[j], _mul(float(np.linalg.norm(ibm[:3, :3])), radius)
                             + float(np.linalg.norm(ibm[:3, 3]))) + off[j]
                        for j, ibm in zip(sk.joints, sk.inverse_bind))
        if not reach <= most:
            fail(f"nodes[{i}]: its mesh can reach {reach:.3g} from the asset's origin (through "
                 f"the node tree's translations and scales, over every animation), beyond "
                 f"+-{most:g}")


def _world_bounds(asset: GltfAsset) -> tuple[list[float], list[float]]:
    """Per node, bounds on World's 3x3 (spectral norm) and translation (length)."""
    n = len(asset.nodes)
    scale, move = [0.0] * n, [0.0] * n
    for nd in asset.nodes:
        if nd.matrix is not None:
            scale[nd.index] = float(np.linalg.norm(nd.matrix[:3, :3]))
            move[nd.index] = float(np.linalg.norm(nd.matrix[:3, 3]))
        else:
            scale[nd.index] = float(np.abs(nd.scale).max())
            move[nd.index] = float(np.linalg.norm(nd.translation))
    for an in asset.animations:
        for ch in an.channels:
            if asset.nodes[ch.node].matrix is not None or ch.path == "rotation":
                continue
            v, k = ch.sampler.values, ch.sampler.times
            size = (np.abs(v).max(axis=-1) if ch.path == "scale"
                    else np.sqrt(np.einsum("...i,...i->...", v, v)))
            top = float(size.max())
            if ch.sampler.interpolation == "CUBICSPLINE" and len(k) > 1:
                top *= 1.0 + _HERMITE * float(np.diff(k).max())
            target = scale if ch.path == "scale" else move
            target[ch.node] = max(target[ch.node], top)
    lin, off = [0.0] * n, [0.0] * n
    for i in walk(asset.nodes, [nd.index for nd in asset.nodes if nd.parent is None]):
        p = asset.nodes[i].parent
        if p is None:
            lin[i], off[i] = scale[i], move[i]
        else:
            lin[i] = _mul(lin[p], scale[i])
            off[i] = min(_mul(lin[p], move[i]) + off[p], _BIG)
    return lin, off


def _mul(a: float, b: float) -> float:
    return min(a * b, _BIG) if math.isfinite(a * b) else _BIG


def check_skins(asset: GltfAsset) -> None:
    """Every skinned mesh node's primitives can be skinned by its skin."""
    for i in asset.mesh_nodes():
        nd = asset.nodes[i]
        if nd.skin is not None:
            for k, part in enumerate(asset.meshes[nd.mesh]):
                _check_skin_part(part, len(asset.skins[nd.skin].joints),
                                 f"nodes[{i}] (skins[{nd.skin}], meshes[{nd.mesh}].primitives[{k}])")


def _check_skin_part(part: GltfPart, n_joints: int, where: str) -> None:
    if part.joints is None or part.weights is None:
        raise GltfError(f"{where}: a skinned primitive needs JOINTS_0 and WEIGHTS_0")
    total = part.weights.sum(axis=1)
    bad = np.nonzero(~(total > 0.0))[0]
    if bad.size:
        raise GltfError(f"{where}: the weights of vertex {int(bad[0])} sum to {float(total[bad[0]])!r}"
                        " (must be > 0)")
    used = part.weights != 0.0
    out = used & ((part.joints >= n_joints) | (part.joints < 0))
    if out.any():
        v = int(np.nonzero(out.any(axis=1))[0][0])
        jj = int(part.joints[v][out[v]][0])
        raise GltfError(f"{where}: vertex {v} uses joint {jj}, but the skin has {n_joints} joints")
