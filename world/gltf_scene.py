"""A glTF entry's nodes in the scene tree (scene format v1.2): the asset's animated node
tree under the entry's placement, and linear blend skinning of its skinned meshes.

One pose evaluation per time: an entry's every node's world matrix at a time is computed
once (all channels sampled, the tree walked once) and kept for the last few times, and a
skinned mesh's vertices at a time likewise; the G-buffer, the motion buffers, the
screen-path bend, the static raster's key and the ray tracer all read these.
"""
from __future__ import annotations

import numpy as np

from world.gltf import GltfAsset, skin_vertices
from world.scene import Placement

# Times kept per entry and per skinned mesh: a frame asks for t, the shutter's ends and
# the path's and bend's points (up to ~8 distinct times).
POSE_MEMO = 12


def _remember(memo: dict, key, value):
    if len(memo) >= POSE_MEMO:
        memo.pop(next(iter(memo)))
    memo[key] = value
    return value


class AssetInstance:
    """One `gltf` entry: the asset, the animations it plays, their timing, and the
    placement P(t) of the asset's root (a Placement without a parent)."""

    def __init__(self, name: str, asset: GltfAsset, animations: tuple[int, ...],
                 time_offset: float, time_scale: float, loop: bool, root: Placement):
        self.name, self.asset, self.animations = name, asset, animations
        self.time_offset, self.time_scale, self.loop = time_offset, time_scale, loop
        self.root = root
        self.node_moving = asset.moving(animations)        # (N,) the animated subtrees
        self._worlds: dict[float, np.ndarray] = {}
        # (t0, f): the animation runs f times as fast about t0 (hmblur bench --speeds, as
        # keyed paths are retimed); None: as written.
        self.retime: tuple[float, float] | None = None

    @property
    def animated(self) -> bool:
        return bool(self.node_moving.any())

    def animation_time(self, t: float) -> float:
        if self.retime is not None:
            t0, f = self.retime
            t = t0 + f * (t - t0)
        return self.asset.animation_time(t, self.animations, self.time_offset,
                                         self.time_scale, self.loop)

    def worlds(self, t: float) -> np.ndarray:
        """(N, 4, 4) every node's World(node, t) in the asset's space (read-only)."""
        a = self.animation_time(t) if self.animated else 0.0
        w = self._worlds.get(a)
        if w is None:
            w = self.asset.world_matrices(a, self.animations)
            w.flags.writeable = False
            _remember(self._worlds, a, w)
        return w

    def node_matrix(self, index: int, t: float) -> np.ndarray:
        """P(t) @ World(node, t): a node's transform in the scene (a new array)."""
        return self.root.matrix(t) @ self.worlds(t)[index]


class AssetNode:
    """A node of a glTF entry, as a parent in the scene tree (named `entry/<node name>`):
    its transform is its object's, P(t) @ World(node, t), or for a skinned mesh node P(t)
    alone (the skinned object's: glTF does not apply a skinned node's own World)."""

    def __init__(self, instance: AssetInstance, index: int, name: str):
        self.instance, self.index, self.name = instance, index, name
        node = instance.asset.nodes[index]
        self.skinned = node.mesh is not None and node.skin is not None

    @property
    def moving(self) -> bool:
        if self.skinned:
            return self.instance.root.moving
        return bool(self.instance.node_moving[self.index]) or self.instance.root.moving

    def matrix(self, t: float) -> np.ndarray:
        if self.skinned:
            return self.instance.root.matrix(t)
        return self.instance.node_matrix(self.index, t)


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
        mats = self.instance.asset.joint_matrices(self.skin, self.instance.worlds(t))
        return skin_vertices(self.positions[::step], None, self.joints[::step],
                             self.weights[::step], mats)[0]

    def deformed(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(positions, unit normals) at time t, (n, 3) float64 each, read-only."""
        a = self.instance.animation_time(t) if self.moving else 0.0
        got = self._memo.get(a)
        if got is None:
            mats = self.instance.asset.joint_matrices(self.skin, self.instance.worlds(t))
            p, n = skin_vertices(self.positions, self.normals, self.joints, self.weights, mats)
            for x in (p, n):
                x.flags.writeable = False
            got = _remember(self._memo, a, (p, n))
        return got
