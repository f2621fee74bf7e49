"""Surface attributes at a hit, in the object's mesh space: what the GPU needs to shade it.

Everything is interpolated with Embree's barycentrics in mesh (local) coordinates. An
affine transform keeps barycentrics, so the same (prim, u, v) describes the hit whether
it was traced in world space (static objects) or in local space (moving ones). The
shader takes the local normal to world space with the inverse transpose of M(t), as the
rasteriser does, and textures the local position.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from viewer.scene import SceneObject


@dataclass
class LocalSurface:
    position: np.ndarray   # (n, 3) float64, mesh space
    normal: np.ndarray     # (n, 3) float64, mesh space, unit length (zeros on a miss)
    uv: np.ndarray         # (n, 2) float64, zeros where the mesh has none or on a miss


def barycentric_weights(u, v) -> np.ndarray:
    """(n, 3) weights of a face's vertices 0, 1, 2 from Embree's (u, v)."""
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    return np.stack([1.0 - u - v, u, v], axis=-1)


def interpolate(values: np.ndarray, faces: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Per-vertex `values` (n_vertices, k) at points with the given faces and weights."""
    return np.einsum("nc,nck->nk", weights, values[faces])


def _normalised(x: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(x, axis=1, keepdims=True)
    return np.divide(x, length, out=np.zeros_like(x), where=length > 0)


def local_surface(objects: dict[int, SceneObject], object_id, prim_id, u, v) -> LocalSurface:
    """Local position, shading normal and uv of hits (object_id 0 = miss: zeros).

    The normal follows the object's `shading`: "flat" gives trimesh's face normal, "smooth"
    the trimesh vertex normals interpolated with the barycentrics, then normalised
    (normalising first or not changes nothing after the shader's own normalisation).
    """
    object_id = np.asarray(object_id)
    n = len(object_id)
    w = barycentric_weights(u, v)
    position = np.zeros((n, 3))
    normal = np.zeros((n, 3))
    uv = np.zeros((n, 2))
    for oid in np.unique(object_id):
        if oid == 0:
            continue
        rows = np.flatnonzero(object_id == oid)
        mesh = objects[int(oid)].mesh
        prims = np.asarray(prim_id)[rows]
        faces = mesh.faces[prims]
        position[rows] = interpolate(mesh.vertices, faces, w[rows])
        if objects[int(oid)].shading == "flat":
            normal[rows] = mesh.face_normals[prims]
        else:
            normal[rows] = _normalised(interpolate(mesh.vertex_normals, faces, w[rows]))
        if mesh.uv is not None:
            uv[rows] = interpolate(mesh.uv, faces, w[rows])
    return LocalSurface(position, normal, uv)
