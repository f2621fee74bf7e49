"""Every face's corners in the object's mesh space: what the GPU interpolates at a hit.

A hit is interpolated with Embree's barycentrics in mesh (local) coordinates. An affine
transform keeps barycentrics, so the same (prim, u, v) describes the hit whether it was
traced in world space (static objects) or in local space (moving ones). The shader takes
the local normal to world space with the inverse transpose of M(t), as the rasteriser
does, and textures the local position.
"""
from __future__ import annotations

import numpy as np

from world.scene import Mesh, SceneObject


class SurfaceTable:
    """Every object's mesh in one table (built once per scene): the first face row of each
    object (face_offset), and each face's corners as one texture for the GPU, made when
    asked (the hybrid uploads it once; the meshes are the scene's, not copied here)."""

    def __init__(self, objects: dict[int, SceneObject]):
        objs = [objects[k] for k in sorted(objects)]
        max_id = max(objects, default=0)
        self.face_offset = np.zeros(max_id + 1, dtype=np.int64)
        self._rows: list[tuple[Mesh, bool]] = []     # each mesh's faces once, in row order
        nf = 0
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
            self._rows.append((m, o.shading == "flat"))
            nf += len(m.faces)
        self.faces = nf

    def gpu_corners(self) -> np.ndarray:
        """(faces, 3 corners, 8) float32: position, shading normal (the face normal at all
        three corners of a flat face), uv: what glsl/modes/hybrid/reveal_shade.frag interpolates."""
        out = np.empty((self.faces, 3, 8), np.float32)
        row = 0
        for m, flat in self._rows:
            f = np.asarray(m.faces, dtype=np.int64)
            rows = out[row: row + len(f)]
            rows[:, :, 0:3] = np.asarray(m.vertices, dtype=np.float64)[f]
            rows[:, :, 3:6] = (np.asarray(m.face_normals, dtype=np.float64)[:, None, :] if flat
                               else np.asarray(m.vertex_normals, dtype=np.float64)[f])
            rows[:, :, 6:8] = 0.0 if m.uv is None else np.asarray(m.uv, dtype=np.float64)[f]
            row += len(f)
        return out
