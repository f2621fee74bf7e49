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

from world.scene import SceneObject


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


def _normalised(x: np.ndarray) -> np.ndarray:
    length = np.sqrt(np.einsum("nk,nk->n", x, x))[:, None]
    return np.divide(x, length, out=np.zeros_like(x), where=length > 0)


class SurfaceTable:
    """Every object's mesh in one set of arrays (built once per scene), so the attributes
    of all hits are a few gathers, not a loop over the objects hit."""

    def __init__(self, objects: dict[int, SceneObject]):
        objs = [objects[k] for k in sorted(objects)]
        max_id = max(objects, default=0)
        self.face_offset = np.zeros(max_id + 1, dtype=np.int64)
        verts, vnorms, uvs, faces, fnorms, flat = [], [], [], [], [], []
        nv = nf = 0
        seen: dict[tuple, int] = {}      # a mesh shared by rigid objects: its faces once
        for o in objs:
            m = o.mesh
            same = (id(m), o.shading)
            if o.skin is None and same in seen:
                self.face_offset[o.id] = seen[same]
                continue
            if o.skin is None:
                seen[same] = nf
            self.face_offset[o.id] = nf
            verts.append(m.vertices)
            vnorms.append(m.vertex_normals)
            uvs.append(m.uv if m.uv is not None else np.zeros((len(m.vertices), 2)))
            faces.append(np.asarray(m.faces, dtype=np.int64) + nv)
            fnorms.append(m.face_normals)
            flat.append(np.full(len(m.faces), o.shading == "flat"))
            nv += len(m.vertices)
            nf += len(m.faces)

        def cat(parts, shape):
            return np.concatenate(parts) if parts else np.zeros(shape)
        vertices = cat(verts, (0, 3)).astype(np.float64)
        faces = cat(faces, (0, 3)).astype(np.int64)
        # Per face, its three corners' values (F, 3, k): one np.take per attribute (much
        # faster than fancy indexing) gathers everything a hit needs.
        self.corner_position = vertices[faces]
        self.corner_normal = cat(vnorms, (0, 3)).astype(np.float64)[faces]
        self.corner_uv = cat(uvs, (0, 2)).astype(np.float64)[faces]
        self.face_normals = cat(fnorms, (0, 3)).astype(np.float64)
        self.flat = cat(flat, (0,)).astype(bool)

    def face_index(self, object_id, prim_id) -> np.ndarray:
        """(n,) int64 row of each hit's face in this table (object_id 0: -1)."""
        object_id = np.asarray(object_id)
        g = np.take(self.face_offset, object_id) + np.asarray(prim_id, dtype=np.int64)
        return np.where(object_id != 0, g, -1)

    def gpu_corners(self) -> np.ndarray:
        """(faces, 3 corners, 8) float32: position, shading normal (the face normal at all
        three corners of a flat face), uv: what glsl/modes/hybrid/reveal_shade.frag interpolates."""
        normal = np.where(self.flat[:, None, None], self.face_normals[:, None, :],
                          self.corner_normal)
        return np.concatenate([self.corner_position, normal, self.corner_uv],
                              axis=2).astype(np.float32)

    def lookup(self, object_id, prim_id, u, v) -> LocalSurface:
        """Local position, shading normal and uv of hits (object_id 0 = miss: zeros)."""
        object_id = np.asarray(object_id)
        n = len(object_id)
        position, normal, uv = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 2))
        rows = np.flatnonzero(object_id != 0)
        if not len(rows):
            return LocalSurface(position, normal, uv)
        g = np.take(self.face_offset, object_id[rows]) + np.take(prim_id, rows)
        b = np.take(u, rows).astype(np.float64)[:, None]
        c = np.take(v, rows).astype(np.float64)[:, None]
        a = 1.0 - b - c

        def interp(corners):
            k = np.take(corners, g, axis=0)
            return a * k[:, 0] + b * k[:, 1] + c * k[:, 2]
        position[rows] = interp(self.corner_position)
        normal[rows] = np.where(np.take(self.flat, g)[:, None],
                                np.take(self.face_normals, g, axis=0),
                                _normalised(interp(self.corner_normal)))
        uv[rows] = interp(self.corner_uv)
        return LocalSurface(position, normal, uv)


def local_surface(objects: dict[int, SceneObject], object_id, prim_id, u, v) -> LocalSurface:
    """Local position, shading normal and uv of hits (object_id 0 = miss: zeros).

    The normal follows the object's `shading`: "flat" gives trimesh's face normal, "smooth"
    the trimesh vertex normals interpolated with the barycentrics, then normalised
    (normalising first or not changes nothing after the shader's own normalisation).
    One-off form of SurfaceTable(objects).lookup (a RayScene keeps its table).
    """
    return SurfaceTable(objects).lookup(object_id, prim_id, u, v)
