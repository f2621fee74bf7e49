"""A glTF entry's nodes in the scene tree (scene format v1.2): the asset's node tree
evaluated at an animation time (every node's local and world matrix), under the entry's
placement. Skinned meshes are posed from these world matrices in world/skinning.py.

One pose evaluation per time: an entry's every node's world matrix at a time is computed
once (all channels sampled, the tree walked once) and kept for the last few times, and a
skinned mesh's vertices at a time likewise; the G-buffer, the motion buffers, the
screen-path bend, the static raster's key and the ray tracer all read these.
"""
from __future__ import annotations

from collections import OrderedDict

import numpy as np

from world import transforms as tf
from world.gltf import GltfAsset, sample
from world.scene import Placement

# Times kept per entry and per skinned mesh: a frame asks for t, the shutter's ends and
# the path's and bend's points (up to ~8 distinct times).
POSE_MEMO = 12


def remember(memo: dict, key, value):
    if len(memo) >= POSE_MEMO:
        memo.pop(next(iter(memo)))
    memo[key] = value
    return value


class NodeTree:
    """An asset's node tree at animation times: which nodes the played animations move,
    and every node's local and world matrix (arrays indexed by glTF node index)."""

    def __init__(self, asset: GltfAsset):
        self.asset = asset
        nodes = asset.nodes
        n = len(nodes)
        self._parent = np.array([-1 if nd.parent is None else nd.parent for nd in nodes], dtype=np.int64)
        self._has_matrix = np.array([nd.matrix is not None for nd in nodes], dtype=bool)
        self._t0 = np.array([nd.translation for nd in nodes], dtype=np.float64).reshape(n, 3)
        self._r0 = np.array([nd.rotation for nd in nodes], dtype=np.float64).reshape(n, 4)
        self._s0 = np.array([nd.scale for nd in nodes], dtype=np.float64).reshape(n, 3)
        self._m0 = np.array([np.eye(4) if nd.matrix is None else nd.matrix for nd in nodes],
                            dtype=np.float64).reshape(n, 4, 4)
        # nodes grouped by depth (all nodes, in or out of the scene): parents before children
        depth = np.zeros(n, dtype=np.int64)
        for i in asset.walk([nd.index for nd in nodes if nd.parent is None]):
            p = nodes[i].parent
            depth[i] = 0 if p is None else depth[p] + 1
        self._levels = [np.nonzero(depth == d)[0] for d in range(int(depth.max()) + 1)] if n else []
        self._cache: OrderedDict = OrderedDict()

    def _channels(self, anims):
        """The played TRS channels in file order, `matrix` nodes left out."""
        for i in sorted(set(int(x) for x in anims)):
            for ch in self.asset.animations[i].channels:
                if not self._has_matrix[ch.node]:
                    yield ch

    def animated(self, anims) -> np.ndarray:
        """(N,) whether a played channel targets the node."""
        out = np.zeros(len(self.asset.nodes), dtype=bool)
        for ch in self._channels(anims):
            out[ch.node] = True
        return out

    def moving(self, anims) -> np.ndarray:
        """animated(anims) or any ancestor animated."""
        out = self.animated(anims)
        for level in self._levels[1:]:
            out[level] |= out[self._parent[level]]
        return out

    def local_matrices(self, a, anims) -> np.ndarray:
        """(N, 4, 4) local matrices at animation time `a` (already wrapped and scaled)."""
        t, r, s = self._t0.copy(), self._r0.copy(), self._s0.copy()
        for ch in self._channels(anims):           # file order: the later channel wins
            v = sample(ch.sampler, a, ch.path)
            if ch.path == "translation":
                t[ch.node] = v
            elif ch.path == "rotation":
                r[ch.node] = v
            else:
                s[ch.node] = v
        m = tf.trs(t, tf.quat_normalised(r), s)
        m[self._has_matrix] = self._m0[self._has_matrix]
        return m

    def world_matrices(self, a, anims) -> np.ndarray:
        """(N, 4, 4) World(node) = World(parent) @ Local(node) at animation time `a`; the last
        few results are memoised (read-only arrays)."""
        key = (float(a), tuple(sorted(set(int(x) for x in anims))))
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
            return hit
        w = self.local_matrices(a, anims)
        for level in self._levels[1:]:
            w[level] = np.matmul(w[self._parent[level]], w[level])
        w.flags.writeable = False
        self._cache[key] = w
        while len(self._cache) > 8:
            self._cache.popitem(last=False)
        return w


class AssetInstance:
    """One `gltf` entry: the asset, the animations it plays, their timing, and the
    placement P(t) of the asset's root (a Placement without a parent)."""

    def __init__(self, name: str, asset: GltfAsset, animations: tuple[int, ...],
                 time_offset: float, time_scale: float, loop: bool, root: Placement):
        self.name, self.asset, self.animations = name, asset, animations
        self.time_offset, self.time_scale, self.loop = time_offset, time_scale, loop
        self.root = root
        self.tree = NodeTree(asset)
        self.node_moving = self.tree.moving(animations)     # (N,) the animated subtrees
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
            w = self.tree.world_matrices(a, self.animations)
            w.flags.writeable = False
            remember(self._worlds, a, w)
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
