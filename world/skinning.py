"""Linear blend skinning (scene format v1.2, "Skins"): a glTF skin's joint matrices, a
mesh's vertices and normals posed by them, and Skin, a skinned mesh node's pose at time t.

Beside world/gltf_scene.py, which evaluates the glTF node tree that the joints are nodes
of; the reader (world/gltf/) checks at load that every skinned primitive can be skinned.
"""
from __future__ import annotations

import numpy as np

from world.gltf import GltfSkin
from world.gltf_scene import AssetInstance, remember


def joint_matrices(skin: GltfSkin, worlds) -> np.ndarray:
    """(J, 4, 4) World(joint_j) @ inverseBind_j of the nodes' world matrices `worlds`."""
    return np.matmul(np.asarray(worlds)[skin.joints], skin.inverse_bind)


def skin_vertices(positions, normals, joints, weights, joint_mats, normalize_normals=True):
    """Linear blend skinning: B = sum_i w_i J[j_i] (weights divided by their sum where it is
    not 1), positions -> B v, normals -> inverse transpose of B's 3x3 (computed as the
    cofactor matrix times sign(det), so a singular B never raises), normalised unless
    `normalize_normals` is False (then scaled as the true inverse transpose where det != 0).
    Zero-weight influences are ignored whatever their joint index. float64, vectorised."""
    p = np.asarray(positions, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    jm = np.asarray(joint_mats, dtype=np.float64)
    total = w.sum(axis=1)
    fix = (total != 1.0) & (total != 0.0)
    if fix.any():
        w = w / np.where(fix, total, 1.0)[:, None]
    j = np.where(w != 0.0, np.asarray(joints), 0)
    np.clip(j, 0, jm.shape[0] - 1, out=j)
    rows = jm[:, :3, :].reshape(jm.shape[0], 12)          # the 3x4 top of each joint matrix
    b = np.einsum("nk,nkc->nc", w, np.take(rows, j, axis=0))   # (n, 12): B row-major
    m = np.ascontiguousarray(b.T)                        # m[4 r + c] = B[r, c], each (n,)
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    out_p = np.empty((p.shape[0], 3))
    for r in range(3):
        out_p[:, r] = m[4 * r] * x + m[4 * r + 1] * y + m[4 * r + 2] * z + m[4 * r + 3]
    if normals is None:
        return out_p, None
    nrm = np.asarray(normals, dtype=np.float64)
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = (m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10])
    # cofactor matrix C = det * inverse transpose: C[r, c] = (-1)^(r+c) minor(r, c)
    c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
    c10, c11, c12 = a02 * a21 - a01 * a22, a00 * a22 - a02 * a20, a01 * a20 - a00 * a21
    c20, c21, c22 = a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10
    det = a00 * c00 + a01 * c01 + a02 * c02
    nx, ny, nz = nrm[:, 0], nrm[:, 1], nrm[:, 2]
    out_n = np.empty((nrm.shape[0], 3))
    out_n[:, 0] = c00 * nx + c01 * ny + c02 * nz
    out_n[:, 1] = c10 * nx + c11 * ny + c12 * nz
    out_n[:, 2] = c20 * nx + c21 * ny + c22 * nz
    if normalize_normals:
        length = np.sqrt(np.einsum("ni,ni->n", out_n, out_n))
        out_n /= np.where(length > 0.0, np.where(det < 0.0, -length, length), 1.0)[:, None]
    else:
        out_n /= np.where(det != 0.0, det, 1.0)[:, None]
    return out_p, out_n


class Skin:
    """Linear blend skinning of one mesh node's vertices by a glTF skin: at time t the
    vertices in the asset's space, B v with B = sum_i w_i J_(j_i)(t) (the skinned node's own
    World is not applied; the object's matrix is the entry's placement P(t))."""

    def __init__(self, instance: AssetInstance, skin: int, positions: np.ndarray,
                 normals: np.ndarray, joints: np.ndarray, weights: np.ndarray):
        self.instance, self.skin = instance, skin
        self.positions, self.normals = positions, normals     # the bind pose, (n, 3)
        self.joints, self.weights = joints, weights            # (n, k)
        joint_nodes = np.asarray(instance.asset.skins[skin].joints, np.int64)
        self.moving = bool(instance.node_moving[joint_nodes].any())
        self._memo: dict[float, tuple[np.ndarray, np.ndarray]] = {}

    def stamp(self, *times) -> tuple:
        """What the poses at `times` depend on (their animation times): a key for what is
        kept of them (posed buffers, Embree scenes)."""
        return tuple(self.instance.animation_time(t) if self.moving else 0.0
                     for t in times if t is not None)

    def points(self, t: float, step: int) -> np.ndarray:
        """Every `step`-th vertex posed at t (the screen-path bend's samples): only those
        skinned, or taken from the whole pose where that is kept already."""
        a = self.instance.animation_time(t) if self.moving else 0.0
        if a in self._memo:
            return self._memo[a][0][::step]
        mats = joint_matrices(self.instance.asset.skins[self.skin], self.instance.worlds(t))
        return skin_vertices(self.positions[::step], None, self.joints[::step],
                             self.weights[::step], mats)[0]

    def deformed(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(positions, unit normals) at time t, (n, 3) float64 each, read-only."""
        a = self.instance.animation_time(t) if self.moving else 0.0
        got = self._memo.get(a)
        if got is None:
            mats = joint_matrices(self.instance.asset.skins[self.skin], self.instance.worlds(t))
            p, n = skin_vertices(self.positions, self.normals, self.joints, self.weights, mats)
            for x in (p, n):
                x.flags.writeable = False
            got = remember(self._memo, a, (p, n))
        return got
