"""Every face's corners in the object's mesh space: what the GPU interpolates at a hit.

A hit is interpolated with Embree's barycentrics in mesh (local) coordinates. An affine
transform keeps barycentrics, so the same (prim, u, v) describes the hit whether it was
traced in world space (static objects) or in local space (moving ones). The shader takes
the local normal to world space with the inverse transpose of M(t), as the rasteriser
does, and textures the local position.
"""
from __future__ import annotations

import numpy as np

from world.scene import SceneObject


class SurfaceTable:
    """Every object's mesh in one set of arrays (built once per scene): the first face row
    of each object (face_offset) and each face's corners, one texture for the GPU."""

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
        # Per face, its three corners' values (F, 3, k).
        self.corner_position = vertices[faces]
        self.corner_normal = cat(vnorms, (0, 3)).astype(np.float64)[faces]
        self.corner_uv = cat(uvs, (0, 2)).astype(np.float64)[faces]
        self.face_normals = cat(fnorms, (0, 3)).astype(np.float64)
        self.flat = cat(flat, (0,)).astype(bool)

    def gpu_corners(self) -> np.ndarray:
        """(faces, 3 corners, 8) float32: position, shading normal (the face normal at all
        three corners of a flat face), uv: what glsl/modes/hybrid/reveal_shade.frag interpolates."""
        normal = np.where(self.flat[:, None, None], self.face_normals[:, None, :],
                          self.corner_normal)
        return np.concatenate([self.corner_position, normal, self.corner_uv],
                              axis=2).astype(np.float32)
